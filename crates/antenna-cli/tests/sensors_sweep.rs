//! Issue #18, "sensors as they are": a scene's `[sensors]` table in `antenna sweep` and
//! `antenna study`. Ideal settings written out give today's lines byte for byte; Hall angle
//! noise makes the wall map worse, reproducibly for a seed; a slower sample rate maps fewer
//! points; a touch threshold above every contact force maps none; debouncing delays the
//! first point; a bad `[sensors]` in a study's scene is a located error, exit 2.
#![allow(clippy::unwrap_used)]

mod common;

use common::{run, scratch, stderr, stdout};
use serde_json::Value;

/// A short version of `examples/mapping_4_2_2.toml` (thesis 4.2.2): 2 s, 200 steps along the
/// sinusoidal wall, touching it at every step.
fn mapping_scene() -> String {
    let text = std::fs::read_to_string(common::example("mapping_4_2_2.toml")).unwrap();
    let short = text.replace("duration_s = 30.0", "duration_s = 2.0");
    assert_ne!(short, text, "the example's duration moved");
    short
}

/// The mapping scene with a `[sensors]` table of `keys`.
fn with_sensors(keys: &str) -> String {
    format!("{}\n[sensors]\n{keys}", mapping_scene())
}

/// `antenna sweep PATH --jsonl`: its lines (exit 0 required).
fn sweep_path(path: &str) -> Vec<String> {
    let out = run(&["sweep", path, "--jsonl"]);
    assert_eq!(out.status.code(), Some(0), "{path}: {}", stderr(&out));
    stdout(&out).lines().map(str::to_string).collect()
}

/// `text` written to `name` and swept.
fn sweep(name: &str, text: &str) -> Vec<String> {
    sweep_path(&scratch(name, text))
}

