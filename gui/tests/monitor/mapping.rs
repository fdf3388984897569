//! Offline: a mapping sweep (thesis 4.2.2) run in the monitor; its wall map, gathered step by
//! step on the sweep's thread, is the coverage sim-core computes from the steps afresh, at
//! every step drawn; the chain panel shows the map's numbers for the step at the cursor and
//! hides them with **wall map**; the map's colour scale runs from captured to missed.
#![allow(clippy::unwrap_used)]

use std::path::Path;

use crate::support::{expect_label, harness, step_until, temp_dir};
use antenna_monitor::mapping::{
    CAPTURED_COLOUR, COLOUR_BANDS, MIDWAY_COLOUR, MISSED_COLOUR, coverage_band, coverage_colour,
    coverage_summary,
};
use antenna_monitor::sweep_run::SweepRunState;
use antenna_monitor::{AppOptions, MonitorApp};
use antenna_scene::Scene;
use egui::Color32;
use egui::accesskit::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use nalgebra::Vector2;
use sim_core::{
    CoverageAccumulator, CoverageSettings, TouchLayout, estimate_contacts, sensed_theta_rad,
    wall_coverage,
};

/// `examples/mapping_4_2_2.toml` cut to 0.6 s (60 steps at 100 Hz), the base moving four
/// times as fast so that it passes 58 mm of the sinusoidal wall.
const SHORT_MAPPING: &str = r#"
[antenna]
links = 9
link_length_m = 0.04
base_angle_deg = 30.0
joint_limits_deg = [-90.0, 90.0]

[antenna.stiffness]
profile = "fast-exponential"
min_n_m_per_rad = 0.004
max_n_m_per_rad = 0.082

[[walls]]
shape = "sinusoid"
point_m = [0.0, 0.17]
angle_deg = 0.0
amplitude_m = 0.01
frequency_per_m = 2.8
phase_deg = 0.0
solid = "left"
surface = "smooth"
mu = 0.3

[sweep]
velocity_m_per_s = [0.096, 0.0]
duration_s = 0.6
step_s = 0.01

[start]
placement = "tip-on-wall"
wall = 0
ahead_m = 0.0
shape = "C"
"#;

fn sweep_state<'a>(
    harness: &'a Harness<'_, MonitorApp>,
) -> std::sync::MutexGuard<'a, SweepRunState> {
    harness
        .state()
        .sweep()
        .expect("a sweep is the source")
        .lock()
}

/// The monitor running `path`'s sweep to its end.
fn run_to_the_end(dir: &Path, path: &Path) -> Harness<'static, MonitorApp> {
    let mut harness = harness(MonitorApp::new(AppOptions {
        scene: Some(path.to_path_buf()),
        export_dir: dir.to_path_buf(),
        ..AppOptions::default()
    }));
    step_until(&mut harness, "the sweep to finish", 120.0, |h| {
        sweep_state(h).is_finished()
    });
    harness.step();
    harness
}

#[test]
fn the_wall_map_is_the_coverage_recomputed_from_the_steps_and_is_shown_at_the_cursor() {
    let dir = temp_dir("mapping");
    let path = dir.join("short_mapping.toml");
    std::fs::write(&path, SHORT_MAPPING).unwrap();
    let mut harness = run_to_the_end(&dir, &path);
    let direction_rad = Scene::from_path(&path)
        .unwrap()
        .sweep_scene()
        .unwrap()
        .motion
        .direction_rad();
    let settings = CoverageSettings::default();
    let last = {
        let state = sweep_state(&harness);
        assert!(state.error().is_none(), "{:?}", state.error());
        assert_eq!(state.frame_count(), 61);
        let mapping = &state.mapping;
        assert_eq!(mapping.steps().len(), state.steps.len());
        assert_eq!(mapping.unmapped_steps(), 0, "{:?}", mapping.first_failure());
        assert!(mapping.sensor_settings().is_ideal());

        // Afresh from the steps: ideal sensors (the 12-bit angles, the steps' own touch
        // bits), every step's points estimated, every step's true contacts passed.
        let mut fresh = CoverageAccumulator::new(direction_rad, state.walls.len());
        let (mut sensed, mut estimates) = (Vec::new(), Vec::new());
        for (k, step) in state.steps.iter().enumerate() {
            sensed.resize(step.theta_rad.len(), 0.0);
            sensed_theta_rad(&step.theta_rad, &mut sensed).unwrap();
            estimates.clear();
            estimate_contacts(
                &state.chain,
                &step.base_m,
                &sensed,
                &step.touch_bits,
                &TouchLayout::default(),
                &mut estimates,
            )
            .unwrap();
            fresh.pass(&step.contacts);
            fresh.estimate(estimates.iter().map(|e| e.point_m));

            assert_eq!(mapping.points_m(k), fresh.points_m(), "points at step {k}");
            assert_eq!(mapping.steps()[k].sections, fresh.sections(), "step {k}");
            let shown = mapping
                .coverage(&state.walls, k, &settings)
                .unwrap()
                .unwrap();
            assert_eq!(shown, fresh.coverage(&state.walls, &settings).unwrap());
            // And by sim-core's function itself, the direction from the scene's motion.
            let (sin, cos) = direction_rad.sin_cos();
            let direct = wall_coverage(
                &state.walls,
                &Vector2::new(cos, sin),
                &fresh.sections(),
                fresh.points_m(),
                &settings,
            )
            .unwrap();
            assert_eq!(shown, direct, "step {k}");
        }
        assert!(
            mapping
                .coverage(&state.walls, 61, &settings)
                .unwrap()
                .is_none(),
            "a step not run has no coverage"
        );

        // The wall passed is mapped, not trivially: hundreds of samples, most captured.
        let last = mapping
            .coverage(&state.walls, 60, &settings)
            .unwrap()
            .unwrap();
        assert!(last.samples.len() > 100, "{} samples", last.samples.len());
        let completeness = last.completeness.unwrap();
        assert!(
            completeness > 0.3 && completeness <= 1.0,
            "completeness {completeness}"
        );
        assert!(last.mean_error_mm.unwrap() <= last.p90_error_mm.unwrap());
        assert!(mapping.points_m(60).len() > 60);
        // Up to a step, the map holds only that step's points and sections.
        let middle = mapping
            .coverage(&state.walls, 30, &settings)
            .unwrap()
            .unwrap();
        assert!(middle.samples.len() < last.samples.len());
        assert!(mapping.points_m(30).len() < mapping.points_m(60).len());
        (
            coverage_summary(&last, mapping.points_m(60).len(), 5.0),
            coverage_summary(&middle, mapping.points_m(30).len(), 5.0),
            state.steps[30].t_s,
            state.steps[60].t_s,
        )
    };
    let (last_summary, middle_summary, middle_s, last_s) = last;
    assert!(
        last_summary.starts_with("wall map: coverage mean ")
            && last_summary.contains("within 5 mm"),
        "{last_summary}"
    );

    // The panel shows the numbers of the step at the cursor: scrubbed to the end, then to the
    // middle.
    for (t_s, summary) in [(last_s, &last_summary), (middle_s, &middle_summary)] {
        harness
            .get_by_role_and_label(Role::Slider, "scrub, s")
            .set_value_accesskit(t_s);
        harness.step();
        expect_label(&mut harness, summary);
    }
    let (sweep, step) = harness.state().coverage_key().unwrap();
    assert_eq!((sweep, step), (1, 30));

    // Hidden, the map is neither drawn nor computed; shown again, it is back.
    harness.get_by_label("wall map").click();
    step_until(&mut harness, "the map hidden", 10.0, |h| {
        h.query_by_label_contains("wall map: coverage").is_none()
    });
    harness
        .get_by_role_and_label(Role::Slider, "scrub, s")
        .set_value_accesskit(last_s);
    for _ in 0..3 {
        harness.step();
    }
    assert_eq!(harness.state().coverage_key(), Some((1, 30)));
    harness.get_by_label("wall map").click();
    expect_label(&mut harness, &last_summary);
    std::fs::remove_dir_all(&dir).ok();
}

