//! The VXM driver against the emulated VXM over real pseudo-terminals: the driver holds the
//! slave side (as it would `/dev/ttyUSB0`), the emulator the master side.

use host_daemon::hardware::stage::{HomingDirection, LimitedStage, StageError, StageGeometry};
use host_daemon::hardware::vxm::{self, Vxm, VxmError, VxmKill, VxmStatus};
use host_daemon::sim::emulator::{VxmEmulator, VxmFault};
use serialport::{SerialPort, TTYPort};
use std::time::{Duration, Instant};

const READ_TIMEOUT: Duration = Duration::from_millis(5);
/// Generous: a reply only takes this long when something is broken, however loaded the
/// machine (the emulator answers within milliseconds).
const REPLY_TIMEOUT: Duration = Duration::from_secs(30);
/// How long a move the tests expect to finish may take before they fail (ditto).
const PATIENCE: Duration = Duration::from_secs(30);

fn rig() -> (VxmEmulator, Vxm<TTYPort>) {
    let (master, mut slave) = TTYPort::pair().expect("a pseudo-terminal pair");
    slave
        .set_timeout(READ_TIMEOUT)
        .expect("a timeout on the slave");
    let emulator = VxmEmulator::spawn(master);
    (emulator, Vxm::new(slave).with_reply_timeout(REPLY_TIMEOUT))
}

/// Waits (at most [`PATIENCE`]) until the emulator has received `expected`, then checks it.
fn assert_received(emulator: &VxmEmulator, expected: &str) {
    let deadline = Instant::now() + PATIENCE;
    while emulator.received().len() < expected.len() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(2));
    }
    assert_eq!(String::from_utf8_lossy(&emulator.received()), expected);
}

#[test]
fn every_command_sends_its_exact_bytes_and_moves_arrive() {
    let (emulator, mut vxm) = rig();
    vxm.online().unwrap();
    vxm.clear().unwrap();
    vxm.zero().unwrap();
    vxm.set_speed_steps_per_s(4000).unwrap();
    assert_received(&emulator, "FCN");
    assert!(emulator.is_online());

    vxm.start_relative_steps(400).unwrap();
    vxm.wait_done(PATIENCE).unwrap();
    assert_eq!(vxm.position_steps().unwrap(), 400);
    assert_eq!(vxm.status().unwrap(), VxmStatus::Ready);
    assert_eq!(emulator.speed_steps_per_s(), 4000);

    vxm.start_absolute_steps(-400).unwrap();
    assert_eq!(vxm.status().unwrap(), VxmStatus::Busy);
    vxm.wait_done(PATIENCE).unwrap();
    assert_eq!(vxm.position_steps().unwrap(), -400);
    vxm.kill().unwrap();
    vxm.decelerate().unwrap();
    // A relative move of zero sends nothing (I1M0 would run to the limit switch).
    vxm.start_relative_steps(0).unwrap();
    vxm.wait_done(Duration::from_millis(10)).unwrap();
    assert_received(&emulator, "FCNC,S1M4000,I1M400,RXVC,S1M4000,IA1M-400,RVXKD");
    assert_eq!(emulator.unknown_bytes(), 0);
}

#[test]
fn out_of_range_speed_and_distance_are_refused_before_sending() {
    let (emulator, mut vxm) = rig();
    assert!(matches!(
        vxm.set_speed_steps_per_s(0),
        Err(VxmError::SpeedOutOfRange(0))
    ));
    assert!(matches!(
        vxm.set_speed_steps_per_s(6001),
        Err(VxmError::SpeedOutOfRange(6001))
    ));
    assert_eq!(vxm.speed_steps_per_s(), 2000);
    assert!(matches!(
        vxm.start_relative_steps(16_777_216),
        Err(VxmError::StepsOutOfRange(16_777_216))
    ));
    std::thread::sleep(Duration::from_millis(30));
    assert!(emulator.received().is_empty());
}

#[test]
fn moves_take_their_time_at_the_set_speed() {
    let (_emulator, mut vxm) = rig();
    vxm.online().unwrap();
    // 3 s at 1000 steps/s: long enough that a test thread held up on a loaded machine still
    // finds it moving after 50 ms.
    vxm.set_speed_steps_per_s(1000).unwrap();
    let start = Instant::now();
    vxm.start_relative_steps(3000).unwrap();
    assert!(matches!(
        vxm.wait_done(Duration::from_millis(50)),
        Err(VxmError::Timeout { expected: "^", .. })
    ));
    let mid = vxm.position_steps().unwrap();
    assert!((1..3000).contains(&mid), "mid-move position {mid}");
    vxm.wait_done(PATIENCE).unwrap();
    // A lower bound: the move cannot end sooner, however fast the machine.
    assert!(start.elapsed() >= Duration::from_millis(2990));
    assert_eq!(vxm.position_steps().unwrap(), 3000);
}

