//! Configuration errors name the key, line and column; the example files parse.
#![allow(clippy::unwrap_used)]

use host_daemon::service::config::Config;
use std::path::Path;

fn error(text: &str) -> host_daemon::service::config::ConfigError {
    Config::from_toml_str(text, "test.toml").unwrap_err()
}

#[test]
fn an_unknown_key_is_named_with_its_line_and_column() {
    let e = error("[stage]\nsteps_per_mm = 80.0\n  max_mn = 3.0\n");
    assert_eq!(e.key, "stage.max_mn");
    assert_eq!((e.line, e.column), (Some(3), Some(3)));
    assert!(e.message.contains("unknown field"), "{e}");
    assert!(
        e.to_string().starts_with("test.toml:3:3: `stage.max_mn`"),
        "{e}"
    );
}

#[test]
fn a_value_of_the_wrong_type_names_its_key() {
    let e = error("data_dir = \"d\"\n\n[bus]\npoll_hz = \"fast\"\n");
    assert_eq!(e.key, "bus.poll_hz");
    assert_eq!(e.line, Some(4));
}

#[test]
fn a_segment_without_its_calibration_names_the_missing_key() {
    let e = error("[[bus.segments]]\naddress = 0x20\ndirection = \"cw\"\n");
    assert_eq!(e.key, "bus.segments.zero_counts");
    assert!(e.message.contains("missing field"), "{e}");
    assert!(e.line.is_some());
}

#[test]
fn out_of_range_values_name_their_key_and_line() {
    let e = error("[stage]\nmin_mm = 10.0\nmax_mm = 5.0\n");
    assert_eq!((e.key.as_str(), e.line), ("stage.max_mm", Some(3)));
    let e = error("[sim.wall]\ndistance_m = 0.3\nangle_deg = 95.0\n");
    assert_eq!((e.key.as_str(), e.line), ("sim.wall.angle_deg", Some(3)));
    let e = error(
        "[[trials]]\nname = \"a\"\n[[trials.moves]]\ndistance_mm = 10.0\n\
         speed_mm_per_s = 500.0\n",
    );
    assert_eq!(e.key, "trials[0].moves[0].speed_mm_per_s");
    assert_eq!(e.line, Some(5));
    let e = error("[sim.antenna]\nstiffness_profile = \"rubber\"\n");
    assert_eq!(
        (e.key.as_str(), e.line),
        ("sim.antenna.stiffness_profile", Some(2))
    );
    assert!(e.message.contains("cockroach"), "{e}");
}

#[test]
fn the_example_files_parse_and_sim_toml_is_the_default() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("config");
    let sim = Config::from_file(&dir.join("sim.toml")).unwrap();
    assert_eq!(sim, Config::default());
    // robot.toml takes its token from $ANTENNAD_TOKEN: given here in the file instead.
    let text = std::fs::read_to_string(dir.join("robot.toml")).unwrap();
    assert!(text.contains("\ntoken_env = \"ANTENNAD_TOKEN\"\n"));
    let text = text.replace(
        "token_env = \"ANTENNAD_TOKEN\"",
        "token = \"robot-token-0123456789\"",
    );
    let robot = Config::from_toml_str(&text, "robot.toml").unwrap();
    assert_eq!(robot.bus.device, "/dev/i2c-1");
    // Serial ports by their stable /dev/serial/by-id/ names.
    assert!(robot.stage.port.starts_with("/dev/serial/by-id/usb-FTDI_"));
    assert!(
        robot
            .servo
            .port
            .starts_with("/dev/serial/by-id/usb-Pololu_")
    );
    assert!(robot.server.token.is_some());
    assert_eq!(robot.server.token_env, None);
}

#[test]
fn no_trial_starts_by_itself_with_any_hardware_configured() {
    use host_daemon::service::daemon::first_trial_for;
    let sim = Config::default();
    assert!(!sim.has_hardware());
    // The simulated rig keeps its demo trial.
    assert_eq!(first_trial_for(&sim, None, false), Some(None));
    assert_eq!(first_trial_for(&sim, None, true), None);
    for hardware in ["bus", "stage", "servo"] {
        let mut config = Config::default();
        match hardware {
            "bus" => config.bus.device = "/dev/i2c-1".to_owned(),
            "stage" => config.stage.port = "/dev/ttyUSB0".to_owned(),
            _ => config.servo.port = "/dev/ttyACM0".to_owned(),
        }
        assert!(config.has_hardware(), "{hardware}");
        assert_eq!(first_trial_for(&config, None, false), None, "{hardware}");
        // Named explicitly, it starts (its moves after homing).
        assert_eq!(
            first_trial_for(&config, Some("t".to_owned()), false),
            Some(Some("t".to_owned()))
        );
    }
}

