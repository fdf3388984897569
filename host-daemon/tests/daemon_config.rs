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
    let e = error(
        "[[trials]]\nname = \"a\"\n[[trials.moves]]\ndistance_mm = 10.0\n\
         speed_mm_per_s = 500.0\n",
    );
    assert_eq!(e.key, "trials[0].moves[0].speed_mm_per_s");
    assert_eq!(e.line, Some(5));
}

#[test]
fn the_example_files_parse_and_sim_toml_is_the_default() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("config");
    let mut sim = Config::from_file(&dir.join("sim.toml")).unwrap();
    // Its scene is the built-in one, read from the file beside it.
    let default = Config::default();
    assert_eq!(sim.sim.scene, Some(dir.join("wall_following_4_2_1.toml")));
    assert_eq!(sim.sim.rig.text, default.sim.rig.text);
    assert_eq!(sim.sim.rig.scene.chain, default.sim.rig.scene.chain);
    assert_eq!(sim.sim.rig.scene.walls, default.sim.rig.scene.walls);
    sim.sim.scene = None;
    sim.sim.rig = default.sim.rig.clone();
    assert_eq!(sim, default);
    // robot.toml takes its token from $ANTENNAD_TOKEN: given here in the file instead.
    let text = std::fs::read_to_string(dir.join("robot.toml")).unwrap();
    assert!(text.contains("\ntoken_env = \"ANTENNAD_TOKEN\"\n"));
    let text = text.replace(
        "token_env = \"ANTENNAD_TOKEN\"",
        "token = \"robot-token-0123456789\"",
    );
    let robot =
        Config::from_toml_str(&text, &dir.join("robot.toml").display().to_string()).unwrap();
    // Its scene, beside it: the bench's antenna (one segment per joint) and flat wall.
    assert_eq!(robot.sim.rig.joints(), 9);
    assert_eq!(robot.sim.scene, Some(dir.join("robot_scene.toml")));
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
    // The default eight segments at 1 kHz on a real device at the default 100 kHz.
    let e = error("[bus]\ndevice = \"/dev/i2c-1\"\npoll_hz = 1000.0\n");
    assert_eq!((e.key.as_str(), e.line), ("bus.poll_hz", Some(3)));
    for part in [
        "8 segments x 38 + 57 = 361 bit times",
        "bus.speed_hz = 100000 is 3610 us, 361 % of the 1000 us poll period",
        "lower bus.poll_hz to 221 or less, raise bus.speed_hz to 451250 or more",
    ] {
        assert!(e.message.contains(part), "{part:?} missing from: {e}");
    }
    // A given speed is the key named; 400 kHz does not carry 1 kHz either (90.25 %).
    let e = error("[bus]\ndevice = \"/dev/i2c-1\"\nspeed_hz = 400000\n");
    assert_eq!((e.key.as_str(), e.line), ("bus.speed_hz", Some(3)));
    assert!(e.message.contains("90 % of the 1000 us poll period"), "{e}");
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

/// A scratch directory with `files` written into it.
fn scratch(name: &str, files: &[(&str, &str)]) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("daemon-config-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (file, text) in files {
        std::fs::write(dir.join(file), text).unwrap();
    }
    dir
}

/// The built-in scene's text with `replace` replacing `with`.
fn scene_with(replace: &str, with: &str) -> String {
    let text = host_daemon::service::config::scene::BUILT_IN_SCENE;
    assert!(text.contains(replace), "{replace}");
    text.replace(replace, with)
}

/// `[sim.antenna]`, `[sim.wall]`, `[sim.sensors]` (before issue #46) are refused where they
/// are written, saying what replaces them.
#[test]
fn the_old_sim_tables_are_refused_with_what_replaces_them() {
    for (text, key, line, part) in [
        (
            "data_dir = \"d\"\n[sim.antenna]\nlinks = 9\nlink_length_m = 0.04\n",
            "sim.antenna",
            2,
            "the scene's [antenna] and [antenna.stiffness]",
        ),
        (
            "[sim.wall]\ndistance_m = 0.3\nangle_deg = 30.0\n",
            "sim.wall",
            1,
            "the scene's [[walls]]",
        ),
        (
            "[sim]\n\n[sim.sensors]\nseed = 4\n",
            "sim.sensors",
            3,
            "the scene's [sensors]",
        ),
    ] {
        let e = error(text);
        assert_eq!((e.key.as_str(), e.line), (key, Some(line)), "{e}");
        assert!(e.message.contains(part), "{part:?} missing from: {e}");
        assert!(e.message.contains("`[sim] scene = \"FILE.toml\"`"), "{e}");
        assert!(
            e.to_string()
                .starts_with(&format!("test.toml:{line}:1: `{key}`")),
            "{e}"
        );
    }
}

