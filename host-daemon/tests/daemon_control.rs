//! A real antennad, in-process on the simulated rig, controlled over TCP: every command with
//! and without the token, malformed commands, moves beyond the soft limits (refused, the stage
//! never passes the limit), the trial rule (move_stage / set_base_angle refused while a
//! trial's script runs) and stop_all; polling and streaming go on throughout.
#![allow(clippy::unwrap_used)]

mod net_support;

use antenna_data::record::TrialReader;
use antenna_data::stream::{ControlReply, ErrorCode, StreamMessage};
use host_daemon::service::config::{Config, MoveConfig};
use host_daemon::service::daemon::{Daemon, DaemonHandle, DaemonOptions};
use net_support::{Client, TOKEN};
use std::path::PathBuf;
use std::time::{Duration, Instant};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("antennad-{name}-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    dir
}

fn config(dir: &std::path::Path) -> Config {
    let mut config = Config::default();
    config.server.listen = "127.0.0.1:0".to_owned();
    config.server.token = Some(host_daemon::net::ControlToken::new(TOKEN).unwrap());
    config.data_dir = dir.to_path_buf();
    config.bus.poll_hz = 500.0;
    config.stage.max_mm = 100.0;
    config.trials[0].duration_s = 30.0;
    config.trials[0].moves = vec![MoveConfig {
        distance_mm: 40.0,
        speed_mm_per_s: 20.0,
        pause_s: 0.0,
    }];
    config
}

