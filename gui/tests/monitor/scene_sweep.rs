//! Offline: a scene file typed into the source bar, its sweep solved by sim-core on the
//! monitor's worker thread, then played, stopped and scrubbed like a recording; a sweep whose
//! step fails keeps the frames before it and says when it failed; a scene file that does not
//! parse names its key in the status line.
#![allow(clippy::unwrap_used)]

use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::support::{expect_label, harness, step_around, step_until, temp_dir};
use antenna_monitor::sweep_run::SweepRunState;
use antenna_monitor::{AppOptions, MonitorApp};
use egui::accesskit::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;

/// `examples/sweep_line_wall.toml` cut to half a second (50 steps at 100 Hz).
const SHORT_SWEEP: &str = r#"
[antenna]
links = 9
link_length_m = 0.04
base_angle_deg = 30.0
joint_limits_deg = [-90.0, 90.0]

[antenna.stiffness]
profile = "linear"
min_n_m_per_rad = 0.004
max_n_m_per_rad = 0.082

[base]
position_m = [0.0, 0.0]

[[walls]]
shape = "line"
point_m = [0.0, 0.2]
angle_deg = -8.0
solid = "left"
surface = "smooth"
mu = 0.3

[sweep]
velocity_m_per_s = [0.0167, 0.0]
duration_s = 0.5
step_s = 0.01

[start]
placement = "tip-on-wall"
wall = 0
ahead_m = 0.0
shape = "C"
"#;

/// The base driven straight at a wall with one Newton iteration allowed per solve: the
/// steps in free space pass, the first one that meets the wall finds no equilibrium.
const FAILING_SWEEP: &str = r#"
[antenna]
links = 9
link_length_m = 0.04
base_angle_deg = 30.0

[antenna.stiffness]
profile = "linear"
min_n_m_per_rad = 0.004
max_n_m_per_rad = 0.082

[[walls]]
shape = "line"
point_m = [0.0, 0.2]
solid = "left"

[sweep]
velocity_m_per_s = [0.0, 0.2]
duration_s = 0.5
step_s = 0.01

[contact]
max_iterations = 1
max_substep_depth = 0
"#;

fn write_scene(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// An idle monitor with `path` typed into the scene field and **Run sweep** clicked.
fn run_sweep_from_the_bar(dir: &Path, path: &Path) -> Harness<'static, MonitorApp> {
    let mut harness = harness(MonitorApp::new(AppOptions {
        export_dir: dir.to_path_buf(),
        ..AppOptions::default()
    }));
    harness.step();
    harness
        .get_by_role_and_label(Role::TextInput, "scene .toml")
        .focus();
    harness.step();
    harness
        .get_by_role_and_label(Role::TextInput, "scene .toml")
        .type_text(&path.display().to_string());
    harness.step();
    harness.get_by_label("Run sweep").click();
    harness.step();
    harness
}

fn sweep_state<'a>(
    harness: &'a Harness<'_, MonitorApp>,
) -> std::sync::MutexGuard<'a, SweepRunState> {
    harness
        .state()
        .sweep()
        .expect("a sweep is the source")
        .lock()
}

fn cursor_s(harness: &Harness<'_, MonitorApp>) -> f64 {
    let latest = sweep_state(harness).history.latest_t_s();
    harness.state().view().cursor_s(latest).unwrap()
}

