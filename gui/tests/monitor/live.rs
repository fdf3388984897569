//! The monitor against a real antennad on the simulated rig, driven through egui_kittest:
//! connect (with the rig's geometry from `hello`), pause while data keeps arriving, zoom,
//! export of the visible range (CSV content checked, PNG and SVG written), control refused
//! without a token or with a wrong one and carried out with the right one (Stop everything
//! always enabled, needing no token), a token given at start proved on connecting, the
//! daemon going away and coming back, and an unhealthy segment.
#![allow(clippy::unwrap_used)]

use crate::support::{
    PATIENCE_S, TOKEN, config, expect_label, monitor, start_daemon, step_until, temp_dir,
    wait_for_history,
};
use antenna_monitor::client::ConnectionState;
use antenna_monitor::history::Health;
use egui::accesskit::Role;
use egui_kittest::kittest::{NodeT, Queryable};
use host_daemon::service::config::{SimFaultConfig, SimFaultKind};

#[test]
fn connect_shows_the_daemon_the_chain_and_the_rig_geometry() {
    let dir = temp_dir("connect");
    let daemon = start_daemon(config(&dir));
    let mut harness = monitor(&daemon, "", dir.clone());
    wait_for_history(&mut harness, 0.3);
    expect_label(&mut harness, "connected to antennad");
    let gaps;
    {
        let state = harness.state().live().unwrap().lock();
        let rig = state.rig.as_ref().unwrap();
        // The rig object of hello: the simulated rig's scene (the built-in 4.2.1 one).
        assert_eq!(rig.segment_count(), 8);
        assert_eq!(rig.link_lengths_m, vec![0.04; 9]);
        assert!((rig.base_mount_angle_rad - 30f64.to_radians()).abs() < 1e-12);
        assert_eq!(rig.walls.len(), 1);
        assert!(rig.scene.is_some());
        assert_eq!(state.segment_addresses, (0x20..=0x27).collect::<Vec<u8>>());
        // Polls arrive at 1 kHz, in order, all healthy, every one held or counted as dropped;
        // a gap in `seq` is a deadline the daemon skipped, late on a loaded machine
        // (docs/stream-protocol.md): no more gaps than the daemon counts skipped deadlines
        // (checked at shutdown below).
        let n = state.history.len();
        let last = state.history.sample(n - 1).unwrap();
        let first = state.history.sample(0).unwrap();
        let seq_span = last.seq.unwrap() - first.seq.unwrap();
        // The polls among the messages dropped (`lagged`'s `samples_dropped`; the others
        // are status and estimate lines).
        let held = n as u64 - 1 + state.lagged_samples_dropped;
        assert!(
            seq_span >= held,
            "seq {} to {}: {n} polls held, {} dropped",
            first.seq.unwrap(),
            last.seq.unwrap(),
            state.lagged_samples_dropped
        );
        gaps = seq_span - held;
        let seqs: Vec<u64> = (0..n)
            .map(|i| state.history.sample(i).unwrap().seq.unwrap())
            .collect();
        assert!(seqs.windows(2).all(|w| w[0] < w[1]), "polls out of order");
        assert!(last.segments.iter().all(|s| s.health == Health::Ok));
        // The chain at the newest sample starts at the stage, along the mounting angle.
        let frame = rig.frame_at(&state.history, n - 1).unwrap();
        assert_eq!(frame.joints_m.len(), 10);
        assert_eq!(frame.base_m, [0.0, 0.0]);
    }
    expect_label(&mut harness, "all 8 segments healthy");
    // The prediction is drawn for the same pose: the difference line appears once solved.
    step_until(&mut harness, "the prediction", PATIENCE_S, |h| {
        h.query_by_label_contains("measured vs predicted").is_some()
    });
    let summary = daemon.shutdown().unwrap();
    assert!(
        gaps <= summary.skipped,
        "{gaps} polls missing from the stream, {} deadlines skipped",
        summary.skipped
    );
}