/// Starts antennad and waits until its (simulated) stage is homed: before that a move is
/// refused for homing under way, which a loaded machine can make last.
fn start(config: Config) -> (DaemonHandle, Client) {
    let daemon = Daemon::start(config, DaemonOptions::default()).unwrap();
    let deadline = std::time::Instant::now() + Duration::from_secs(60);
    while !daemon.log_lines().iter().any(|l| l.contains("stage homed")) {
        assert!(
            std::time::Instant::now() < deadline,
            "the stage never homed"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    let mut client = Client::connect(daemon.local_addr().unwrap());
    assert!(matches!(client.next_message(), StreamMessage::Hello { .. }));
    (daemon, client)
}

fn request(client: &mut Client, id: u64, body: &str) -> ControlReply {
    let line = format!(r#"{{"id":{id},"token":"{TOKEN}",{body}}}"#);
    client.send_line(&line);
    let reply = client.next_reply();
    assert_eq!(reply.id, Some(id), "{reply:?}");
    reply
}

/// What [`watch`] saw.
struct Watched {
    /// Every stage position, metres.
    stage: Vec<f64>,
    /// Per segment, base to tip, the OR of every poll's touch bits.
    touch_bits_seen: Vec<u8>,
}

/// Reads samples until `done(stage_m, base_deg)` holds (at most 60 s), checking that every
/// segment of every poll reads, with its four touch bits, and that `contact` is any of them.
fn watch(client: &mut Client, mut done: impl FnMut(Option<f64>, Option<f64>) -> bool) -> Watched {
    let deadline = Instant::now() + Duration::from_secs(60);
    let mut seen = Watched {
        stage: Vec::new(),
        touch_bits_seen: vec![0; 8],
    };
    loop {
        assert!(
            Instant::now() < deadline,
            "condition not reached; stage {:?}",
            seen.stage
        );
        if let StreamMessage::Samples {
            stage_position_m,
            base_angle_deg,
            segments,
            ..
        } = client.next_message()
        {
            assert_eq!(segments.len(), 8);
            assert!(segments.iter().all(|s| s.error.is_none() && !s.stale));
            for (s, or) in segments.iter().zip(&mut seen.touch_bits_seen) {
                let bits = s
                    .touch_bits
                    .unwrap_or_else(|| panic!("no touch_bits: {s:?}"));
                assert!(bits <= 0x0F, "{s:?}");
                assert_eq!(s.contact, Some(bits != 0), "{s:?}");
                *or |= bits;
            }
            seen.stage.extend(stage_position_m);
            if done(stage_position_m, base_angle_deg) {
                return seen;
            }
        }
    }
}

#[test]
fn every_command_but_stop_all_needs_the_token_and_malformed_ones_get_clear_errors() {
    let dir = temp_dir("tokens");
    let (daemon, mut client) = start(config(&dir));
    for (id, (body, token)) in [
        (
            r#""cmd":"start_trial","name":"wall-sweep""#,
            r#""token":"wrong","#,
        ),
        (r#""cmd":"stop_trial""#, ""),
        (
            r#""cmd":"move_stage","relative_m":0.01"#,
            r#""token":"wrong","#,
        ),
        (r#""cmd":"set_base_angle","angle_deg":5"#, ""),
    ]
    .iter()
    .enumerate()
    {
        client.send_line(&format!(r#"{{"id":{id},{token}{body}}}"#));
        let reply = client.next_reply();
        assert_eq!(reply.error, Some(ErrorCode::BadToken), "{body}: {reply:?}");
    }
    assert_eq!(daemon.trial(), None, "no trial started without the token");
    // Stopping needs no token, and is logged with the peer's address.
    client.send_line(r#"{"id":7,"cmd":"stop_all"}"#);
    let reply = client.next_reply();
    assert!(reply.ok, "{reply:?}");
    let peer = client.writer.local_addr().unwrap().to_string();
    let log = daemon.log_lines();
    assert!(
        log.iter()
            .any(|l| l.contains(&format!("stop_all from {peer}"))),
        "{log:#?}"
    );
    let failures = log
        .iter()
        .filter(|l| l.contains(&format!("authentication failed from {peer}")))
        .count();
    assert_eq!(failures, 4, "{log:#?}");
    assert!(log.iter().all(|l| !l.contains(TOKEN)));
    // Malformed: not JSON, a misspelt field, both targets, a bad number, an unknown command.
    client.send_line("move the stage please");
    assert_eq!(client.next_reply().error, Some(ErrorCode::BadJson));
    for (body, code) in [
        (
            r#""cmd":"move_stage","positon_m":0.3"#,
            ErrorCode::BadRequest,
        ),
        (
            r#""cmd":"move_stage","position_m":0.1,"relative_m":0.1"#,
            ErrorCode::BadRequest,
        ),
        (
            r#""cmd":"set_base_angle","angle_deg":"ten""#,
            ErrorCode::BadRequest,
        ),
        (r#""cmd":"start_trial""#, ErrorCode::BadRequest),
        (r#""cmd":"self_destruct""#, ErrorCode::UnknownCommand),
    ] {
        let reply = request(&mut client, 50, body);
        assert_eq!(reply.error, Some(code), "{body}: {reply:?}");
    }
    // Nothing moved, and the daemon still streams every poll.
    let seen = watch(&mut client, {
        let mut n = 0;
        move |_, _| {
            n += 1;
            n > 200
        }
    });
    assert!(seen.stage.iter().all(|&m| m == 0.0), "{:?}", seen.stage);
    // At home the built-in scene's antenna is placed with its tip on the wall: the tip
    // segment's switches fire, the proximal segments' do not.
    assert_ne!(seen.touch_bits_seen[7], 0, "{:?}", seen.touch_bits_seen);
    assert_eq!(
        seen.touch_bits_seen[..4],
        [0; 4],
        "{:?}",
        seen.touch_bits_seen
    );
    let summary = daemon.shutdown().unwrap();
    assert!(summary.trials.is_empty());
    assert_eq!(summary.dropped, 0);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn moves_and_angles_work_between_trials_and_never_pass_the_soft_limits() {
    let dir = temp_dir("moves");
    let (daemon, mut client) = start(config(&dir));
    // Beyond the soft limits (0..=100 mm): refused, nothing moves.
    for body in [
        r#""cmd":"move_stage","position_m":0.15,"speed_m_per_s":0.05"#,
        r#""cmd":"move_stage","relative_m":-0.001"#,
        r#""cmd":"move_stage","relative_m":0.5"#,
    ] {
        let reply = request(&mut client, 1, body);
        assert_eq!(reply.error, Some(ErrorCode::Rejected), "{reply:?}");
        assert!(reply.message.contains("soft limits"), "{reply:?}");
    }
    let reply = request(
        &mut client,
        2,
        r#""cmd":"move_stage","relative_m":0.01,"speed_m_per_s":0.5"#,
    );
    assert!(reply.message.contains("faster than"), "{reply:?}");
    // Within them: moves and arrives.
    let reply = request(
        &mut client,
        3,
        r#""cmd":"move_stage","position_m":0.09,"speed_m_per_s":0.05"#,
    );
    assert!(reply.ok, "{reply:?}");
    let seen = watch(&mut client, |s, _| s == Some(0.09));
    assert!(seen.stage.windows(2).all(|w| w[1] >= w[0]));
    // On the way the antenna slid along the wall (it comes closer as the stage moves
    // forward): the distal segments' switches fired, each poll's `contact` being any of its
    // four bits (checked in `watch`).
    assert!(
        seen.touch_bits_seen[5..].iter().any(|&b| b != 0),
        "{:?}",
        seen.touch_bits_seen
    );
    // From 90 mm, +20 mm would end at 110 mm: refused; the stage stays at 90 mm.
    let reply = request(&mut client, 4, r#""cmd":"move_stage","relative_m":0.02"#);
    assert!(
        !reply.ok && reply.message.contains("soft limits"),
        "{reply:?}"
    );
    let reply = request(&mut client, 5, r#""cmd":"set_base_angle","angle_deg":12.5"#);
    assert!(reply.ok, "{reply:?}");
    let stage = watch(&mut client, |_, b| {
        b.is_some_and(|b| (b - 12.5).abs() < 1e-9)
    })
    .stage;
    assert!(stage.iter().all(|&m| m <= 0.1), "{stage:?}");
    assert!(stage.iter().rev().take(10).all(|&m| m == 0.09), "{stage:?}");
    // The servo's calibration covers -45..=45 deg: beyond it is refused, nothing moves.
    for angle_deg in [90.0, -45.5, 170.0] {
        let body = format!(r#""cmd":"set_base_angle","angle_deg":{angle_deg}"#);
        let reply = request(&mut client, 6, &body);
        assert_eq!(reply.error, Some(ErrorCode::Rejected), "{reply:?}");
        assert!(
            reply.message.contains("calibrated range -45..=45"),
            "{reply:?}"
        );
    }
    let reply = request(&mut client, 6, r#""cmd":"set_base_angle","angle_deg":-45"#);
    assert!(reply.ok, "{reply:?}");
    watch(&mut client, |_, b| {
        b.is_some_and(|b| (b + 45.0).abs() < 1e-9)
    });
    // stop_all with no trial: the stage stops, nothing else to end.
    let reply = request(&mut client, 7, r#""cmd":"move_stage","position_m":0.0"#);
    assert!(reply.ok, "{reply:?}");
    watch(&mut client, |s, _| s.is_some_and(|s| s < 0.08));
    let reply = request(&mut client, 8, r#""cmd":"stop_all""#);
    assert!(
        reply.ok && reply.message.contains("stage stopped"),
        "{reply:?}"
    );
    let mut last = None;
    let stage = watch(&mut client, {
        let mut n = 0;
        move |_, _| {
            n += 1;
            n > 300
        }
    })
    .stage;
    // Stopped where it was: the kill came before the reply, so after it the stream's stage
    // position changes at most once (from the last sample taken before the kill to the
    // first after it, however late the motion thread is on a loaded machine), then holds.
    let mut changes = 0;
    for &s in &stage {
        changes += usize::from(last.is_some_and(|l| l != s));
        last = Some(s);
    }
    assert!(changes <= 1, "{stage:?}");
    assert!(last.unwrap() > 0.0);
    daemon.shutdown().unwrap();
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_trial_is_a_recorded_window_that_owns_the_stage_until_it_stops() {
    let dir = temp_dir("trials");
    let (daemon, mut client) = start(config(&dir));
    let reply = request(
        &mut client,
        1,
        r#""cmd":"start_trial","name":"no-such-trial""#,
    );
    assert!(
        !reply.ok && reply.message.contains("trials: wall-sweep"),
        "{reply:?}"
    );
    let reply = request(
        &mut client,
        2,
        r#""cmd":"start_trial","name":"wall-sweep","metadata":{"operator":"test"}"#,
    );
    assert!(reply.ok, "{reply:?}");
    assert_eq!(daemon.trial().as_deref(), Some("wall-sweep"));
    let reply = request(&mut client, 3, r#""cmd":"start_trial","name":"wall-sweep""#);
    assert!(
        !reply.ok && reply.message.contains("already running"),
        "{reply:?}"
    );
    for body in [
        r#""cmd":"move_stage","relative_m":0.01"#,
        r#""cmd":"set_base_angle","angle_deg":3"#,
    ] {
        let reply = request(&mut client, 4, body);
        assert_eq!(reply.error, Some(ErrorCode::Rejected), "{reply:?}");
        assert!(reply.message.contains("stop_trial"), "{reply:?}");
    }
    // The script moves the stage; stop the trial half way.
    watch(&mut client, |s, _| s.is_some_and(|s| s > 0.01));
    let reply = request(&mut client, 5, r#""cmd":"stop_trial""#);
    assert!(reply.ok && reply.message.contains("recorded"), "{reply:?}");
    assert_eq!(daemon.trial(), None);
    let reply = request(&mut client, 6, r#""cmd":"stop_trial""#);
    assert!(
        !reply.ok && reply.message.contains("no trial is running"),
        "{reply:?}"
    );
    // The file is finalized and complete; between trials the stage is ours again.
    let first = TrialReader::read(dir.join("wall-sweep.mcap")).unwrap();
    assert!(first.truncated.is_none());
    assert_eq!(first.metadata.as_ref().unwrap().notes["operator"], "test");
    assert!(first.segments.len() > 50);
    let reply = request(&mut client, 7, r#""cmd":"move_stage","relative_m":0.001"#);
    assert!(reply.ok, "{reply:?}");
    // A second trial, ended by stop_all: a second file.
    let reply = request(&mut client, 8, r#""cmd":"start_trial","name":"wall-sweep""#);
    assert!(
        reply.ok && reply.message.contains("wall-sweep-2.mcap"),
        "{reply:?}"
    );
    let reply = request(&mut client, 9, r#""cmd":"stop_all""#);
    assert!(
        reply.ok && reply.message.contains("ended (stop_all)"),
        "{reply:?}"
    );
    let summary = daemon.shutdown().unwrap();
    let names: Vec<(&str, &str)> = summary
        .trials
        .iter()
        .map(|t| (t.name.as_str(), t.ended.as_str()))
        .collect();
    assert_eq!(
        names,
        [("wall-sweep", "stop_trial"), ("wall-sweep", "stop_all")]
    );
    let second = TrialReader::read(dir.join("wall-sweep-2.mcap")).unwrap();
    assert!(second.truncated.is_none());
    // Every poll of each window, numbered on the daemon's clock with no gap but skipped
    // deadlines.
    for trial in [&first, &second] {
        let seqs: Vec<u64> = trial.segments.iter().map(|m| m.seq.unwrap()).collect();
        let gaps: u64 = seqs.windows(2).map(|w| w[1] - w[0] - 1).sum();
        assert!(
            gaps <= summary.skipped,
            "{gaps} gaps, {} skipped",
            summary.skipped
        );
    }
    assert_eq!(summary.dropped, 0);
    std::fs::remove_dir_all(&dir).ok();
}
