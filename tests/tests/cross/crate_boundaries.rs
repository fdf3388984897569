//! The crates' boundaries, as the workspace's manifests state them: `antenna-cli` and
//! `antenna-monitor` read recordings and the stream through `antenna-data` and never depend
//! on the daemon (`host-daemon`), except for their tests; `antenna-data` depends on none of
//! the daemon, the CLI or the monitor; `antenna-bus` (the segments' bus and commissioning,
//! which `antenna segments` shares with the daemon) depends on none of them either.
//!
//! Scenes: `antenna-scene` is the one scene model. It depends on none of the applications
//! (the CLI, the daemon, the monitor) nor on `antenna-data`; the monitor reads scenes through
//! it and no longer depends on the CLI, not even in its tests; and no crate but
//! `antenna-scene` defines an antenna or a wall description of its own (found by what makes
//! one: a struct with a link length and a joint stiffness, or a wall placed by a distance and
//! an angle), so that a scene's keys mean the same thing everywhere.
#![allow(clippy::unwrap_used)]

use std::path::Path;

/// The workspace's root folder.
fn root() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

/// The dependency tables (`dependencies`, `build-dependencies`, target ones) of a manifest.
fn normal_dependencies(manifest: &str) -> Vec<String> {
    dependencies(manifest, &["dependencies", "build-dependencies"])
}

/// Every dependency table of a manifest, `dev-dependencies` too.
fn all_dependencies(manifest: &str) -> Vec<String> {
    dependencies(
        manifest,
        &["dependencies", "build-dependencies", "dev-dependencies"],
    )
}

