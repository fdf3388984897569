//! `antennad` as a service, the built binary end to end: SIGTERM during a trial ends it with
//! exit status 0 and a finalized recording, telling systemd `READY=1`, `WATCHDOG=1` (with
//! `WATCHDOG_USEC`) and `STOPPING=1` on a test-side `NOTIFY_SOCKET`; SIGHUP re-reads the
//! configuration and reports what changed while the daemon keeps running; a closed stdout
//! and a stdout nobody reads neither kill nor stall it; the configuration is looked for in
//! `--config`, then the search path, then the built-in rig.
#![cfg(target_os = "linux")]
#![allow(clippy::unwrap_used)]

use antenna_data::record::TrialReader;
use std::io::{BufRead, BufReader};
use std::os::unix::net::UnixDatagram;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

/// How long any one expected line or message may take: generous, for a loaded machine (the
/// daemon needs well under a second for each).
const PATIENCE: Duration = Duration::from_secs(30);

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("antennad-service-{name}-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// antennad's log (stderr), read on a thread so a test can wait with a deadline.
struct Log {
    lines: Receiver<String>,
    seen: Vec<String>,
}

impl Log {
    fn of(child: &mut Child) -> Self {
        let stderr = child.stderr.take().unwrap();
        let (sender, lines) = channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines() {
                let Ok(line) = line else { break };
                if sender.send(line).is_err() {
                    break;
                }
            }
        });
        Self {
            lines,
            seen: Vec::new(),
        }
    }

    /// The next line containing `text`; panics with the log so far after [`PATIENCE`].
    fn wait_for(&mut self, text: &str) -> String {
        let deadline = Instant::now() + PATIENCE;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(line) => {
                    self.seen.push(line.clone());
                    if line.contains(text) {
                        return line;
                    }
                }
                Err(e) => panic!("no log line with {text:?} ({e}); the log:\n{}", self.text()),
            }
        }
    }

    /// Everything logged until the daemon closed stderr.
    fn rest(&mut self) -> String {
        while let Ok(line) = self.lines.recv_timeout(PATIENCE) {
            self.seen.push(line);
        }
        self.text()
    }

    fn text(&self) -> String {
        self.seen.join("\n")
    }
}

/// A test-side service manager socket: what antennad sends to `NOTIFY_SOCKET`.
struct NotifySocket {
    path: PathBuf,
    socket: UnixDatagram,
}

impl NotifySocket {
    fn bind(dir: &Path) -> Self {
        let path = dir.join("notify.sock");
        let socket = UnixDatagram::bind(&path).unwrap();
        socket
            .set_read_timeout(Some(Duration::from_millis(100)))
            .unwrap();
        Self { path, socket }
    }

    /// The datagrams that arrive within `within`, stopping early once `until` holds.
    fn receive(&self, within: Duration, until: impl Fn(&[String]) -> bool) -> Vec<String> {
        let deadline = Instant::now() + within;
        let mut messages = Vec::new();
        let mut buffer = [0u8; 4096];
        while Instant::now() < deadline && !until(&messages) {
            if let Ok(n) = self.socket.recv(&mut buffer) {
                messages.push(String::from_utf8_lossy(&buffer[..n]).into_owned());
            }
        }
        messages
    }
}

fn kill(child: &Child, signal: &str) {
    let status = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
}

