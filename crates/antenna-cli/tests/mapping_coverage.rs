//! Issue #18, "mapping metrics": the sweep summary's wall coverage
//! (`mapping_coverage_error_mm`, `mapping_coverage_p90_mm`, `mapping_completeness`) is the
//! coverage of the points its step lines print (`mapping_points_m`) over the section their
//! contacts passed, recomputed here from the lines alone with `sim_core::wall_coverage`.
#![allow(clippy::unwrap_used)]

mod common;

use antenna_cli::sweep::{COMPLETE_WITHIN_MM, coverage_settings};
use antenna_scene::Scene;
use common::{run, scratch, stderr, stdout};
use nalgebra::Vector2;
use serde_json::Value;
use sim_core::{Section, wall_coverage};

/// `examples/mapping_4_2_2.toml` for `duration_s` at `frequency_per_m`.
fn mapping_scene(duration_s: f64, frequency_per_m: f64) -> String {
    let text = std::fs::read_to_string(common::example("mapping_4_2_2.toml")).unwrap();
    let short = text
        .replace("duration_s = 30.0", &format!("duration_s = {duration_s:?}"))
        .replace(
            "frequency_per_m = 2.8",
            &format!("frequency_per_m = {frequency_per_m:?}"),
        );
    assert!(
        !short.contains("duration_s = 30.0")
            && short.contains(&format!("frequency_per_m = {frequency_per_m:?}")),
        "the example moved"
    );
    short
}

fn lines_of(path: &str) -> Vec<Value> {
    let out = run(&["sweep", path, "--jsonl"]);
    assert_eq!(out.status.code(), Some(0), "{path}: {}", stderr(&out));
    stdout(&out)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

fn point(v: &Value) -> Vector2<f64> {
    Vector2::new(v[0].as_f64().unwrap(), v[1].as_f64().unwrap())
}

#[test]
fn the_summary_coverage_is_that_of_the_printed_map() {
    for frequency_per_m in [2.8, 14.2] {
        let text = mapping_scene(4.0, frequency_per_m);
        let path = scratch(&format!("coverage_{frequency_per_m}.toml"), &text);
        let lines = lines_of(&path);
        let summary = lines.last().unwrap();
        assert_eq!(summary["type"], "summary");

        // The section and the map, from the step lines alone: the motion is along +x.
        let scene = Scene::parse(&text, &path).unwrap();
        let walls = scene.sweep_scene().unwrap().walls;
        let mut extent: Option<(f64, f64)> = None;
        let mut points = Vec::new();
        for step in lines.iter().filter(|v| v["type"] == "step") {
            for c in step["contacts"].as_array().unwrap() {
                assert_eq!(c["wall"], 0);
                let x = point(&c["point_m"]).x;
                extent = Some(extent.map_or((x, x), |(lo, hi)| (lo.min(x), hi.max(x))));
            }
            let printed = step["mapping_points_m"].as_array().unwrap();
            assert_eq!(
                printed.len() as u64,
                step["mapping_points"].as_u64().unwrap()
            );
            points.extend(printed.iter().map(point));
        }
        let (from_m, to_m) = extent.unwrap();
        let section = Section {
            wall: 0,
            from_m,
            to_m,
        };
        let c = wall_coverage(
            &walls,
            &Vector2::x(),
            &[section],
            &points,
            &coverage_settings(),
        )
        .unwrap();
        let close = |key: &str, expected: Option<f64>| {
            let got = summary[key].as_f64().unwrap();
            let expected = expected.unwrap();
            assert!(
                (got - expected).abs() <= 1e-9 * expected.abs().max(1.0),
                "{frequency_per_m} 1/m: {key} = {got}, recomputed {expected}"
            );
        };
        close("mapping_coverage_error_mm", c.mean_error_mm);
        close("mapping_coverage_p90_mm", c.p90_error_mm);
        close("mapping_completeness", c.completeness);
        let completeness = summary["mapping_completeness"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&completeness));
        // The coverage's p90 bounds its mean from above, and a wall that is not captured
        // everywhere has a p90 beyond the completeness threshold only if incomplete.
        let mean = summary["mapping_coverage_error_mm"].as_f64().unwrap();
        let p90 = summary["mapping_coverage_p90_mm"].as_f64().unwrap();
        assert!(mean <= p90 + 1e-12 || completeness < 0.9);
        if p90 > COMPLETE_WITHIN_MM {
            assert!(completeness < 0.9 + 1e-12);
        }
    }
}

#[test]
fn a_sweep_without_contacts_has_no_coverage() {
    // The wall moved out of reach: no section passed, so nothing to score.
    let text = mapping_scene(0.5, 2.8).replace("point_m = [0.0, 0.17]", "point_m = [0.0, 0.8]");
    let start = text.find("[start]").unwrap();
    let text = format!("{}[start]\nplacement = \"rest\"\n", &text[..start]);
    let lines = lines_of(&scratch("coverage_no_contact.toml", &text));
    let summary = lines.last().unwrap();
    assert_eq!(summary["steps_with_contact"], 0);
    assert!(summary["mapping_coverage_error_mm"].is_null());
    assert!(summary["mapping_coverage_p90_mm"].is_null());
    assert!(summary["mapping_completeness"].is_null());
}
