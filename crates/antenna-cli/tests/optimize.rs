//! `antenna optimize` (issue #17): the worked example beats every named profile within its
//! budget and its stiffnesses sweep back to its objective through `antenna sweep`; a small
//! run is the same run twice for a seed; wires are reported per joint; a sweep that fails is
//! counted; bad input is a located error with exit 2 and nothing on stdout.
#![allow(clippy::unwrap_used)]

mod common;

use std::path::{Path, PathBuf};

use common::{example, run, stderr, stdout};
use serde_json::Value;

/// A fresh, empty folder for one case.
fn folder(case: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("antenna-cli-optimize")
        .join(case);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A short 4.2.1-like sweep: 5 links along the 8 degree wall, 40 steps.
const SMALL_SCENE: &str = r#"[antenna]
links = 5
link_length_m = 0.04
base_angle_deg = 30.0
joint_limits_deg = [-90.0, 90.0]

[antenna.stiffness]
profile = "fast-exponential"
min_n_m_per_rad = 0.004
max_n_m_per_rad = 0.082

[[walls]]
shape = "line"
point_m = [0.0, 0.12]
angle_deg = -8.0
solid = "left"
surface = "smooth"
mu = 0.3

[sweep]
velocity_m_per_s = [0.0167, 0.0]
duration_s = 2.0
step_s = 0.05

[start]
placement = "tip-on-wall"
wall = 0
ahead_m = 0.0
shape = "C"
"#;

/// An antenna nearly rigid, pointing straight at the wall and driven into it: it jams at
/// the first step, whatever its stiffness.
const JAMMING_SCENE: &str = r#"[antenna]
links = 5
link_length_m = 0.04
base_angle_deg = 90.0
joint_limits_deg = [-0.5, 0.5]

[antenna.stiffness]
profile = "linear"
min_n_m_per_rad = 0.004
max_n_m_per_rad = 0.082

[[walls]]
shape = "line"
point_m = [0.0, 0.2]
angle_deg = 0.0
solid = "left"

[sweep]
velocity_m_per_s = [0.0, 0.05]
duration_s = 0.5
step_s = 0.01
"#;

/// Writes the small scene (and the jamming one) and `optimize` as `opt.toml` into a fresh
/// folder; returns the optimization file's path.
fn write_case(case: &str, optimize: &str) -> String {
    let dir = folder(case);
    std::fs::write(dir.join("small.toml"), SMALL_SCENE).unwrap();
    std::fs::write(dir.join("jam.toml"), JAMMING_SCENE).unwrap();
    std::fs::write(
        dir.join("no_walls.toml"),
        "[antenna]\nlinks = 5\nlink_length_m = 0.04\n[antenna.stiffness]\nvalues_n_m_per_rad = \
         [0.01, 0.01, 0.01, 0.01]\n[sweep]\nduration_s = 0.1\n",
    )
    .unwrap();
    let path = dir.join("opt.toml");
    std::fs::write(&path, optimize).unwrap();
    path.display().to_string()
}

/// Runs `antenna optimize FILE --json extra...` (on 2 threads unless `extra` says); the exit
/// code and the report.
fn optimize(file: &str, extra: &[&str]) -> (Option<i32>, Value) {
    let mut args = vec!["optimize", file, "--json"];
    if !extra.contains(&"--jobs") {
        args.extend_from_slice(&["--jobs", "2"]);
    }
    args.extend_from_slice(extra);
    let out = run(&args);
    let text = stdout(&out);
    let report = serde_json::from_str(&text)
        .unwrap_or_else(|e| panic!("{e}: {text}\nstderr: {}", stderr(&out)));
    (out.status.code(), report)
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

/// What every report must hold: within the budget, the history the running best of the
/// evaluations' objectives, the result at least the best named profile's.
fn check_report(report: &Value) {
    let budget = report["budget"].as_u64().unwrap();
    let sweeps = report["sweeps"].as_u64().unwrap();
    let evaluations = report["evaluations"].as_u64().unwrap() as usize;
    assert!(sweeps <= budget, "{sweeps} sweeps of a budget of {budget}");
    let own = report["objective_values"].as_array().unwrap();
    let history = report["history"].as_array().unwrap();
    assert_eq!((own.len(), history.len()), (evaluations, evaluations));
    let mut best = f64::NEG_INFINITY;
    for (o, h) in own.iter().zip(history) {
        if let Some(v) = o.as_f64() {
            best = best.max(v);
        }
        assert_eq!(h.as_f64().unwrap_or(f64::NEG_INFINITY), best);
    }
    let failed = own.iter().filter(|o| o.is_null()).count();
    assert_eq!(
        report["failed_evaluations"].as_u64().unwrap() as usize,
        failed
    );
    assert_eq!(report["failures"].as_array().unwrap().len(), failed);
    assert_eq!(report["named_profiles"].as_array().unwrap().len(), 7);
    if let Some(named) = report["best_named_profile"]["objective_value"].as_f64() {
        assert!(num(&report["objective_value"]) >= named);
        for n in report["named_profiles"].as_array().unwrap() {
            assert!(n["objective_value"].as_f64().is_none_or(|v| v <= named));
        }
    }
    let [lo, hi] = [0, 1].map(|i| num(&report["stiffness_bounds_n_m_per_rad"][i]));
    for k in report["values_n_m_per_rad"].as_array().unwrap() {
        assert!((lo..=hi).contains(&num(k)), "{k} outside [{lo}, {hi}]");
    }
}

/// `antenna sweep SCENE --jsonl`'s summary line.
fn sweep_summary(scene: &str) -> Value {
    let out = run(&["sweep", scene, "--jsonl"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    serde_json::from_str(text.lines().last().unwrap()).unwrap()
}

#[test]
fn the_worked_example_beats_every_named_profile_and_sweeps_back_to_its_objective() {
    let dir = folder("worked-example");
    let best_scene = dir.join("best.toml").display().to_string();
    let plot = dir.join("optimize.svg").display().to_string();
    let (code, report) = optimize(
        &example("optimize/wall_following.toml"),
        &["--scene-out", &best_scene, "--plot", &plot],
    );
    assert_eq!(code, Some(0), "{report}");
    check_report(&report);
    assert_eq!(report["budget"], 300);
    assert_eq!(report["values_n_m_per_rad"].as_array().unwrap().len(), 8);
    let found = num(&report["objective_value"]);
    let named = &report["best_named_profile"];
    assert_eq!(named["name"], "fast-exponential", "{report}");
    assert!(found > num(&named["objective_value"]), "{report}");
    assert_eq!(report["found_by"], "search");
    // the scene written with the values: `antenna sweep` gives the same preview
    let summary = sweep_summary(&best_scene);
    let swept = num(&summary["preview_mean_m"]);
    assert!((swept - found).abs() <= 1e-9, "{swept} != {found}");
    let svg = std::fs::read_to_string(&plot).unwrap();
    assert!(svg.contains("best so far") && svg.contains("fast-exponential"));
}

#[test]
fn a_small_run_is_the_same_run_twice_for_its_seed() {
    for (case, method, parameters) in [
        ("nelder-mead", "nelder-mead", "per-joint"),
        ("particle-swarm", "particle-swarm", "exponential-taper"),
    ] {
        let file = write_case(
            case,
            &format!(
                "[optimize]\nscenes = [\"small.toml\"]\nobjective = \"preview-mean\"\n\
                 parameters = \"{parameters}\"\nmethod = \"{method}\"\nbudget = 30\nseed = 7\n"
            ),
        );
        let (code, mut first) = optimize(&file, &[]);
        assert_eq!(code, Some(0), "{first}");
        check_report(&first);
        let (_, mut second) = optimize(&file, &["--jobs", "1"]);
        first["elapsed_s"] = Value::Null;
        second["elapsed_s"] = Value::Null;
        assert_eq!(first, second, "{case}: two runs differ");
        assert_eq!(first["method"], method);
        assert_eq!(first["sweeps"], 30, "{case}: the budget is spent");
        assert_eq!(first["stopped_by"], "budget");
        // the values sweep back to the objective through a scene file
        let best = folder(&format!("{case}-best")).join("best.toml");
        let best = best.display().to_string();
        let out = run(&["optimize", &file, "--scene-out", &best, "-o", "/dev/null"]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        let swept = num(&sweep_summary(&best)["preview_mean_m"]);
        assert!((swept - num(&first["objective_value"])).abs() <= 1e-9);
    }
}

#[test]
fn available_wires_are_reported_per_joint_and_the_table_names_them() {
    let file = write_case(
        "wires",
        "[optimize]\nscenes = [\"small.toml\"]\nobjective = \"flip-free-preview\"\n\
         parameters = \"exponential-taper\"\nwires = \"available\"\nmethod = \"particle-swarm\"\n\
         budget = 24\nseed = 3\n",
    );
    let (code, report) = optimize(&file, &[]);
    assert_eq!(code, Some(0), "{report}");
    check_report(&report);
    let values = report["values_n_m_per_rad"].as_array().unwrap();
    let wires = report["wire_diameters_in"].as_array().unwrap();
    assert_eq!(values.len(), wires.len());
    for (k, d) in values.iter().zip(wires) {
        // k = 2.0614e12 r^4 + 0.0016 N m/rad (docs/model.md 5)
        let r_m = num(d) * 0.0254 / 2.0;
        let made = 2.0614e12 * r_m.powi(4) + 0.0016;
        assert!(
            (num(k) - made).abs() < 1e-12,
            "{k} is not the {d} in wire's {made}"
        );
    }
    let out = run(&["optimize", &file, "--jobs", "2"]);
    let table = stdout(&out);
    assert!(
        table.contains("wire (in)") && table.contains("named profiles"),
        "{table}"
    );
}

#[test]
fn a_sweep_that_fails_makes_its_evaluation_infeasible_and_is_counted() {
    let file = write_case(
        "failing",
        "[optimize]\nscenes = [\"small.toml\", \"jam.toml\"]\nobjective = \"preview-mean\"\n\
         parameters = \"exponential-taper\"\nbudget = 20\n",
    );
    let (code, report) = optimize(&file, &[]);
    assert_eq!(code, Some(1), "every evaluation failed: exit 1: {report}");
    check_report(&report);
    let evaluations = report["evaluations"].as_u64().unwrap();
    assert!(evaluations >= 7);
    assert_eq!(report["failed_evaluations"].as_u64().unwrap(), evaluations);
    assert!(report["objective_value"].is_null());
    let why = report["failures"][0]["why"][0].as_str().unwrap();
    assert!(why.contains("jam.toml: jammed"), "{why}");
    // alone, the good scene fails nothing
    let file = write_case(
        "not-failing",
        "[optimize]\nscenes = [\"small.toml\"]\nobjective = \"mapping-error\"\n\
         parameters = \"exponential-taper\"\nbudget = 10\n",
    );
    let (code, report) = optimize(&file, &[]);
    assert_eq!(code, Some(0));
    assert_eq!(report["failed_evaluations"], 0);
    assert!(
        num(&report["objective_value"]) < 0.0,
        "minus the mapping error"
    );
}

#[test]
fn bad_input_is_a_located_error_with_exit_2() {
    let base = "[optimize]\nscenes = [\"small.toml\"]\nobjective = \"preview-mean\"\n\
                parameters = \"per-joint\"\nbudget = 40\n";
    let cases: [(&str, String, &str); 12] = [
        (
            "duration-negative",
            format!("{base}duration_s = -1.0\n"),
            "opt.toml:6:14: `duration_s` in [optimize]: -1 must be > 0",
        ),
        (
            "duration-too-long",
            format!("{base}duration_s = 1e9\n"),
            "opt.toml:6:14: `duration_s` in [optimize]: 1000000000 s is more than",
        ),
        (
            "unknown-objective",
            base.replace("\"preview-mean\"", "\"speed\""),
            "opt.toml:3:13: `objective` in [optimize]: \"speed\" is not one of \
             \"preview-mean\", \"mapping-error\", \"flip-free-preview\"",
        ),
        (
            "bounds-reversed",
            format!("{base}stiffness_bounds_n_m_per_rad = [0.08, 0.004]\n"),
            "opt.toml:6:32: `stiffness_bounds_n_m_per_rad` in [optimize]: [0.08, 0.004] \
             needs 0 < min < max",
        ),
        (
            "budget-zero",
            base.replace("budget = 40", "budget = 0"),
            "opt.toml:5:10: `budget` in [optimize]: 0 sweep(s) is too few",
        ),
        (
            "budget-below-the-start",
            base.replace("budget = 40", "budget = 10"),
            "the 7 named profiles and the 4 first points of nelder-mead over 4 coordinate(s), \
             on 1 scene(s), take 11",
        ),
        (
            "scene-without-walls",
            base.replace("small.toml", "no_walls.toml"),
            "opt.toml:2:11: `scenes` in [optimize]: ",
        ),
        (
            "unknown-method",
            format!("{base}method = \"gradient\"\n"),
            "opt.toml:6:10: `method` in [optimize]",
        ),
        (
            "unknown-key",
            format!("{base}budgets = 3\n"),
            "opt.toml:6:1: unknown key `budgets` in [optimize]",
        ),
        (
            "missing-scenes",
            "[optimize]\nobjective = \"preview-mean\"\nbudget = 40\n".to_string(),
            "missing key `scenes` in [optimize]",
        ),
        (
            "missing-scene-file",
            base.replace("small.toml", "nowhere.toml"),
            "nowhere.toml: cannot read the scene file",
        ),
        (
            "mixed-joints",
            base.replace("[\"small.toml\"]", "[\"small.toml\", \"jam2.toml\"]"),
            "has 3 joint(s) but",
        ),
    ];
    for (case, text, expected) in cases {
        let file = write_case(case, &text);
        let dir = Path::new(&file).parent().unwrap();
        std::fs::write(
            dir.join("jam2.toml"),
            JAMMING_SCENE.replace("links = 5", "links = 4"),
        )
        .unwrap();
        let out = run(&["optimize", &file, "--json"]);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{case}: {err}");
        assert!(stdout(&out).is_empty(), "{case}: stdout not empty");
        assert!(err.contains(expected), "{case}: {err}");
    }
    let out = run(&[
        "optimize",
        &example("optimize/wall_following.toml"),
        "--plot",
        "x.pdf",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("--plot x.pdf: the file name must end in .svg or .png"));
    // an output in a folder that does not exist is refused before the search, not after
    for option in ["-o", "--plot", "--scene-out", "--log"] {
        let out = run(&[
            "optimize",
            &example("optimize/wall_following.toml"),
            option,
            "/nonexistent-folder/out.svg",
        ]);
        assert_eq!(out.status.code(), Some(2), "{option}");
        assert!(
            stderr(&out).contains("the folder /nonexistent-folder does not exist"),
            "{option}: {}",
            stderr(&out)
        );
        assert!(stdout(&out).is_empty());
    }
}

/// The report without what differs from run to run (the time) or with how it was run (what
/// came from a log).
fn comparable(mut report: Value) -> Value {
    for key in ["elapsed_s", "replayed_evaluations", "file", "scenes"] {
        report[key] = Value::Null;
    }
    report
}

fn evaluation_lines(log: &Path) -> usize {
    let text = std::fs::read_to_string(log).unwrap();
    text.lines()
        .filter(|l| l.contains("\"type\":\"evaluation\""))
        .count()
}

#[test]
fn a_logged_run_resumes_where_it_stopped_and_ends_as_a_run_that_never_stopped() {
    let text = |budget: usize| {
        format!(
            "[optimize]\nscenes = [\"small.toml\"]\nobjective = \"preview-mean\"\n\
             parameters = \"per-joint\"\nmethod = \"particle-swarm\"\nbudget = {budget}\nseed = 5\n"
        )
    };
    let fresh_file = write_case("resume-fresh", &text(40));
    let (code, fresh) = optimize(&fresh_file, &[]);
    assert_eq!(code, Some(0), "{fresh}");

    let file = write_case("resume", &text(25));
    let dir = Path::new(&file).parent().unwrap().to_path_buf();
    let log = dir.join("run.jsonl");
    let log_arg = log.display().to_string();
    let (code, first) = optimize(&file, &["--log", &log_arg]);
    assert_eq!(code, Some(0), "{first}");
    let first_evaluations = first["evaluations"].as_u64().unwrap() as usize;
    assert_eq!(evaluation_lines(&log), first_evaluations);

    // the log exists: refused without --resume, and nothing is overwritten
    let out = run(&["optimize", &file, "--log", &log_arg]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("the log exists: --resume continues"),
        "{}",
        stderr(&out)
    );
    assert_eq!(evaluation_lines(&log), first_evaluations);

    // a stop cut the last line short: it is dropped and swept again
    let whole = std::fs::read_to_string(&log).unwrap();
    std::fs::write(&log, &whole[..whole.len() - 40]).unwrap();

    // a larger budget goes on: the same run as one that never stopped
    std::fs::write(&file, text(40)).unwrap();
    let (code, resumed) = optimize(&file, &["--log", &log_arg, "--resume"]);
    assert_eq!(code, Some(0), "{resumed}");
    assert_eq!(
        resumed["replayed_evaluations"].as_u64().unwrap() as usize,
        first_evaluations - 1
    );
    assert_eq!(comparable(resumed.clone()), comparable(fresh));
    assert_eq!(
        evaluation_lines(&log),
        resumed["evaluations"].as_u64().unwrap() as usize
    );

    // another optimization's log is refused, naming what differs
    std::fs::write(&file, text(40).replace("seed = 5", "seed = 6")).unwrap();
    let out = run(&["optimize", &file, "--log", &log_arg, "--resume"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("records another optimization: its seed is 5, this one's is 6"),
        "{}",
        stderr(&out)
    );
    // so is an edited scene
    std::fs::write(&file, text(40)).unwrap();
    std::fs::write(
        dir.join("small.toml"),
        SMALL_SCENE.replace("mu = 0.3", "mu = 0.4"),
    )
    .unwrap();
    let out = run(&["optimize", &file, "--log", &log_arg, "--resume"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("digest"), "{}", stderr(&out));
}

#[test]
fn ctrl_c_stops_the_search_and_still_reports_what_was_swept() {
    let dir = folder("interrupt");
    let log = dir.join("run.jsonl");
    let child = common::antenna()
        .args([
            "optimize",
            &example("optimize/wall_following.toml"),
            "--json",
            "--jobs",
            "1",
            "--log",
            &log.display().to_string(),
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // wait until a few evaluations are on disk, then Ctrl-C
    let started = std::time::Instant::now();
    while std::fs::read_to_string(&log).map_or(0, |t| t.lines().count()) < 4 {
        assert!(started.elapsed().as_secs() < 120, "no evaluation logged");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let status = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("interrupted: the report covers the"));
    let report: Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert_eq!(report["stopped_by"], "interrupted");
    let evaluations = report["evaluations"].as_u64().unwrap() as usize;
    assert!((3..300).contains(&evaluations), "{evaluations}");
    assert_eq!(evaluation_lines(&log), evaluations);
}
