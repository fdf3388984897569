//! `antenna segments` on the simulated bus: scan finds configured, unassigned and
//! conflicting segments; assign moves a segment and refuses taken or reserved addresses
//! (exit 2, naming them); zero measures and writes a rig's zero_counts; status shows the
//! firmware version and a fault bit.
#![allow(clippy::unwrap_used)]

mod common;

use common::{run, stderr, stdout};
use host_daemon::service::config::Config;
use std::path::PathBuf;

/// A scratch directory holding the rig's scene ([`SCENE`], which [`RIG`] names).
fn dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("antenna-segments-{name}-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("bench_scene.toml"), SCENE).unwrap();
    dir
}

/// The simulated rig's scene: an antenna of three flexible joints (four links), one per
/// segment.
const SCENE: &str = "\
[antenna]
links = 4
link_length_m = 0.04
base_angle_deg = 30.0
[antenna.stiffness]
profile = \"linear\"
min_n_m_per_rad = 0.01
max_n_m_per_rad = 0.05
";

/// A configuration of three simulated segments, with comments to keep.
const RIG: &str = "\
# the bench rig
[bus]
device = \"sim\"

# base
[[bus.segments]]
address = 0x20
zero_counts = 2048 # placeholder
direction = \"ccw\"
[[bus.segments]]
address = 0x21
zero_counts = 2048
direction = \"cw\"
[[bus.segments]]
address = 0x22
zero_counts = 2048
direction = \"ccw\"

[sim]
scene = \"bench_scene.toml\"
";

fn json(out: &std::process::Output) -> serde_json::Value {
    serde_json::from_str(&stdout(out)).unwrap_or_else(|e| panic!("{e}: {}", stdout(out)))
}

