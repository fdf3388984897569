//! Offline: a trial recorded by a real antennad on the simulated rig, opened in the monitor
//! through its source bar, played and scrubbed; the chain at the scrubbed instant is the
//! recorded one, with the touches the recording holds.
#![allow(clippy::unwrap_used)]

use std::time::Duration;

use crate::support::{config, expect_label, harness, step_around, temp_dir};
use antenna_monitor::{AppOptions, MonitorApp};
use egui::accesskit::Role;
use egui_kittest::kittest::Queryable;
use host_daemon::service::daemon::{Daemon, DaemonOptions};

#[test]
fn open_a_recorded_trial_play_and_scrub_it() {
    let dir = temp_dir("trial");
    let daemon = Daemon::start(
        config(&dir),
        DaemonOptions {
            first_trial: Some(None),
            first_trial_duration: Some(Duration::from_millis(2500)),
            exit_after_trial: true,
            serve: false,
            ..DaemonOptions::default()
        },
    )
    .unwrap();
    let summary = daemon.wait().unwrap();
    let path = summary.trials[0].path.clone().unwrap();

    let mut harness = harness(MonitorApp::new(AppOptions {
        export_dir: dir.clone(),
        ..AppOptions::default()
    }));
    harness.step();
    let field = harness.get_by_role_and_label(Role::TextInput, "trial .mcap");
    field.focus();
    harness.step();
    harness
        .get_by_role_and_label(Role::TextInput, "trial .mcap")
        .type_text(&path.display().to_string());
    harness.step();
    harness.get_by_label("Open").click();
    harness.step();
    harness.step();
    let trial = harness.state().trial().expect("the trial opened");
    assert_eq!(trial.name, "wall-sweep");
    let polls = trial.history.len() as u64;
    // 2.5 s at 1 kHz, give or take the polls at either end: every deadline polled or
    // skipped (the daemon counts those, however loaded the machine), never more polls than
    // deadlines.
    assert!(
        polls <= 2510 && polls + summary.skipped >= 2400,
        "{polls} polls, {} deadlines skipped",
        summary.skipped
    );
    assert!(!trial.rig.walls.is_empty());
    let (start_s, end_s) = (
        trial.history.first_t_s(),
        trial.history.latest_t_s().unwrap(),
    );
    expect_label(&mut harness, "trial wall-sweep");
    // Opened at its start, the whole trial in view.
    assert_eq!(harness.state().view().cursor_s(Some(end_s)), start_s);
    let (t0, t1) = harness.state().view().window(Some(end_s)).unwrap();
    assert!(
        (t0 - start_s.unwrap()).abs() < 1e-9 && (t1 - end_s).abs() < 1e-9,
        "window {t0}..{t1}, trial {start_s:?}..{end_s}"
    );

    // Play it: the cursor moves on in real time, as much as passed between the two frames
    // (at least the time between them, at most the time around them), up to the end.
    harness.get_by_label("Play").click();
    let (least, most) = step_around(&mut harness, Duration::from_millis(300));
    let played = harness.state().view().cursor_s(Some(end_s)).unwrap() - start_s.unwrap();
    let least = least.min(end_s - start_s.unwrap());
    assert!(
        played >= least - 1e-9 && played <= most + 1e-9,
        "played {played} s in {least} to {most} s"
    );
    harness.get_by_label("Stop playing").click();
    harness.step();
    let stopped = harness.state().view().cursor_s(Some(end_s));
    std::thread::sleep(Duration::from_millis(100));
    harness.step();
    assert_eq!(harness.state().view().cursor_s(Some(end_s)), stopped);
    harness.get_by_label("Play");

    // Scrub to the end: the stage has carried the antenna along the wall, its tip placed on it
    // when the trial started (the built-in 4.2.1 scene).
    harness
        .get_by_role_and_label(Role::Slider, "scrub, s")
        .set_value_accesskit(end_s - 0.01);
    harness.step();
    let cursor = harness.state().view().cursor_s(Some(end_s)).unwrap();
    assert!((cursor - (end_s - 0.01)).abs() < 1e-3, "cursor {cursor}");
    let trial = harness.state().trial().unwrap();
    let index = trial.history.index_at(cursor).unwrap();
    let frame = trial.rig.frame_at(&trial.history, index).unwrap();
    let sample = trial.history.sample(index).unwrap();
    assert!(
        frame.segments.iter().any(|s| s.touched()),
        "nothing touches the wall at {cursor} s"
    );
    assert_eq!(frame.stage_position_m, sample.stage_position_m);
    assert!(sample.stage_position_m.unwrap() > 0.05);
    // Scrub back to the start: the base at home.
    harness
        .get_by_role_and_label(Role::Slider, "scrub, s")
        .set_value_accesskit(0.0);
    harness.step();
    let trial = harness.state().trial().unwrap();
    let frame = trial.rig.frame_at(&trial.history, 0).unwrap();
    assert!(frame.base_m[0].abs() < 1e-3, "{:?}", frame.base_m);
    std::fs::remove_dir_all(&dir).ok();
}
