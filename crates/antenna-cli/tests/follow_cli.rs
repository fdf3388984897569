//! `antenna follow` (issue #47) on bad input: every case exits 2 with a message on stderr
//! located at the offending key (file:line:column), nothing on stdout and no plot file
//! written, with `--json`, `--jsonl` and neither; and on a good scene: `--json` is one
//! object with status "ok", `--jsonl` a start line, a line per step and a summary line.
#![allow(clippy::unwrap_used)]

mod common;

use std::path::Path;

use common::{run, scratch, stderr, stdout};
use serde_json::Value;

/// A short follow scene (the example's straight wall, 0.5 s). Line numbers matter to the
/// tests: each key they break is found by [`line_of`].
const GOOD: &str = r#"[antenna]
links = 9
link_length_m = 0.04
joint_limits_deg = [-90.0, 90.0]

[antenna.stiffness]
profile = "fast-exponential"
min_n_m_per_rad = 0.004
max_n_m_per_rad = 0.082

[[walls]]
shape = "line"
point_m = [0.0, 0.2]
angle_deg = 0.0
solid = "left"
surface = "smooth"
mu = 0.3

[robot]
speed_m_per_s = 0.3
body = "template"
inertia_kg_m2 = 2.0e-4
damping_n_m_s_per_rad = 4.0e-3
footprint_m = [0.12, 0.06]
mount_m = [0.04, 0.02]
mount_angle_deg = 30.0

[controller]
estimator = "contact-line"
window_s = 0.5
setpoint_m = 0.10
kp_n = 0.05
kd_n_s = 0.002
delay_s = 0.0

[follow]
duration_s = 0.5
step_s = 0.01
pose_m = [0.0, 0.12]
heading_deg = 0.0
"#;

/// The 1-based line of the first line of `text` that starts with `start`.
fn line_of(text: &str, start: &str) -> usize {
    text.lines()
        .position(|l| l.starts_with(start))
        .unwrap_or_else(|| panic!("no line starts with {start:?}"))
        + 1
}

/// `GOOD` with the line starting `key` replaced by `with`.
fn replace_line(key: &str, with: &str) -> String {
    let mut out = String::new();
    let mut done = false;
    for l in GOOD.lines() {
        if !done && l.starts_with(key) {
            out += with;
            done = true;
        } else {
            out += l;
        }
        out.push('\n');
    }
    assert!(done, "no line starts with {key:?}");
    out
}

