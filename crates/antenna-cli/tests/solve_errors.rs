//! `antenna solve` on bad input exits 2 with nothing on stdout and a message on stderr that
//! names the file, the key and (where it can) the line and column; a solve that runs out of
//! iterations exits 1 and still prints its JSON with `"converged": false`.
#![allow(clippy::unwrap_used)]

mod common;

use common::{example, run, scratch, stderr, stdout};
use serde_json::Value;

const GOOD: &str = r#"[antenna]
links = 9
link_length_m = 0.04
base_angle_deg = 30.0
joint_limits_deg = [-90.0, 90.0]

[antenna.stiffness]
profile = "linear"
min_n_m_per_rad = 0.004
max_n_m_per_rad = 0.082
"#;

/// Solves `text` (written to `name`) and checks the bad-input contract; returns stderr.
fn bad_input(name: &str, text: &str) -> (String, String) {
    let path = scratch(name, text);
    for args in [vec!["solve", &path], vec!["solve", &path, "--json"]] {
        let out = run(&args);
        assert_eq!(out.status.code(), Some(2), "{name}: {}", stderr(&out));
        assert!(stdout(&out).is_empty(), "{name}: stdout {}", stdout(&out));
    }
    let out = run(&["solve", &path, "--json"]);
    (path, stderr(&out))
}