/// Waits for `child` to exit, at most [`PATIENCE`].
fn exit_status(child: &mut Child) -> std::process::ExitStatus {
    let deadline = Instant::now() + PATIENCE;
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status;
        }
        if Instant::now() >= deadline {
            child.kill().ok();
            panic!("antennad did not exit within {PATIENCE:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// The poll deadlines a trial's recording spans, first to last poll number: the deadlines the
/// poller skipped are the gaps. The numbers only grow.
fn deadlines_spanned(trial: &antenna_data::record::Trial) -> u64 {
    let seqs: Vec<u64> = trial.segments.iter().map(|m| m.seq.unwrap()).collect();
    assert!(
        seqs.windows(2).all(|w| w[1] > w[0]),
        "poll numbers out of order"
    );
    match (seqs.first(), seqs.last()) {
        (Some(first), Some(last)) => last - first + 1,
        _ => 0,
    }
}

fn antennad() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_antennad"));
    command
        .env_remove("NOTIFY_SOCKET")
        .env_remove("WATCHDOG_USEC")
        .env_remove("WATCHDOG_PID")
        .env("RUST_LOG", "info")
        // No system configuration file may leak into a test.
        .arg("--config-search-path=/nonexistent/antennad.toml");
    command
}

#[test]
fn sigterm_during_a_trial_exits_0_with_the_recording_finalized_and_tells_systemd() {
    let dir = scratch("sigterm");
    let notify = NotifySocket::bind(&dir);
    let mut child = antennad()
        .args(["--duration-s", "60", "--no-server", "--quiet", "--data-dir"])
        .arg(dir.join("data"))
        .env("NOTIFY_SOCKET", &notify.path)
        // 300 ms: pings every 150 ms.
        .env("WATCHDOG_USEC", "300000")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut log = Log::of(&mut child);
    log.wait_for("systemd watchdog: pinging every 150 ms");
    let messages = notify.receive(PATIENCE, |m| {
        m.iter().any(|m| m.contains("READY=1"))
            && m.iter().filter(|m| *m == "WATCHDOG=1\n").count() >= 3
    });
    let ready = messages.iter().find(|m| m.contains("READY=1")).unwrap();
    assert!(
        ready.contains("STATUS=polling; trial \"wall-sweep\" running"),
        "{messages:?}"
    );
    assert!(
        messages.iter().filter(|m| *m == "WATCHDOG=1\n").count() >= 3,
        "{messages:?}"
    );
    log.wait_for("-- move 1");
    kill(&child, "-TERM");
    let stopping = notify.receive(PATIENCE, |m| m.iter().any(|m| m.contains("STOPPING=1")));
    assert!(
        stopping
            .iter()
            .any(|m| m.starts_with("STOPPING=1\nSTATUS=stopping on SIGTERM")),
        "{stopping:?}"
    );
    let status = exit_status(&mut child);
    let text = log.rest();
    assert!(status.success(), "{status}\n{text}");
    assert!(text.contains("SIGTERM received, stopping"), "{text}");
    assert!(text.contains("ended (the daemon stopped)"), "{text}");
    let trial = TrialReader::read(dir.join("data/wall-sweep.mcap")).unwrap();
    assert!(trial.truncated.is_none(), "the file was finalized");
    assert!(!trial.segments.is_empty());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn sighup_rereads_the_configuration_reports_the_changed_keys_and_keeps_running() {
    let dir = scratch("sighup");
    let notify = NotifySocket::bind(&dir);
    let config = dir.join("rig.toml");
    let original = "data_dir = \"recordings\"\n[bus]\npoll_hz = 1000.0\n\
                    [[trials]]\nname = \"short\"\nduration_s = 0.3\n";
    std::fs::write(&config, original).unwrap();
    let mut child = antennad()
        .arg("--config")
        .arg(&config)
        .args(["--no-server", "--quiet"])
        // Under a service manager, without a watchdog.
        .env("NOTIFY_SOCKET", &notify.path)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut log = Log::of(&mut child);
    let used = log.wait_for("configuration: ");
    assert!(used.contains("rig.toml (--config)"), "{used}");
    // A relative data_dir is relative to the configuration file's directory.
    let ended = log.wait_for("ended (its duration passed)");
    let recording = dir.join("recordings/short.mcap");
    assert!(ended.contains(&recording.display().to_string()), "{ended}");
    assert!(TrialReader::read(&recording).unwrap().truncated.is_none());

    std::fs::write(
        &config,
        original
            .replace("poll_hz = 1000.0", "poll_hz = 500.0")
            .replace("duration_s = 0.3", "duration_s = 2.0"),
    )
    .unwrap();
    kill(&child, "-HUP");
    let line = log.wait_for("SIGHUP: ");
    assert!(
        line.contains(
            "2 key(s) differ from the running configuration: bus.poll_hz, trials[0].duration_s"
        ),
        "{line}"
    );
    assert!(line.contains("nothing was changed now"), "{line}");

    std::fs::write(&config, "[bus]\npoll_hz = -1\n").unwrap();
    kill(&child, "-HUP");
    let line = log.wait_for("SIGHUP: ");
    assert!(line.contains(" WARN "), "{line}");
    assert!(line.contains(":2:1: `bus.poll_hz`"), "{line}");
    assert!(line.contains("the running configuration stays"), "{line}");

    std::fs::write(&config, original).unwrap();
    kill(&child, "-HUP");
    let line = log.wait_for("SIGHUP: ");
    assert!(
        line.contains("re-read: unchanged (no trial running)"),
        "{line}"
    );
    assert!(child.try_wait().unwrap().is_none(), "still running");

    // READY=1 came, and no watchdog pings: none was asked for.
    let messages = notify.receive(Duration::from_millis(500), |_| false);
    assert!(
        messages.iter().any(|m| m.contains("READY=1")),
        "{messages:?}"
    );
    assert!(
        !messages.iter().any(|m| m.contains("WATCHDOG=1")),
        "{messages:?}"
    );

    kill(&child, "-TERM");
    let status = exit_status(&mut child);
    let text = log.rest();
    assert!(status.success(), "{status}\n{text}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_closed_stdout_does_not_stop_the_daemon() {
    let dir = scratch("closed-stdout");
    let mut child = antennad()
        .args([
            "--duration-s",
            "1",
            "--print-hz",
            "100",
            "--no-server",
            "--data-dir",
        ])
        .arg(dir.join("data"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The reader goes away at once: every write to stdout fails with EPIPE.
    drop(child.stdout.take());
    let mut log = Log::of(&mut child);
    let warned = log.wait_for("stdout: ");
    assert!(warned.contains("Broken pipe"), "{warned}");
    assert!(warned.contains("the daemon goes on"), "{warned}");
    // The trial goes on to its end, and the daemon past it.
    log.wait_for("ended (its duration passed)");
    std::thread::sleep(Duration::from_millis(300));
    assert!(child.try_wait().unwrap().is_none(), "still running");
    kill(&child, "-TERM");
    let status = exit_status(&mut child);
    let text = log.rest();
    assert!(status.success(), "{status}\n{text}");
    assert!(!text.contains("panicked"), "{text}");
    let trial = TrialReader::read(dir.join("data/wall-sweep.mcap")).unwrap();
    assert!(trial.truncated.is_none());
    // 1 s at 1 kHz: every deadline polled or skipped (the skipped ones leave gaps in the poll
    // numbers), however loaded the machine.
    let deadlines = deadlines_spanned(&trial);
    assert!(deadlines > 900, "{deadlines} deadlines");
    std::fs::remove_dir_all(&dir).ok();
}

/// A stdout that is never read fills its pipe (64 KiB here: a line per poll fills it in under
/// a second); the hub must not wait for it: the trial ends on time, every poll recorded, and
/// SIGTERM still ends the daemon at once.
#[test]
fn a_stdout_nobody_reads_does_not_stall_the_daemon() {
    let dir = scratch("full-stdout");
    let mut child = antennad()
        .args([
            "--duration-s",
            "2",
            "--print-hz",
            "1000",
            "--no-server",
            "--data-dir",
        ])
        .arg(dir.join("data"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let _unread = child.stdout.take();
    let mut log = Log::of(&mut child);
    log.wait_for("ended (its duration passed)");
    let trial = TrialReader::read(dir.join("data/wall-sweep.mcap")).unwrap();
    // 2 s at 1 kHz: every deadline polled or skipped (the skipped ones leave gaps in the
    // poll numbers), however loaded the machine; the trial ended on its own clock.
    let deadlines = deadlines_spanned(&trial);
    assert!(deadlines > 1900, "{deadlines} deadlines");
    // The exit waits at most a second for stdout: it comes (a daemon stalled on the pipe
    // would never exit, and `exit_status` gives up after PATIENCE).
    kill(&child, "-TERM");
    let status = exit_status(&mut child);
    let text = log.rest();
    assert!(status.success(), "{status}\n{text}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_configuration_is_the_given_file_then_the_search_path_then_the_built_in_rig() {
    let dir = scratch("search");
    let trial = |name: &str| format!("[[trials]]\nname = \"{name}\"\nduration_s = 0.2\n");
    std::fs::write(dir.join("found.toml"), trial("from-search")).unwrap();
    std::fs::write(dir.join("given.toml"), trial("from-config")).unwrap();
    let search = format!(
        "--config-search-path={}:{}",
        dir.join("missing.toml").display(),
        dir.join("found.toml").display()
    );
    let run = |extra: &[&str]| {
        let output = Command::new(env!("CARGO_BIN_EXE_antennad"))
            .args([
                "--exit-after-trial",
                "--no-server",
                "--no-record",
                "--quiet",
            ])
            .args(extra)
            .output()
            .unwrap();
        let log = String::from_utf8_lossy(&output.stderr).into_owned();
        assert!(output.status.success(), "{log}");
        log
    };
    let log = run(&[&search]);
    assert!(
        log.contains("found.toml (found on the search path)"),
        "{log}"
    );
    assert!(log.contains("trial \"from-search\" started"), "{log}");
    let given = dir.join("given.toml").display().to_string();
    let log = run(&[&search, "--config", &given]);
    assert!(log.contains("given.toml (--config)"), "{log}");
    assert!(log.contains("trial \"from-config\" started"), "{log}");
    let nothing = format!(
        "--config-search-path={}",
        dir.join("missing.toml").display()
    );
    let log = run(&[&nothing, "--duration-s", "0.2"]);
    assert!(
        log.contains("configuration: the built-in simulated rig"),
        "{log}"
    );
    assert!(log.contains("trial \"wall-sweep\" started"), "{log}");
    std::fs::remove_dir_all(&dir).ok();
}