#[test]
fn pause_freezes_the_view_while_data_keeps_arriving() {
    let dir = temp_dir("pause");
    let daemon = start_daemon(config(&dir));
    let mut harness = monitor(&daemon, "", dir.clone());
    wait_for_history(&mut harness, 0.2);
    assert!(harness.state().view().is_following());
    harness.get_by_label("Pause").click();
    harness.step();
    assert!(!harness.state().view().is_following());
    let latest = |h: &egui_kittest::Harness<'_, antenna_monitor::MonitorApp>| {
        let state = h.state().live().unwrap().lock();
        (state.history.latest_t_s(), state.history.total_pushed())
    };
    let (t_paused, pushed_paused) = latest(&harness);
    let window = harness.state().view().window(t_paused).unwrap();
    let cursor = harness.state().view().cursor_s(t_paused);
    step_until(&mut harness, "300 more polls", PATIENCE_S, |h| {
        latest(h).1 >= pushed_paused + 300
    });
    let (t_now, _) = latest(&harness);
    assert!(t_now.unwrap() > t_paused.unwrap() + 0.25);
    // The view stands still while the history grows.
    assert_eq!(harness.state().view().window(t_now), Some(window));
    assert_eq!(harness.state().view().cursor_s(t_now), cursor);
    // Follow latest resumes.
    harness.get_by_label("Follow latest").click();
    harness.step();
    assert!(harness.state().view().is_following());
    let (t_now, _) = latest(&harness);
    assert_eq!(
        harness.state().view().window(t_now).unwrap().1,
        t_now.unwrap()
    );
    daemon.shutdown().unwrap();
}

#[test]
fn zoom_then_export_the_visible_range() {
    let dir = temp_dir("export");
    let daemon = start_daemon(config(&dir));
    let mut harness = monitor(&daemon, "", dir.clone());
    assert_eq!(harness.state().view().window_s(), 10.0);
    for expected in [5.0, 2.5, 1.25, 0.625] {
        harness.get_by_label("Zoom in").click();
        harness.step();
        assert_eq!(harness.state().view().window_s(), expected);
    }
    harness.get_by_label("Zoom out").click();
    harness.step();
    assert_eq!(harness.state().view().window_s(), 1.25);
    wait_for_history(&mut harness, 1.5);
    harness.get_by_label("Pause").click();
    harness.step();
    harness.get_by_label("Export CSV").click();
    harness.step();
    let export = harness.state().exports().last().unwrap().clone();
    assert!((export.t1_s - export.t0_s - 1.25).abs() < 1e-9);
    let text = std::fs::read_to_string(&export.path).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let header: Vec<&str> = lines[0].split(',').collect();
    assert_eq!(header.len(), 4 + 8 * 3);
    assert_eq!(
        &header[..5],
        [
            "t_s",
            "seq",
            "stage_position_m",
            "servo_angle_deg",
            "s1_angle_rad"
        ]
    );
    assert_eq!(header[27], "s8_health");
    let rows: Vec<Vec<&str>> = lines[1..].iter().map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), export.rows.unwrap());
    // Every poll of the visible 1.25 s at 1 kHz, and nothing outside it: the rows are the
    // history's polls in the window, in order (a deadline the daemon skipped on a loaded
    // machine has no poll, and so no row), so their numbers span at most the window's 1250
    // deadlines.
    let seqs: Vec<u64> = rows.iter().map(|r| r[1].parse().unwrap()).collect();
    let span = seqs[seqs.len() - 1] - seqs[0] + 1;
    assert!(span <= 1251, "{span} deadlines, {} rows", rows.len());
    assert!(seqs.windows(2).all(|w| w[1] > w[0]));
    let times: Vec<f64> = rows.iter().map(|r| r[0].parse().unwrap()).collect();
    assert!(
        times
            .iter()
            .all(|t| (export.t0_s..=export.t1_s).contains(t))
    );
    let live = harness.state().live().unwrap().lock();
    let in_window: Vec<u64> = (0..live.history.len())
        .filter_map(|i| live.history.sample(i))
        .filter(|s| (export.t0_s..=export.t1_s).contains(&s.t_s))
        .filter_map(|s| s.seq)
        .collect();
    drop(live);
    assert_eq!(seqs, in_window, "the rows are the polls in the window");
    for row in &rows {
        assert_eq!(row.len(), header.len());
        for k in 0..8 {
            let angle: f64 = row[4 + 3 * k].parse().unwrap();
            assert!(angle.abs() < 1.6);
            assert_eq!(row[6 + 3 * k], "ok");
        }
        assert_eq!(row[2].parse::<f64>().unwrap(), 0.0);
    }
    // The view as PNG and SVG.
    harness.get_by_label("Export PNG").click();
    harness.step();
    harness.get_by_label("Export SVG").click();
    harness.step();
    let exports = harness.state().exports();
    let png = std::fs::read(&exports[exports.len() - 2].path).unwrap();
    assert!(png.starts_with(b"\x89PNG\r\n\x1a\n") && png.len() > 10_000);
    let svg = std::fs::read_to_string(&exports[exports.len() - 1].path).unwrap();
    assert!(svg.contains("<svg") && svg.contains("joint 8") && svg.contains("chain at t"));
    expect_label(&mut harness, "exported");
    daemon.shutdown().unwrap();
    std::fs::remove_dir_all(&dir).ok();
}

