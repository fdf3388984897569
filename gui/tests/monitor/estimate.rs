//! The live wall estimate and message types the monitor does not know, against a fake
//! antennad: a loopback server that writes a `hello` with the simulated rig's geometry, then
//! samples, `estimate` lines and a line of a type from the future, as a newer daemon would;
//! a real antennad's estimates on the simulated rig, placed on the scene's wall; and a
//! recorded trial's estimates.
#![allow(clippy::unwrap_used)]

use std::io::{Read, Write};
use std::net::TcpListener;
use std::thread::JoinHandle;

use crate::support::{
    PATIENCE_S, config, expect_label, harness, monitor, start_daemon, step_until, temp_dir,
};
use antenna_data::stream::{EstimateMessage, PROTOCOL_VERSION, SegmentSample, StreamMessage};
use antenna_monitor::app::attach_estimate;
use antenna_monitor::client::ConnectionState;
use antenna_monitor::estimate::WallSide;
use antenna_monitor::{AppOptions, MonitorApp};
use host_daemon::service::config::Config;

/// Polls the fake daemon sends (1.5 s)...
const POLLS: u64 = 1500;
/// ...with an estimate every 10th up to this one (then its estimator stops).
const LAST_ESTIMATE: u64 = 400;
/// The stage's position throughout, metres.
const STAGE_M: f64 = 0.1;

/// One poll of the default rig's 8 segments, straight and untouched, the stage at
/// [`STAGE_M`].
fn samples(seq: u64) -> StreamMessage {
    StreamMessage::Samples {
        seq,
        t_ns: seq * 1_000_000,
        segments: (0x20..0x28)
            .map(|address| SegmentSample {
                address,
                angle_rad: Some(0.0),
                contact: Some(false),
                touch_bits: Some(0),
                counter: Some(seq as u32),
                error: None,
                stale: false,
            })
            .collect(),
        stage_position_m: Some(STAGE_M),
        base_angle_deg: Some(0.0),
    }
}

/// The estimate made at poll `seq`: none before poll 100 (with the daemon's reason), then a
/// wall 350 mm away at 50 mm ahead, at 0.1 rad; the truth 360 mm throughout.
fn estimate(seq: u64) -> StreamMessage {
    let known = seq >= 100;
    StreamMessage::Estimate(EstimateMessage {
        seq,
        t_ns: seq * 1_000_000,
        estimated_ns: seq * 1_000_000 + 20_000,
        estimator: "contact-line".to_owned(),
        distance_m: known.then_some(0.35),
        angle_rad: known.then_some(0.1),
        preview_m: known.then_some(0.05),
        reason: (!known).then(|| "no contact in the window".to_owned()),
        true_distance_m: Some(0.36),
        true_angle_rad: Some(0.1),
    })
}

/// Serves one connection: `hello`, then [`POLLS`] polls with an estimate every 10th up to
/// [`LAST_ESTIMATE`] and a `future_thing` line after poll 5; then holds the connection open until the client closes
/// it. Returns the server's address and its thread.
fn fake_daemon() -> (String, JoinHandle<()>) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let thread = std::thread::spawn(move || {
        let (mut stream, _) = listener.accept().unwrap();
        let config = Config::default();
        let hello = StreamMessage::Hello {
            protocol_version: PROTOCOL_VERSION,
            daemon: "antennad 9.9.9-future".to_owned(),
            segment_count: 8,
            segment_addresses: (0x20..0x28).collect(),
            rig: Some(host_daemon::service::daemon::rig_info(&config)),
        };
        let mut text = serde_json::to_string(&hello).unwrap() + "\n";
        for seq in 1..=POLLS {
            text += &(serde_json::to_string(&samples(seq)).unwrap() + "\n");
            if seq % 10 == 0 && seq <= LAST_ESTIMATE {
                text += &(serde_json::to_string(&estimate(seq)).unwrap() + "\n");
            }
            if seq == 5 {
                text += "{\"type\":\"future_thing\",\"x\":1}\n";
            }
        }
        stream.write_all(text.as_bytes()).unwrap();
        // Until the monitor goes: read (and drop) whatever it sends.
        let mut buffer = [0u8; 1024];
        while matches!(stream.read(&mut buffer), Ok(n) if n > 0) {}
    });
    (address, thread)
}