#[test]
fn a_poll_rate_the_bus_cannot_carry_is_refused_with_the_arithmetic() {
    // Nine segments (the default) at 1 kHz on a real device at the default 100 kHz.
    let e = error("[bus]\ndevice = \"/dev/i2c-1\"\npoll_hz = 1000.0\n");
    assert_eq!((e.key.as_str(), e.line), ("bus.poll_hz", Some(3)));
    for part in [
        "9 segments x 38 + 57 = 399 bit times",
        "bus.speed_hz = 100000 is 3990 us, 399 % of the 1000 us poll period",
        "lower bus.poll_hz to 200 or less, raise bus.speed_hz to 498750 or more",
    ] {
        assert!(e.message.contains(part), "{part:?} missing from: {e}");
    }
    // A given speed is the key named; 400 kHz does not carry 1 kHz either (99.75 %).
    let e = error("[bus]\ndevice = \"/dev/i2c-1\"\nspeed_hz = 400000\n");
    assert_eq!((e.key.as_str(), e.line), ("bus.speed_hz", Some(3)));
    assert!(
        e.message.contains("100 % of the 1000 us poll period"),
        "{e}"
    );
    // What it does carry is accepted.
    for text in [
        "[bus]\ndevice = \"/dev/i2c-1\"\npoll_hz = 200.0\n",
        "[bus]\ndevice = \"/dev/i2c-1\"\nspeed_hz = 400000\npoll_hz = 500.0\n",
        "[bus]\ndevice = \"/dev/i2c-1\"\nspeed_hz = 1000000\n",
    ] {
        assert!(Config::from_toml_str(text, "t.toml").is_ok(), "{text}");
    }
    // The simulated bus moves no bits: unlimited unless a speed is given, then checked too.
    let sim = Config::from_toml_str("[bus]\npoll_hz = 5000.0\n", "t.toml").unwrap();
    assert_eq!(sim.bus.checked_speed_hz(), None);
    let e = error("[bus]\nspeed_hz = 100000\n");
    assert_eq!(e.key, "bus.speed_hz");
    let e = error("[bus]\nspeed_hz = 0\n");
    assert!(e.message.contains("must be positive"), "{e}");
}

/// `[sim.sensors]` (issue #18): every bad value is named with its line and column.
#[test]
fn bad_sensor_settings_are_located() {
    let located = |body: &str, key: &str, column: usize, part: &str| {
        let e = error(&format!(
            "[sim.wall]\nmu = 0.3\n\n[sim.sensors]\nseed = 4\n{body}\n"
        ));
        assert_eq!(e.key, format!("sim.sensors.{key}"), "{e}");
        assert_eq!((e.line, e.column), (Some(6), Some(column)), "{e}");
        assert!(e.message.contains(part), "{part:?} missing from: {e}");
        assert!(
            e.to_string()
                .starts_with(&format!("test.toml:6:{column}: `sim.sensors.{key}`")),
            "{e}"
        );
    };
    located(
        "angle_noise_counts = -1.0",
        "angle_noise_counts",
        1,
        "must be finite and at least 0, got -1",
    );
    located(
        "touch_threshold_n = -0.2",
        "touch_threshold_n",
        1,
        "must be finite and at least 0, got -0.2",
    );
    located(
        "offset_counts = [1.0, 2.0]",
        "offset_counts",
        1,
        "has 2 entries; a list needs one per segment on the bus, base to tip (9)",
    );
    located(
        "offset_counts = -3",
        "offset_counts",
        1,
        "the spread each segment's value is drawn from",
    );
    located(
        "gain_error = [0, 0, 0, -1.0, 0, 0, 0, 0, 0]",
        "gain_error",
        1,
        "has -1; every entry must be above -1",
    );
    // A value of the wrong type is put at the value.
    located(
        "gain_error = \"large\"",
        "gain_error",
        14,
        "a number (the spread each segment's value is drawn from) or a list",
    );
    located("  angle_noise = 2.0", "angle_noise", 3, "unknown field");
    located(
        "touch_debounce_samples = 5",
        "touch_debounce_samples",
        1,
        "debounces its touch switches over 3 consecutive reads",
    );
    located(
        "sample_rate_hz = 120.0",
        "sample_rate_hz",
        1,
        "the sample rate is bus.poll_hz (now 1000 Hz); set that instead",
    );
    let e = error("[sim.sensors]\nseed = -1\n");
    assert_eq!(
        (e.key.as_str(), e.line, e.column),
        ("sim.sensors.seed", Some(2), Some(8))
    );
    assert!(e.message.contains("u64"), "{e}");
    // The firmware's own debounce may be repeated; the list's length follows the bus.
    let config = Config::from_toml_str(
        "[bus]\n[[bus.segments]]\naddress = 0x20\nzero_counts = 1\ndirection = \"cw\"\n\
         [[bus.segments]]\naddress = 0x21\nzero_counts = 2\ndirection = \"ccw\"\n\
         [sim.antenna]\nlinks = 2\n[sim.sensors]\ntouch_debounce_samples = 3\n\
         offset_counts = [1.5, -2]\ngain_error = 0.01\nangle_noise_counts = 0.5\nseed = 8\n",
        "t.toml",
    )
    .unwrap();
    let settings = config.sensor_settings();
    assert_eq!(settings.touch_debounce_samples, 3);
    assert_eq!(settings.sample_rate_hz, Some(config.bus.poll_hz));
    assert_eq!(
        settings.offset_counts,
        sim_core::CalibrationError::PerJoint(vec![1.5, -2.0])
    );
    assert_eq!(
        settings.gain_error,
        sim_core::CalibrationError::Spread(0.01)
    );
    // What is recorded reads back as what was in force.
    let back = Config::from_toml_str(&config.to_recorded_toml(), "recorded").unwrap();
    assert_eq!(back, config);
}