#[test]
fn the_good_scene_solves() {
    let path = scratch("good.toml", GOOD);
    let out = run(&["solve", &path, "--json"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
}

#[test]
fn unknown_key_names_key_line_column_and_allowed_keys() {
    let text = GOOD.replace("profile = \"linear\"", "profile = \"linear\"\nfoo = 3");
    let (path, err) = bad_input("unknown_key.toml", &text);
    assert!(
        err.contains(&format!(
            "{path}:9:1: unknown key `foo` in [antenna.stiffness]; allowed: profile, \
             min_n_m_per_rad, max_n_m_per_rad, values_n_m_per_rad"
        )),
        "{err}"
    );

    let text = GOOD.replace("links = 9", "links = 9\n  lenght_m = 0.04");
    let (path, err) = bad_input("unknown_key_antenna.toml", &text);
    assert!(
        err.contains(&format!(
            "{path}:3:3: unknown key `lenght_m` in [antenna]; allowed: links, link_length_m, \
             link_lengths_m, base_angle_deg, joint_limits_deg, rest_angles_deg, stiffness"
        )),
        "{err}"
    );

    let (path, err) = bad_input("unknown_table.toml", &format!("{GOOD}\n[wall]\nx = 1\n"));
    assert!(
        err.contains(&format!(
            "{path}:12:2: unknown key `wall` in the top level; allowed: antenna, base, \
             tip_load, tip_pin, solver, walls, sweep, start, contact"
        )),
        "{err}"
    );
}

#[test]
fn missing_file_is_bad_input() {
    let out = run(&["solve", "/nonexistent/scene.toml"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stdout(&out).is_empty());
    let err = stderr(&out);
    assert!(
        err.contains("/nonexistent/scene.toml: cannot read the scene file"),
        "{err}"
    );
}

#[test]
fn both_link_length_keys_are_rejected() {
    let text = GOOD.replace(
        "link_length_m = 0.04",
        "link_length_m = 0.04\nlink_lengths_m = [0.04, 0.04, 0.04, 0.04, 0.04, 0.04, 0.04, 0.04, 0.04]",
    );
    let (path, err) = bad_input("both_lengths.toml", &text);
    assert!(
        err.contains(&format!(
            "{path}:4:18: `link_lengths_m` and `link_length_m` in [antenna] exclude each other"
        )),
        "{err}"
    );
}

#[test]
fn wrong_list_lengths_name_the_key_and_the_count() {
    let text = GOOD.replace(
        "base_angle_deg",
        "rest_angles_deg = [1.0, 2.0, 3.0]\nbase_angle_deg",
    );
    let (path, err) = bad_input("rest_len.toml", &text);
    assert!(
        err.contains(&format!(
            "{path}:4:19: `rest_angles_deg` in [antenna]: has 3 value(s); expected 8"
        )),
        "{err}"
    );
    let text = GOOD.replace(
        "link_length_m = 0.04",
        "link_lengths_m = [0.04, 0.04, 0.04, 0.04, 0.04, 0.04, 0.04, 0.04]",
    );
    let (_, err) = bad_input("lengths_len.toml", &text);
    assert!(
        err.contains("`link_lengths_m` in [antenna]: has 8 value(s); expected 9 (one per link"),
        "{err}"
    );
    let (_, err) = bad_input(
        "force_len.toml",
        &format!("{GOOD}[tip_load]\nforce_n = [0.0, -0.05, 1.0]\n"),
    );
    assert!(
        err.contains(":12:11: `force_n` in [tip_load]: has 3 value(s); expected 2"),
        "{err}"
    );
    let (_, err) = bad_input(
        "initial_len.toml",
        &format!("{GOOD}[solver]\ninitial = [10, 10]\n"),
    );
    assert!(
        err.contains(":12:11: `initial` in [solver]: has 2 value(s); expected 8"),
        "{err}"
    );
}

#[test]
fn bad_values_name_the_key() {
    let (_, err) = bad_input("profile.toml", &GOOD.replace("\"linear\"", "\"fast-exp\""));
    assert!(
        err.contains(
            ":8:11: `profile` in [antenna.stiffness]: unknown stiffness profile name \"fast-exp\"; \
             known profiles: constant, linear, slow-exponential, fast-exponential, logarithmic, \
             slow-reciprocal, fast-reciprocal, cockroach"
        ),
        "{err}"
    );
    let (_, err) = bad_input("min_max.toml", &GOOD.replace("0.082", "0.002"));
    assert!(
        err.contains(":10:19: `max_n_m_per_rad` in [antenna.stiffness]: 0.002 is below min_n_m_per_rad = 0.004"),
        "{err}"
    );
    let (_, err) = bad_input("nan.toml", &GOOD.replace("30.0", "nan"));
    assert!(
        err.contains(":4:18: `base_angle_deg` in [antenna]: NaN is not a finite number"),
        "{err}"
    );
    let (_, err) = bad_input("type.toml", &GOOD.replace("links = 9", "links = 9.5"));
    assert!(err.contains(":2:9: `links` in [antenna]:"), "{err}");
    let (_, err) = bad_input("start.toml", &format!("{GOOD}[solver]\ninitial = \"U\"\n"));
    assert!(
        err.contains(":12:11: `initial` in [solver]: invalid value: string \"U\""),
        "{err}"
    );
    let (_, err) = bad_input(
        "values_and_profile.toml",
        &GOOD.replace("profile = \"linear\"", "values_n_m_per_rad = [0.01, 0.01, 0.01, 0.01, 0.01, 0.01, 0.01, 0.01]\nprofile = \"linear\""),
    );
    assert!(
        err.contains(
            "`profile` and `values_n_m_per_rad` in [antenna.stiffness] exclude each other"
        ),
        "{err}"
    );
    let (_, err) = bad_input("missing.toml", &GOOD.replace("link_length_m = 0.04\n", ""));
    assert!(
        err.contains("missing key `link_length_m` or `link_lengths_m` in [antenna]"),
        "{err}"
    );
}

#[test]
fn unreachable_pins_name_the_pin() {
    // Farther than the links reach: caught while reading the scene.
    let (path, err) = bad_input(
        "far_pin.toml",
        &format!("{GOOD}[tip_pin]\nposition_m = [1.0, 0.5]\n"),
    );
    assert!(
        err.contains(&format!(
            "{path}:12:14: `position_m` in [tip_pin]: the pin is"
        )),
        "{err}"
    );
    assert!(
        err.contains("farther than the flexible links reach (0.320000 m)"),
        "{err}"
    );
    // Within reach of the links but not within the joint limits: the solver says so.
    let text = GOOD.replace("[-90.0, 90.0]", "[-10.0, 10.0]");
    let (path, err) = bad_input(
        "limited_pin.toml",
        &format!("{text}[tip_pin]\nposition_m = [0.06, 0.05]\n"),
    );
    assert!(
        err.contains(&format!("{path}:12:14: `position_m` in [tip_pin]: pin")),
        "{err}"
    );
}

#[test]
fn running_out_of_iterations_exits_1_with_the_json() {
    let text = std::fs::read_to_string(example("pinned_c.toml"))
        .unwrap()
        .replace("max_iterations = 200", "max_iterations = 1");
    assert!(text.contains("max_iterations = 1\n"));
    let path = scratch("one_iteration.toml", &text);
    let out = run(&["solve", &path, "--json"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let v: Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert_eq!(v["converged"], Value::Bool(false));
    assert_eq!(v["theta_rad"].as_array().unwrap().len(), 9);
    assert!(v["residual"].as_f64().unwrap() > 1e-10);
    assert!(
        stderr(&out).contains("did not converge"),
        "{}",
        stderr(&out)
    );
    // Without --json the summary still prints, saying so.
    let out = run(&["solve", &path]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stdout(&out).contains("converged: no"), "{}", stdout(&out));
}

#[test]
fn usage_errors_exit_2_and_help_has_examples() {
    let out = run(&["solve"]);
    assert_eq!(out.status.code(), Some(2));
    let out = run(&["solve", "--seed", "3", &example("pinned_c.toml")]);
    assert_eq!(out.status.code(), Some(2), "--seed needs --all-minima");
    for cmd in ["solve", "design", "identify"] {
        let out = run(&[cmd, "--help"]);
        assert_eq!(out.status.code(), Some(0));
        assert!(
            stdout(&out).contains("Examples:"),
            "{cmd}: {}",
            stdout(&out)
        );
    }
}