/// The token field (a password input labelled `token`).
fn type_token(harness: &mut egui_kittest::Harness<'_, antenna_monitor::MonitorApp>, token: &str) {
    let field = harness.get_by_role_and_label(Role::PasswordInput, "token");
    field.focus();
    harness.step();
    // Select what is there, so the typing replaces it.
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::A);
    harness.step();
    harness
        .get_by_role_and_label(Role::PasswordInput, "token")
        .type_text(token);
    harness.step();
}

#[test]
fn control_is_refused_without_a_token_and_carried_out_with_it() {
    let dir = temp_dir("control");
    let daemon = start_daemon(config(&dir));
    let mut harness = monitor(&daemon, "", dir.clone());
    wait_for_history(&mut harness, 0.1);
    // No token: every control but Stop everything is disabled.
    for label in ["Start trial", "Stop trial", "Move stage", "Set base angle"] {
        let button = harness.get_by_label(label);
        assert!(button.accesskit_node().is_disabled(), "{label} is enabled");
    }
    expect_label(&mut harness, "enter the daemon's token");
    // Stopping is always allowed: no token needed.
    let stop = harness.get_by_label("Stop everything");
    assert!(!stop.accesskit_node().is_disabled());
    stop.click();
    step_until(
        &mut harness,
        "the token-less stop_all reply",
        PATIENCE_S,
        |h| !h.state().live().unwrap().lock().replies.is_empty(),
    );
    {
        let state = harness.state().live().unwrap().lock();
        let reply = &state.replies[0];
        assert!(reply.ok, "{reply:?}");
        assert_eq!(reply.command.as_deref(), Some("stop_all"));
    }

    // A wrong token: the daemon refuses (bad_token) and nothing moves.
    type_token(&mut harness, "not-the-token");
    assert!(
        !harness
            .get_by_label("Move stage")
            .accesskit_node()
            .is_disabled()
    );
    harness.get_by_label("Move stage").click();
    step_until(&mut harness, "the bad_token reply", PATIENCE_S, |h| {
        h.state().live().unwrap().lock().replies.len() >= 2
    });
    {
        let state = harness.state().live().unwrap().lock();
        let reply = &state.replies[1];
        assert!(!reply.ok);
        assert_eq!(reply.error.as_deref(), Some("bad_token"));
        assert_eq!(reply.command.as_deref(), Some("move_stage"));
    }
    harness.step();
    expect_label(&mut harness, "refused move_stage: [bad_token]");

    // The right token: the stage moves to 100 mm.
    let mut harness_token = harness;
    type_token(&mut harness_token, TOKEN);
    harness_token.get_by_label("Move stage").click();
    step_until(
        &mut harness_token,
        "the move_stage reply",
        PATIENCE_S,
        |h| h.state().live().unwrap().lock().replies.len() >= 3,
    );
    {
        let state = harness_token.state().live().unwrap().lock();
        let reply = &state.replies[2];
        assert!(reply.ok, "{reply:?}");
        assert!(
            reply.message.contains("stage moving to 100.0 mm"),
            "{reply:?}"
        );
    }
    step_until(&mut harness_token, "the stage moving", PATIENCE_S, |h| {
        let state = h.state().live().unwrap().lock();
        let n = state.history.len();
        state
            .history
            .sample(n - 1)
            .and_then(|s| s.stage_position_m)
            .is_some_and(|x| x > 0.005)
    });
    harness_token.get_by_label("Stop everything").click();
    step_until(&mut harness_token, "the stop_all reply", PATIENCE_S, |h| {
        let state = h.state().live().unwrap().lock();
        state.replies.len() >= 4 && state.replies[3].ok
    });
    daemon.shutdown().unwrap();
}

