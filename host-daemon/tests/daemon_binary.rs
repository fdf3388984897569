//! The `antennad` binary end to end: a short trial on the simulated rig prints sample lines
//! and its summary on stdout, its log on stderr, and records every poll to MCAP; without `--exit-after-trial` it keeps
//! serving after the trial and stops cleanly on SIGTERM; `kill -9` during a trial leaves a
//! file that reads back up to its last flush; bad configurations and a missing I2C device are
//! clear errors naming the key.
#![allow(clippy::unwrap_used)]

mod net_support;

use antenna_data::record::TrialReader;
use antenna_data::stream::StreamMessage;
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

#[test]
fn a_short_trial_is_printed_recorded_and_streamed() {
    let dir = std::env::temp_dir().join(format!("antennad-bin-{}", std::process::id()));
    let output = Command::new(env!("CARGO_BIN_EXE_antennad"))
        .args([
            "--exit-after-trial",
            "--duration-s",
            "1.5",
            "--listen",
            "127.0.0.1:0",
            "--foxglove-listen",
            "127.0.0.1:0",
            "--data-dir",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stdout}\n{stderr}");
    // The log, on stderr: timestamped and leveled.
    assert!(stderr.contains("watch it with: nc 127.0.0.1 "), "{stderr}");
    // The simulated rig is on view in Foxglove by default (here on a free port).
    assert!(
        stderr
            .contains("see it in Foxglove: open a connection, Foxglove WebSocket, ws://127.0.0.1:"),
        "{stderr}"
    );
    assert!(
        stderr.contains("-- move 1: +500.0 mm at 25 mm/s"),
        "{stderr}"
    );
    let started = stderr
        .lines()
        .find(|l| l.contains("trial \"wall-sweep\" started"))
        .unwrap();
    assert!(started.contains(" INFO antennad: trial"), "{started}");
    assert!(
        started.starts_with("20") && started.contains('T'),
        "{started}"
    );
    // The data, on stdout: sample lines ("   0.25     5.5  ...  ......##", a touch column
    // per segment) and the summary.
    assert!(stdout.lines().any(|l| {
        l.trim_start().starts_with("0.")
            && l.split_whitespace().last().is_some_and(|touch| {
                touch.len() == 8 && touch.chars().all(|c| c == '.' || c == '#')
            })
    }));
    assert!(stdout.contains("polls in"), "{stdout}");
    assert!(!stdout.contains("watch it with"), "{stdout}");
    // "... ended (its duration passed); recorded N polls, ..." and the file agree.
    let polls: u64 = stderr
        .lines()
        .find_map(|l| {
            l.split_once("ended (its duration passed); recorded ")?
                .1
                .split_once(" polls")?
                .0
                .parse()
                .ok()
        })
        .unwrap();
    let trial = TrialReader::read(dir.join("wall-sweep.mcap")).unwrap();
    assert!(trial.truncated.is_none());
    assert_eq!(trial.segments.len() as u64, polls);
    assert!(polls > 500);
    assert!(
        trial
            .segments
            .iter()
            .all(|m| m.segments.len() == 8 && m.segments.iter().all(|s| s.ok))
    );
    assert!(trial.stage.last().unwrap().position_m > 0.02);
    assert_eq!(
        trial.metadata.unwrap().notes["wall"],
        "thesis 4.2.1: smooth wall at 8 deg, mu 0.3"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A configured token is never printed; a generated one (128 random bits, 32 hexadecimal
/// digits) is printed exactly once, at start, and recorded nowhere.
#[test]
fn a_configured_token_is_never_printed_and_a_generated_one_once() {
    let dir = std::env::temp_dir().join(format!("antennad-token-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    std::fs::create_dir_all(&dir).unwrap();
    let secret = "SECRET-TOKEN-123-configured";
    let config = dir.join("antennad.toml");
    std::fs::write(&config, format!("[server]\ntoken = \"{secret}\"\n")).unwrap();
    let run = |extra: &[&std::ffi::OsStr]| {
        let output = Command::new(env!("CARGO_BIN_EXE_antennad"))
            .args([
                "--exit-after-trial",
                "--duration-s",
                "0.3",
                "--listen",
                "127.0.0.1:0",
                "--foxglove-listen",
                "127.0.0.1:0",
            ])
            .arg("--data-dir")
            .arg(dir.join("data"))
            .args(extra)
            .output()
            .unwrap();
        assert!(output.status.success());
        [output.stdout, output.stderr].concat()
    };
    let printed = run(&["--config".as_ref(), config.as_os_str()]);
    let text = String::from_utf8_lossy(&printed);
    assert!(!text.contains(secret), "{text}");
    assert!(
        text.contains("control token: the configured server.token"),
        "{text}"
    );
    let printed = run(&[]);
    let text = String::from_utf8_lossy(&printed).into_owned();
    let shown: Vec<&str> = text
        .lines()
        .filter_map(|l| {
            l.split_once("(generated; shown only here): ")
                .map(|(_, t)| t)
        })
        .collect();
    assert_eq!(shown.len(), 1, "{text}");
    let token = shown[0].trim();
    assert_eq!(token.len(), 32);
    assert!(token.chars().all(|c| c.is_ascii_hexdigit()));
    assert_eq!(text.matches(token).count(), 1, "{text}");
    for entry in std::fs::read_dir(dir.join("data")).unwrap() {
        let bytes = std::fs::read(entry.unwrap().path()).unwrap();
        assert!(!bytes.windows(token.len()).any(|w| w == token.as_bytes()));
        assert!(!bytes.windows(secret.len()).any(|w| w == secret.as_bytes()));
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_bad_configuration_names_the_key_and_exits_with_failure() {
    let path = std::env::temp_dir().join(format!("antennad-bad-{}.toml", std::process::id()));
    std::fs::write(&path, "[bus]\npoll_hz = 0.0\n").unwrap();
    let output = Command::new(env!("CARGO_BIN_EXE_antennad"))
        .arg("--config")
        .arg(&path)
        .output()
        .unwrap();
    std::fs::remove_file(&path).ok();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert!(
        stderr.contains(":2:1: `bus.poll_hz`: must be in (0, 10000]"),
        "{stderr}"
    );
}

/// Runs antennad on a config file of `text` (named after `name`) as a one-trial run without
/// recording; asserts that it exits with failure and returns its stderr.
fn refused(name: &str, text: &str) -> String {
    let path = std::env::temp_dir().join(format!("antennad-{name}-{}.toml", std::process::id()));
    std::fs::write(&path, text).unwrap();
    let output = Command::new(env!("CARGO_BIN_EXE_antennad"))
        .arg("--config")
        .arg(&path)
        .args([
            "--exit-after-trial",
            "--listen",
            "127.0.0.1:0",
            "--foxglove-listen",
            "127.0.0.1:0",
            "--no-record",
        ])
        .output()
        .unwrap();
    std::fs::remove_file(&path).ok();
    assert!(!output.status.success());
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// The old `[sim.sensors]`, a missing scene file, a scene with `[tip_pin]`, a scene whose
/// joints do not match the segments: each a located error, and antennad does not start.
#[test]
fn a_configuration_the_simulated_rig_cannot_run_is_refused_before_the_daemon_starts() {
    let stderr = refused(
        "sensors",
        "[sim.sensors]\nseed = 1\nangle_noise_counts = -2.0\n",
    );
    assert!(
        stderr.contains(":1:1: `sim.sensors`: [sim.sensors] is gone"),
        "{stderr}"
    );
    assert!(!stderr.contains("watch it with"), "{stderr}");
    let stderr = refused("antenna", "data_dir = \"d\"\n[sim.antenna]\nlinks = 9\n");
    assert!(
        stderr.contains(":2:1: `sim.antenna`: [sim.antenna] is gone"),
        "{stderr}"
    );
    let stderr = refused("missing", "[sim]\nscene = \"no-such-scene.toml\"\n");
    assert!(
        stderr.contains(":2:1: `sim.scene`: cannot read the scene file"),
        "{stderr}"
    );
    assert!(!stderr.contains("watch it with"), "{stderr}");
    let examples = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples");
    let stderr = refused(
        "pinned",
        &format!("[sim]\nscene = \"{examples}/scene_format.toml\"\n"),
    );
    assert!(stderr.contains(":2:1: `sim.scene`:"), "{stderr}");
    assert!(stderr.contains("[tip_pin]"), "{stderr}");
    let stderr = refused(
        "segments",
        &format!(
            "[sim]\nscene = \"{examples}/mapping_4_2_2.toml\"\n[[bus.segments]]\naddress = 0x20\nzero_counts = 0\ndirection = \"cw\"\n"
        ),
    );
    assert!(
        stderr.contains("`bus.segments`: the rig has one segment per flexible joint"),
        "{stderr}"
    );
    assert!(!stderr.contains("watch it with"), "{stderr}");
}

/// A running antennad: its log lines (stderr) and its data lines (stdout).
type Lines = Box<dyn Iterator<Item = String>>;

/// Spawns antennad with `args` and reads its log (stderr) until the "watch it with" line;
/// returns the child, the stream address, the rest of the log and the stdout lines.
fn spawn(
    args: &[&str],
    dir: &std::path::Path,
) -> (std::process::Child, std::net::SocketAddr, Lines, Lines) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_antennad"))
        .args(args)
        .args([
            "--listen",
            "127.0.0.1:0",
            "--foxglove-listen",
            "127.0.0.1:0",
            "--data-dir",
        ])
        .arg(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut log = BufReader::new(child.stderr.take().unwrap())
        .lines()
        .map(Result::unwrap);
    let out = BufReader::new(child.stdout.take().unwrap())
        .lines()
        .map(Result::unwrap);
    let addr = log
        .by_ref()
        .find_map(|l| {
            let rest = l.split_once("watch it with: nc ")?.1;
            let mut words = rest.split_whitespace();
            let ip = words.next()?;
            let port = words.next()?;
            format!("{ip}:{port}").parse().ok()
        })
        .unwrap();
    (child, addr, Box::new(log), Box::new(out))
}

#[test]
fn without_exit_after_trial_it_keeps_serving_and_stops_cleanly_on_sigterm() {
    let dir = std::env::temp_dir().join(format!("antennad-serve-{}", std::process::id()));
    let (mut child, addr, mut log, out) = spawn(&["--duration-s", "0.5"], &dir);
    assert!(
        log.by_ref()
            .any(|l| l.contains("ended (its duration passed)"))
    );
    // After the trial: still streaming.
    let mut client = net_support::Client::connect(addr);
    assert!(matches!(client.next_message(), StreamMessage::Hello { .. }));
    let mut samples = 0;
    while samples < 100 {
        if let StreamMessage::Samples { segments, .. } = client.next_message() {
            assert_eq!(segments.len(), 8);
            samples += 1;
        }
    }
    let status = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let rest: Vec<String> = out.collect();
    let log: Vec<String> = log.collect();
    assert!(child.wait().unwrap().success(), "{rest:?}\n{log:?}");
    assert!(rest.iter().any(|l| l.contains("polls in")), "{rest:?}");
    assert!(
        log.iter().any(|l| l.contains("SIGTERM received, stopping")),
        "{log:?}"
    );
    assert!(
        TrialReader::read(dir.join("wall-sweep.mcap"))
            .unwrap()
            .truncated
            .is_none()
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// `kill -9` during a trial: the file opens in the standard readers as it is (Python's
/// `mcap` `make_reader(...).iter_messages()`, the Rust `mcap` crate), with every poll up to
/// 100 ms before the kill, log times in Unix-epoch nanoseconds.
#[test]
fn kill_9_during_a_trial_leaves_every_poll_up_to_the_last_flush() {
    let dir = std::env::temp_dir().join(format!("antennad-kill9-{}", std::process::id()));
    let (mut child, _addr, _log, mut lines) =
        spawn(&["--duration-s", "60", "--print-hz", "10"], &dir);
    // Wait for two seconds of trial, in sample lines ("   2.00 ..."): antennad prints a
    // poll's line after recording it.
    let printed_t_s: f64 = lines
        .by_ref()
        .find(|l| l.trim_start().starts_with("2."))
        .and_then(|l| l.split_whitespace().next()?.parse().ok())
        .unwrap();
    let unix_now_ns = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_nanos() as u64;
    child.kill().unwrap(); // SIGKILL
    assert!(!child.wait().unwrap().success());
    let path = dir.join("wall-sweep.mcap");

    // Python's standard reader, no recovery code.
    let script =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/python/read_killed.py");
    let out = Command::new("python3")
        .arg(&script)
        .arg(&path)
        .output()
        .expect("python3 (scripts/setup installs it with the mcap package)");
    assert!(
        out.status.success(),
        "make_reader(...).iter_messages() failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let python: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let python_polls = python["polls"].as_u64().unwrap();
    // Lost at most the 100 ms before the kill (the printed time has two decimals).
    let last_t_s = python["last_t_s"].as_f64().unwrap();
    assert!(
        last_t_s >= printed_t_s - 0.1 - 0.005,
        "the last poll read is at {last_t_s} s, the trial was at {printed_t_s} s"
    );
    assert_eq!(python["log_times_ok"], true, "{python}");
    // Log times are Unix-epoch nanoseconds: the trial started seconds before the kill.
    let started_unix_ns = python["started_unix_ns"].as_u64().unwrap();
    let age_s = (unix_now_ns as f64 - started_unix_ns as f64) * 1e-9;
    assert!(
        (1.0..120.0).contains(&age_s),
        "the trial started {age_s} s before"
    );

    // The Rust mcap crate, no recovery code either.
    let bytes = std::fs::read(&path).unwrap();
    let rust_polls = mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(Result::unwrap)
        .filter(|m| m.channel.topic == "/antenna/segments")
        .count() as u64;
    assert_eq!(rust_polls, python_polls);

    let trial = TrialReader::read(&path).unwrap();
    assert!(
        trial.truncated.is_some(),
        "a killed recorder leaves no summary"
    );
    let n = trial.segments.len();
    assert_eq!(n as u64, python_polls);
    // At least the two seconds of trial seen, less the 100 ms flush interval, at 1 kHz
    // (with room for skipped deadlines on a loaded machine).
    assert!(n > 1000, "{n} polls read back");
    let seqs: Vec<u64> = trial.segments.iter().map(|m| m.seq.unwrap()).collect();
    assert!(seqs.windows(2).all(|w| w[1] > w[0]), "polls in order");
    assert!(
        trial
            .segments
            .iter()
            .all(|m| m.segments.len() == 8 && m.segments.iter().all(|s| s.ok))
    );
    assert!(trial.segments.windows(2).all(|w| w[1].t_s > w[0].t_s));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_missing_i2c_device_names_the_key_and_the_path() {
    // 100 Hz: a rate the default 100 kHz bus carries (9 segments at 1 kHz it does not).
    let stderr = refused("i2c", "[bus]\ndevice = \"/dev/i2c-250\"\npoll_hz = 100.0\n");
    assert!(
        stderr.contains("`bus.device` = \"/dev/i2c-250\": cannot open the I2C bus"),
        "{stderr}"
    );
}

/// With hardware configured (here a VXM, emulated on a pseudo-terminal) a restart must not
/// drive the stage from wherever it is: no trial starts by itself, antennad says it waits for
/// a client's start_trial, and the stage is only homed.
#[test]
fn with_a_stage_configured_no_trial_starts_by_itself_and_it_waits_idle() {
    use host_daemon::sim::emulator::VxmEmulator;
    use serialport::{SerialPort, TTYPort};
    let dir = std::env::temp_dir().join(format!("antennad-idle-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (master, slave) = TTYPort::pair().unwrap();
    let port = slave.name().unwrap();
    drop(slave);
    let vxm = VxmEmulator::spawn(master);
    let config = dir.join("robot.toml");
    std::fs::write(&config, format!("[stage]\nport = \"{port}\"\n")).unwrap();
    let args = ["--config", config.to_str().unwrap()];
    let (mut child, _addr, mut log, out) = spawn(&args, &dir);
    assert!(
        log.by_ref()
            .any(|l| l.contains("no trial starts by itself; waiting idle")),
    );
    // Only a hang takes this long, however loaded the machine.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    while vxm.negative_limit_steps() != 0 {
        assert!(std::time::Instant::now() < deadline, "never homed");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    std::thread::sleep(std::time::Duration::from_millis(700));
    let sent = String::from_utf8_lossy(&vxm.received()).into_owned();
    // The homing program's `I1M-0` and nothing else that moves.
    assert_eq!(sent.matches("I1M").count(), 1, "{sent}");
    assert_eq!(vxm.position_steps(), 0);
    let status = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let rest: Vec<String> = log.collect();
    let data: Vec<String> = out.collect();
    assert!(child.wait().unwrap().success(), "{rest:?}");
    assert!(!rest.iter().any(|l| l.contains("started")), "{rest:?}");
    assert!(data.iter().any(|l| l.contains("0 trials")), "{data:?}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_poll_rate_the_bus_cannot_carry_is_refused_with_the_arithmetic() {
    // The default eight segments at the default 1 kHz, on a real device at the default 100 kHz.
    let stderr = refused("rate", "[bus]\ndevice = \"/dev/i2c-250\"\n");
    for part in [
        "`bus.poll_hz`",
        "8 segments x 38 + 57 = 361 bit times",
        "bus.speed_hz = 100000 is 3610 us",
        "lower bus.poll_hz to 221 or less",
    ] {
        assert!(stderr.contains(part), "{part:?} missing from: {stderr}");
    }
    // Nothing was opened: the refusal comes before the device.
    assert!(!stderr.contains("cannot open the I2C bus"), "{stderr}");
}
