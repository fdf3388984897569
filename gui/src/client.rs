//! [`LiveClient`]: antennad's stream over TCP (`docs/stream-protocol.md`), on its own thread.
//!
//! The reader thread connects, reads the newline-delimited JSON, appends every `samples`
//! line to the shared [`History`] (bounded: the user's history window times the poll rate),
//! keeps the latest `status`, the wall estimates of `estimate` lines ([`EstimateHistory`],
//! bounded by the same window), counts `lagged` drops and files `reply` lines. A line of a
//! type it does not know (a newer daemon's message, added under the protocol's additive rule)
//! is skipped and counted ([`LiveState::unknown_lines`]): not an error, and the connection
//! goes on. When the daemon
//! goes away it says so in [`ConnectionState::Disconnected`] and reconnects with exponential
//! backoff. The UI thread only locks [`LiveState`] for as long as it reads it and hands
//! control requests to a channel that the reader thread writes out: nothing here waits on the
//! network from the UI thread.
//!
//! Each segment's four touch bits come as the stream's `touch_bits` and are stored as they
//! are. An older daemon sends only the `contact` flag: its contact is stored as all four bits
//! set (the switch that fired is not known).

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, ErrorKind, Write};
use std::net::{TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use antenna_data::stream::{
    ControlRequest, SegmentSample, SegmentStatus, StreamMessage, WireCommand,
};

use crate::error::MonitorError;
use crate::estimate::{Estimate, EstimateHistory};
use crate::history::{Health, History, Sample, SegmentReading};
use crate::rig::RigGeometry;

/// A segment's four touch bits.
const TOUCH_BITS_MASK: u8 = 0x0F;
/// Replies kept for the controls panel.
const REPLIES_KEPT: usize = 64;
/// How long a read waits before the thread looks at its stop flag and its outgoing queue.
const READ_POLL: Duration = Duration::from_millis(20);
/// The server message types this monitor reads (`docs/stream-protocol.md`); a line of
/// another type is a newer daemon's message and is skipped.
pub const KNOWN_TYPES: [&str; 6] = ["hello", "samples", "status", "estimate", "lagged", "reply"];

/// How to connect.
#[derive(Debug, Clone)]
pub struct ClientOptions {
    /// `host:port` of antennad's stream.
    pub address: String,
    /// The history window, seconds (samples older than this are dropped).
    pub history_s: f64,
    /// How long one connection attempt may take.
    pub connect_timeout: Duration,
    /// The first wait before reconnecting; it doubles on every failure...
    pub backoff_min: Duration,
    /// ...up to this.
    pub backoff_max: Duration,
}

impl ClientOptions {
    /// Defaults for `address`: a 60 s history, 1 s connect timeout, reconnecting after
    /// 0.25 s, 0.5 s, ... up to 4 s.
    pub fn new(address: impl Into<String>) -> Self {
        Self {
            address: address.into(),
            history_s: 60.0,
            connect_timeout: Duration::from_secs(1),
            backoff_min: Duration::from_millis(250),
            backoff_max: Duration::from_secs(4),
        }
    }
}

/// Where the connection stands.
#[derive(Debug, Clone, PartialEq)]
pub enum ConnectionState {
    /// Trying to connect (attempt number since the last success).
    Connecting {
        /// Attempts since the last connection.
        attempt: u32,
    },
    /// Connected; `hello` received.
    Connected {
        /// The daemon's name and version.
        daemon: String,
    },
    /// Not connected: why, and when the next attempt is.
    Disconnected {
        /// What went wrong.
        error: String,
        /// When the next attempt starts.
        retry_at: Instant,
    },
}

/// The daemon's latest `status` line.
#[derive(Debug, Clone, PartialEq)]
pub struct DaemonStatus {
    /// Its time, seconds since the daemon started.
    pub t_s: f64,
    /// The trial being recorded.
    pub trial: Option<String>,
    /// Health counters per segment since the daemon started.
    pub segments: Vec<SegmentStatus>,
    /// What is wrong now and what last happened.
    pub note: Option<String>,
}

/// A control command (`docs/stream-protocol.md`, "Client to server").
#[derive(Debug, Clone, PartialEq)]
pub enum Command {
    /// Start the configured trial of this name.
    StartTrial {
        /// The trial's name.
        name: String,
    },
    /// End the running trial.
    StopTrial,
    /// Move the stage to an absolute position.
    MoveStage {
        /// Target, metres from home.
        position_m: f64,
    },
    /// Set the base servo's angle.
    SetBaseAngle {
        /// Servo angle, degrees.
        angle_deg: f64,
    },
    /// Stop the stage, hold the servo, end any trial (needs no token).
    StopAll,
    /// Prove the token, so the daemon keeps this connection when it is full of readers.
    Auth,
}

impl Command {
    /// The protocol's `cmd`.
    pub fn name(&self) -> &'static str {
        match self {
            Command::StartTrial { .. } => "start_trial",
            Command::StopTrial => "stop_trial",
            Command::MoveStage { .. } => "move_stage",
            Command::SetBaseAngle { .. } => "set_base_angle",
            Command::StopAll => "stop_all",
            Command::Auth => "auth",
        }
    }

    /// Whether the daemon wants the token with it (every command but `stop_all`).
    pub fn needs_token(&self) -> bool {
        !matches!(self, Command::StopAll)
    }

    /// The command as antenna-data's wire type writes it.
    pub fn wire(&self) -> WireCommand {
        match self {
            Command::StartTrial { name } => WireCommand::StartTrial {
                name: name.clone(),
                metadata: BTreeMap::new(),
            },
            Command::StopTrial => WireCommand::StopTrial {},
            Command::MoveStage { position_m } => WireCommand::MoveStage {
                position_m: Some(*position_m),
                relative_m: None,
                speed_m_per_s: None,
            },
            Command::SetBaseAngle { angle_deg } => WireCommand::SetBaseAngle {
                angle_deg: *angle_deg,
            },
            Command::StopAll => WireCommand::StopAll {},
            Command::Auth => WireCommand::Auth {},
        }
    }

    /// The request line (without the newline), antenna-data's [`ControlRequest`]; an empty
    /// `token` is left out.
    pub fn request_line(&self, id: u64, token: &str) -> Result<String, MonitorError> {
        let request = ControlRequest {
            id: Some(id),
            token: (!token.is_empty()).then(|| token.to_owned()),
            command: self.wire(),
        };
        serde_json::to_string(&request).map_err(|e| {
            MonitorError::Control(format!("{}: cannot encode the request: {e}", self.name()))
        })
    }
}

