//! The crates' boundaries, as the workspace's manifests state them: `antenna-cli` and
//! `antenna-monitor` read recordings and the stream through `antenna-data` and never depend
//! on the daemon (`host-daemon`), except for their tests; `antenna-data` depends on none of
//! the daemon, the CLI or the monitor; `antenna-bus` (the segments' bus and commissioning,
//! which `antenna segments` shares with the daemon) depends on none of them either.
#![allow(clippy::unwrap_used)]

use std::path::Path;

/// The dependency tables (`dependencies`, `build-dependencies`, target ones) of a manifest.
fn normal_dependencies(manifest: &str) -> Vec<String> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(manifest);
    let value: toml::Value = toml::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let table = value.as_table().unwrap();
    let mut names = Vec::new();
    let mut collect = |t: &toml::Table| {
        for key in ["dependencies", "build-dependencies"] {
            if let Some(deps) = t.get(key).and_then(toml::Value::as_table) {
                names.extend(deps.keys().cloned());
            }
        }
    };
    collect(table);
    if let Some(targets) = table.get("target").and_then(toml::Value::as_table) {
        for target in targets.values().filter_map(toml::Value::as_table) {
            collect(target);
        }
    }
    names
}

#[test]
fn the_cli_and_the_monitor_do_not_depend_on_the_daemon() {
    for manifest in ["crates/antenna-cli/Cargo.toml", "gui/Cargo.toml"] {
        let deps = normal_dependencies(manifest);
        assert!(
            deps.iter().any(|d| d == "antenna-data"),
            "{manifest}: {deps:?}"
        );
        assert!(
            !deps.iter().any(|d| d == "host-daemon"),
            "{manifest}: {deps:?}"
        );
    }
    let deps = normal_dependencies("crates/antenna-data/Cargo.toml");
    for other in ["host-daemon", "antenna-cli", "antenna-monitor", "sim-core"] {
        assert!(!deps.iter().any(|d| d == other), "antenna-data: {deps:?}");
    }
    let deps = normal_dependencies("crates/antenna-bus/Cargo.toml");
    for other in [
        "host-daemon",
        "antenna-cli",
        "antenna-monitor",
        "antenna-data",
    ] {
        assert!(!deps.iter().any(|d| d == other), "antenna-bus: {deps:?}");
    }
}