#[test]
fn an_unknown_message_type_is_skipped_and_the_estimate_is_shown() {
    let (address, server) = fake_daemon();
    let app = MonitorApp::new(AppOptions {
        connect: Some(address),
        history_s: 30.0,
        ..AppOptions::default()
    });
    let mut harness = harness(app);
    step_until(&mut harness, "every poll", PATIENCE_S, |h| {
        h.state().live().unwrap().lock().history.len() == POLLS as usize
    });
    {
        let state = harness.state().live().unwrap().lock();
        // The future line was skipped and counted: not a protocol error, no disconnect.
        assert_eq!(state.unknown_lines, (1, Some("future_thing".to_owned())));
        assert_eq!(state.bad_lines, (0, None));
        assert_eq!(state.connections, 1);
        assert!(matches!(
            state.connection,
            ConnectionState::Connected { .. }
        ));
        // Every poll after it arrived, in order.
        let seqs: Vec<u64> = (0..state.history.len())
            .map(|i| state.history.sample(i).unwrap().seq.unwrap())
            .collect();
        assert_eq!(seqs, (1..=POLLS).collect::<Vec<_>>());
        // Every estimate, the newest last.
        assert_eq!(state.estimates.len(), (LAST_ESTIMATE / 10) as usize);
        let latest = state.estimates.latest().unwrap();
        assert_eq!(latest.seq, LAST_ESTIMATE);
        assert_eq!(latest.distance_m, Some(0.35));
        // The estimated wall over the chain: from the base pivot at the stage's position, x
        // along the travel, y toward the wall (on the left of the default rig's travel).
        let rig = state.rig.as_ref().unwrap();
        assert_eq!(rig.wall_side(), WallSide::Left);
        let index = state.history.index_at(LAST_ESTIMATE as f64 * 1e-3).unwrap();
        assert_eq!(
            state.history.sample(index).unwrap().seq,
            Some(LAST_ESTIMATE)
        );
        let mut frame = rig.frame_at(&state.history, index).unwrap();
        attach_estimate(&mut frame, &state.estimates, rig, &state.history);
        let wall = frame.estimated_wall.clone().unwrap();
        assert!(wall.angle_known && frame.estimate_note.is_none());
        assert!(
            (wall.at_m[0] - (STAGE_M + 0.05)).abs() < 1e-12 && (wall.at_m[1] - 0.35).abs() < 1e-12,
            "{:?}",
            wall.at_m
        );
        let [a, b] = wall.ends_m;
        assert!(((b[1] - a[1]) / (b[0] - a[0]) - 0.1f64.tan()).abs() < 1e-9);
        // The segment spans the chain along the travel.
        let tip = frame.tip_m().unwrap();
        assert!(a[0] < STAGE_M && b[0] > tip[0], "{a:?} {b:?} tip {tip:?}");
        // Before poll 100 there was no estimate: the frame says why.
        let early = state.history.index_at(0.05).unwrap();
        let mut frame = rig.frame_at(&state.history, early).unwrap();
        attach_estimate(&mut frame, &state.estimates, rig, &state.history);
        assert!(frame.estimated_wall.is_none());
        let note = frame.estimate_note.unwrap();
        assert!(note.contains("no contact in the window"), "{note}");
        // At the newest poll, 1.1 s after the last estimate: it is no longer drawn.
        let newest = state.history.len() - 1;
        let mut frame = rig.frame_at(&state.history, newest).unwrap();
        attach_estimate(&mut frame, &state.estimates, rig, &state.history);
        assert!(frame.estimated_wall.is_none());
        assert_eq!(
            frame.estimate_note.as_deref(),
            Some("the newest was made 1.1 s before")
        );
    }
    // Following the newest poll: the last estimate is too old.
    expect_label(
        &mut harness,
        "no current wall estimate: the newest was made 1.1 s before the cursor",
    );
    expect_label(&mut harness, "line(s) of message types not known here");
    // At the last estimate's poll, the panel says it.
    harness.state_mut().scrub_to(LAST_ESTIMATE as f64 * 1e-3);
    expect_label(
        &mut harness,
        "wall estimate (contact-line): 350.0 mm, 5.7 deg at 50 mm ahead; true 360.0 mm, error -10.0 mm",
    );
    // Scrubbed to before the first estimate: the reason.
    harness.state_mut().scrub_to(0.05);
    expect_label(
        &mut harness,
        "no wall estimate (contact-line): no contact in the window",
    );
    drop(harness);
    server.join().unwrap();
}