/// The names in the tables `keys` (and the target-specific ones) of a manifest.
fn dependencies(manifest: &str, keys: &[&str]) -> Vec<String> {
    let path = root().join(manifest);
    let value: toml::Value = toml::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let table = value.as_table().unwrap();
    let mut names = Vec::new();
    let mut collect = |t: &toml::Table| {
        for &key in keys {
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

#[test]
fn the_scene_model_is_a_library_of_its_own_and_the_monitor_does_not_need_the_cli() {
    let deps = all_dependencies("gui/Cargo.toml");
    assert!(!deps.iter().any(|d| d == "antenna-cli"), "gui: {deps:?}");
    assert!(deps.iter().any(|d| d == "antenna-scene"), "gui: {deps:?}");
    let deps = normal_dependencies("crates/antenna-cli/Cargo.toml");
    assert!(
        deps.iter().any(|d| d == "antenna-scene"),
        "antenna-cli: {deps:?}"
    );
    let deps = normal_dependencies("crates/antenna-scene/Cargo.toml");
    for other in [
        "antenna-cli",
        "antenna-monitor",
        "host-daemon",
        "antenna-data",
        "antenna-sim-physics",
        "antenna-bus",
    ] {
        assert!(!deps.iter().any(|d| d == other), "antenna-scene: {deps:?}");
    }
    let deps = normal_dependencies("crates/antenna-figure/Cargo.toml");
    for other in [
        "antenna-cli",
        "antenna-monitor",
        "host-daemon",
        "antenna-scene",
    ] {
        assert!(!deps.iter().any(|d| d == other), "antenna-figure: {deps:?}");
    }
}

/// What makes a struct an antenna description: a link length (one for all links, or one per
/// link) and a joint stiffness (a profile's bounds, a profile, or one per joint).
fn describes_an_antenna(fields: &[String]) -> bool {
    let has = |f: &dyn Fn(&str) -> bool| fields.iter().any(|x| f(x));
    has(&|x| x == "link_length_m" || x == "link_lengths_m")
        && has(&|x| x.contains("stiffness") || x.contains("n_m_per_rad") || x == "profile")
}

/// What makes a struct a wall description: a line placed by its distance from the track and
/// its angle to it.
fn describes_a_wall(fields: &[String]) -> bool {
    fields.iter().any(|x| x == "distance_m")
        && fields
            .iter()
            .any(|x| x == "angle_deg" || x == "angle_rad" || x == "angle")
}

/// Structs that look like descriptions but are not one of their own, and why.
const NOT_DESCRIPTIONS: &[(&str, &str)] = &[
    // `antenna design`'s flags: the shorthand for a scene's `[antenna]` and
    // `[antenna.stiffness]` on the command line (`antenna design --scene FILE` reads a scene).
    ("crates/antenna-cli/src/bin/antenna/main.rs", "DesignArgs"),
    // The live wall estimate (stream protocol 1's `estimate`, as sent and as the monitor keeps
    // it): a measurement of a wall's distance and angle, not a wall a scene describes.
    (
        "crates/antenna-data/src/stream/message.rs",
        "EstimateMessage",
    ),
    ("gui/src/estimate.rs", "Estimate"),
];

/// Every struct in `text` with its fields' names (fields at the struct's top level; comments
/// and attributes skipped).
fn structs_with_fields(text: &str) -> Vec<(String, Vec<String>)> {
    let code: String = text
        .lines()
        .map(|line| line.split("//").next().unwrap_or_default())
        .collect::<Vec<_>>()
        .join("\n");
    let mut found = Vec::new();
    let mut rest = code.as_str();
    while let Some(at) = rest.find("struct ") {
        let preceded_by_ident = rest[..at]
            .chars()
            .next_back()
            .is_some_and(|c| c.is_alphanumeric() || c == '_');
        rest = &rest[at + "struct ".len()..];
        if preceded_by_ident {
            continue;
        }
        let name: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        // a braced struct: `{` before any `;` or `(` (tuple and unit structs have no keys)
        let Some(open) = rest.find(['{', ';', '(']) else {
            break;
        };
        if name.is_empty() || !rest[open..].starts_with('{') {
            continue;
        }
        let body = &rest[open + 1..];
        let mut depth = 0usize;
        let mut fields = Vec::new();
        let mut start = 0;
        let mut end = body.len();
        for (i, c) in body.char_indices() {
            match c {
                '{' | '(' | '[' | '<' => depth += 1,
                '}' | ')' | ']' | '>' if depth > 0 => depth -= 1,
                '}' => {
                    end = i;
                    break;
                }
                ',' if depth == 0 => {
                    fields.extend(field_name(&body[start..i]));
                    start = i + 1;
                }
                _ => {}
            }
        }
        fields.extend(field_name(&body[start..end]));
        found.push((name, fields));
        rest = &body[end..];
    }
    found
}

/// The name of a field declaration (`#[attr] pub name: Type`), if it is one.
fn field_name(declaration: &str) -> Option<String> {
    let mut text = declaration.trim();
    while let Some(attribute) = text.strip_prefix("#[") {
        let close = attribute.find(']')?;
        text = attribute[close + 1..].trim_start();
    }
    for visibility in ["pub(crate)", "pub(super)", "pub"] {
        if let Some(after) = text.strip_prefix(visibility)
            && after.starts_with(char::is_whitespace)
        {
            text = after.trim_start();
            break;
        }
    }
    let name: String = text
        .chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect();
    let after = text[name.len()..].trim_start();
    (!name.is_empty() && after.starts_with(':') && !after.starts_with("::")).then_some(name)
}

/// The `.rs` files under `dir`, recursively.
fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.map(Result::unwrap) {
        let path = entry.path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn the_description_finder_sees_antennas_and_walls() {
    let text = "/// doc\n#[derive(Debug)]\npub struct A {\n    /// x, m\n    pub links: usize,\n    \
                #[serde(default)]\n    pub link_length_m: f64,\n    pub profile: Vec<(u8, String)>,\n}\n\
                struct W { distance_m: f64, angle_deg: f64 }\nstruct T(f64);\nstruct U;\n\
                struct Chain { link_lengths_m: Vec<f64>, stiffness_nm_per_rad: Vec<f64> }\n\
                struct Point { x_m: f64, y_m: f64 }";
    let found = structs_with_fields(text);
    let names: Vec<&str> = found.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["A", "W", "Chain", "Point"]);
    assert_eq!(found[0].1, ["links", "link_length_m", "profile"]);
    assert!(describes_an_antenna(&found[0].1));
    assert!(describes_a_wall(&found[1].1));
    assert!(describes_an_antenna(&found[2].1));
    assert!(!describes_an_antenna(&found[3].1) && !describes_a_wall(&found[3].1));
}

#[test]
fn no_crate_but_antenna_scene_describes_an_antenna_or_a_wall() {
    let manifest: toml::Value =
        toml::from_str(&std::fs::read_to_string(root().join("Cargo.toml")).unwrap()).unwrap();
    let members = manifest["workspace"]["members"].as_array().unwrap();
    let mut offenders = Vec::new();
    let mut scanned = 0;
    for member in members.iter().filter_map(toml::Value::as_str) {
        // antenna-scene is the description; sim-core is the model a scene is turned into
        // (`Chain`, `Wall`), which describes nothing of its own.
        if member == "crates/antenna-scene" || member == "sim-core" {
            continue;
        }
        let mut files = Vec::new();
        rust_files(&root().join(member).join("src"), &mut files);
        for file in files {
            let text = std::fs::read_to_string(&file).unwrap();
            let shown = file
                .strip_prefix(root())
                .unwrap_or(&file)
                .display()
                .to_string();
            for (name, fields) in structs_with_fields(&text) {
                scanned += 1;
                let allowed = NOT_DESCRIPTIONS
                    .iter()
                    .any(|&(f, n)| shown == f && name == n);
                if !allowed && (describes_an_antenna(&fields) || describes_a_wall(&fields)) {
                    offenders.push(format!(
                        "{shown}: struct {name} {{ {} }}",
                        fields.join(", ")
                    ));
                }
            }
        }
    }
    assert!(scanned > 100, "only {scanned} structs found");
    assert!(
        offenders.is_empty(),
        "antenna or wall descriptions outside antenna-scene (a scene's keys belong there):\n{}",
        offenders.join("\n")
    );
    for (file, name) in NOT_DESCRIPTIONS {
        let text = std::fs::read_to_string(root().join(file)).unwrap();
        assert!(
            structs_with_fields(&text).iter().any(|(n, _)| n == name),
            "{file}: no struct {name}: drop it from NOT_DESCRIPTIONS"
        );
    }
}
