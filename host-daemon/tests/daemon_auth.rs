//! A real antennad, in-process on the simulated rig, against a stranger on its port:
//! 1,000 wrong tokens on one connection are slowed (growing delays), logged with the peer's
//! address and cut off, and the right token still works at once afterwards; 40 idle readers
//! cannot lock out an operator, nor a token-less `stop_all`.
#![allow(clippy::unwrap_used)]

mod net_support;

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

use antenna_data::stream::{ErrorCode, StreamMessage};
use host_daemon::net::{AuthPolicy, ControlToken};
use host_daemon::service::config::Config;
use host_daemon::service::daemon::{Daemon, DaemonHandle, DaemonOptions};
use net_support::{Client, TOKEN};

fn start(name: &str) -> (DaemonHandle, std::path::PathBuf) {
    let dir = std::env::temp_dir().join(format!("antennad-auth-{name}-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    let mut config = Config::default();
    config.server.listen = "127.0.0.1:0".to_owned();
    config.server.token = Some(ControlToken::new(TOKEN).unwrap());
    config.data_dir = dir.clone();
    config.bus.poll_hz = 200.0;
    config.trials[0].duration_s = 60.0;
    (
        Daemon::start(config, DaemonOptions::default()).unwrap(),
        dir,
    )
}

fn connect(daemon: &DaemonHandle) -> Client {
    let mut client = Client::connect(daemon.local_addr().unwrap());
    assert!(matches!(client.next_message(), StreamMessage::Hello { .. }));
    client
}

#[test]
fn a_thousand_wrong_tokens_are_slowed_logged_and_cut_off() {
    let (daemon, dir) = start("guess");
    let policy = AuthPolicy::default();
    let mut stranger = connect(&daemon);
    let peer = stranger.writer.local_addr().unwrap().to_string();
    let started = Instant::now();
    let guesses: String = (0..1000)
        .map(|i| format!("{{\"id\":{i},\"token\":\"guess-{i:012}\",\"cmd\":\"stop_trial\"}}\n"))
        .collect();
    // The server may close before it has read every guess.
    let _ = stranger.writer.write_all(guesses.as_bytes());
    let mut refused = 0u32;
    let closing = loop {
        let reply = stranger.next_reply();
        match reply.error {
            Some(ErrorCode::BadToken) => refused += 1,
            _ => break reply,
        }
    };
    let elapsed = started.elapsed();
    assert_eq!(
        closing.error,
        Some(ErrorCode::TooManyFailures),
        "{closing:?}"
    );
    stranger.expect_closed();
    // Only the first few guesses were answered, each after a longer wait than the last.
    assert_eq!(refused, policy.max_failures_per_connection);
    let least: Duration = (1..=refused).map(|n| policy.delay(n)).sum();
    assert!(elapsed >= least, "{elapsed:?} < {least:?}");
    let log = daemon.log_lines();
    let logged = log
        .iter()
        .filter(|l| l.contains(&format!("authentication failed from {peer}")))
        .count();
    assert_eq!(logged, refused as usize, "{log:#?}");
    assert!(
        log.iter()
            .any(|l| l.contains(&format!("closing {peer}: {refused} failed authentications"))),
        "{log:#?}"
    );
    // The right token works at once afterwards, from the same address (no lock-out).
    let mut operator = connect(&daemon);
    operator.send_line(&format!(
        r#"{{"id":1,"token":"{TOKEN}","cmd":"start_trial","name":"wall-sweep"}}"#
    ));
    let reply = operator.next_reply();
    assert!(reply.ok, "{reply:?}");
    assert_eq!(daemon.trial().as_deref(), Some("wall-sweep"));
    // No guess reached the daemon: the only trial is the operator's.
    let summary = daemon.shutdown().unwrap();
    assert_eq!(summary.trials.len(), 1);
    std::fs::remove_dir_all(&dir).ok();
}

/// Idle readers: connected, reading the stream, never sending a line.
struct Readers {
    streams: Vec<TcpStream>,
    /// Per stream: whether the server has sent it anything (it handled the connection).
    heard: Vec<bool>,
    /// Per stream: whether it was told it was dropped to make room.
    evicted: Vec<bool>,
    /// Per stream: whether it is closed.
    closed: Vec<bool>,
}

impl Readers {
    fn connect(daemon: &DaemonHandle, n: usize) -> Self {
        let addr = daemon.local_addr().unwrap();
        let streams = (0..n)
            .map(|_| {
                let s = TcpStream::connect(addr).unwrap();
                s.set_nonblocking(true).unwrap();
                s
            })
            .collect();
        Self {
            streams,
            heard: vec![false; n],
            evicted: vec![false; n],
            closed: vec![false; n],
        }
    }

    /// Reads what each has; returns how many are still open and how many were told (so far)
    /// they were dropped to make room.
    fn drain(&mut self) -> (usize, usize) {
        let mut buffer = vec![0u8; 1 << 16];
        for (k, stream) in self.streams.iter_mut().enumerate() {
            if self.closed[k] {
                continue;
            }
            let mut text = Vec::new();
            self.closed[k] = loop {
                match stream.read(&mut buffer) {
                    Ok(0) => break true,
                    Ok(n) => text.extend_from_slice(&buffer[..n]),
                    Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => break false,
                    Err(_) => break true,
                }
            };
            self.heard[k] |= !text.is_empty() || self.closed[k];
            if String::from_utf8_lossy(&text).contains("\"error\":\"evicted\"") {
                self.evicted[k] = true;
            }
        }
        self.counts()
    }

    /// How many are still open, and how many were told they were dropped to make room.
    fn counts(&self) -> (usize, usize) {
        let open = self.closed.iter().filter(|&&c| !c).count();
        let evicted = self.evicted.iter().filter(|&&e| e).count();
        (open, evicted)
    }

    /// Drains until `settled` holds; returns the last counts. Gives up after [`PATIENCE`]
    /// (only a hang takes that long), returning what it saw.
    fn drain_until(&mut self, settled: impl Fn(&Self) -> bool) -> (usize, usize) {
        let deadline = Instant::now() + PATIENCE;
        loop {
            let counts = self.drain();
            if settled(self) || Instant::now() >= deadline {
                return counts;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    /// Whether the server has answered every connection (a hello, or a notice and close).
    fn all_heard(&self) -> bool {
        self.heard.iter().all(|&h| h)
    }
}

/// How long to wait for the server to handle connections before the test fails: only a
/// hang takes this long, however loaded the machine.
const PATIENCE: Duration = Duration::from_secs(60);

#[test]
fn forty_idle_readers_cannot_lock_out_an_operator_or_a_stop() {
    let (daemon, dir) = start("lockout");
    let mut readers = Readers::connect(&daemon, 40);
    let (open, evicted) = readers.drain_until(|r| r.counts() == (16, 24));
    // One address may hold 16 connections: the oldest readers made room for the newest.
    assert_eq!(open, 16, "{open} readers open");
    assert_eq!(evicted, 24);
    // The operator connects and controls.
    let mut operator = connect(&daemon);
    operator.send_line(&format!(r#"{{"id":1,"token":"{TOKEN}","cmd":"auth"}}"#));
    assert!(operator.next_reply().ok);
    operator.send_line(&format!(
        r#"{{"id":2,"token":"{TOKEN}","cmd":"start_trial","name":"wall-sweep"}}"#
    ));
    let reply = operator.next_reply();
    assert!(reply.ok, "{reply:?}");
    assert_eq!(daemon.trial().as_deref(), Some("wall-sweep"));
    // 40 more readers: the operator's connection is never the one dropped.
    let mut more = Readers::connect(&daemon, 40);
    // Once the server has handled each of them.
    more.drain_until(Readers::all_heard);
    assert!(
        more.all_heard(),
        "the server never handled every connection"
    );
    readers.drain();
    operator.send_line(&format!(
        r#"{{"id":3,"token":"{TOKEN}","cmd":"move_stage","relative_m":0.01}}"#
    ));
    let reply = operator.next_reply();
    assert_eq!(reply.id, Some(3));
    assert_eq!(
        reply.error,
        Some(ErrorCode::Rejected),
        "the trial owns the stage"
    );
    // A stranger without the token stops everything.
    let mut stranger = connect(&daemon);
    stranger.send_line(r#"{"id":9,"cmd":"stop_all"}"#);
    let reply = stranger.next_reply();
    assert!(
        reply.ok && reply.message.contains("ended (stop_all)"),
        "{reply:?}"
    );
    assert_eq!(daemon.trial(), None);
    let peer = stranger.writer.local_addr().unwrap().to_string();
    let log = daemon.log_lines();
    assert!(
        log.iter()
            .any(|l| l.contains(&format!("stop_all from {peer}"))),
        "{log:#?}"
    );
    assert!(
        log.iter().any(|l| l.contains("to make room for")),
        "{log:#?}"
    );
    let summary = daemon.shutdown().unwrap();
    assert_eq!(summary.trials[0].ended, "stop_all");
    std::fs::remove_dir_all(&dir).ok();
}
