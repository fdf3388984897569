//! `antenna design` on known inputs: a target equal to a wire's own stiffness maps to that
//! wire with zero error, targets outside the wires are flagged, a profile from the command
//! line or from a scene gives one row per joint with the profile's values, and bad input
//! exits 2.
#![allow(clippy::unwrap_used)]

mod common;

use common::{example, run, stderr, stdout};
use serde_json::Value;

/// `k = 2.0614e12 r^4 + 0.0016` for a diameter in inches.
fn wire_k(diameter_in: f64) -> f64 {
    let r = diameter_in * 0.0254 / 2.0;
    2.0614e12 * r.powi(4) + 0.0016
}

fn design_json(args: &[&str]) -> Value {
    let mut all = vec!["design"];
    all.extend_from_slice(args);
    all.push("--json");
    let out = run(&all);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    serde_json::from_str(&stdout(&out)).unwrap()
}

#[test]
fn explicit_targets_map_to_the_nearest_wire() {
    let k16 = wire_k(0.016);
    let values = format!("{k16},0.082,0.001,0.0169");
    let v = design_json(&["--values", &values]);
    let joints = v["joints"].as_array().unwrap();
    assert_eq!(joints.len(), 4);
    let j = &joints[0];
    assert_eq!(j["joint"], 1);
    assert!((j["wire_diameter_in"].as_f64().unwrap() - 0.016).abs() < 1e-12);
    assert!(j["error_percent"].as_f64().unwrap().abs() < 1e-9);
    assert!((j["realized_n_m_per_rad"].as_f64().unwrap() - k16).abs() < 1e-15);
    assert_eq!(j["range"], "in-range");
    // 0.082 is beyond the stiffest wire (0.030 in): it gets that wire and is flagged.
    assert!((joints[1]["wire_diameter_in"].as_f64().unwrap() - 0.030).abs() < 1e-12);
    assert_eq!(joints[1]["range"], "above-stiffest-wire");
    let err = joints[1]["error_n_m_per_rad"].as_f64().unwrap();
    assert!((err - (wire_k(0.030) - 0.082)).abs() < 1e-12);
    // Below the cable alone.
    assert_eq!(joints[2]["range"], "below-cable-only");
    // 0.0169 lies between the 0.022 in and 0.024 in wires: the nearest is 0.024 in.
    assert!((joints[3]["wire_diameter_in"].as_f64().unwrap() - 0.024).abs() < 1e-12);
    assert_eq!(v["all_in_range"], false);
    let max = v["max_abs_error_percent"].as_f64().unwrap();
    assert!(
        (max - 100.0 * (wire_k(0.010) / 0.001 - 1.0)).abs() < 1e-9,
        "{max}"
    );
}

#[test]
fn a_profile_gives_one_wire_per_joint() {
    let v = design_json(&[
        "--profile",
        "linear",
        "--links",
        "5",
        "--link-length-m",
        "0.04",
    ]);
    let joints = v["joints"].as_array().unwrap();
    assert_eq!(joints.len(), 4);
    // Linear from 0.082 at joint 1 to 0.004 at joint 4, in equal steps.
    let targets: Vec<f64> = joints
        .iter()
        .map(|j| j["target_n_m_per_rad"].as_f64().unwrap())
        .collect();
    let expected = [0.082, 0.056, 0.030, 0.004];
    for (t, e) in targets.iter().zip(expected) {
        assert!((t - e).abs() < 1e-12, "{targets:?}");
    }
    for j in joints {
        let realized = j["realized_n_m_per_rad"].as_f64().unwrap();
        let d = j["wire_diameter_in"].as_f64().unwrap();
        assert!((realized - wire_k(d)).abs() < 1e-15);
    }

    let out = run(&["design", "--profile", "fast-exponential"]);
    assert_eq!(out.status.code(), Some(0));
    let table = stdout(&out);
    assert_eq!(table.lines().count(), 1 + 8 + 1, "{table}");
    assert!(
        table.contains("above-stiffest-wire") && table.contains("max |error|"),
        "{table}"
    );
}

#[test]
fn a_scene_gives_its_own_stiffness() {
    let v = design_json(&["--scene", &example("explicit_values.toml")]);
    let targets: Vec<f64> = v["joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["target_n_m_per_rad"].as_f64().unwrap())
        .collect();
    assert_eq!(targets, vec![0.06, 0.04, 0.025, 0.012, 0.006]);
}

#[test]
fn bad_design_input_exits_2() {
    for args in [
        vec!["design", "--profile", "wiggly"],
        vec!["design", "--values", "0.01,-0.02"],
        vec!["design", "--profile", "linear", "--links", "1"],
        vec!["design", "--profile", "linear", "--min-n-m-per-rad", "0.1"],
        vec!["design", "--scene", "/nonexistent.toml"],
    ] {
        let out = run(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(stdout(&out).is_empty(), "{args:?}");
        assert!(
            stderr(&out).starts_with("error: "),
            "{args:?}: {}",
            stderr(&out)
        );
    }
    let out = run(&["design", "--profile", "wiggly"]);
    assert!(
        stderr(&out).contains("known profiles: constant, linear"),
        "{}",
        stderr(&out)
    );
}