/// A recorded trial's estimates (`/antenna/estimate`) are shown as live ones are: the
/// estimate at the cursor above its plot, the reason before there is one.
#[test]
fn a_recorded_trials_estimates_are_shown() {
    use antenna_data::record::{
        EstimateMessage as RecordedEstimate, TrialRecorder, synthetic_metadata, synthetic_segments,
    };
    let dir = temp_dir("recorded-estimate");
    let path = dir.join("estimates.mcap");
    let mut metadata = synthetic_metadata("estimates");
    metadata.rig = Some(host_daemon::service::daemon::rig_info(&Config::default()));
    let mut recorder = TrialRecorder::create(&path, &metadata).unwrap();
    let mut times = Vec::new();
    for i in 0..400 {
        let segments = synthetic_segments(i, 8);
        times.push(segments.t_s);
        recorder.record_segments(&segments).unwrap();
        if i % 10 == 0 {
            let known = i >= 200;
            recorder
                .record_estimate(&RecordedEstimate {
                    t_s: segments.t_s,
                    seq: i,
                    estimator: "bend".to_owned(),
                    distance_m: known.then_some(0.25),
                    wall_angle_rad: None,
                    preview_m: known.then_some(0.04),
                    reason: (!known).then(|| "no bend calibration yet".to_owned()),
                    true_distance_m: None,
                    true_angle_rad: None,
                })
                .unwrap();
        }
    }
    recorder.finish().unwrap();
    let mut harness = harness(MonitorApp::new(AppOptions {
        trial: Some(path),
        export_dir: dir.clone(),
        ..AppOptions::default()
    }));
    harness.step();
    assert_eq!(harness.state().trial().unwrap().estimates.len(), 40);
    harness.state_mut().scrub_to(times[100]);
    expect_label(
        &mut harness,
        "no wall estimate (bend): no bend calibration yet",
    );
    harness.state_mut().scrub_to(times[305]);
    expect_label(
        &mut harness,
        "wall estimate (bend): 250.0 mm, no angle at 40 mm ahead",
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A real antennad on the simulated rig with the `ideal-preview` estimator (the true wall
/// along y from the base pivot): its estimates arrive after their polls, and the wall the
/// monitor draws from one (the daemon's carriage frame turned into the chain's track frame)
/// passes through the scene's wall where the estimate measured it.
#[test]
fn a_real_daemons_estimate_lies_on_the_scenes_wall() {
    use host_daemon::service::config::EstimatorName;
    let dir = temp_dir("daemon-estimate");
    let mut daemon_config = config(&dir);
    daemon_config.estimate.estimator = EstimatorName::IdealPreview;
    let daemon = start_daemon(daemon_config);
    let mut harness = monitor(&daemon, "", dir.clone());
    // An estimate whose poll is held (estimates come after their poll's samples).
    step_until(
        &mut harness,
        "an estimate of a held poll",
        PATIENCE_S,
        |h| {
            let state = h.state().live().unwrap().lock();
            state.estimates.latest().is_some_and(|e| {
                state
                    .history
                    .index_at(e.t_s)
                    .and_then(|i| state.history.sample(i))
                    .is_some_and(|s| s.seq == Some(e.seq))
            })
        },
    );
    {
        let state = harness.state().live().unwrap().lock();
        assert_eq!(state.unknown_lines.0, 0);
        assert_eq!(state.bad_lines.0, 0);
        let e = state.estimates.latest().unwrap().clone();
        assert_eq!(e.estimator, "ideal-preview");
        let distance_m = e.distance_m.unwrap();
        // The truth is the same ray from the same pose.
        assert!((e.true_distance_m.unwrap() - distance_m).abs() < 1e-9);
        assert_eq!((e.angle_rad, e.preview_m), (None, Some(0.0)));
        let rig = state.rig.as_ref().unwrap();
        let index = state.history.index_at(e.t_s).unwrap();
        let mut frame = rig.frame_at(&state.history, index).unwrap();
        attach_estimate(&mut frame, &state.estimates, rig, &state.history);
        let wall = frame.estimated_wall.clone().unwrap();
        assert!(!wall.angle_known);
        // The preview point (on y through the base pivot) is on the scene's wall, and
        // `distance_m` from the base pivot.
        let at = nalgebra::Vector2::new(wall.at_m[0], wall.at_m[1]);
        let gap_m = rig.walls[0].signed_distance(&at).gap_m;
        assert!(
            gap_m.abs() < 1e-6,
            "the estimate's point is {gap_m} m off the wall"
        );
        let base = frame.base_m;
        let from_base_m = (wall.at_m[0] - base[0]).hypot(wall.at_m[1] - base[1]);
        assert!((from_base_m - distance_m).abs() < 1e-9);
    }
    // The panel says it: no angle from this estimator, and no error against the truth.
    expect_label(&mut harness, "wall estimate (ideal-preview): ");
    expect_label(&mut harness, "no angle at 0 mm ahead; true ");
    daemon.shutdown().unwrap();
    std::fs::remove_dir_all(&dir).ok();
}