/// With the token given at start, the monitor proves it on connecting (`auth`), so antennad
/// keeps its connection, an operator's, however many readers come.
#[test]
fn a_token_given_at_start_is_proved_on_connecting() {
    let dir = temp_dir("auth");
    let daemon = start_daemon(config(&dir));
    let mut harness = monitor(&daemon, TOKEN, dir.clone());
    step_until(&mut harness, "the auth reply", PATIENCE_S, |h| {
        !h.state().live().unwrap().lock().replies.is_empty()
    });
    {
        let state = harness.state().live().unwrap().lock();
        let reply = &state.replies[0];
        assert!(reply.ok, "{reply:?}");
        assert_eq!(reply.command.as_deref(), Some("auth"));
    }
    let log = daemon.log_lines();
    assert!(
        log.iter().any(|l| l.contains("proved the control token")),
        "{log:#?}"
    );
    daemon.shutdown().unwrap();
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_daemon_going_away_is_shown_and_the_monitor_reconnects() {
    let dir = temp_dir("reconnect");
    let daemon = start_daemon(config(&dir));
    let address = daemon.local_addr().unwrap();
    let mut harness = monitor(&daemon, "", dir.clone());
    wait_for_history(&mut harness, 0.1);
    daemon.shutdown().unwrap();
    step_until(&mut harness, "the disconnection", PATIENCE_S, |h| {
        matches!(
            h.state().live().unwrap().lock().connection,
            ConnectionState::Disconnected { .. }
        )
    });
    expect_label(&mut harness, "DISCONNECTED");
    // The samples received stay on screen.
    assert!(!harness.state().live().unwrap().lock().history.is_empty());
    let mut again = config(&dir);
    again.server.listen = address.to_string();
    let daemon = start_daemon(again);
    step_until(&mut harness, "the reconnection", PATIENCE_S, |h| {
        let state = h.state().live().unwrap().lock();
        state.connections == 2 && matches!(state.connection, ConnectionState::Connected { .. })
    });
    harness.step();
    expect_label(&mut harness, "connected to antennad");
    daemon.shutdown().unwrap();
}

#[test]
fn an_unhealthy_segment_is_shown_as_such() {
    let dir = temp_dir("unhealthy");
    let mut config = config(&dir);
    config.sim.faults = vec![SimFaultConfig {
        address: 0x22,
        kind: SimFaultKind::Nack,
        from_s: 0.0,
        until_s: 600.0,
    }];
    let daemon = start_daemon(config);
    let mut harness = monitor(&daemon, "", dir.clone());
    wait_for_history(&mut harness, 0.2);
    expect_label(&mut harness, "1 of 8 segments unhealthy");
    {
        let state = harness.state().live().unwrap().lock();
        let rig = state.rig.as_ref().unwrap();
        let frame = rig
            .frame_at(&state.history, state.history.len() - 1)
            .unwrap();
        assert_eq!(frame.segments[2].health, Health::Nack);
        assert!(!frame.segments[2].angle_current);
        assert!(
            frame
                .segments
                .iter()
                .enumerate()
                .all(|(k, s)| k == 2 || s.health == Health::Ok)
        );
    }
    daemon.shutdown().unwrap();
}

#[test]
fn the_history_window_the_user_sets_bounds_the_history() {
    let dir = temp_dir("history");
    let daemon = start_daemon(config(&dir));
    let mut harness = monitor(&daemon, "", dir.clone());
    wait_for_history(&mut harness, 0.1);
    assert_eq!(
        harness.state().live().unwrap().lock().history.capacity(),
        30_000
    );
    // One second at 1 kHz, set in the view bar.
    harness
        .get_by_role_and_label(Role::SpinButton, "history, s")
        .set_value_accesskit(1.0);
    harness.step();
    step_until(&mut harness, "1.5 s of polls", PATIENCE_S, |h| {
        h.state().live().unwrap().lock().history.total_pushed() >= 1500
    });
    let state = harness.state().live().unwrap().lock();
    assert_eq!(state.history.capacity(), 1000);
    assert_eq!(state.history.len(), 1000);
    let span = state.history.latest_t_s().unwrap() - state.history.first_t_s().unwrap();
    // 1000 polls at 1 kHz: 0.999 s, more by 1 ms for each deadline the daemon skipped on a
    // loaded machine (which has no poll): the polls' numbers say how many deadlines the
    // window spans, and its time span is theirs.
    let seq = |i: usize| state.history.sample(i).and_then(|s| s.seq).unwrap();
    let deadlines = seq(state.history.len() - 1) - seq(0) + 1;
    assert!(deadlines >= 1000, "{deadlines} deadlines");
    let expected_s = (deadlines - 1) as f64 * 1e-3;
    assert!(
        (span - expected_s).abs() < 0.005,
        "{span} s held over {deadlines} deadlines"
    );
    drop(state);
    daemon.shutdown().unwrap();
}