/// The scene is read relative to the configuration's directory; a missing one, one with
/// `[tip_pin]`, one whose joints do not match the segments, and one whose own keys are
/// wrong are each refused at `sim.scene` (or `bus.segments`), the scene's own place named.
#[test]
fn a_scene_the_rig_cannot_run_is_refused_where_it_is_named() {
    let dir = scratch(
        "scenes",
        &[
            ("good.toml", &scene_with("", "")),
            (
                "pinned.toml",
                &format!(
                    "{}[tip_pin]\nposition_m = [0.2, 0.1]\n",
                    &scene_with("", "")[..scene_with("", "").find("[[walls]]").unwrap()]
                ),
            ),
            ("short.toml", &scene_with("links = 9\n", "links = 4\n")),
            (
                "noisy.toml",
                &format!(
                    "{}\n[sensors]\nangle_noise_counts = -1.0\n",
                    scene_with("", "")
                ),
            ),
        ],
    );
    let config = |scene: &str| {
        let path = dir.join("rig.toml");
        std::fs::write(
            &path,
            format!("data_dir = \"d\"\n\n[sim]\nscene = \"{scene}\"\n"),
        )
        .unwrap();
        Config::from_file(&path)
    };
    let good = config("good.toml").unwrap();
    assert_eq!(good.sim.scene, Some(dir.join("good.toml")));
    assert_eq!(good.sim.rig.joints(), 8);

    let e = config("missing.toml").unwrap_err();
    assert_eq!(
        (e.key.as_str(), e.line, e.column),
        ("sim.scene", Some(4), Some(1))
    );
    assert!(e.message.contains("cannot read the scene file"), "{e}");
    assert!(e.message.contains("missing.toml"), "{e}");

    let e = config("pinned.toml").unwrap_err();
    assert_eq!((e.key.as_str(), e.line), ("sim.scene", Some(4)));
    assert!(e.message.contains("pinned.toml:"), "{e}");
    assert!(e.message.contains("[tip_pin]"), "{e}");

    let e = config("short.toml").unwrap_err();
    assert_eq!(e.key, "bus.segments");
    assert!(
        e.message.contains("links = 4 (the base link and 3 flexible joints), so 3 [[bus.segments]] are needed, not 8"),
        "{e}"
    );

    let e = config("noisy.toml").unwrap_err();
    assert_eq!((e.key.as_str(), e.line), ("sim.scene", Some(4)));
    assert!(e.message.contains("noisy.toml:"), "{e}");
    assert!(e.message.contains("angle_noise_counts"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The scene's `[sensors]` are the simulated segments' sensors; what the rig cannot apply
/// (its own sample rate, another debounce) is ignored with a warning, not refused.
#[test]
fn the_scene_s_sensors_are_the_segments_and_what_the_rig_cannot_apply_is_ignored() {
    let sensors = "\n[sensors]\ntouch_debounce_samples = 5\nsample_rate_hz = 120.0\n\
                   offset_counts = [1.5, -2, 0, 0, 0, 0, 0, 0]\ngain_error = 0.01\n\
                   angle_noise_counts = 0.5\nseed = 8\n";
    let dir = scratch(
        "sensors",
        &[("scene.toml", &format!("{}{sensors}", scene_with("", "")))],
    );
    let path = dir.join("rig.toml");
    std::fs::write(&path, "[sim]\nscene = \"scene.toml\"\n").unwrap();
    let config = Config::from_file(&path).unwrap();
    let settings = config.sensor_settings();
    assert_eq!(settings.touch_debounce_samples, 3);
    assert_eq!(settings.sample_rate_hz, Some(config.bus.poll_hz));
    assert_eq!(
        settings.offset_counts,
        sim_core::CalibrationError::PerJoint(vec![1.5, -2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    );
    assert_eq!(
        settings.gain_error,
        sim_core::CalibrationError::Spread(0.01)
    );
    assert_eq!((settings.angle_noise_counts, settings.seed), (0.5, 8));
    let said = config.sim.rig.ignored(config.bus.poll_hz);
    let warnings: Vec<&String> = said.iter().filter(|(w, _)| *w).map(|(_, t)| t).collect();
    assert_eq!(warnings.len(), 2, "{said:?}");
    assert!(warnings[0].contains("sample_rate_hz (") && warnings[0].contains("1000 Hz"));
    assert!(warnings[1].contains("touch_debounce_samples = 5"));
    // What is recorded reads back as what was in force.
    let back = Config::from_toml_str(&config.to_recorded_toml(), "recorded").unwrap();
    assert_eq!(back, config);
    std::fs::remove_dir_all(&dir).unwrap();
}
