//! Follow studies and the follow objectives (issue #47): a study of a follow scene over speeds
//! x kp_n gives one row per combination with the follow summary as columns, in grid order
//! and in shards; `[v_max]` gives each row's highest speed, finite, monotone and the same
//! twice; an axis that does not fit the scene is a located error with exit 2; `antenna
//! optimize` with `follow-rms` and `follow-v-max` runs a tiny budget and reports.
#![allow(clippy::unwrap_used)]

mod common;

use common::{example, run, scratch, stderr, stdout};
use serde_json::Value;

use antenna_cli::study::{FOLLOW_COLUMNS, V_MAX_COLUMNS};

/// The straight-wall follow example (`examples/follow/straight_wall.toml`) with a short
/// settling window, so that short runs have an RMS error.
fn follow_scene(name: &str) -> String {
    let text = std::fs::read_to_string(example("follow/straight_wall.toml")).unwrap();
    let text = text.replace("settling_window_m = 0.5", "settling_window_m = 0.02");
    assert!(text.contains("settling_window_m = 0.02"));
    scratch(name, &text)
}

fn rows(text: &str) -> Vec<Value> {
    text.lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// The keys of a JSON line, in the order written.
fn keys(line: &str) -> Vec<String> {
    let row: Value = serde_json::from_str(line).unwrap();
    let mut keys: Vec<(usize, String)> = row
        .as_object()
        .unwrap()
        .keys()
        .map(|k| (line.find(&format!("\"{k}\":")).unwrap(), k.clone()))
        .collect();
    keys.sort();
    keys.into_iter().map(|(_, k)| k).collect()
}

/// The rows without the wall-clock time (which differs from run to run).
fn comparable(rows: &[Value]) -> Vec<Value> {
    rows.iter()
        .map(|r| {
            let mut r = r.clone();
            r.as_object_mut().unwrap().remove("wall_clock_ms");
            r
        })
        .collect()
}

#[test]
fn a_follow_study_over_speeds_and_kp_has_a_row_per_combination() {
    let scene = follow_scene("follow_study_scene.toml");
    let study = scratch(
        "follow_study.toml",
        &format!(
            "[study]\nscene = \"{scene}\"\nduration_s = 0.3\n\n[axes]\n\
             speeds_m_per_s = [0.2, 0.4]\nkp_n = [0.03, 0.05]\n"
        ),
    );
    let out = run(&["study", &study, "--format", "jsonl", "--jobs", "2"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("4 grid points (2 speeds x 2 kp_n)"),
        "{}",
        stderr(&out)
    );
    let all = rows(&stdout(&out));
    assert_eq!(all.len(), 4);
    let combinations: Vec<(f64, f64)> = all
        .iter()
        .map(|r| {
            (
                r["speed_m_per_s"].as_f64().unwrap(),
                r["kp_n"].as_f64().unwrap(),
            )
        })
        .collect();
    // The last axis varies fastest.
    assert_eq!(
        combinations,
        [(0.2, 0.03), (0.2, 0.05), (0.4, 0.03), (0.4, 0.05)]
    );
    let text = stdout(&out);
    for (i, (r, line)) in all.iter().zip(text.lines()).enumerate() {
        assert_eq!(keys(line), FOLLOW_COLUMNS, "the columns, in order");
        assert_eq!(r["index"], i as u64);
        assert_eq!(r["status"], "ok", "{r}");
        assert_eq!(r["steps"], 30);
        assert_eq!(r["profile"], "fast-exponential");
        assert_eq!(r["kd_n_s"], 0.002);
        assert!(r["kp_rad_per_s_per_m"].is_null());
        assert_eq!(r["collisions"], 0);
        let travel_m = r["travel_m"].as_f64().unwrap();
        let speed = r["speed_m_per_s"].as_f64().unwrap();
        // 30 steps of 0.01 s: the travel of the steps after the first.
        assert!(
            travel_m <= speed * 0.3 + 1e-9 && travel_m >= speed * 0.28,
            "{r}"
        );
        let rms = r["rms_error_m"].as_f64().unwrap();
        let max = r["max_error_m"].as_f64().unwrap();
        assert!(rms > 0.0 && rms <= max && max < 0.1, "{r}");
        let share = r["contact_share"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&share));
    }

    // A row is `antenna follow`'s run of the scene with the row's values.
    let text = std::fs::read_to_string(&scene)
        .unwrap()
        .replace("speed_m_per_s = 0.3", "speed_m_per_s = 0.4")
        .replace("duration_s = 10.0", "duration_s = 0.3");
    let single = scratch("follow_study_single.toml", &text);
    let out = run(&["follow", &single, "--json"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let summary: Value = serde_json::from_str(&stdout(&out)).unwrap();
    for key in [
        "status",
        "steps",
        "travel_m",
        "rms_error_m",
        "max_error_m",
        "collisions",
        "contact_share",
        "estimate_share",
        "estimate_rms_error_m",
    ] {
        assert_eq!(all[3][key], summary[key], "{key}");
    }

    // The two shards together are the rows, each once.
    let mut sharded = Vec::new();
    for shard in ["1/2", "2/2"] {
        let out = run(&["study", &study, "--format", "jsonl", "--shard", shard]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        sharded.extend(rows(&stdout(&out)));
    }
    sharded.sort_by_key(|r| r["index"].as_u64().unwrap());
    assert_eq!(comparable(&sharded), comparable(&all));

    // CSV: the same columns as a header.
    let out = run(&["study", &study, "--shard", "1/4"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), FOLLOW_COLUMNS.join(","));
    assert!(
        lines
            .next()
            .unwrap()
            .starts_with("0,fast-exponential,scene,scene,0.2,0.03,0.002,,,0.0,ok,")
    );
    assert_eq!(lines.next(), None);
}

#[test]
fn v_max_on_the_straight_wall_is_finite_monotone_and_reproducible() {
    let study = scratch(
        "follow_v_max.toml",
        &format!(
            "[study]\nscene = \"{}\"\n\n[axes]\nprofiles = [\"constant\", \"fast-exponential\"]\n\n\
             [v_max]\nspeeds_m_per_s = [0.5, 1.0]\ndistance_m = 0.15\ntolerance_m_per_s = 0.1\n\
             final_band_m = 0.05\n",
            example("follow/straight_wall.toml")
        ),
    );
    let mut results = Vec::new();
    for _ in 0..2 {
        let out = run(&["study", &study, "--format", "jsonl", "--jobs", "2"]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        assert!(
            stderr(&out).contains("2 v_max search(es)"),
            "{}",
            stderr(&out)
        );
        let text = stdout(&out);
        let all = rows(&text);
        assert_eq!(all.len(), 2);
        for (r, line) in all.iter().zip(text.lines()) {
            assert_eq!(keys(line), V_MAX_COLUMNS, "the columns, in order");
            assert_eq!(r["status"], "ok", "{r}");
            let v = r["v_max_m_per_s"].as_f64().unwrap();
            assert!(v.is_finite() && (0.5..=1.0).contains(&v), "{r}");
            assert_eq!(r["v_max_monotone"], true, "{r}");
            let runs = r["v_max_runs"].as_u64().unwrap();
            assert!(runs >= 2, "the grid's two speeds at least: {r}");
            // Below the first failing speed, or the grid's top when none fails.
            if r["v_max_failure"].is_null() {
                assert_eq!(v, 1.0);
            }
        }
        assert_eq!(all[0]["profile"], "constant");
        assert_eq!(all[1]["profile"], "fast-exponential");
        results.push(comparable(&all));
    }
    assert_eq!(results[0], results[1], "the same figures twice");
}

#[test]
fn axes_that_do_not_fit_the_scene_are_located_errors() {
    let follow = follow_scene("follow_study_bad_scene.toml");
    let sweep = example("sweep_line_wall.toml");
    let cases = [
        (
            format!("[study]\nscene = \"{follow}\"\n[axes]\nbase_angles_deg = [20.0]\n"),
            ":4:19: `base_angles_deg` in [axes]:",
            "is a follow scene",
        ),
        (
            format!("[study]\nscene = \"{follow}\"\n[axes]\nwall_distances_m = [0.1]\n"),
            ":4:20: `wall_distances_m` in [axes]:",
            "is a follow scene",
        ),
        (
            format!("[study]\nscene = \"{sweep}\"\n[axes]\nkp_n = [0.1]\n"),
            ":4:8: `kp_n` in [axes]:",
            "is not a follow scene",
        ),
        (
            format!("[study]\nscene = \"{sweep}\"\n[axes]\nspeeds_m_per_s = [0.1]\n"),
            ":4:18: `speeds_m_per_s` in [axes]:",
            "is not a follow scene",
        ),
        (
            format!("[study]\nscene = \"{sweep}\"\n[v_max]\ndistance_m = 0.2\n"),
            ":3:1: [v_max]:",
            "is not a follow scene",
        ),
        (
            format!(
                "[study]\nscene = \"{follow}\"\n[axes]\nspeeds_m_per_s = [0.1]\n\
                 [v_max]\ndistance_m = 0.2\n"
            ),
            ":4:18: `speeds_m_per_s` in [axes]:",
            "searches the speed itself",
        ),
        (
            format!("[study]\nscene = \"{follow}\"\n[axes]\nkd_rad_per_m = [1.0]\n"),
            ":4:16: `kd_rad_per_m` in [axes]:",
            "\"template\"",
        ),
        (
            format!("[study]\nscene = \"{follow}\"\n[axes]\nspeeds_m_per_s = [0.2, 0.0]\n"),
            ":4:18: `speeds_m_per_s` in [axes]:",
            "must be > 0",
        ),
        (
            format!("[study]\nscene = \"{follow}\"\n[axes]\ndelays_s = [-0.01]\n"),
            ":4:12: `delays_s` in [axes]:",
            "must be >= 0",
        ),
        (
            format!("[study]\nscene = \"{follow}\"\n[v_max]\nspeeds_m_per_s = []\n"),
            ":4:18: `speeds_m_per_s` in [v_max]:",
            "no speeds",
        ),
        (
            format!("[study]\nscene = \"{follow}\"\n[v_max]\ndistance_m = -1.0\n"),
            ":4:14: `distance_m` in [v_max]:",
            "must be > 0",
        ),
        (
            format!("[study]\nscene = \"{follow}\"\nduration_s = 1.0\n[v_max]\n"),
            ":3:14: `duration_s` in [study]:",
            "distance_m",
        ),
        (
            format!("[study]\nscene = \"{follow}\"\nstep_s = 0.2\n"),
            ":3:10: `step_s` in [study]:",
            "0.0005 to 0.05",
        ),
    ];
    for (i, (text, place, why)) in cases.iter().enumerate() {
        let path = scratch(&format!("follow_study_bad_{i}.toml"), text);
        let out = run(&["study", &path]);
        assert_eq!(out.status.code(), Some(2), "{text}: {}", stderr(&out));
        assert!(stdout(&out).is_empty(), "{text}: nothing on stdout");
        let err = stderr(&out);
        assert!(err.contains(&format!("{path}{place}")), "{text}: {err}");
        assert!(err.contains(why), "{text}: {err}");
    }
}

/// An optimization of the short follow scene with `objective` (and its extra lines).
fn optimize(case: &str, objective: &str, extra: &str) -> Value {
    let text = std::fs::read_to_string(example("follow/straight_wall.toml")).unwrap();
    let text = text
        .replace("duration_s = 10.0", "duration_s = 0.3")
        .replace("settling_window_m = 0.5", "settling_window_m = 0.02");
    let scene = scratch(&format!("follow_optimize_{case}_scene.toml"), &text);
    let file = scratch(
        &format!("follow_optimize_{case}.toml"),
        &format!(
            "[optimize]\nscenes = [\"{scene}\"]\nobjective = \"{objective}\"\n\
             parameters = \"exponential-taper\"\nmethod = \"nelder-mead\"\nbudget = 10\n{extra}"
        ),
    );
    let out = run(&["optimize", &file, "--json", "--jobs", "2"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    serde_json::from_str(&stdout(&out)).unwrap()
}

#[test]
fn optimize_minimizes_the_follow_rms_error() {
    let report = optimize("rms", "follow-rms", "");
    assert_eq!(report["objective"], "follow-rms");
    let best = report["objective_value"].as_f64().unwrap();
    assert!(
        best < 0.0 && best > -0.1,
        "minus an RMS error in metres: {best}"
    );
    let evaluations = report["evaluations"].as_u64().unwrap();
    assert!((7..=10).contains(&evaluations), "{report}");
    assert!(report["sweeps"].as_u64().unwrap() <= 10);
    for named in report["named_profiles"].as_array().unwrap() {
        let v = named["objective_value"].as_f64().unwrap();
        assert!(
            v <= best,
            "the best is at least every named profile's: {named}"
        );
    }
    assert_eq!(report["values_n_m_per_rad"].as_array().unwrap().len(), 8);
}

#[test]
fn optimize_maximizes_the_follow_v_max() {
    let report = optimize(
        "v_max",
        "follow-v-max",
        "[v_max]\nspeeds_m_per_s = [0.5, 1.0]\ndistance_m = 0.1\ntolerance_m_per_s = 0.25\n\
         final_band_m = 0.05\n",
    );
    assert_eq!(report["objective"], "follow-v-max");
    let best = report["objective_value"].as_f64().unwrap();
    assert!((0.5..=1.0).contains(&best), "m/s within the grid: {best}");
    assert!(report["sweeps"].as_u64().unwrap() <= 10);
    let table = {
        let text = std::fs::read_to_string(example("follow/straight_wall.toml")).unwrap();
        let scene = scratch("follow_optimize_table_scene.toml", &text);
        let file = scratch(
            "follow_optimize_table.toml",
            &format!(
                "[optimize]\nscenes = [\"{scene}\"]\nobjective = \"follow-v-max\"\n\
                 parameters = \"exponential-taper\"\nbudget = 9\n\
                 [v_max]\nspeeds_m_per_s = [0.5]\ndistance_m = 0.05\nfinal_band_m = 0.05\n"
            ),
        );
        let out = run(&["optimize", &file, "--jobs", "2"]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        stdout(&out)
    };
    assert!(table.contains("best: 0.5000 m/s"), "{table}");
}

#[test]
fn follow_objectives_refuse_what_does_not_fit() {
    let follow = example("follow/straight_wall.toml");
    let sweep = example("sweep_line_wall.toml");
    let cases = [
        (
            format!(
                "[optimize]\nscenes = [\"{sweep}\"]\nobjective = \"follow-rms\"\nbudget = 20\n"
            ),
            ":2:11: `scenes` in [optimize]:",
            "is not a follow scene",
        ),
        (
            format!(
                "[optimize]\nscenes = [\"{follow}\"]\nobjective = \"preview-mean\"\nbudget = 20\n"
            ),
            ":2:11: `scenes` in [optimize]:",
            "is a follow scene",
        ),
        (
            format!(
                "[optimize]\nscenes = [\"{follow}\"]\nobjective = \"follow-rms\"\nbudget = 20\n\
                 [v_max]\ndistance_m = 0.2\n"
            ),
            ":5:1: [v_max]:",
            "follow-v-max",
        ),
        (
            format!(
                "[optimize]\nscenes = [\"{follow}\"]\nobjective = \"follow-v-max\"\nbudget = 20\n\
                 duration_s = 2.0\n"
            ),
            ":5:14: `duration_s` in [optimize]:",
            "distance_m",
        ),
    ];
    for (i, (text, place, why)) in cases.iter().enumerate() {
        let path = scratch(&format!("follow_optimize_bad_{i}.toml"), text);
        let out = run(&["optimize", &path]);
        assert_eq!(out.status.code(), Some(2), "{text}: {}", stderr(&out));
        assert!(stdout(&out).is_empty(), "{text}: nothing on stdout");
        let err = stderr(&out);
        assert!(err.contains(&format!("{path}{place}")), "{text}: {err}");
        assert!(err.contains(why), "{text}: {err}");
    }
}

#[test]
fn the_example_follow_studies_and_optimization_read() {
    let dir = common::examples_dir();
    let v_max =
        antenna_cli::study::Study::from_path(&dir.join("studies/follow_v_max.toml")).unwrap();
    assert!(v_max.is_follow());
    assert_eq!(v_max.len(), 7);
    assert_eq!(v_max.columns(), V_MAX_COLUMNS);
    let options = v_max.v_max.unwrap();
    assert_eq!(options.speeds_m_per_s.len(), 20);
    assert_eq!(options.distance_m, 1.5);
    let gains =
        antenna_cli::study::Study::from_path(&dir.join("studies/follow_gains.toml")).unwrap();
    assert_eq!(gains.len(), 18);
    assert_eq!(gains.columns(), FOLLOW_COLUMNS);
    let spec =
        antenna_cli::optimize::OptimizeSpec::from_path(&dir.join("optimize/follow_rms.toml"))
            .unwrap();
    assert_eq!(spec.objective.name(), "follow-rms");
}
