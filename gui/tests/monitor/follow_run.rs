//! Offline: a follow scene (closed-loop wall following, issue #47) typed into the source bar
//! and run by sim-core on the monitor's worker thread, then scrubbed: the top view, the error
//! plot and the run's figures follow the cursor; the same run written as `antenna follow
//! --jsonl` lines and opened from the bar, and dropped on the window, plays the same steps;
//! a follow file with a bad line names the file and the line and leaves the monitor as it
//! was.
#![allow(clippy::unwrap_used)]

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::support::{expect_label, harness, step_until, temp_dir};
use antenna_monitor::follow::FollowRunState;
use antenna_monitor::{AppOptions, MonitorApp};
use antenna_scene::follow_lines::FollowLine;
use egui::accesskit::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;

/// `examples/follow/straight_wall.toml` cut to half a second (50 steps at 100 Hz).
fn short_follow_scene(dir: &Path) -> PathBuf {
    let text = include_str!("../../../examples/follow/straight_wall.toml")
        .replace("duration_s = 10.0", "duration_s = 0.5");
    assert!(text.contains("duration_s = 0.5"));
    let path = dir.join("straight_wall_short.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn follow_state<'a>(
    harness: &'a Harness<'_, MonitorApp>,
) -> std::sync::MutexGuard<'a, FollowRunState> {
    harness
        .state()
        .follow()
        .expect("a follow run is the source")
        .lock()
}

fn cursor_s(harness: &Harness<'_, MonitorApp>) -> f64 {
    let latest = follow_state(harness).history.latest_t_s();
    harness.state().view().cursor_s(latest).unwrap()
}

/// `state` as the lines `antenna follow --jsonl` writes.
fn jsonl(state: &FollowRunState) -> String {
    let mut lines = vec![serde_json::to_string(&FollowLine::Start(state.start.clone())).unwrap()];
    for step in &state.steps {
        lines.push(serde_json::to_string(&FollowLine::Step(step.clone())).unwrap());
    }
    if let Some(summary) = &state.summary {
        lines.push(serde_json::to_string(&FollowLine::Summary(summary.clone())).unwrap());
    }
    lines.join("\n") + "\n"
}

/// A file dropped on the window.
#[derive(Debug)]
struct Dropped(PathBuf);

impl egui::DroppedFile for Dropped {
    fn path(&self) -> &Path {
        &self.0
    }

    fn bytes(&self) -> Result<Vec<u8>, String> {
        std::fs::read(&self.0).map_err(|e| e.to_string())
    }
}