#[test]
fn kill_mid_move_stops_short_and_no_caret_follows() {
    let (emulator, mut vxm) = rig();
    vxm.online().unwrap();
    vxm.set_speed_steps_per_s(1000).unwrap();
    vxm.start_relative_steps(5000).unwrap();
    std::thread::sleep(Duration::from_millis(100));
    vxm.kill().unwrap();
    // Stopped short of the 5 s move's end, however late the kill came.
    let stopped = vxm.position_steps().unwrap();
    assert!((20..5000).contains(&stopped), "stopped at {stopped}");
    assert_eq!(vxm.status().unwrap(), VxmStatus::Ready);
    assert!(matches!(
        vxm.wait_done(Duration::from_millis(50)),
        Err(VxmError::Timeout { .. })
    ));
    assert_eq!(vxm.position_steps().unwrap(), stopped);
    assert_eq!(i64::from(stopped), emulator.position_steps());
}

#[test]
fn a_vxm_that_never_sends_the_caret_times_out() {
    let (emulator, mut vxm) = rig();
    emulator.set_fault(VxmFault::NeverFinish);
    vxm.online().unwrap();
    vxm.set_speed_steps_per_s(4000).unwrap();
    vxm.start_relative_steps(100).unwrap();
    let start = Instant::now();
    let error = vxm.wait_done(Duration::from_millis(150)).unwrap_err();
    assert!(matches!(error, VxmError::Timeout { expected: "^", .. }));
    // It waited its own timeout, not the (much longer) reply timeout.
    assert!(start.elapsed() >= Duration::from_millis(150));
    assert!(start.elapsed() < REPLY_TIMEOUT);
    // The move itself happened; only the caret is missing.
    assert_eq!(vxm.position_steps().unwrap(), 100);
}

#[test]
fn garbage_answers_are_typed_errors_and_the_driver_recovers() {
    let (emulator, mut vxm) = rig();
    vxm.online().unwrap();
    emulator.set_fault(VxmFault::Garbage);
    assert!(matches!(
        vxm.status(),
        Err(VxmError::Garbage { command: "V", ref answer }) if answer == "?"
    ));
    assert!(matches!(
        vxm.position_steps(),
        Err(VxmError::Garbage { command: "X", ref answer }) if answer == "?!#"
    ));
    emulator.set_fault(VxmFault::None);
    assert_eq!(vxm.position_steps().unwrap(), 0);
    assert_eq!(vxm.status().unwrap(), VxmStatus::Ready);
}

#[test]
fn a_vanished_device_is_a_typed_error_and_reconnecting_by_path_restores_it() {
    let (master, mut slave) = TTYPort::pair().unwrap();
    slave.set_timeout(READ_TIMEOUT).unwrap();
    let emulator = VxmEmulator::spawn(master);
    let port: Box<dyn SerialPort> = Box::new(slave);
    let mut vxm = Vxm::new(port).with_reply_timeout(REPLY_TIMEOUT);
    vxm.online().unwrap();
    vxm.set_speed_steps_per_s(6000).unwrap();
    vxm.start_relative_steps(300).unwrap();
    vxm.wait_done(PATIENCE).unwrap();

    emulator.close();
    assert!(matches!(
        vxm.position_steps(),
        Err(VxmError::Disconnected(_))
    ));
    assert!(matches!(
        vxm.start_relative_steps(10),
        Err(VxmError::Disconnected(_))
    ));

    // The controller comes back (it kept its position) on a new device node, opened by
    // path the way the daemon opens a configured port.
    let (master, pair_slave) = TTYPort::pair().unwrap();
    let path = pair_slave.name().unwrap();
    let port = vxm::open_port(&path, READ_TIMEOUT).unwrap();
    drop(pair_slave);
    let emulator = VxmEmulator::spawn_at(master, 300);
    let (_dead, power_cycled) = vxm.reconnect(port).unwrap();
    assert!(!power_cycled, "a VXM that kept its power does not echo");
    assert_eq!(vxm.position_steps().unwrap(), 300);
    vxm.start_relative_steps(-300).unwrap();
    vxm.wait_done(PATIENCE).unwrap();
    assert_eq!(vxm.position_steps().unwrap(), 0);
    assert_received(&emulator, "VFXC,S1M6000,I1M-300,RX");
}