/// One request and its answer.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplyRecord {
    /// The request's id.
    pub id: Option<u64>,
    /// The command, if the id was ours.
    pub command: Option<String>,
    /// Whether the daemon carried it out.
    pub ok: bool,
    /// What the daemon said.
    pub message: String,
    /// The machine-readable reason on failure (`bad_token`, `rejected`, ...).
    pub error: Option<String>,
}

/// What the reader thread shares with the UI.
#[derive(Debug)]
pub struct LiveState {
    /// The connection.
    pub connection: ConnectionState,
    /// Samples received, bounded by the history window.
    pub history: History,
    /// The rig's geometry from `hello` (a stand-in if it sends none).
    pub rig: Option<RigGeometry>,
    /// The segments' addresses from `hello`.
    pub segment_addresses: Vec<u8>,
    /// The latest `status`.
    pub status: Option<DaemonStatus>,
    /// Messages the daemon dropped for us (from `lagged`), since we started.
    pub lagged_dropped: u64,
    /// How many of them were polls (`lagged`'s `samples_dropped`): the gaps in `seq` they
    /// leave (0 from a daemon before it counted them).
    pub lagged_samples_dropped: u64,
    /// Replies, oldest first (the last few dozen).
    pub replies: Vec<ReplyRecord>,
    /// Successful connections so far.
    pub connections: u32,
    /// Lines that did not parse (protocol errors), and the last one's error.
    pub bad_lines: (u64, Option<String>),
    /// Lines of a message type this monitor does not know (a newer daemon's), skipped: how
    /// many, and the last one's type.
    pub unknown_lines: (u64, Option<String>),
    /// The daemon's wall estimates (`estimate` lines), the newest last, bounded by the
    /// history window.
    pub estimates: EstimateHistory,
    history_s: f64,
    pending: BTreeMap<u64, &'static str>,
}

impl LiveState {
    /// Nothing received yet; `history_s` is the history window, seconds.
    fn new(history_s: f64) -> Self {
        Self {
            connection: ConnectionState::Connecting { attempt: 1 },
            history: History::new(0, 1),
            rig: None,
            segment_addresses: Vec::new(),
            status: None,
            lagged_dropped: 0,
            lagged_samples_dropped: 0,
            replies: Vec::new(),
            connections: 0,
            bad_lines: (0, None),
            unknown_lines: (0, None),
            estimates: EstimateHistory::new(history_s, (history_s * 1000.0).ceil() as usize),
            history_s,
            pending: BTreeMap::new(),
        }
    }