#[test]
fn a_follow_scene_runs_from_the_bar_and_its_jsonl_plays_the_same_steps() {
    let dir = temp_dir("follow-run");
    let scene = short_follow_scene(&dir);
    let mut harness = harness(MonitorApp::new(AppOptions {
        export_dir: dir.clone(),
        ..AppOptions::default()
    }));
    harness.step();
    harness
        .get_by_role_and_label(Role::TextInput, "scene .toml")
        .focus();
    harness.step();
    harness
        .get_by_role_and_label(Role::TextInput, "scene .toml")
        .type_text(&scene.display().to_string());
    harness.step();
    harness.get_by_label("Run sweep").click();
    step_until(&mut harness, "the follow run to end", 120.0, |h| {
        h.state().follow().is_some_and(|w| w.lock().is_finished())
    });
    expect_label(&mut harness, "ran ");
    let (message, is_error) = harness
        .state()
        .message()
        .map(|(m, e)| (m.to_owned(), e))
        .unwrap();
    assert!(!is_error, "{message}");
    assert!(message.contains("50 steps, status ok"), "{message}");
    {
        let state = follow_state(&harness);
        assert!(!state.from_file);
        assert_eq!(state.steps.len(), 50);
        assert_eq!(state.history.len(), 50);
    }
    // The run's panels: its figures, the top view's two modes, the error plot.
    expect_label(&mut harness, "Follow run");
    expect_label(&mut harness, "distance error, mm (setpoint 100 mm)");
    harness.get_by_label("fit run").click();
    harness.step();
    harness.get_by_label("follow robot");
    // Shown from its start; the slider scrubs the top view, the plot and the figures.
    assert_eq!(cursor_s(&harness), 0.0);
    harness
        .get_by_role_and_label(Role::Slider, "scrub, s")
        .set_value_accesskit(0.25);
    harness.step();
    let cursor = cursor_s(&harness);
    assert!((cursor - 0.25).abs() < 1e-3, "cursor {cursor}");
    let (shown, text) = {
        let state = follow_state(&harness);
        let shown = state.frame_at(cursor).unwrap();
        (shown, jsonl(&state))
    };
    assert!(
        (shown.t_s - 0.25).abs() < 0.011,
        "the frame at {} s",
        shown.t_s
    );
    expect_label(&mut harness, &format!("at t = {:.3} s", shown.t_s));
    expect_label(&mut harness, &format!("at {:.3} s: true ", shown.t_s));
    let steps = follow_state(&harness).steps.clone();

    // The same run as antenna follow --jsonl writes it, opened from the trial field.
    let file = dir.join("run.jsonl");
    std::fs::write(&file, &text).unwrap();
    harness
        .get_by_role_and_label(Role::TextInput, "trial .mcap")
        .focus();
    harness.step();
    harness
        .get_by_role_and_label(Role::TextInput, "trial .mcap")
        .type_text(&file.display().to_string());
    harness.step();
    harness.get_by_label("Open").click();
    harness.step();
    let (message, is_error) = harness
        .state()
        .message()
        .map(|(m, e)| (m.to_owned(), e))
        .unwrap();
    assert!(!is_error && message.contains("50 steps"), "{message}");
    {
        let state = follow_state(&harness);
        assert!(state.from_file);
        assert_eq!(state.steps, steps);
        assert_eq!(state.frame_at(cursor).unwrap(), shown);
    }
    expect_label(&mut harness, "status: ok");
    // The exports work as for a recording: the figure of the robot at the cursor.
    harness.get_by_label("Export PNG").click();
    harness.step();
    let exports = harness.state().exports().to_vec();
    assert_eq!(exports.len(), 1, "{:?}", harness.state().message());
    assert!(std::fs::metadata(&exports[0].path).unwrap().len() > 1000);
    harness.get_by_label("Export CSV").click();
    harness.step();
    let exports = harness.state().exports().to_vec();
    assert_eq!(exports.len(), 2, "{:?}", harness.state().message());
    assert!(exports[1].rows.unwrap() >= 2);

    // Dropped on the window: opened too.
    let copy = dir.join("dropped.jsonl");
    std::fs::write(&copy, &text).unwrap();
    harness
        .input_mut()
        .dropped_files
        .push(Arc::new(Dropped(copy.clone())));
    harness.step();
    assert_eq!(follow_state(&harness).path, copy);
    assert_eq!(follow_state(&harness).steps, steps);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_follow_file_with_a_bad_line_names_it_and_leaves_the_monitor_as_it_was() {
    let dir = temp_dir("follow-bad");
    let file = dir.join("bad.jsonl");
    std::fs::write(
        &file,
        "{\"type\":\"summary\",\"status\":\"ok\"}\nnot json\n",
    )
    .unwrap();
    let mut harness = harness(MonitorApp::new(AppOptions {
        follow: Some(file.clone()),
        export_dir: dir.clone(),
        ..AppOptions::default()
    }));
    harness.step();
    let (message, is_error) = harness
        .state()
        .message()
        .map(|(m, e)| (m.to_owned(), e))
        .unwrap();
    assert!(is_error, "{message}");
    assert!(
        message.starts_with(&format!("{}:1: ", file.display())),
        "{message}"
    );
    assert!(harness.state().follow().is_none());
    // A bad line after a good start: named by its number.
    let text = format!(
        "{}\n{{\"type\": \"step\", \"t_s\": }}\n",
        serde_json::to_string(&FollowLine::Start(
            antenna_scene::follow_lines::FollowStart {
                scene: "s.toml".into(),
                scene_toml: String::new(),
                note: String::new(),
                estimator: "contact-line".into(),
                body: "template".into(),
                wall_side: "left".into(),
                speed_m_per_s: 0.3,
                setpoint_m: 0.1,
                steps: 1,
                step_s: 0.01,
                delay_steps: 0,
                footprint_m: [0.12, 0.06],
                links: 2,
                link_lengths_m: vec![0.04, 0.04],
            }
        ))
        .unwrap()
    );
    std::fs::write(&file, text).unwrap();
    harness.state_mut().open(&file);
    harness.step();
    let (message, is_error) = harness
        .state()
        .message()
        .map(|(m, e)| (m.to_owned(), e))
        .unwrap();
    assert!(is_error, "{message}");
    assert!(
        message.starts_with(&format!("{}:2: not a follow line", file.display())),
        "{message}"
    );
    expect_label(&mut harness, ":2: not a follow line");
    std::fs::remove_dir_all(&dir).ok();
}