#[test]
fn soft_limits_refuse_a_move_and_nothing_is_sent() {
    let (emulator, vxm) = rig();
    let geometry = StageGeometry::new(100.0, -5.0, 20.0).unwrap();
    let stage = LimitedStage::new(vxm, geometry);
    let mut stage = stage
        .online()
        .unwrap()
        .home(HomingDirection::Negative, PATIENCE)
        .unwrap();
    stage.set_speed_mm_per_s(40.0).unwrap();
    assert_received(&emulator, "FC,S1M2000,I1M-0,IA1M-0,RX");
    emulator.clear_received();

    let refused = stage.start_absolute_mm(20.5);
    assert!(matches!(
        refused,
        Err(StageError::BeyondSoftLimits {
            target_steps: 2050,
            min_steps: -500,
            max_steps: 2000
        })
    ));
    std::thread::sleep(Duration::from_millis(30));
    assert!(emulator.received().is_empty(), "a refused move wrote bytes");

    // A relative move is checked against the position read back: only `X` goes out.
    let refused = stage.start_relative_mm(-5.01);
    assert!(matches!(
        refused,
        Err(StageError::BeyondSoftLimits {
            target_steps: -501,
            ..
        })
    ));
    assert!(matches!(
        stage.start_relative_mm(f64::NAN),
        Err(StageError::InvalidNumber { .. })
    ));
    std::thread::sleep(Duration::from_millis(30));
    assert_eq!(emulator.received(), b"X");
    assert!(!emulator.is_busy());

    stage.move_absolute_mm(2.0, PATIENCE).unwrap();
    assert_eq!(stage.position_mm().unwrap(), 2.0);
    assert_eq!(emulator.position_steps(), 200);
}

#[test]
fn homing_runs_to_the_limit_switch_and_a_power_cycle_shows_as_an_echo() {
    let (emulator, mut vxm) = rig();
    vxm.online().unwrap();
    vxm.set_speed_steps_per_s(4000).unwrap();
    vxm.start_homing(HomingDirection::Negative).unwrap();
    assert_eq!(vxm.status().unwrap(), VxmStatus::Busy);
    vxm.wait_done(PATIENCE).unwrap();
    // Zero is the switch, 400 steps below where it started.
    assert_eq!(vxm.position_steps().unwrap(), 0);
    assert_eq!(emulator.negative_limit_steps(), 0);
    assert_received(&emulator, "FC,S1M4000,I1M-0,IA1M-0,RVX");
    vxm.start_absolute_steps(200).unwrap();
    vxm.wait_done(PATIENCE).unwrap();

    // Power lost and back: the register reads zero 200 steps from the switch, and the VXM
    // echoes. The driver says so instead of trusting the zero.
    emulator.power_cycle();
    assert!(matches!(
        vxm.position_steps(),
        Err(VxmError::PowerCycled { command: "X" })
    ));
    assert!(matches!(
        vxm.status(),
        Err(VxmError::PowerCycled { command: "V" })
    ));
    assert_eq!(emulator.negative_limit_steps(), -200);
    // Homing again finds the switch.
    vxm.online().unwrap();
    vxm.start_homing(HomingDirection::Negative).unwrap();
    vxm.wait_done(PATIENCE).unwrap();
    assert_eq!(vxm.position_steps().unwrap(), 0);
    assert_eq!(emulator.negative_limit_steps(), 0);
}

/// The kill line does not wait behind a query the VXM never answers: its `K` arrives before
/// the query times out. How soon is a benchmark figure (printed here), not asserted.
#[test]
fn the_kill_line_reaches_the_vxm_while_a_query_hangs() {
    let (master, mut slave) = TTYPort::pair().unwrap();
    slave.set_timeout(READ_TIMEOUT).unwrap();
    let emulator = VxmEmulator::spawn(master);
    let port: Box<dyn SerialPort> = Box::new(slave);
    let kill = VxmKill::new();
    assert!(!kill.kill().unwrap(), "unarmed: nothing sent");
    kill.arm(port.as_ref()).unwrap();
    let mut vxm = Vxm::new(port).with_reply_timeout(Duration::from_secs(5));
    vxm.online().unwrap();
    vxm.set_speed_steps_per_s(100).unwrap();
    vxm.start_relative_steps(1000).unwrap();
    emulator.set_fault(VxmFault::Stall);
    let query = std::thread::spawn(move || {
        let answer = vxm.position_steps();
        (vxm, answer)
    });
    // The query is out, and hangs.
    let deadline = Instant::now() + PATIENCE;
    while !emulator.received().ends_with(b"X") {
        assert!(Instant::now() < deadline, "no query");
        std::thread::sleep(Duration::from_millis(1));
    }
    let sent = Instant::now();
    assert!(kill.kill().unwrap());
    while !emulator.received().contains(&b'K') {
        // The query was still waiting when the kill went through.
        assert!(
            !query.is_finished(),
            "the query timed out before the K came"
        );
        std::thread::sleep(Duration::from_micros(200));
    }
    let latency = sent.elapsed();
    assert!(!emulator.is_busy(), "the move was killed");
    assert!(emulator.position_steps() < 1000);
    let (_vxm, answer) = query.join().unwrap();
    assert!(matches!(answer, Err(VxmError::Timeout { .. })));
    eprintln!("kill line to K at the VXM: {latency:?}");
}
