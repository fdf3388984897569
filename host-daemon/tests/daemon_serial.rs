//! A real antennad, in-process, driving the emulated Velmex VXM and Pololu Maestro on real
//! pseudo-terminals (the daemon opens the slave side by its path, as it would
//! `/dev/ttyUSB0`), with the segments on the simulated bus: the trial's stage positions and
//! base angles are what the emulators were told; the stage's serial device vanishing and
//! returning mid-trial costs stage samples only, never a segment sample.
#![allow(clippy::unwrap_used)]

mod net_support;

use antenna_data::record::TrialReader;
use antenna_data::stream::{ControlReply, StreamMessage};
use host_daemon::service::config::{Config, MoveConfig};
use host_daemon::service::daemon::{Daemon, DaemonHandle, DaemonOptions};
use host_daemon::sim::emulator::{MaestroEmulator, VxmEmulator, VxmFault};
use net_support::{Client, TOKEN};
use serialport::{SerialPort, TTYPort};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("antennad-{name}-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A pseudo-terminal with the emulator on its master side; returns the slave's path (the
/// slave handle itself is closed, for the daemon to open by name).
fn pty() -> (TTYPort, String) {
    let (master, slave) = TTYPort::pair().unwrap();
    let path = slave.name().unwrap();
    drop(slave);
    (master, path)
}

fn config(dir: &Path, stage_port: &str, servo_port: &str) -> Config {
    let mut config = Config::default();
    config.server.listen = "127.0.0.1:0".to_owned();
    config.server.token = Some(host_daemon::net::ControlToken::new(TOKEN).unwrap());
    config.data_dir = dir.to_path_buf();
    config.bus.poll_hz = 500.0;
    config.stage.port = stage_port.to_owned();
    // The default (the robot's): a reply only takes this long when something is broken; a
    // short one fails on a loaded machine, where the emulator's thread can wait its turn.
    config.stage.reply_timeout_ms = 2000;
    config.stage.steps_per_mm = 80.0;
    config.stage.max_mm = 60.0;
    config.servo.port = servo_port.to_owned();
    config.servo.channel = 3;
    config
}

/// How long a wait for something the daemon does may take before the test fails: only a hang
/// takes this long, however loaded the machine.
const PATIENCE: Duration = Duration::from_secs(60);

fn wait_for(what: &str, timeout: Duration, mut ok: impl FnMut() -> bool) {
    let deadline = Instant::now() + timeout;
    while !ok() {
        assert!(Instant::now() < deadline, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// The daemon's answer to a command, unless it answered that the thread carrying it out (the
/// motion thread, the hub) did not answer within the daemon's own deadline for a command's
/// answer (5 s): on a loaded machine a thread can wait its turn that long, and the command is
/// carried out all the same (what the tests check then is what the devices were told and
/// what the daemon did).
fn in_time(reply: ControlReply) -> Option<ControlReply> {
    (reply.message != "the daemon did not answer in time").then_some(reply)
}

/// [`wait_for`] something `daemon` does, at most [`PATIENCE`]; a failure shows its log.
fn wait_logged(daemon: &DaemonHandle, what: &str, mut ok: impl FnMut() -> bool) {
    let deadline = Instant::now() + PATIENCE;
    while !ok() {
        assert!(
            Instant::now() < deadline,
            "timed out waiting for {what}; the daemon's log:\n{}",
            daemon.log_lines().join("\n")
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn a_trial_on_the_vxm_and_maestro_records_what_they_were_told() {
    let dir = temp_dir("serial-trial");
    let (vxm_master, vxm_path) = pty();
    let (maestro_master, maestro_path) = pty();
    let vxm = VxmEmulator::spawn(vxm_master);
    let maestro = MaestroEmulator::spawn(maestro_master);
    let mut config = config(&dir, &vxm_path, &maestro_path);
    config.trials[0].base_angle_deg = 10.0;
    config.trials[0].duration_s = 0.0;
    config.trials[0].moves = vec![
        MoveConfig {
            distance_mm: 25.0,
            speed_mm_per_s: 50.0,
            pause_s: 0.2,
        },
        // Beyond the 60 mm soft limit from 25 mm: refused, the VXM never hears of it.
        MoveConfig {
            distance_mm: 40.0,
            speed_mm_per_s: 50.0,
            pause_s: 0.0,
        },
        MoveConfig {
            distance_mm: -5.0,
            speed_mm_per_s: 25.0,
            pause_s: 0.2,
        },
    ];
    let options = DaemonOptions {
        first_trial: Some(None),
        exit_after_trial: true,
        ..DaemonOptions::default()
    };
    let daemon = Daemon::start(config, options).unwrap();
    let log_lines = {
        let summary_wait = Instant::now();
        while !daemon.is_finished() {
            assert!(
                summary_wait.elapsed() < Duration::from_secs(120),
                "trial too long"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        daemon.log_lines()
    };
    let summary = daemon.wait().unwrap();
    let log = log_lines.join("\n");
    assert!(log.contains("VXM on /dev/pts/"), "{log}");
    assert!(log.contains("move 2 refused"), "{log}");
    assert_eq!(summary.trials.len(), 1);
    assert_eq!(summary.trials[0].ended, "its moves are done");

    // What the emulators were told: online, homing against the negative limit switch (at
    // the default 10 mm/s, 800 steps/s) before any move, two moves at 80 steps/mm; never the
    // refused one; the servo target for 10 degrees on channel 3.
    let sent = String::from_utf8_lossy(&vxm.received()).into_owned();
    assert!(sent.starts_with("FFC,S1M800,I1M-0,IA1M-0,R"), "{sent}");
    assert_eq!(vxm.negative_limit_steps(), 0, "zero is the switch");
    assert!(sent.contains("C,S1M4000,I1M2000,R"), "{sent}");
    assert!(sent.contains("C,S1M2000,I1M-400,R"), "{sent}");
    assert!(!sent.contains("I1M3200"), "{sent}");
    assert_eq!(vxm.position_steps(), 1600);
    let calibration = host_daemon::PulseCalibration::new(
        (-45f64).to_radians(),
        1000.0,
        45f64.to_radians(),
        2000.0,
    )
    .unwrap();
    let target = (calibration.pulse_us(10f64.to_radians()) * 4.0).round() as u16;
    assert_eq!(maestro.position_quarter_us(3), Some(target));

    // What was recorded: the stage's path out to 25 mm and back to 20 mm, the base at 10 deg.
    let trial = TrialReader::read(summary.trials[0].path.as_ref().unwrap()).unwrap();
    assert!(trial.truncated.is_none());
    let stage: Vec<f64> = trial.stage.iter().map(|s| s.position_m).collect();
    let max = stage.iter().copied().fold(f64::MIN, f64::max);
    assert!((max - 0.025).abs() < 1e-9, "{stage:?}");
    assert!((stage.last().unwrap() - 0.020).abs() < 1e-9, "{stage:?}");
    // Out, then back: however few samples a busy machine took on the way.
    let out = stage.iter().position(|&m| m == max).unwrap();
    assert!(stage[..=out].windows(2).all(|w| w[0] <= w[1]), "{stage:?}");
    assert!(stage[out..].windows(2).all(|w| w[0] >= w[1]), "{stage:?}");
    let last_base = trial.servo.last().unwrap().base_angle_rad;
    assert!(
        (last_base - calibration.angle_rad(f64::from(target) / 4.0)).abs() < 1e-12,
        "{last_base}"
    );
    // Within the Maestro's quarter-microsecond resolution (0.0225 degrees here).
    assert!((last_base.to_degrees() - 10.0).abs() < 0.025);
    assert!(
        trial
            .segments
            .iter()
            .all(|m| m.segments.iter().all(|s| s.ok))
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_stage_vanishing_and_returning_mid_trial_loses_no_segment_sample() {
    let dir = temp_dir("serial-vanish");
    let link = dir.join("vxm");
    let (vxm_master, vxm_path) = pty();
    let (maestro_master, maestro_path) = pty();
    std::os::unix::fs::symlink(&vxm_path, &link).unwrap();
    let vxm = VxmEmulator::spawn(vxm_master);
    let _maestro = MaestroEmulator::spawn(maestro_master);
    let mut config = config(&dir, link.to_str().unwrap(), &maestro_path);
    // Longer than any run of this test: the test ends the trial (`stop_trial`) once the
    // stage is back, however long the outage took on this machine.
    config.trials[0].duration_s = 3600.0;
    config.trials[0].moves = vec![MoveConfig {
        distance_mm: 10.0,
        speed_mm_per_s: 20.0,
        pause_s: 0.0,
    }];
    let options = DaemonOptions {
        first_trial: Some(None),
        ..DaemonOptions::default()
    };
    let daemon = Daemon::start(config, options).unwrap();
    let mut client = Client::connect(daemon.local_addr().unwrap());
    let log_has = |text: &str| -> bool { daemon.log_lines().iter().any(|l| l.contains(text)) };
    wait_logged(&daemon, "the move to end", || vxm.position_steps() == 800);
    // The script saw the move end before the stage vanishes (else the trial would end with
    // the move pending once the stage stayed away for `STAGE_LOST_AFTER`, as a slow machine
    // showed): while a move runs the script asks `V` at every step, after each stage sample
    // (`X`); two samples with no `V` after the last one mean it found the stage stopped and
    // took its next step, which finds no move left.
    wait_logged(&daemon, "the script to see the move end", || {
        let sent = vxm.received();
        let program = b"I1M800,R";
        let Some(moved) = sent.windows(program.len()).position(|w| w == program) else {
            return false;
        };
        let after = &sent[moved..];
        after
            .iter()
            .rposition(|&b| b == b'V')
            .is_some_and(|v| after[v..].iter().filter(|&&b| b == b'X').count() >= 2)
    });

    // The device vanishes: the emulator's end closes and the path disappears.
    vxm.close();
    std::fs::remove_file(&link).unwrap();
    wait_logged(&daemon, "the stage to be reported unavailable", || {
        log_has("stage unavailable")
    });
    // The stream says so: samples with a null stage, a status naming it.
    let (mut null_stage, mut status_note) = (false, false);
    let deadline = Instant::now() + PATIENCE;
    while !(null_stage && status_note) {
        assert!(
            Instant::now() < deadline,
            "null {null_stage}, status {status_note}; the daemon's log:\n{}",
            daemon.log_lines().join("\n")
        );
        match client.next_message() {
            StreamMessage::Samples {
                stage_position_m: None,
                segments,
                ..
            } => {
                null_stage = true;
                assert!(segments.iter().all(|s| s.error.is_none()));
            }
            StreamMessage::Status {
                note: Some(note), ..
            } if note.contains("stage unavailable") => status_note = true,
            _ => {}
        }
    }
    std::thread::sleep(Duration::from_millis(500));

    // It returns on a new pseudo-terminal behind the same path, where it was.
    let (vxm_master, vxm_path) = pty();
    let vxm = VxmEmulator::spawn_at(vxm_master, 800);
    std::os::unix::fs::symlink(&vxm_path, &link).unwrap();
    wait_logged(&daemon, "the stage to come back", || log_has("stage back"));
    // The daemon put the VXM on line again (the emulator reads its bytes on its own thread).
    wait_logged(&daemon, "the VXM on line again", || vxm.is_online());
    let mut back = false;
    let deadline = Instant::now() + PATIENCE;
    while !back {
        assert!(
            Instant::now() < deadline,
            "no stage sample after the return; the daemon's log:\n{}",
            daemon.log_lines().join("\n")
        );
        if let StreamMessage::Samples {
            stage_position_m: Some(m),
            ..
        } = client.next_message()
        {
            assert!((m - 0.01).abs() < 1e-9, "{m}");
            back = true;
        }
    }
    client.send_line(&format!(
        r#"{{"id":1,"token":"{TOKEN}","cmd":"stop_trial"}}"#
    ));
    if let Some(reply) = in_time(client.next_reply()) {
        assert!(reply.ok, "{reply:?}\n{}", daemon.log_lines().join("\n"));
    }
    drop(client);
    wait_logged(&daemon, "the trial to end", || daemon.trial().is_none());
    let summary = daemon.shutdown().unwrap();
    assert_eq!(summary.dropped, 0);
    let trial = TrialReader::read(summary.trials[0].path.as_ref().unwrap()).unwrap();
    assert!(trial.truncated.is_none());
    // Every segment poll of the trial is there, intact: consecutive numbers but for the
    // deadlines the poller reports skipped, every segment read.
    let seqs: Vec<u64> = trial.segments.iter().map(|m| m.seq.unwrap()).collect();
    let gaps: u64 = seqs.windows(2).map(|w| w[1] - w[0] - 1).sum();
    assert!(seqs.windows(2).all(|w| w[1] > w[0]));
    assert!(
        gaps <= summary.skipped,
        "{gaps} gaps, {} skipped",
        summary.skipped
    );
    assert!(
        trial
            .segments
            .iter()
            .all(|m| m.segments.len() == 8 && m.segments.iter().all(|s| s.ok))
    );
    // The recording says why: when the stage vanished and when it came back. No stage
    // sample lies between the two (the outage is one hole in the stage samples, whatever
    // its length on this machine), and they resume at the same position.
    let said = |what: &str| {
        trial
            .log
            .iter()
            .find(|l| l.text.contains(what))
            .unwrap_or_else(|| panic!("no {what:?} in {:?}", trial.log))
            .t_s
    };
    let (gone, back) = (said("stage unavailable"), said("stage back"));
    assert!(gone < back, "{gone} {back}");
    // The segments were polled all along: before, during and after the outage.
    let polled = |from: f64, to: f64| trial.segments.iter().any(|m| m.t_s > from && m.t_s < to);
    assert!(polled(f64::MIN, gone) && polled(gone, back) && polled(back, f64::MAX));
    let times: Vec<f64> = trial.stage.iter().map(|s| s.t_s).collect();
    assert!(
        times.iter().all(|&t| t <= gone || t >= back),
        "a stage sample between {gone} s and {back} s"
    );
    assert!(times.iter().any(|&t| t <= gone) && times.iter().any(|&t| t >= back));
    assert!((trial.stage.last().unwrap().position_m - 0.01).abs() < 1e-9);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn stop_all_kills_a_vxm_move_at_once_and_a_move_beyond_the_limits_never_reaches_it() {
    let dir = temp_dir("serial-stop");
    let (vxm_master, vxm_path) = pty();
    let (maestro_master, maestro_path) = pty();
    let vxm = VxmEmulator::spawn(vxm_master);
    let _maestro = MaestroEmulator::spawn(maestro_master);
    let daemon = Daemon::start(
        config(&dir, &vxm_path, &maestro_path),
        DaemonOptions::default(),
    )
    .unwrap();
    let mut client = Client::connect(daemon.local_addr().unwrap());
    let mut request = |id: u64, body: &str| {
        client.send_line(&format!(r#"{{"id":{id},"token":"{TOKEN}",{body}}}"#));
        client.next_reply()
    };
    wait_for("the VXM homed", PATIENCE, || {
        daemon.log_lines().iter().any(|l| l.contains("stage homed"))
    });
    vxm.clear_received();
    // 61 mm is beyond the 60 mm soft limit: refused before anything is sent.
    let reply = request(1, r#""cmd":"move_stage","position_m":0.061"#);
    assert!(
        !reply.ok && reply.message.contains("soft limits"),
        "{reply:?}"
    );
    std::thread::sleep(Duration::from_millis(100));
    assert!(!String::from_utf8_lossy(&vxm.received()).contains('I'));
    // A slow move (5 mm/s), killed early.
    let reply = request(
        2,
        r#""cmd":"move_stage","position_m":0.05,"speed_m_per_s":0.005"#,
    );
    if let Some(reply) = in_time(reply) {
        assert!(reply.ok, "{reply:?}");
    }
    wait_for("the move to start", PATIENCE, || vxm.is_busy());
    std::thread::sleep(Duration::from_millis(300));
    let reply = request(3, r#""cmd":"stop_all""#);
    if let Some(reply) = in_time(reply) {
        assert!(
            reply.ok && reply.message.contains("stage stopped"),
            "{reply:?}"
        );
    }
    wait_for("the kill", PATIENCE, || !vxm.is_busy());
    let sent = String::from_utf8_lossy(&vxm.received()).into_owned();
    assert!(sent.contains("C,S1M400,IA1M4000,R"), "{sent}");
    assert!(sent.contains('K'), "{sent}");
    // Killed on the way: short of the move's 4000 steps, however late the kill came.
    let stopped_at = vxm.position_steps();
    assert!(stopped_at > 0 && stopped_at < 4000, "{stopped_at}");
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(vxm.position_steps(), stopped_at);
    daemon.shutdown().unwrap();
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_missing_serial_port_names_the_key_and_the_path() {
    let dir = temp_dir("serial-missing");
    let error = Daemon::start(
        config(&dir, "/dev/antennad-no-such-tty", "sim"),
        DaemonOptions::default(),
    )
    .unwrap_err();
    let text = format!("{error:#}");
    assert!(
        text.contains("`stage.port` = \"/dev/antennad-no-such-tty\": cannot open the serial port"),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

fn log_has(daemon: &DaemonHandle, text: &str) -> bool {
    daemon.log_lines().iter().any(|l| l.contains(text))
}

#[test]
fn the_stage_is_homed_before_its_first_move_and_again_after_a_power_cycle() {
    let dir = temp_dir("serial-homing");
    let (vxm_master, vxm_path) = pty();
    let vxm = VxmEmulator::spawn(vxm_master);
    // Restarted 10 mm from the near end: the register reads zero there all the same.
    vxm.set_limit_below(800);
    let mut config = config(&dir, &vxm_path, "sim");
    config.stage.homing_speed_mm_per_s = 40.0;
    // The trial asked for by name: it waits for the homing, then moves 20 mm from the switch.
    config.trials[0].duration_s = 0.0;
    config.trials[0].moves = vec![MoveConfig {
        distance_mm: 20.0,
        speed_mm_per_s: 50.0,
        pause_s: 0.0,
    }];
    let name = config.trials[0].name.clone();
    let options = DaemonOptions {
        first_trial: Some(Some(name)),
        ..DaemonOptions::default()
    };
    let daemon = Daemon::start(config, options).unwrap();
    wait_for("the trial to end", PATIENCE, || {
        daemon.trial().is_none() && log_has(&daemon, "ended")
    });
    let sent = String::from_utf8_lossy(&vxm.received()).into_owned();
    let homing = sent.find("I1M-0,IA1M-0,R").expect("a homing program");
    let first_move = sent.find("I1M1600").expect("the trial's move");
    assert!(homing < first_move, "{sent}");
    // 20 mm from the switch, not from where it was restarted.
    assert_eq!(vxm.negative_limit_steps(), 0);
    assert_eq!(vxm.position_steps(), 1600);

    // Power lost and back: the register reads zero 20 mm out. The daemon sees the echo,
    // forgets its home and homes again; no stage sample from the bogus zero is trusted.
    vxm.clear_received();
    vxm.power_cycle();
    wait_for("the home lost", PATIENCE, || {
        log_has(&daemon, "stage home lost")
    });
    wait_for("homing again", PATIENCE, || {
        daemon
            .log_lines()
            .iter()
            .filter(|l| l.contains("stage homed"))
            .count()
            == 2
    });
    let sent = String::from_utf8_lossy(&vxm.received()).into_owned();
    assert!(sent.contains("FC,S1M3200,I1M-0,IA1M-0,R"), "{sent}");
    assert_eq!(vxm.negative_limit_steps(), 0);
    assert_eq!(vxm.position_steps(), 0);
    let summary = daemon.shutdown().unwrap();
    assert_eq!(summary.trials[0].ended, "its moves are done");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_trial_whose_stage_loses_power_or_vanishes_ends_with_the_reason_recorded() {
    let dir = temp_dir("serial-lost");
    let link = dir.join("vxm");
    let (vxm_master, vxm_path) = pty();
    std::os::unix::fs::symlink(&vxm_path, &link).unwrap();
    let vxm = VxmEmulator::spawn(vxm_master);
    let mut config = config(&dir, link.to_str().unwrap(), "sim");
    config.stage.homing_speed_mm_per_s = 40.0;
    // Slow moves with nothing else to end the trial: without its stage it would run forever.
    config.trials[0].duration_s = 0.0;
    config.trials[0].moves = vec![MoveConfig {
        distance_mm: 50.0,
        speed_mm_per_s: 5.0,
        pause_s: 0.0,
    }];
    let name = config.trials[0].name.clone();
    let daemon = Daemon::start(config, DaemonOptions::default()).unwrap();
    let mut client = Client::connect(daemon.local_addr().unwrap());
    let mut start = |id: u64| {
        client.send_line(&format!(
            r#"{{"id":{id},"token":"{TOKEN}","cmd":"start_trial","name":"{name}"}}"#
        ));
        if let Some(reply) = in_time(client.next_reply()) {
            assert!(reply.ok, "{reply:?}");
        }
    };

    // A power cycle mid-move (the trial's, not the homing's: homed first, however long that
    // takes here).
    wait_for("the VXM homed", PATIENCE, || {
        log_has(&daemon, "stage homed")
    });
    start(1);
    wait_for("the move", PATIENCE, || vxm.is_busy());
    std::thread::sleep(Duration::from_millis(200));
    vxm.power_cycle();
    wait_for("the trial to end", PATIENCE, || daemon.trial().is_none());
    let homed = || {
        daemon
            .log_lines()
            .iter()
            .filter(|l| l.contains("stage homed"))
            .count()
    };
    let deadline = Instant::now() + PATIENCE;
    while homed() < 2 {
        assert!(
            Instant::now() < deadline,
            "never homed again:\n{}",
            daemon.log_lines().join("\n")
        );
        std::thread::sleep(Duration::from_millis(10));
    }

    // The stage vanishing mid-move, for good.
    start(2);
    wait_for("the move", PATIENCE, || vxm.is_busy());
    vxm.close();
    std::fs::remove_file(&link).unwrap();
    wait_for("the trial to end", PATIENCE, || daemon.trial().is_none());
    let summary = daemon.shutdown().unwrap();
    assert_eq!(summary.trials.len(), 2);
    assert!(
        summary.trials[0].ended.contains("lost its home")
            && summary.trials[0].ended.contains("power cycle"),
        "{}",
        summary.trials[0].ended
    );
    assert!(
        summary.trials[1].ended.contains("the stage vanished")
            && summary.trials[1].ended.contains("moves left"),
        "{}",
        summary.trials[1].ended
    );
    for outcome in &summary.trials {
        let trial = TrialReader::read(outcome.path.as_ref().unwrap()).unwrap();
        let last = trial.log.last().unwrap();
        assert_eq!(last.text, format!("trial ended: {}", outcome.ended));
    }
    // The second trial ended because the stage stayed away: the daemon noted it gone first.
    let trial = TrialReader::read(summary.trials[1].path.as_ref().unwrap()).unwrap();
    let said = |what: &str| {
        trial
            .log
            .iter()
            .position(|l| l.text.contains(what))
            .unwrap_or_else(|| panic!("no {what:?} in {:?}", trial.log))
    };
    assert!(said("stage unavailable") < said("trial script ended"));
    std::fs::remove_dir_all(&dir).ok();
}

/// A `stop_all` does not wait behind a query the VXM never answers: its `K` goes out on the
/// VXM's kill line from the client's thread and stops the motor while the motion thread still
/// waits for that query's answer. Here the query hangs for as long as the test wants: its
/// timeout is [`PATIENCE`] (only a hang takes that long), and the emulator answers it once the
/// `K` is in. The daemon's log then shows each stop with no query timed out before it,
/// however late any thread ran; a `K` that waited behind the query would come only after
/// the query's timeout, which the log would show. How soon the `K` came is a benchmark
/// figure (printed here), not asserted.
#[test]
fn stop_all_reaches_the_vxm_while_a_query_to_it_hangs() {
    let dir = temp_dir("serial-stall");
    let (vxm_master, vxm_path) = pty();
    let vxm = VxmEmulator::spawn(vxm_master);
    let mut config = config(&dir, &vxm_path, "sim");
    config.stage.reply_timeout_ms = PATIENCE.as_millis() as u64;
    let daemon = Daemon::start(config, DaemonOptions::default()).unwrap();
    wait_logged(&daemon, "the VXM homed", || log_has(&daemon, "stage homed"));
    let mut client = Client::connect(daemon.local_addr().unwrap());
    let stops = || {
        daemon
            .log_lines()
            .iter()
            .filter(|l| l.contains("stop_all: stage stopped"))
            .count()
    };
    let mut latencies = Vec::new();
    for id in 0..3 {
        // A slow move (5 mm/s toward 50 mm), to be killed while the VXM hangs on a query.
        client.send_line(&format!(
            r#"{{"id":{id},"token":"{TOKEN}","cmd":"move_stage","position_m":0.05,"speed_m_per_s":0.005}}"#
        ));
        if let Some(reply) = in_time(client.next_reply()) {
            assert!(reply.ok, "{reply:?}");
        }
        wait_logged(&daemon, "the move to start", || vxm.is_busy());
        // The VXM stops answering queries: the motion thread sits in its next one (`X`, the
        // stage sampled at 50 Hz).
        vxm.set_fault(VxmFault::Stall);
        wait_logged(&daemon, "a query to hang", || vxm.stalled_queries() > 0);
        let asked = Instant::now();
        // Every byte the daemon wrote before the hanging query (the previous stops' `K`s
        // among them) was received before it.
        let query_at = vxm.received().len();
        client.send_line(&format!(r#"{{"id":{},"cmd":"stop_all"}}"#, 100 + id));
        // Polled finely: how soon it came is the benchmark figure printed below.
        while !vxm.received()[query_at..].contains(&b'K') {
            assert!(
                asked.elapsed() < 2 * PATIENCE,
                "no K; the daemon's log:\n{}",
                daemon.log_lines().join("\n")
            );
            std::thread::sleep(Duration::from_micros(200));
        }
        latencies.push(asked.elapsed());
        assert!(!vxm.is_busy(), "the K stopped the move");
        // The VXM answers at last: the motion thread takes the stop, kills again through
        // the driver, and answers.
        vxm.answer_stalled();
        wait_logged(&daemon, "the stop in the log", || stops() == id + 1);
        // The motion thread's notes are logged in its order: had its query timed out, the
        // timeout would be in the log before the stop.
        let log = daemon.log_lines().join("\n");
        assert!(
            !log.contains("no position from the VXM"),
            "a query timed out before the K reached the VXM:\n{log}"
        );
        if let Some(reply) = in_time(client.next_reply()) {
            assert!(
                reply.ok && reply.message.contains("stage stopped"),
                "{reply:?}\n{log}"
            );
        }
    }
    latencies.sort();
    eprintln!("stop_all to K at the VXM (from the hanging query seen), sorted: {latencies:?}");
    daemon.shutdown().unwrap();
    std::fs::remove_dir_all(&dir).ok();
}