/// Runs `antenna follow` on `text` (written to `name`) in every output mode with a plot
/// asked for, and checks the bad-input contract: exit 2, nothing on stdout, no plot file,
/// and stderr naming `path:line:column` with `line` the line of `at` and `what` in it.
fn assert_bad_input(name: &str, text: &str, at: &str, what: &[&str]) {
    let path = scratch(&format!("{name}.toml"), text);
    let line = line_of(text, at);
    let plot = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("antenna-cli-tests")
        .join(format!("{name}.svg"));
    for mode in [None, Some("--json"), Some("--jsonl")] {
        let _ = std::fs::remove_file(&plot);
        let plot_arg = plot.display().to_string();
        let mut args = vec!["follow", path.as_str(), "--plot", plot_arg.as_str()];
        if let Some(m) = mode {
            // --json conflicts with --jsonl, not with --plot.
            args.push(m);
        }
        let out = run(&args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{name} {mode:?}: {err}");
        assert!(
            stdout(&out).is_empty(),
            "{name} {mode:?}: stdout {:?}",
            stdout(&out)
        );
        assert!(!plot.exists(), "{name} {mode:?}: a plot was written");
        let located = format!("{path}:{line}:");
        let at_line = err
            .find(&located)
            .unwrap_or_else(|| panic!("{name} {mode:?}: not located at {located}: {err}"));
        // A column follows the line.
        let column: String = err[at_line + located.len()..]
            .chars()
            .take_while(char::is_ascii_digit)
            .collect();
        assert!(
            column.parse::<usize>().is_ok_and(|c| c >= 1),
            "{name} {mode:?}: no column after {located}: {err}"
        );
        for w in what {
            assert!(err.contains(w), "{name} {mode:?}: {w:?} not in {err}");
        }
    }
}

#[test]
fn a_negative_speed_is_located() {
    assert_bad_input(
        "follow_negative_speed",
        &replace_line("speed_m_per_s", "speed_m_per_s = -0.3"),
        "speed_m_per_s",
        &["speed_m_per_s", "-0.3"],
    );
}

#[test]
fn a_negative_inertia_is_located() {
    assert_bad_input(
        "follow_negative_inertia",
        &replace_line("inertia_kg_m2", "inertia_kg_m2 = -2.0e-4"),
        "inertia_kg_m2",
        &["inertia_kg_m2"],
    );
}

#[test]
fn nan_gains_are_located() {
    assert_bad_input(
        "follow_nan_kp",
        &replace_line("kp_n", "kp_n = nan"),
        "kp_n",
        &["kp_n", "NaN"],
    );
    assert_bad_input(
        "follow_nan_kd",
        &replace_line("kd_n_s", "kd_n_s = nan"),
        "kd_n_s",
        &["kd_n_s"],
    );
}

#[test]
fn a_negative_delay_is_located() {
    assert_bad_input(
        "follow_negative_delay",
        &replace_line("delay_s", "delay_s = -0.01"),
        "delay_s",
        &["delay_s", "-0.01"],
    );
}

#[test]
fn an_unknown_estimator_is_located_with_the_known_ones() {
    assert_bad_input(
        "follow_unknown_estimator",
        &replace_line("estimator", "estimator = \"sonar\""),
        "estimator",
        &["sonar", "contact-line", "bend", "ideal-preview"],
    );
}

#[test]
fn a_footprint_overlapping_the_wall_at_the_start_is_located() {
    // The wall is at y = 0.2 m and the footprint 6 cm wide: at y = 0.19 m its side is 2 cm
    // beyond the wall.
    assert_bad_input(
        "follow_starts_in_wall",
        &replace_line("pose_m", "pose_m = [0.0, 0.19]"),
        "pose_m",
        &["footprint", "overlaps wall 0"],
    );
}

#[test]
fn preview_m_without_the_ideal_preview_is_located() {
    assert_bad_input(
        "follow_preview_without_ideal",
        &replace_line("window_s", "preview_m = 0.05"),
        "preview_m",
        &["preview_m", "ideal-preview"],
    );
}

#[test]
fn a_sweep_table_in_a_follow_scene_is_located() {
    let text = format!(
        "{GOOD}\n[sweep]\nvelocity_m_per_s = [0.0167, 0.0]\nduration_s = 0.2\nstep_s = 0.01\n"
    );
    assert_bad_input(
        "follow_with_sweep",
        &text,
        "[sweep]",
        &["`sweep`", "refused in a follow scene"],
    );
}

/// Runs the good scene with `mode`; its stdout.
fn good_run(name: &str, mode: &str) -> String {
    let path = scratch(name, GOOD);
    let out = run(&["follow", &path, mode]);
    assert_eq!(out.status.code(), Some(0), "{mode}: {}", stderr(&out));
    stdout(&out)
}

#[test]
fn a_good_run_with_json_is_one_object_with_status_ok() {
    let text = good_run("follow_good_json.toml", "--json");
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 1, "{text}");
    let v: Value = serde_json::from_str(lines[0]).unwrap();
    assert_eq!(v["status"], "ok", "{v}");
    assert_eq!(v["collisions"], 0, "{v}");
    assert!(v["contact_share"].as_f64().unwrap() > 0.0, "{v}");
}

#[test]
fn a_good_run_with_jsonl_has_a_start_line_step_lines_and_a_summary_line() {
    let text = good_run("follow_good_jsonl.toml", "--jsonl");
    let lines: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    // 0.5 s at 0.01 s: 50 steps.
    assert_eq!(lines.len(), 1 + 50 + 1, "{text}");
    assert_eq!(lines[0]["type"], "start", "{}", lines[0]);
    let last = lines.last().unwrap();
    assert_eq!(last["type"], "summary", "{last}");
    assert_eq!(last["status"], "ok", "{last}");
    let steps = &lines[1..lines.len() - 1];
    let mut t_prev = -1.0;
    for s in steps {
        assert_eq!(s["type"], "step", "{s}");
        for key in [
            "t_s",
            "pose_m",
            "heading_rad",
            "omega_rad_per_s",
            "u_n_m",
            "wall_distance_m",
            "estimate_m",
            "contacts",
            "touch",
        ] {
            assert!(s.get(key).is_some(), "no {key} in {s}");
        }
        let t = s["t_s"].as_f64().unwrap();
        assert!(t > t_prev, "{s}");
        t_prev = t;
        let pose = s["pose_m"].as_array().unwrap();
        assert_eq!(pose.len(), 2);
        assert!(pose.iter().all(|p| p.as_f64().unwrap().is_finite()));
    }
    assert!(
        steps.iter().any(|s| !s["estimate_m"].is_null()),
        "no step has an estimate"
    );
}