    /// The history window, seconds.
    pub fn history_s(&self) -> f64 {
        self.history_s
    }

    fn capacity(&self) -> usize {
        let hz = self.rig.as_ref().map_or(1000.0, |r| r.poll_hz);
        (self.history_s * hz).ceil().max(1.0) as usize
    }

    /// Bounds the samples and the estimates by the history window (estimates come at most
    /// once a poll).
    fn apply_window(&mut self) {
        let capacity = self.capacity();
        self.history.set_capacity(capacity);
        self.estimates.set_window(self.history_s, capacity);
    }
}

/// What one line of the stream is.
#[derive(Debug)]
enum Line {
    /// A message this monitor reads.
    Message(StreamMessage),
    /// A message of a type it does not know (its `type`): skipped.
    Unknown(String),
    /// Not a message of the protocol (why).
    Bad(String),
}

/// Reads one line (without or with its newline).
fn parse_line(line: &[u8]) -> Line {
    match serde_json::from_slice::<StreamMessage>(line) {
        Ok(message) => Line::Message(message),
        Err(e) => {
            // Only on failure: is it an object whose `type` names a message not known here?
            let kind = serde_json::from_slice::<serde_json::Value>(line)
                .ok()
                .and_then(|v| v.get("type")?.as_str().map(str::to_owned));
            match kind {
                Some(kind) if !KNOWN_TYPES.contains(&kind.as_str()) => Line::Unknown(kind),
                _ => Line::Bad(e.to_string()),
            }
        }
    }
}

/// Applies one parsed line to `state`; an error ends the connection.
fn on_line(state: &mut LiveState, line: Line, greeted: &mut bool) -> Result<(), String> {
    match line {
        Line::Message(message) => on_message(state, message, greeted)?,
        Line::Unknown(kind) => {
            state.unknown_lines.0 += 1;
            state.unknown_lines.1 = Some(kind);
        }
        Line::Bad(error) => {
            state.bad_lines.0 += 1;
            state.bad_lines.1 = Some(error);
        }
    }
    Ok(())
}

/// The stream client (see the module documentation).
#[derive(Debug)]
pub struct LiveClient {
    address: String,
    shared: Arc<Mutex<LiveState>>,
    outgoing: Sender<String>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    next_id: u64,
}

impl LiveClient {
    /// Starts the reader thread; returns at once (the connection is made on that thread).
    pub fn connect(options: ClientOptions) -> Result<Self, MonitorError> {
        let state = LiveState::new(options.history_s);
        let shared = Arc::new(Mutex::new(state));
        let stop = Arc::new(AtomicBool::new(false));
        let (outgoing, requests) = channel();
        let address = options.address.clone();
        let thread = {
            let shared = Arc::clone(&shared);
            let stop = Arc::clone(&stop);
            std::thread::Builder::new()
                .name("monitor-stream".to_owned())
                .spawn(move || reader_loop(&options, &shared, &stop, &requests))
                .map_err(|e| MonitorError::Control(format!("starting the stream thread: {e}")))?
        };
        Ok(Self {
            address,
            shared,
            outgoing,
            stop,
            thread: Some(thread),
            next_id: 1,
        })
    }

    /// The daemon's address.
    pub fn address(&self) -> &str {
        &self.address
    }

    /// The shared state, locked (briefly, please: the reader thread waits meanwhile).
    pub fn lock(&self) -> MutexGuard<'_, LiveState> {
        self.shared
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// Changes the history window (keeps the newest samples that fit).
    pub fn set_history_s(&self, history_s: f64) {
        let mut state = self.lock();
        state.history_s = history_s.max(0.001);
        state.apply_window();
    }

    /// Sends a control command with `token`; returns its request id. Refused here, with
    /// nothing sent, without a connection, or without a token for a command that needs one
    /// (`stop_all` needs none).
    pub fn send(&mut self, command: &Command, token: &str) -> Result<u64, MonitorError> {
        if token.is_empty() && command.needs_token() {
            return Err(MonitorError::Control(format!(
                "{}: no token; control commands need the daemon's token (antennad prints it \
                 at start)",
                command.name()
            )));
        }
        let id = self.next_id;
        {
            let mut state = self
                .shared
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            if !matches!(state.connection, ConnectionState::Connected { .. }) {
                return Err(MonitorError::Control(format!(
                    "{}: not connected to {}",
                    command.name(),
                    self.address
                )));
            }
            state.pending.insert(id, command.name());
        }
        self.next_id += 1;
        let line = command.request_line(id, token)?;
        self.outgoing
            .send(line)
            .map_err(|_| MonitorError::Control("the stream thread has stopped".to_owned()))?;
        Ok(id)
    }
}