/// Hue in degrees, `0..360` (`None` for a grey).
fn hue_deg(c: Color32) -> Option<f64> {
    let (r, g, b) = (f64::from(c.r()), f64::from(c.g()), f64::from(c.b()));
    let (max, min) = (r.max(g).max(b), r.min(g).min(b));
    let d = max - min;
    if d == 0.0 {
        return None;
    }
    let h = if max == r {
        ((g - b) / d).rem_euclid(6.0)
    } else if max == g {
        (b - r) / d + 2.0
    } else {
        (r - g) / d + 4.0
    };
    Some(h * 60.0)
}

#[test]
fn the_colour_scale_runs_from_captured_to_missed_monotonely() {
    let within_mm = CoverageSettings::default().complete_within_m * 1e3;
    assert_eq!(coverage_colour(Some(0.0), within_mm), CAPTURED_COLOUR);
    assert_eq!(coverage_colour(Some(-1.0), within_mm), CAPTURED_COLOUR);
    assert_eq!(
        coverage_colour(Some(within_mm / 2.0), within_mm),
        MIDWAY_COLOUR
    );
    for missed in [within_mm, within_mm + 1e-9, 2.0 * within_mm, f64::INFINITY] {
        assert_eq!(coverage_colour(Some(missed), within_mm), MISSED_COLOUR);
    }
    assert_eq!(coverage_colour(None, within_mm), MISSED_COLOUR);
    assert_eq!(coverage_colour(Some(f64::NAN), within_mm), MISSED_COLOUR);
    // A zero threshold: only a zero error is captured.
    assert_eq!(coverage_colour(Some(0.0), 0.0), CAPTURED_COLOUR);
    assert_eq!(coverage_colour(Some(1e-6), 0.0), MISSED_COLOUR);

    // Monotone: blue never rises, the hue turns one way (bluish green,
    // yellow, vermillion; give or take the rounding to 8-bit channels, under a degree), and
    // the scale changes all along (no flat stretch of 5 %).
    let colours: Vec<Color32> = (0..=1000)
        .map(|i| coverage_colour(Some(within_mm * f64::from(i) / 1000.0), within_mm))
        .collect();
    for pair in colours.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        assert!(b.b() <= a.b(), "{a:?} then {b:?}");
        assert!(
            hue_deg(b).unwrap() <= hue_deg(a).unwrap() + 1.0,
            "{a:?} then {b:?}"
        );
    }
    for window in colours.windows(51) {
        assert_ne!(window[0], window[50]);
    }
    let (captured, missed) = (
        hue_deg(CAPTURED_COLOUR).unwrap(),
        hue_deg(MISSED_COLOUR).unwrap(),
    );
    assert!(captured > 150.0 && missed < 40.0, "{captured} {missed}");

    // The bands the map is drawn in: the first captured, the last missed, in order.
    assert_eq!(coverage_band(Some(0.0), within_mm), (0, CAPTURED_COLOUR));
    assert_eq!(
        coverage_band(Some(within_mm), within_mm),
        (COLOUR_BANDS, MISSED_COLOUR)
    );
    let bands: Vec<usize> = (0..=100)
        .map(|i| coverage_band(Some(within_mm * f64::from(i) / 100.0), within_mm).0)
        .collect();
    assert!(bands.windows(2).all(|w| w[0] <= w[1]));
}