#[test]
fn run_a_scene_file_sweep_play_and_scrub_it() {
    let dir = temp_dir("scene-sweep");
    let path = write_scene(&dir, "short_line_wall.toml", SHORT_SWEEP);
    let mut harness = run_sweep_from_the_bar(&dir, &path);
    step_until(&mut harness, "the sweep to finish", 60.0, |h| {
        sweep_state(h).is_finished()
    });
    expect_label(
        &mut harness,
        "sweep short_line_wall: done, 50 steps (0.50 s)",
    );
    expect_label(&mut harness, &format!("ran {}: 51 frames", path.display()));
    assert_eq!(
        harness.state().message().map(|(_, error)| error),
        Some(false)
    );

    // The placed posture and every step, as frames and as samples of the history.
    let (first, last) = {
        let state = sweep_state(&harness);
        assert!(state.error().is_none(), "{:?}", state.error());
        assert_eq!(state.steps_total, 50);
        assert_eq!(state.frame_count(), state.steps_total + 1);
        assert_eq!(state.history.len(), 51);
        assert_eq!(state.history.segment_count(), 8);
        let first = state.frame_at(0.0).unwrap().unwrap();
        let last = state.frame_at(0.5).unwrap().unwrap();
        (first, last)
    };
    assert_eq!(first.t_s, 0.0);
    assert!(
        (last.t_s - 0.5).abs() < 1e-9,
        "the last frame at {} s",
        last.t_s
    );
    // The base moved along the track by 0.5 s x 16.7 mm/s, carrying the chain with it.
    assert!((last.base_m[0] - first.base_m[0] - 0.5 * 0.0167).abs() < 1e-9);
    assert_eq!(last.base_m[1], first.base_m[1]);
    let moved = first.difference(&last).unwrap();
    assert!(moved.max_m > 0.005, "the chain moved {} m", moved.max_m);
    // Placed with its tip on the wall: some segment touches, and the contact is drawn.
    assert!(last.segments.iter().any(|s| s.touched()));
    assert!(!last.contacts_m.is_empty());
    assert_eq!(last.walls_m.len(), 1);

    // Done, the whole sweep is in view with the chain at its start.
    let (t0, t1) = harness.state().view().window(Some(0.5)).unwrap();
    assert!(
        t0.abs() < 1e-9 && (t1 - 0.5).abs() < 1e-9,
        "window {t0}..{t1}"
    );
    assert_eq!(cursor_s(&harness), 0.0);

    // Play: the cursor moves on in real time, as much as passed between the two frames (at
    // least the time between them, at most the time around them), up to the end.
    harness.get_by_label("Play").click();
    let (least, most) = step_around(&mut harness, Duration::from_millis(200));
    let played = cursor_s(&harness);
    let least = least.min(0.5);
    assert!(
        played >= least - 1e-9 && played <= most + 1e-9,
        "played {played} s in {least} to {most} s"
    );
    // Stop: the cursor stays where it stopped. On a loaded machine the frames can be far
    // enough apart that playing reached the end, and stopped there by itself, already.
    if harness.query_by_label("Stop playing").is_some() {
        harness.get_by_label("Stop playing").click();
    } else {
        assert!((played - 0.5).abs() < 1e-9, "not playing at {played} s");
    }
    harness.step();
    let stopped = cursor_s(&harness);
    std::thread::sleep(Duration::from_millis(100));
    harness.step();
    assert_eq!(cursor_s(&harness), stopped);
    harness.get_by_label("Play");

    // Scrub: the chain panel shows the step at the slider's instant.
    harness
        .get_by_role_and_label(Role::Slider, "scrub, s")
        .set_value_accesskit(0.25);
    harness.step();
    let cursor = cursor_s(&harness);
    assert!((cursor - 0.25).abs() < 1e-3, "cursor {cursor}");
    let shown = sweep_state(&harness).frame_at(cursor).unwrap().unwrap();
    assert!(
        (shown.t_s - 0.25).abs() < 0.011,
        "the frame at {} s",
        shown.t_s
    );
    assert!(first.base_m[0] < shown.base_m[0] && shown.base_m[0] < last.base_m[0]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_failed_step_is_reported_with_its_time_and_the_frames_before_it_are_kept() {
    let dir = temp_dir("scene-sweep-fails");
    let path = write_scene(&dir, "into_the_wall.toml", FAILING_SWEEP);
    let mut harness = run_sweep_from_the_bar(&dir, &path);
    step_until(&mut harness, "the sweep to stop", 60.0, |h| {
        sweep_state(h).is_finished()
    });
    expect_label(&mut harness, "sweep into_the_wall: stopped at step");
    let (kept, end_s) = {
        let state = sweep_state(&harness);
        let error = state.error().expect("a step fails").to_string();
        let kept = state.frame_count();
        assert!((2..51).contains(&kept), "{kept} frames kept: {error}");
        let end_s = state.history.latest_t_s().unwrap();
        // The failed step is the one after the last kept.
        let failed_s = end_s + 0.01;
        assert!(
            error.contains(&format!(
                "stopped at t = {failed_s:.3} s, {kept} frames kept"
            )),
            "{error}"
        );
        assert!(error.contains("into_the_wall.toml: step"), "{error}");
        (kept, end_s)
    };
    let (message, is_error) = harness.state().message().unwrap();
    assert!(is_error && message.contains("stopped at t = "), "{message}");
    expect_label(&mut harness, &format!("{kept} frames kept"));

    // The steps before the failure are shown at the last one; played from the start, and
    // scrubbed, they are drawn.
    assert!((cursor_s(&harness) - end_s).abs() < 1e-9);
    harness.get_by_label("Play").click();
    harness.step();
    assert_eq!(
        cursor_s(&harness),
        0.0,
        "play did not restart from the start"
    );
    expect_label(&mut harness, "Stop playing");
    let mid_s = end_s / 2.0;
    harness
        .get_by_role_and_label(Role::Slider, "scrub, s")
        .set_value_accesskit(mid_s);
    harness.step();
    assert!((cursor_s(&harness) - mid_s).abs() < 1e-3);
    let state = sweep_state(&harness);
    let (start, middle) = (
        state.frame_at(0.0).unwrap().unwrap(),
        state.frame_at(mid_s).unwrap().unwrap(),
    );
    assert!(
        middle.base_m[1] > start.base_m[1],
        "the base did not move toward the wall"
    );
    drop(state);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_scene_file_that_does_not_parse_names_its_key_in_the_status_line() {
    let dir = temp_dir("scene-sweep-broken");
    let broken = SHORT_SWEEP.replace("duration_s = 0.5", "duraton_s = 0.5");
    let path = write_scene(&dir, "broken.toml", &broken);
    let line = broken
        .lines()
        .position(|l| l.starts_with("duraton_s"))
        .unwrap()
        + 1;
    let mut harness = run_sweep_from_the_bar(&dir, &path);
    expect_label(&mut harness, "unknown key `duraton_s` in [sweep]");
    let (message, is_error) = harness.state().message().unwrap();
    assert!(is_error, "{message}");
    assert!(
        message.contains(&format!("broken.toml:{line}:")),
        "line {line} not in {message}"
    );
    // Nothing ran: the monitor stays idle.
    assert!(harness.state().sweep().is_none());
    expect_label(&mut harness, "no source");
    std::fs::remove_dir_all(&dir).ok();
}