fn parsed(lines: &[String]) -> Vec<Value> {
    lines
        .iter()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// The step lines.
fn steps(lines: &[String]) -> Vec<Value> {
    parsed(lines)
        .into_iter()
        .filter(|v| v["type"] == "step")
        .collect()
}

/// The summary line.
fn summary(lines: &[String]) -> Value {
    let v = parsed(lines).pop().unwrap();
    assert_eq!(v["type"], "summary");
    v
}

/// A line without its `"wall_clock_ms":...,` field (which differs from run to run).
fn without_clock(line: &str) -> String {
    match line.find("\"wall_clock_ms\":") {
        Some(start) => {
            let end = start + line[start..].find(',').unwrap() + 1;
            format!("{}{}", &line[..start], &line[end..])
        }
        None => line.to_string(),
    }
}

fn mean_error_mm(lines: &[String]) -> f64 {
    summary(lines)["mapping_mean_error_mm"].as_f64().unwrap()
}

fn points(lines: &[String]) -> u64 {
    summary(lines)["mapping_points"].as_u64().unwrap()
}

/// The first step that maps a point.
fn first_point_step(lines: &[String]) -> u64 {
    steps(lines)
        .iter()
        .find(|s| s["mapping_points"].as_u64().unwrap() > 0)
        .map(|s| s["step"].as_u64().unwrap())
        .unwrap()
}

/// Every key at its ideal value (the seed is free: ideal sensors draw nothing); without
/// `sample_rate_hz`, whose ideal is to sample every step.
const IDEAL_TABLE: &str = "angle_noise_counts = 0.0\noffset_counts = 0.0\n\
gain_error = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]\ntouch_threshold_n = 0.0\n\
touch_debounce_samples = 1\nseed = 12345\n";

#[test]
fn ideal_sensors_written_out_give_todays_lines_byte_for_byte() {
    // The same file name, so that the placement lines (which name the scene) can match.
    let path = scratch("sensors_ideal.toml", &mapping_scene());
    let today = sweep_path(&path);
    scratch("sensors_ideal.toml", &with_sensors(IDEAL_TABLE));
    let ideal = sweep_path(&path);
    assert!(points(&today) > 100, "the scene maps the wall");
    assert_eq!(today.len(), ideal.len());
    for (k, (a, b)) in today.iter().zip(&ideal).enumerate() {
        assert_eq!(without_clock(a), without_clock(b), "line {k}");
    }
    assert!(!ideal.iter().any(|l| l.contains("\"sensed\"")));
    assert!(!ideal.iter().any(|l| l.contains("\"sensors\"")));

    // A sample rate equal to the step rate samples every step: the same mapping, with the
    // sensed data and the sensors' summary added.
    let at_step_rate = sweep(
        "sensors_step_rate.toml",
        &with_sensors("sample_rate_hz = 100.0\n"),
    );
    let s = summary(&at_step_rate);
    assert_eq!(s["sensors"]["samples"], 201, "{s}");
    for key in [
        "mapping_points",
        "mapping_mean_error_mm",
        "mapping_max_error_mm",
    ] {
        assert_eq!(s[key], summary(&today)[key], "{key}");
    }
    for (a, b) in steps(&at_step_rate).iter().zip(steps(&today)) {
        assert_eq!(a["sensed"]["sampled"], true);
        assert_eq!(a["sensed"]["touch_bits"], b["touch_bits"]);
        assert_eq!(a["mapping_error_mm"], b["mapping_error_mm"]);
    }
}

#[test]
fn angle_noise_grows_the_mapping_error() {
    let errors: Vec<f64> = [0.0, 2.0, 8.0, 32.0]
        .iter()
        .map(|noise| {
            let lines = sweep(
                &format!("sensors_noise_{noise}.toml"),
                &with_sensors(&format!("angle_noise_counts = {noise}\nseed = 1\n")),
            );
            mean_error_mm(&lines)
        })
        .collect();
    assert!(
        errors.windows(2).all(|w| w[0] < w[1]),
        "mean mapping errors over noise 0, 2, 8, 32 counts: {errors:?}"
    );
}

#[test]
fn one_seed_gives_one_run_another_seed_another() {
    let table =
        |seed: u64| format!("angle_noise_counts = 2.0\noffset_counts = 3.0\nseed = {seed}\n");
    let a = sweep("sensors_seed_a.toml", &with_sensors(&table(1)));
    let b = sweep("sensors_seed_b.toml", &with_sensors(&table(1)));
    let c = sweep("sensors_seed_c.toml", &with_sensors(&table(2)));
    let (sa, sb, sc) = (steps(&a), steps(&b), steps(&c));
    assert_eq!(sa, sb, "the same seed, the same steps");
    assert_eq!(
        without_clock(a.last().unwrap()),
        without_clock(b.last().unwrap())
    );
    assert_ne!(
        sa.iter().map(|s| &s["sensed"]).collect::<Vec<_>>(),
        sc.iter().map(|s| &s["sensed"]).collect::<Vec<_>>(),
        "another seed, other readings"
    );
    assert_ne!(mean_error_mm(&a), mean_error_mm(&c));
    // The noise does not touch the true state: the same contacts and true angles.
    for (x, y) in sa.iter().zip(&sc) {
        assert_eq!(x["theta_rad"], y["theta_rad"]);
        assert_eq!(x["touch_bits"], y["touch_bits"]);
    }
}

#[test]
fn a_slower_sample_rate_maps_fewer_points() {
    let ideal = points(&sweep("sensors_rate_ideal.toml", &mapping_scene()));
    let mut last = ideal;
    for (rate, samples) in [(50.0, 101), (20.0, 41), (5.0, 11)] {
        let lines = sweep(
            &format!("sensors_rate_{rate}.toml"),
            &with_sensors(&format!("sample_rate_hz = {rate}\n")),
        );
        let s = summary(&lines);
        assert_eq!(s["sensors"]["samples"], samples, "{rate} Hz");
        assert_eq!(s["sensors"]["sample_rate_hz"], rate);
        let sampled = steps(&lines)
            .iter()
            .filter(|s| s["sensed"]["sampled"] == true)
            .count();
        assert_eq!(sampled, samples, "{rate} Hz");
        for step in steps(&lines) {
            if step["sensed"]["sampled"] == false {
                assert_eq!(step["mapping_points"], 0, "{step}");
                assert_eq!(step["sensed"]["touch_bits"], Value::Null);
            }
        }
        let p = points(&lines);
        assert!(0 < p && p < last, "{rate} Hz: {p} points after {last}");
        last = p;
    }
}

#[test]
fn a_touch_threshold_above_every_contact_force_maps_nothing() {
    let today = sweep("sensors_threshold_ideal.toml", &mapping_scene());
    let strongest_n = steps(&today)
        .iter()
        .flat_map(|s| s["contacts"].as_array().unwrap().clone())
        .map(|c| {
            let f = &c["force_n"];
            f[0].as_f64().unwrap().hypot(f[1].as_f64().unwrap())
        })
        .fold(0.0_f64, f64::max);
    assert!(strongest_n > 0.0);
    let above = sweep(
        "sensors_threshold_above.toml",
        &with_sensors(&format!("touch_threshold_n = {}\n", 1.01 * strongest_n)),
    );
    assert_eq!(points(&above), 0);
    for step in steps(&above) {
        let bits = step["sensed"]["touch_bits"].as_array().unwrap();
        assert!(bits.iter().all(|b| b == 0), "{step}");
        assert!(!step["contacts"].as_array().unwrap().is_empty());
    }
    // Half the strongest force: some contacts still close their switches, not all.
    let half = sweep(
        "sensors_threshold_half.toml",
        &with_sensors(&format!("touch_threshold_n = {}\n", 0.5 * strongest_n)),
    );
    assert!(0 < points(&half) && points(&half) < points(&today));
}

#[test]
fn debouncing_delays_the_first_point() {
    let today = sweep("sensors_debounce_1.toml", &mapping_scene());
    let first = first_point_step(&today);
    for samples in [3_u64, 5] {
        let lines = sweep(
            &format!("sensors_debounce_{samples}.toml"),
            &with_sensors(&format!("touch_debounce_samples = {samples}\n")),
        );
        assert_eq!(
            first_point_step(&lines),
            first + samples - 1,
            "a bit closes after {samples} agreeing reads"
        );
    }
}

/// A one-sweep study of the mapping scene, 0.5 s.
fn study(name: &str, scene_text: &str) -> (String, String) {
    let scene = scratch(&format!("{name}_scene.toml"), scene_text);
    let path = scratch(
        &format!("{name}.toml"),
        &format!("[study]\nscene = \"{scene}\"\nduration_s = 0.5\n"),
    );
    (scene, path)
}

fn study_row(path: &str) -> Value {
    let out = run(&["study", path, "--format", "jsonl", "--jobs", "1"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let mut row: Value = serde_json::from_str(stdout(&out).lines().next().unwrap()).unwrap();
    row.as_object_mut().unwrap().remove("wall_clock_ms");
    row
}

#[test]
fn studies_sweep_with_the_scenes_sensors() {
    let (_, today) = study("sensors_study_today", &mapping_scene());
    let (_, ideal) = study("sensors_study_ideal", &with_sensors(IDEAL_TABLE));
    let (_, noisy) = study(
        "sensors_study_noisy",
        &with_sensors("angle_noise_counts = 8.0\nsample_rate_hz = 20.0\nseed = 4\n"),
    );
    let (today, ideal, noisy) = (study_row(&today), study_row(&ideal), study_row(&noisy));
    assert_eq!(today, ideal);
    assert!(
        noisy["mapping_points"].as_u64() < today["mapping_points"].as_u64(),
        "{noisy}"
    );
    assert_ne!(
        noisy["mapping_mean_error_mm"],
        today["mapping_mean_error_mm"]
    );

    let (scene, path) = study(
        "sensors_study_bad",
        &with_sensors("touch_debounce_samples = 0\n"),
    );
    let out = run(&["study", &path]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stdout(&out).is_empty());
    assert!(
        stderr(&out).contains(&format!(
            "{scene}:46:26: `touch_debounce_samples` in [sensors]: 0 is out of range"
        )),
        "{}",
        stderr(&out)
    );
}