#[test]
fn scan_finds_configured_unassigned_and_conflicting_segments() {
    let dir = dir("scan");
    let config = dir.join("rig.toml");
    std::fs::write(&config, RIG).unwrap();
    let config = config.to_str().unwrap();
    // 0x20 configured, 0x77 fresh, two at 0x30 with different angles; 0x21 and 0x22 absent.
    let out = run(&[
        "segments",
        "scan",
        "--config",
        config,
        "--sim-segment",
        "0x20:1500",
        "--sim-segment",
        "0x77:900",
        "--sim-segment",
        "0x30:240",
        "--sim-segment",
        "0x30:15",
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let report = json(&out);
    let found = report["found"].as_array().unwrap();
    let addresses: Vec<&str> = found
        .iter()
        .map(|f| f["address_hex"].as_str().unwrap())
        .collect();
    assert_eq!(addresses, vec!["0x20", "0x30", "0x77"]);
    assert_eq!(found[0]["firmware"], "1.0");
    assert_eq!(found[0]["configured"], true);
    assert_eq!(found[0]["unassigned"], false);
    assert_eq!(found[0]["angle_counts"], 1500);
    assert_eq!(found[1]["conflict"], true);
    assert_eq!(found[2]["unassigned"], true);
    assert_eq!(found[2]["address_not_set"], true);
    assert_eq!(found[2]["angle_counts"], 900);
    assert_eq!(
        report["configured_missing"],
        serde_json::json!(["0x21", "0x22"])
    );

    // The table says the same in words.
    let out = run(&[
        "segments",
        "scan",
        "--bus",
        "sim",
        "--sim-segment",
        "0x77",
        "--sim-segment",
        "0x30:240",
        "--sim-segment",
        "0x30:15",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    assert!(
        text.contains("more than one segment answers at 0x30"),
        "{text}"
    );
    assert!(
        text.contains("unassigned: `antenna segments assign 0x77 <ADDR>`"),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn assign_moves_a_fresh_segment_and_refuses_taken_or_reserved_addresses() {
    let sim = [
        "--bus",
        "sim",
        "--sim-segment",
        "0x20",
        "--sim-segment",
        "0x77",
    ];
    let assign = |from: &str, to: &str| {
        let mut args = vec!["segments", "assign", from, to];
        args.extend(sim);
        run(&args)
    };
    let out = assign("0x77", "0x21");
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    assert!(
        text.contains("the segment at 0x77 now answers at 0x21"),
        "{text}"
    );
    // What it says at its new address: version 1.0, its address set.
    assert!(text.contains("0x21     1.0       ok"), "{text}");

    for (to, why) in [
        ("0x20", "cannot assign 0x20: a device already answers there"),
        (
            "0x78",
            "cannot assign 0x78: address 0x78 is outside the assignable range 0x08..=0x77",
        ),
        ("0x05", "cannot assign 0x05"),
    ] {
        let out = assign("0x77", to);
        assert_eq!(out.status.code(), Some(2), "{to}: {}", stderr(&out));
        let message = stderr(&out);
        assert!(
            message.contains(&format!("sim: assign 0x77 -> {to}")) && message.contains(why),
            "{message}"
        );
        assert!(message.contains("refused, nothing written"), "{message}");
        assert!(stdout(&out).is_empty());
    }
    // Nothing at the source, and two at it.
    let out = assign("0x40", "0x41");
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("no segment answers at 0x40"),
        "{}",
        stderr(&out)
    );
    let out = run(&[
        "segments",
        "assign",
        "0x77",
        "0x21",
        "--bus",
        "sim",
        "--sim-segment",
        "0x77:100",
        "--sim-segment",
        "0x77:3000",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("more than one segment answers at 0x77"),
        "{}",
        stderr(&out)
    );
    // Not an address at all: clap's usage error, also 2.
    let out = assign("0x77", "0x1ff");
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn zero_measures_the_rig_at_rest_and_writes_a_commented_copy() {
    let dir = dir("zero");
    let config = dir.join("rig.toml");
    std::fs::write(&config, RIG).unwrap();
    let output = dir.join("rig-zeroed.toml");
    let (config_s, output_s) = (config.to_str().unwrap(), output.to_str().unwrap());
    // The magnets read 1500, 4088 and 7 with the joints straight.
    let sim = [
        "--sim-segment",
        "0x20:1500",
        "--sim-segment",
        "0x21:4088",
        "--sim-segment",
        "0x22:7",
    ];
    let mut args = vec![
        "segments",
        "zero",
        "--config",
        config_s,
        "--samples",
        "20",
        "-o",
        output_s,
        "--json",
    ];
    args.extend(sim);
    let out = run(&args);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let report = json(&out);
    let zeros: Vec<u64> = report["segments"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["zero_counts"].as_u64().unwrap())
        .collect();
    assert_eq!(zeros, vec![1500, 4088, 7]);
    assert_eq!(report["segments"][0]["configured_zero_counts"], 2048);
    assert_eq!(report["segments"][0]["max_deviation_counts"], 0);

    let written = std::fs::read_to_string(&output).unwrap();
    assert!(
        written.contains("# the bench rig") && written.contains("zero_counts = 1500 # placeholder"),
        "{written}"
    );
    let zeroed = Config::from_toml_str(&written, output_s).unwrap();
    let zeros: Vec<u16> = zeroed.bus.segments.iter().map(|s| s.zero_counts).collect();
    assert_eq!(zeros, vec![1500, 4088, 7]);
    // The input is untouched.
    assert_eq!(std::fs::read_to_string(&config).unwrap(), RIG);

    // Not again over the same file without --force, never over the input.
    let out = run(&args);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("the file exists"), "{}", stderr(&out));
    let mut over_input = vec!["segments", "zero", "--config", config_s, "-o", config_s];
    over_input.extend(sim);
    let out = run(&over_input);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("the --config file itself"),
        "{}",
        stderr(&out)
    );
    assert_eq!(std::fs::read_to_string(&config).unwrap(), RIG);

    // A sensor on a rail: measured, reported, nothing written.
    let faulty = dir.join("faulty.toml");
    let out = run(&[
        "segments",
        "zero",
        "--config",
        config_s,
        "-o",
        faulty.to_str().unwrap(),
        "--sim-segment",
        "0x20:1500",
        "--sim-segment",
        "0x21:1500:rail",
        "--sim-segment",
        "0x22:1500",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("0x21: its angle sensor reports an ADC fault"),
        "{}",
        stderr(&out)
    );
    assert!(!faulty.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn zero_on_the_default_sim_rig_reads_back_its_calibration() {
    // Without --sim-segment or --config the simulated rig is the default one: its joints at
    // rest read its configured zero_counts, 1500 + 97 k for segment k at 0x20 + k.
    let out = run(&[
        "segments",
        "zero",
        "--bus",
        "sim",
        "0x20",
        "0x23",
        "--samples",
        "3",
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let report = json(&out);
    assert_eq!(report["segments"][0]["zero_counts"], 1500);
    assert_eq!(report["segments"][1]["zero_counts"], 1500 + 3 * 97);
    assert_eq!(report["segments"][1]["samples"], 3);
    // Neither addresses nor a configuration: nothing to measure.
    let out = run(&["segments", "zero", "--bus", "sim"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("no segments"), "{}", stderr(&out));
}

#[test]
fn status_shows_the_version_and_a_faulty_segment() {
    let out = run(&[
        "segments",
        "status",
        "0x20",
        "0x21",
        "0x22",
        "--bus",
        "sim",
        "--sim-segment",
        "0x20:1500",
        "--sim-segment",
        "0x21:1800:rail",
        "--json",
    ]);
    // A flag set and a segment missing: exit 1, the report still printed.
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let report = json(&out);
    let segments = report["segments"].as_array().unwrap();
    assert_eq!(segments[0]["firmware"], "1.0");
    assert_eq!(segments[0]["status_bits"], 0);
    assert_eq!(segments[0]["angle_counts"], 1500);
    assert_eq!(segments[0]["touch_bits"], 0);
    assert_eq!(segments[1]["firmware"], "1.0");
    assert_eq!(segments[1]["adc_fault"], true);
    assert_eq!(segments[1]["status_bits"], 1);
    assert_eq!(segments[2]["error"], "no segment answers at 0x22");
    assert!(
        stderr(&out).contains("2 of 3 segment(s)"),
        "{}",
        stderr(&out)
    );

    let out = run(&[
        "segments",
        "status",
        "0x21",
        "--bus",
        "sim",
        "--sim-segment",
        "0x21:1800:rail",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stdout(&out).contains("0x21     1.0       adc-fault"),
        "{}",
        stdout(&out)
    );

    // Healthy: exit 0.
    let out = run(&["segments", "status", "0x20", "--bus", "sim"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(
        stdout(&out).contains("0x20     1.0       ok"),
        "{}",
        stdout(&out)
    );
}

#[test]
fn a_missing_bus_or_bad_spec_exits_2_saying_what() {
    let out = run(&["segments", "scan"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("no bus: give --bus sim"),
        "{}",
        stderr(&out)
    );
    let out = run(&[
        "segments",
        "scan",
        "--bus",
        "sim",
        "--sim-segment",
        "0x20:5000",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("--sim-segment \"0x20:5000\": zero counts \"5000\""),
        "{}",
        stderr(&out)
    );
    let out = run(&["segments", "scan", "--bus", "/dev/i2c-250"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("/dev/i2c-250"), "{}", stderr(&out));
}
