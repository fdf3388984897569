//! Test support: a real antennad in-process on the simulated rig, and the monitor in an
//! egui_kittest harness (no renderer: clicks and queries go through AccessKit).
#![allow(clippy::unwrap_used)]

use std::path::PathBuf;
use std::time::{Duration, Instant};

use antenna_monitor::{AppOptions, MonitorApp};
use egui_kittest::Harness;
use host_daemon::service::config::Config;
use host_daemon::service::daemon::{Daemon, DaemonHandle, DaemonOptions};

/// How long a wait for something the daemon or the monitor does may take before the test
/// fails: only a hang takes this long, however loaded the machine.
pub const PATIENCE_S: f64 = 60.0;

/// The control token the test daemons use (test constant, not the crate's).
pub const TOKEN: &str = "monitor-test-token";

/// A fresh temporary directory for one test.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("antenna-monitor-{name}-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The simulated rig's configuration, listening on a free loopback port with [`TOKEN`].
pub fn config(dir: &std::path::Path) -> Config {
    let mut config = Config::default();
    config.server.listen = "127.0.0.1:0".to_owned();
    config.server.token = Some(host_daemon::net::ControlToken::new(TOKEN).unwrap());
    config.data_dir = dir.to_path_buf();
    config
}

/// Starts antennad (no trial: polling and streaming run, the stage waits for commands) and
/// waits until its stage is homed, so a move command is not refused for homing under way.
pub fn start_daemon(config: Config) -> DaemonHandle {
    let daemon = Daemon::start(config, DaemonOptions::default()).unwrap();
    let deadline = Instant::now() + Duration::from_secs_f64(PATIENCE_S);
    while !daemon.log_lines().iter().any(|l| l.contains("stage homed")) {
        assert!(Instant::now() < deadline, "the stage never homed");
        std::thread::sleep(Duration::from_millis(10));
    }
    daemon
}

/// The monitor connected to `daemon` (token as given), in a 1280 x 800 harness.
pub fn monitor(
    daemon: &DaemonHandle,
    token: &str,
    export_dir: PathBuf,
) -> Harness<'static, MonitorApp> {
    let app = MonitorApp::new(AppOptions {
        connect: Some(daemon.local_addr().unwrap().to_string()),
        token: token.to_owned(),
        trial: None,
        scene: None,
        follow: None,
        history_s: 30.0,
        export_dir,
    });
    harness(app)
}

/// `app` in a 1280 x 800 harness.
pub fn harness(app: MonitorApp) -> Harness<'static, MonitorApp> {
    Harness::builder()
        .with_size(egui::vec2(1280.0, 800.0))
        .build_ui_state(|ui, app: &mut MonitorApp| app.ui(ui), app)
}

/// Steps the harness (every 10 ms of real time) until `done` holds; panics after `timeout_s`
/// naming `what`.
pub fn step_until(
    harness: &mut Harness<'_, MonitorApp>,
    what: &str,
    timeout_s: f64,
    mut done: impl FnMut(&mut Harness<'_, MonitorApp>) -> bool,
) {
    let deadline = Instant::now() + Duration::from_secs_f64(timeout_s);
    loop {
        harness.step();
        if done(harness) {
            return;
        }
        assert!(Instant::now() < deadline, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Steps a frame, waits `pause`, steps another; returns the least and most time (s) that
/// passed between the two frames' clock readings: the time between the two steps, and the
/// time around them. What plays in real time moves on by an amount between the two.
pub fn step_around(harness: &mut Harness<'_, MonitorApp>, pause: Duration) -> (f64, f64) {
    let before_first = Instant::now();
    harness.step();
    let after_first = Instant::now();
    std::thread::sleep(pause);
    let before_second = Instant::now();
    harness.step();
    let after_second = Instant::now();
    (
        (before_second - after_first).as_secs_f64(),
        (after_second - before_first).as_secs_f64(),
    )
}

/// Steps until the monitor is connected and holds at least `seconds` of samples.
pub fn wait_for_history(harness: &mut Harness<'_, MonitorApp>, seconds: f64) {
    step_until(
        harness,
        &format!("{seconds} s of samples"),
        PATIENCE_S,
        |h| {
            let state = h.state().live().unwrap().lock();
            state
                .history
                .first_t_s()
                .zip(state.history.latest_t_s())
                .is_some_and(|(a, b)| b - a >= seconds)
        },
    );
}

/// Steps the harness until a widget whose label contains `text` is on screen (the state a
/// label shows can change after the frame that was last drawn); panics after [`PATIENCE_S`].
pub fn expect_label(harness: &mut Harness<'_, MonitorApp>, text: &str) {
    use egui_kittest::kittest::Queryable;
    step_until(harness, &format!("the label {text:?}"), PATIENCE_S, |h| {
        h.query_by_label_contains(text).is_some()
    });
}
