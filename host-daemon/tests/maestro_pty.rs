//! The Maestro driver against the emulated Maestro over real pseudo-terminals.

use core::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
use host_daemon::hardware::maestro::{Maestro, MaestroConfig, MaestroError};
use host_daemon::hardware::servo::{PulseCalibration, Servo};
use host_daemon::sim::emulator::{MaestroEmulator, MaestroFault};
use serialport::{SerialPort, TTYPort};
use std::time::{Duration, Instant};

const READ_TIMEOUT: Duration = Duration::from_millis(5);
/// Generous: a reply or a byte only takes this long when something is broken, however loaded
/// the machine (the emulator answers within milliseconds).
const PATIENCE: Duration = Duration::from_secs(30);

fn calibration() -> PulseCalibration {
    PulseCalibration::new(-FRAC_PI_2, 1000.0, FRAC_PI_2, 2000.0).expect("a valid calibration")
}

fn rig(channel: u8) -> (MaestroEmulator, Maestro<TTYPort>) {
    let (master, mut slave) = TTYPort::pair().expect("a pseudo-terminal pair");
    slave
        .set_timeout(READ_TIMEOUT)
        .expect("a timeout on the slave");
    let config = MaestroConfig::new(channel, calibration()).expect("a valid channel");
    let maestro = Maestro::new(slave, config).with_reply_timeout(PATIENCE);
    (MaestroEmulator::spawn(master), maestro)
}

fn assert_received(emulator: &MaestroEmulator, expected: &[u8]) {
    let deadline = Instant::now() + PATIENCE;
    while emulator.received().len() < expected.len() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(2));
    }
    assert_eq!(emulator.received(), expected);
}

#[test]
fn set_target_and_get_position_use_the_compact_bytes_and_round_trip() {
    let (emulator, mut maestro) = rig(3);
    // 0 rad is 1500 us, target 6000 quarter-us = 0x1770.
    maestro.set_angle_rad(0.0).unwrap();
    assert_received(&emulator, &[0x84, 3, 0x70, 0x2E]);
    assert_eq!(emulator.position_quarter_us(3), Some(6000));
    assert_eq!(maestro.angle_rad().unwrap(), 0.0);
    assert_received(&emulator, &[0x84, 3, 0x70, 0x2E, 0x90, 3]);

    // pi/4 is 1750 us = 7000 quarter-us; position comes back low byte first.
    maestro.set_angle_rad(FRAC_PI_4).unwrap();
    assert_eq!(maestro.position_quarter_us().unwrap(), 7000);
    assert!((maestro.angle_rad().unwrap() - FRAC_PI_4).abs() < 1e-12);
    let t = 7000u16;
    assert!(emulator.received().ends_with(&[
        0x84,
        3,
        (t & 0x7F) as u8,
        ((t >> 7) & 0x7F) as u8,
        0x90,
        3,
        0x90,
        3
    ]));
    // A raw 14-bit target spans both data bytes.
    maestro.set_target_quarter_us(0x3FFF).unwrap();
    assert_eq!(maestro.position_quarter_us().unwrap(), 0x3FFF);
    assert_eq!(emulator.protocol_errors(), 0);
}

#[test]
fn out_of_range_angles_targets_and_channels_are_refused_and_nothing_sent() {
    let (emulator, mut maestro) = rig(0);
    assert!(matches!(
        maestro.set_angle_rad(PI),
        Err(MaestroError::AngleOutOfRange { pulse_us, .. }) if pulse_us == 2500.0
    ));
    // -3pi/4 is 750 us, below the factory limit of 992 us.
    assert!(matches!(
        maestro.set_angle_rad(-3.0 * FRAC_PI_4),
        Err(MaestroError::AngleOutOfRange { .. })
    ));
    assert!(matches!(
        maestro.set_angle_rad(f64::NAN),
        Err(MaestroError::AngleOutOfRange { .. })
    ));
    assert!(matches!(
        maestro.set_target_quarter_us(0x4000),
        Err(MaestroError::TargetOutOfRange(0x4000))
    ));
    assert!(matches!(
        MaestroConfig::new(24, calibration()),
        Err(MaestroError::InvalidChannel(24))
    ));
    std::thread::sleep(Duration::from_millis(30));
    assert!(emulator.received().is_empty());

    // Wider limits admit -3pi/4 (750 us, target 3000 = 23 * 128 + 56).
    let config = MaestroConfig::new(0, calibration())
        .unwrap()
        .with_pulse_limits_us(700.0, 2100.0)
        .unwrap();
    let mut maestro = Maestro::new(maestro.destroy(), config);
    maestro.set_angle_rad(-3.0 * FRAC_PI_4).unwrap();
    assert_received(&emulator, &[0x84, 0, 56, 23]);
    assert!(
        MaestroConfig::new(0, calibration())
            .unwrap()
            .with_pulse_limits_us(2000.0, 1000.0)
            .is_err()
    );
}

#[test]
fn a_silent_maestro_times_out_and_a_vanished_one_reconnects() {
    let (emulator, maestro) = rig(1);
    // A short timeout for the silent Maestro, the generous one again after reconnecting.
    let mut maestro = maestro.with_reply_timeout(Duration::from_millis(100));
    emulator.set_fault(MaestroFault::Silent);
    assert!(matches!(
        maestro.position_quarter_us(),
        Err(MaestroError::Timeout(_))
    ));
    emulator.close();
    assert!(matches!(
        maestro.set_angle_rad(0.0),
        Err(MaestroError::Disconnected(_))
    ));

    let (master, mut slave) = TTYPort::pair().unwrap();
    slave.set_timeout(READ_TIMEOUT).unwrap();
    let emulator = MaestroEmulator::spawn(master);
    let _dead = maestro.reconnect(slave);
    let mut maestro = maestro.with_reply_timeout(PATIENCE);
    maestro.set_angle_rad(0.5).unwrap();
    assert!((maestro.angle_rad().unwrap() - 0.5).abs() < 1e-3);
    assert_eq!(emulator.protocol_errors(), 0);
}
