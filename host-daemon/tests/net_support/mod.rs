//! Shared helpers for the `net_*` tests: a line-reading client with timeouts, so no test hangs.
#![allow(clippy::unwrap_used, dead_code)]

use std::io::{BufRead, BufReader, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::{Duration, Instant};

use antenna_data::stream::{ControlReply, SegmentSample, StreamMessage};
use host_daemon::net::StreamServer;

/// The control token every test server uses.
pub const TOKEN: &str = "test-token-0123456789";

/// How long any single read may wait before the test fails.
pub const READ_TIMEOUT: Duration = Duration::from_secs(10);

/// A client speaking the line protocol.
pub struct Client {
    pub reader: BufReader<TcpStream>,
    pub writer: TcpStream,
}

impl Client {
    pub fn connect(addr: SocketAddr) -> Self {
        Self::from_stream(TcpStream::connect(addr).unwrap())
    }

    pub fn from_stream(stream: TcpStream) -> Self {
        stream.set_read_timeout(Some(READ_TIMEOUT)).unwrap();
        let writer = stream.try_clone().unwrap();
        Self {
            reader: BufReader::new(stream),
            writer,
        }
    }

    /// The next line as raw text; `None` at end of stream. Panics on timeout.
    pub fn next_line(&mut self) -> Option<String> {
        let mut line = String::new();
        match self.reader.read_line(&mut line) {
            Ok(0) => None,
            Ok(_) => Some(line),
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionReset => None,
            Err(e) => panic!("read failed (timeout?): {e}"),
        }
    }

    pub fn next_message(&mut self) -> StreamMessage {
        let line = self.next_line().expect("connection closed early");
        serde_json::from_str(&line).unwrap_or_else(|e| panic!("bad line {line:?}: {e}"))
    }

    /// Skips stream messages until a reply arrives.
    pub fn next_reply(&mut self) -> ControlReply {
        for _ in 0..100_000 {
            if let StreamMessage::Reply(reply) = self.next_message() {
                return reply;
            }
        }
        panic!("no reply");
    }

    pub fn send(&mut self, bytes: &[u8]) {
        self.writer.write_all(bytes).unwrap();
    }

    pub fn send_line(&mut self, line: &str) {
        self.send(format!("{line}\n").as_bytes());
    }

    /// Reads until end of stream (bounded by the read timeout per read).
    pub fn expect_closed(&mut self) {
        for _ in 0..10_000_000 {
            if self.next_line().is_none() {
                return;
            }
        }
        panic!("the connection was not closed");
    }
}

/// Waits (bounded) until the server counts `n` clients.
pub fn wait_for_clients(server: &StreamServer, n: usize) {
    let deadline = Instant::now() + Duration::from_secs(20);
    while server.client_count() != n {
        assert!(
            Instant::now() < deadline,
            "server has {} clients, expected {n}",
            server.client_count()
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// A nine-segment sample message numbered `seq`.
pub fn samples(seq: u64) -> StreamMessage {
    let segments = (0..9)
        .map(|i| SegmentSample {
            address: 0x21 + i,
            angle_rad: Some(0.001 * seq as f64 + f64::from(i)),
            contact: Some(seq.is_multiple_of(2)),
            touch_bits: Some(if seq.is_multiple_of(2) { 0b0100 } else { 0 }),
            counter: Some((seq % 65_536) as u32),
            error: None,
            stale: i == 4 && seq.is_multiple_of(3),
        })
        .collect();
    StreamMessage::Samples {
        seq,
        t_ns: seq * 1_000_000,
        segments,
        stage_position_m: Some(0.25),
        base_angle_deg: Some(-12.5),
    }
}

/// Follows a client's stream until a `Samples` with `seq >= stop_at`, checking that every
/// delivered sequence number is the previous one plus one plus the drops reported in between.
/// Returns (samples received, drops reported).
pub fn follow_exactly(client: &mut Client, stop_at: u64) -> (u64, u64) {
    let mut expected_next = 0u64;
    let mut pending_dropped = 0u64;
    let (mut received, mut dropped_total) = (0u64, 0u64);
    loop {
        match client.next_message() {
            StreamMessage::Hello { .. } => {}
            StreamMessage::Lagged { dropped, .. } => {
                assert!(dropped > 0);
                pending_dropped += dropped;
                dropped_total += dropped;
            }
            StreamMessage::Samples { seq, .. } => {
                assert_eq!(
                    seq,
                    expected_next + pending_dropped,
                    "gap not accounted for"
                );
                pending_dropped = 0;
                expected_next = seq + 1;
                received += 1;
                if seq >= stop_at {
                    return (received, dropped_total);
                }
            }
            other => panic!("unexpected {other:?}"),
        }
    }
}