impl Drop for LiveClient {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

fn reader_loop(
    options: &ClientOptions,
    shared: &Mutex<LiveState>,
    stop: &AtomicBool,
    requests: &Receiver<String>,
) {
    let lock = || {
        shared
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    };
    let mut backoff = options.backoff_min;
    let mut attempt = 1;
    while !stop.load(Ordering::Relaxed) {
        lock().connection = ConnectionState::Connecting { attempt };
        let error = match open(&options.address, options.connect_timeout) {
            Ok(stream) => {
                attempt = 1;
                backoff = options.backoff_min;
                serve(stream, shared, stop, requests)
            }
            Err(e) => e,
        };
        if stop.load(Ordering::Relaxed) {
            return;
        }
        // Requests written to a dead connection get no reply: say so.
        while requests.try_recv().is_ok() {}
        {
            let mut state = lock();
            let lost: Vec<(u64, &'static str)> =
                std::mem::take(&mut state.pending).into_iter().collect();
            for (id, command) in lost {
                push_reply(
                    &mut state,
                    ReplyRecord {
                        id: Some(id),
                        command: Some(command.to_owned()),
                        ok: false,
                        message: "no reply: the connection was lost".to_owned(),
                        error: None,
                    },
                );
            }
            state.connection = ConnectionState::Disconnected {
                error: format!("{}: {error}", options.address),
                retry_at: Instant::now() + backoff,
            };
        }
        let until = Instant::now() + backoff;
        while Instant::now() < until && !stop.load(Ordering::Relaxed) {
            std::thread::sleep(Duration::from_millis(10).min(until - Instant::now()));
        }
        backoff = (backoff * 2).min(options.backoff_max);
        attempt += 1;
    }
}

fn open(address: &str, timeout: Duration) -> Result<TcpStream, String> {
    let addrs: Vec<_> = address
        .to_socket_addrs()
        .map_err(|e| format!("cannot resolve the address: {e}"))?
        .collect();
    let mut last = "the address resolves to nothing".to_owned();
    for addr in addrs {
        match TcpStream::connect_timeout(&addr, timeout) {
            Ok(stream) => return Ok(stream),
            Err(e) => last = format!("cannot connect: {e}"),
        }
    }
    Err(last)
}

/// Reads one connection until it fails or `stop`; returns why it ended.
fn serve(
    stream: TcpStream,
    shared: &Mutex<LiveState>,
    stop: &AtomicBool,
    requests: &Receiver<String>,
) -> String {
    let lock = || {
        shared
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    };
    if let Err(e) = stream.set_read_timeout(Some(READ_POLL)) {
        return format!("configuring the socket: {e}");
    }
    let _ = stream.set_nodelay(true);
    let mut writer = match stream.try_clone() {
        Ok(w) => w,
        Err(e) => return format!("configuring the socket: {e}"),
    };
    let _ = writer.set_write_timeout(Some(Duration::from_secs(2)));
    let mut reader = BufReader::with_capacity(1 << 16, stream);
    let mut line = Vec::with_capacity(4096);
    let mut greeted = false;
    loop {
        if stop.load(Ordering::Relaxed) {
            return "stopped".to_owned();
        }
        if greeted {
            while let Ok(request) = requests.try_recv() {
                if let Err(e) = writer
                    .write_all(request.as_bytes())
                    .and_then(|()| writer.write_all(b"\n"))
                {
                    return format!("sending a control request: {e}");
                }
            }
        }
        match reader.read_until(b'\n', &mut line) {
            Ok(0) => return "the daemon closed the connection".to_owned(),
            Ok(_) if line.last() == Some(&b'\n') => {
                let parsed = parse_line(&line);
                line.clear();
                let mut state = lock();
                if let Err(e) = on_line(&mut state, parsed, &mut greeted) {
                    return e;
                }
            }
            // A partial line: the rest comes with the next read.
            Ok(_) => {}
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {}
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) => return format!("reading the stream: {e}"),
        }
    }
}

fn on_message(
    state: &mut LiveState,
    message: StreamMessage,
    greeted: &mut bool,
) -> Result<(), String> {
    match message {
        StreamMessage::Hello {
            daemon,
            segment_count,
            segment_addresses,
            rig,
            ..
        } => {
            let geometry = match rig {
                Some(rig) => RigGeometry::from_rig_info(&rig, format!("{daemon} hello")),
                None => RigGeometry::fallback(segment_count),
            }
            .or_else(|_| RigGeometry::fallback(segment_count))
            .map_err(|e| format!("the daemon's hello: {e}"))?;
            if geometry.segment_count() != segment_count {
                return Err(format!(
                    "the daemon's hello: {segment_count} segments but a rig of {} links after \
                     the base link",
                    geometry.segment_count()
                ));
            }
            if state.history.segment_count() != segment_count {
                state.history = History::new(segment_count, 1);
            }
            state.rig = Some(geometry);
            state.apply_window();
            state.segment_addresses = segment_addresses;
            state.connections += 1;
            state.connection = ConnectionState::Connected { daemon };
            *greeted = true;
        }
        StreamMessage::Samples {
            seq,
            t_ns,
            segments,
            stage_position_m,
            base_angle_deg,
        } => {
            if !*greeted {
                return Err("samples before hello: not an antennad stream".to_owned());
            }
            let sample = Sample {
                seq: Some(seq),
                t_s: t_ns as f64 * 1e-9,
                segments: segments.iter().map(reading).collect(),
                stage_position_m,
                servo_angle_rad: base_angle_deg.map(f64::to_radians),
            };
            if state
                .history
                .latest_t_s()
                .is_some_and(|latest| sample.t_s < latest)
            {
                // A new daemon (its clock restarted): start the history afresh, and the
                // estimates (the old daemon's times mean nothing on the new clock).
                let capacity = state.history.capacity();
                state.history = History::new(state.history.segment_count(), capacity);
                state.estimates.clear();
            }
            state
                .history
                .push(&sample)
                .map_err(|e| format!("samples line {seq}: {e}"))?;
        }
        StreamMessage::Status {
            t_ns,
            trial,
            segments,
            note,
            ..
        } => {
            state.status = Some(DaemonStatus {
                t_s: t_ns as f64 * 1e-9,
                trial,
                segments,
                note,
            });
        }
        StreamMessage::Lagged {
            dropped,
            samples_dropped,
        } => {
            state.lagged_dropped += dropped;
            state.lagged_samples_dropped += samples_dropped;
        }
        StreamMessage::Estimate(estimate) => {
            if !*greeted {
                return Err("estimate before hello: not an antennad stream".to_owned());
            }
            state.estimates.push(Estimate::from(estimate));
        }
        StreamMessage::Reply(reply) => {
            let command = reply
                .id
                .and_then(|id| state.pending.remove(&id))
                .map(str::to_owned);
            let error = reply.error.map(|e| {
                serde_json::to_value(e)
                    .ok()
                    .and_then(|v| v.as_str().map(str::to_owned))
                    .unwrap_or_else(|| format!("{e:?}"))
            });
            push_reply(
                state,
                ReplyRecord {
                    id: reply.id,
                    command,
                    ok: reply.ok,
                    message: reply.message,
                    error,
                },
            );
        }
    }
    Ok(())
}

fn push_reply(state: &mut LiveState, record: ReplyRecord) {
    if state.replies.len() >= REPLIES_KEPT {
        state.replies.remove(0);
    }
    state.replies.push(record);
}

fn reading(s: &SegmentSample) -> SegmentReading {
    let health = match s.error.as_deref() {
        None if s.stale => Health::Stale,
        None => Health::Ok,
        Some("nack") => Health::Nack,
        Some("pec") => Health::Pec,
        Some(_) => Health::Bus,
    };
    // The four bits as the segment sent them; from an older daemon, which sends only
    // `contact`, a contact as all four.
    let touch_bits = match (s.touch_bits, s.contact) {
        (Some(bits), _) => Some(bits & TOUCH_BITS_MASK),
        (None, contact) => contact.map(|c| if c { TOUCH_BITS_MASK } else { 0 }),
    };
    SegmentReading {
        angle_rad: s.angle_rad,
        touch_bits,
        health,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use antenna_data::stream::{ControlCommand, Request, RequestEnvelope, StageTarget};

    /// Feeds stream lines to a fresh state as the reader thread does.
    fn receive(lines: &[&str]) -> LiveState {
        let mut state = LiveState::new(1.0);
        let mut greeted = false;
        for line in lines {
            on_line(&mut state, parse_line(line.as_bytes()), &mut greeted).unwrap();
        }
        state
    }

    const HELLO: &str = r#"{"type":"hello","protocol_version":1,"daemon":"antennad 0.1.0","segment_count":2,"segment_addresses":[33,34]}"#;

    fn samples_line(seq: u64) -> String {
        format!(
            r#"{{"type":"samples","seq":{seq},"t_ns":{},"segments":[{{"address":33,"angle_rad":0.1,"contact":false,"touch_bits":0,"counter":null,"error":null}},{{"address":34,"angle_rad":0.2,"contact":false,"touch_bits":0,"counter":null,"error":null}}],"stage_position_m":0.1,"base_angle_deg":0.0}}"#,
            seq * 1_000_000
        )
    }

    /// A newer daemon's message type between samples is skipped and counted, not a protocol
    /// error: the samples after it keep coming in.
    #[test]
    fn a_message_type_not_known_is_skipped_and_counted() {
        let (first, second) = (samples_line(1), samples_line(2));
        let state = receive(&[HELLO, &first, r#"{"type":"future_thing","x":1}"#, &second]);
        assert_eq!(state.history.len(), 2);
        assert_eq!(state.history.sample(1).unwrap().seq, Some(2));
        assert_eq!(state.unknown_lines, (1, Some("future_thing".to_owned())));
        assert_eq!(state.bad_lines.0, 0);
        assert!(matches!(
            state.connection,
            ConnectionState::Connected { .. }
        ));
    }

    /// A line of a type known here that does not read, a line without a `type` and one that
    /// is not JSON are protocol errors (counted, the connection goes on), not unknown types.
    #[test]
    fn known_types_that_do_not_read_are_bad_lines() {
        for kind in KNOWN_TYPES {
            let line = format!(r#"{{"type":"{kind}","seq":"not a number"}}"#);
            assert!(
                matches!(parse_line(line.as_bytes()), Line::Bad(_)),
                "{line}"
            );
        }
        for line in [r#"{"x":1}"#, "not json", r#"{"type":3}"#] {
            assert!(
                matches!(parse_line(line.as_bytes()), Line::Bad(_)),
                "{line}"
            );
        }
        let first = samples_line(1);
        let state = receive(&[HELLO, &first, r#"{"type":"samples","seq":"x"}"#]);
        assert_eq!(state.bad_lines.0, 1);
        assert_eq!(state.unknown_lines.0, 0);
        assert_eq!(state.history.len(), 1);
    }

    /// `lagged` counts the messages dropped and, of them, the polls (an older daemon's line
    /// without `samples_dropped` counts none).
    #[test]
    fn lagged_counts_the_polls_dropped_apart() {
        let state = receive(&[
            HELLO,
            r#"{"type":"lagged","dropped":5,"samples_dropped":3}"#,
            r#"{"type":"lagged","dropped":2}"#,
        ]);
        assert_eq!(state.lagged_dropped, 7);
        assert_eq!(state.lagged_samples_dropped, 3);
    }

    /// A new daemon (its samples' clock restarted) starts the estimates afresh too.
    #[test]
    fn a_new_daemons_samples_clear_the_estimates() {
        let (late, early) = (samples_line(500), samples_line(2));
        let state = receive(&[
            HELLO,
            &late,
            r#"{"type":"estimate","seq":500,"t_ns":500000000,"estimated_ns":500000100,"estimator":"bend","distance_m":0.3,"angle_rad":null,"preview_m":0.05}"#,
            &early,
        ]);
        assert_eq!(state.history.len(), 1);
        assert!(state.estimates.is_empty());
        assert_eq!(state.estimates.received(), 1);
    }

    /// Every message this monitor reads has its type among [`KNOWN_TYPES`].
    #[test]
    fn the_known_types_are_the_messages_read() {
        let estimate = r#"{"type":"estimate","seq":2,"t_ns":2000000,"estimated_ns":2000100,"estimator":"bend","distance_m":0.3,"angle_rad":null,"preview_m":0.05}"#;
        let lagged = r#"{"type":"lagged","dropped":3,"samples_dropped":2}"#;
        let reply = r#"{"type":"reply","id":1,"ok":true,"message":"ok"}"#;
        let status = r#"{"type":"status","t_ns":1,"trial":null,"segments":[],"note":null}"#;
        let first = samples_line(1);
        for line in [HELLO, first.as_str(), estimate, lagged, reply, status] {
            let Line::Message(message) = parse_line(line.as_bytes()) else {
                panic!("{line} does not read");
            };
            let value = serde_json::to_value(&message).unwrap();
            assert!(KNOWN_TYPES.contains(&value["type"].as_str().unwrap()));
        }
    }

    /// `estimate` lines are kept, the newest last; one without an estimate says why, and one
    /// before `hello` ends the connection as samples do.
    #[test]
    fn estimates_are_kept_with_their_reason() {
        let first = samples_line(1);
        let state = receive(&[
            HELLO,
            &first,
            r#"{"type":"estimate","seq":1,"t_ns":1000000,"estimated_ns":1000050,"estimator":"contact-line","distance_m":null,"angle_rad":null,"preview_m":null,"reason":"no contact in the window","true_distance_m":0.31}"#,
            r#"{"type":"estimate","seq":1,"t_ns":1000000,"estimated_ns":1000080,"estimator":"contact-line","distance_m":0.3,"angle_rad":0.1,"preview_m":0.05,"true_distance_m":0.31,"true_angle_rad":0.1}"#,
        ]);
        assert_eq!(state.estimates.len(), 2);
        let first = state.estimates.iter().next().unwrap();
        assert_eq!(first.reason.as_deref(), Some("no contact in the window"));
        assert!(!first.has_estimate());
        let latest = state.estimates.latest().unwrap();
        assert_eq!(latest.distance_m, Some(0.3));
        assert!((latest.error_m().unwrap() + 0.01).abs() < 1e-12);
        assert!((latest.t_s - 1e-3).abs() < 1e-15);
        let mut state = LiveState::new(1.0);
        let mut greeted = false;
        let early = parse_line(
            br#"{"type":"estimate","seq":1,"t_ns":1,"estimated_ns":2,"estimator":"bend","distance_m":0.3,"angle_rad":null,"preview_m":0.0}"#,
        );
        let error = on_line(&mut state, early, &mut greeted).unwrap_err();
        assert!(error.contains("estimate before hello"), "{error}");
    }

    /// An older daemon's lines (no `rig` in `hello`; no `touch_bits`, no `stale` in
    /// `samples`) still parse and fill the history, a contact as all four bits.
    #[test]
    fn an_older_daemons_samples_without_touch_bits_still_parse() {
        let state = receive(&[
            r#"{"type":"hello","protocol_version":1,"daemon":"antennad 0.0.9","segment_count":2,"segment_addresses":[33,34]}"#,
            r#"{"type":"samples","seq":7,"t_ns":7000000,"segments":[{"address":33,"angle_rad":0.1,"contact":true,"counter":null,"error":null},{"address":34,"angle_rad":null,"contact":null,"counter":null,"error":"nack"}],"stage_position_m":null,"base_angle_deg":null}"#,
            r#"{"type":"samples","seq":8,"t_ns":8000000,"segments":[{"address":33,"angle_rad":0.1,"contact":false,"counter":null,"error":null},{"address":34,"angle_rad":0.2,"contact":false,"counter":null,"error":null}],"stage_position_m":null,"base_angle_deg":null}"#,
        ]);
        assert_eq!(state.bad_lines.0, 0);
        assert_eq!(state.history.len(), 2);
        let first = state.history.sample(0).unwrap();
        assert_eq!(first.segments[0].touch_bits, Some(0x0F));
        assert_eq!(first.segments[0].health, Health::Ok);
        assert_eq!(first.segments[1].touch_bits, None);
        assert_eq!(first.segments[1].health, Health::Nack);
        let second = state.history.sample(1).unwrap();
        assert_eq!(second.segments[0].touch_bits, Some(0));
        assert_eq!(second.segments[1].touch_bits, Some(0));
    }

    /// A sample whose second segment sends `touch_bits` 4 (`0b0100`) lights exactly switch 2
    /// of that segment in the chain frame, 5/8 of the way along its link; `touch_bits` wins
    /// over `contact`.
    #[test]
    fn touch_bits_0b0100_light_exactly_switch_2_of_their_segment() {
        let state = receive(&[
            r#"{"type":"hello","protocol_version":1,"daemon":"antennad 0.1.0","segment_count":3,"segment_addresses":[33,34,35]}"#,
            r#"{"type":"samples","seq":1,"t_ns":1000000,"segments":[{"address":33,"angle_rad":0.1,"contact":false,"touch_bits":0,"counter":null,"error":null,"stale":false},{"address":34,"angle_rad":-0.2,"contact":true,"touch_bits":4,"counter":null,"error":null,"stale":false},{"address":35,"angle_rad":0.0,"contact":true,"touch_bits":0,"counter":null,"error":null,"stale":false}],"stage_position_m":0.1,"base_angle_deg":0.0}"#,
        ]);
        let sample = state.history.sample(0).unwrap();
        assert_eq!(
            sample
                .segments
                .iter()
                .map(|s| s.touch_bits)
                .collect::<Vec<_>>(),
            [Some(0), Some(0b0100), Some(0)]
        );
        let rig = state.rig.as_ref().unwrap();
        let frame = rig.frame_at(&state.history, 0).unwrap();
        let lit = frame.lit_switches();
        assert_eq!(
            lit.iter()
                .map(|l| (l.segment, l.switch))
                .collect::<Vec<_>>(),
            [(1, 2)]
        );
        // On segment 2's link (link 2, from joint 2 to joint 3), 5/8 of the way along it.
        let (a, b) = frame.link_m(2).unwrap();
        let expected = [a[0] + 0.625 * (b[0] - a[0]), a[1] + 0.625 * (b[1] - a[1])];
        let p = lit[0].point_m;
        assert!(
            (p[0] - expected[0]).hypot(p[1] - expected[1]) < 1e-12,
            "{p:?} {expected:?}"
        );
        assert!(frame.segments[1].touched() && !frame.segments[2].touched());
    }

    #[test]
    fn request_lines_follow_the_protocol() {
        let line = Command::MoveStage { position_m: 0.1 }
            .request_line(3, "s3cret")
            .unwrap();
        let v: serde_json::Value = serde_json::from_str(&line).unwrap();
        assert_eq!(v["cmd"], "move_stage");
        assert_eq!(v["position_m"], 0.1);
        assert_eq!(v["token"], "s3cret");
        assert_eq!(v["id"], 3);
        assert_eq!(
            Command::StopAll.request_line(5, "").unwrap(),
            r#"{"id":5,"cmd":"stop_all"}"#
        );
        assert!(!Command::StopAll.needs_token() && Command::Auth.needs_token());
        let line = Command::StartTrial {
            name: "wall-sweep".to_owned(),
        }
        .request_line(4, "t")
        .unwrap();
        assert!(line.contains(r#""name":"wall-sweep""#), "{line}");
        // Every line is one the daemon's parser accepts, as the command it was.
        let commands = [
            (
                Command::StartTrial {
                    name: "wall-sweep".to_owned(),
                },
                ControlCommand::StartTrial {
                    name: "wall-sweep".to_owned(),
                    metadata: BTreeMap::new(),
                },
            ),
            (Command::StopTrial, ControlCommand::StopTrial),
            (
                Command::MoveStage { position_m: 0.1 },
                ControlCommand::MoveStage {
                    target: StageTarget::Absolute { position_m: 0.1 },
                    speed_m_per_s: None,
                },
            ),
            (
                Command::SetBaseAngle { angle_deg: -12.5 },
                ControlCommand::SetBaseAngle { angle_deg: -12.5 },
            ),
            (Command::StopAll, ControlCommand::StopAll),
        ];
        for (command, expected) in commands {
            let line = command.request_line(7, "t").unwrap();
            let envelope = RequestEnvelope::parse(line.as_bytes()).unwrap();
            assert_eq!(envelope.id(), Some(7));
            assert_eq!(envelope.cmd(), command.name());
            assert_eq!(envelope.command().unwrap(), Request::Control(expected));
        }
        let auth = RequestEnvelope::parse(Command::Auth.request_line(8, "t").unwrap().as_bytes());
        assert_eq!(auth.unwrap().command().unwrap(), Request::Auth);
    }

    #[test]
    fn unreachable_daemon_is_reported_and_retried() {
        // A port nobody listens on: bind, note it, close.
        let port = std::net::TcpListener::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap()
            .port();
        let mut options = ClientOptions::new(format!("127.0.0.1:{port}"));
        options.backoff_min = Duration::from_millis(20);
        options.backoff_max = Duration::from_millis(40);
        let mut client = LiveClient::connect(options).unwrap();
        // Generous: only a hang takes this long, however loaded the machine.
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            let state = client.lock();
            if let ConnectionState::Disconnected { error, .. } = &state.connection {
                assert!(error.contains("cannot connect"), "{error}");
                break;
            }
            drop(state);
            assert!(Instant::now() < deadline);
            std::thread::sleep(Duration::from_millis(5));
        }
        let err = client.send(&Command::StopAll, "t").unwrap_err().to_string();
        assert!(err.contains("not connected"), "{err}");
        // Stopping needs no token: only the connection is missing.
        let err = client.send(&Command::StopAll, "").unwrap_err().to_string();
        assert!(err.contains("not connected"), "{err}");
        let err = client
            .send(&Command::StopTrial, "")
            .unwrap_err()
            .to_string();
        assert!(err.contains("no token"), "{err}");
    }
}
