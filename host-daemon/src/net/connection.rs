//! One client's two threads: the writer drains the client's queues (control replies first,
//! then the stream), the reader serves the client's requests, slowing failed
//! authentications ([`super::auth_throttle`]) and closing the connection after too many.

use std::io::{BufReader, Write};
use std::net::{Shutdown, SocketAddr, TcpStream};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TryRecvError};
use std::time::{Duration, Instant};

use antenna_data::stream::{
    ControlReply, ErrorCode, LineRead, MAX_LINE_BYTES, StreamMessage, encode_line, read_line_capped,
};

use super::auth_throttle::AuthThrottle;
use super::control::{AuthOutcome, ControlHandler, serve_request};
use super::server_log::ServerLog;
use crate::config::token::ControlToken;

/// Control replies queued for one client at most before its reader waits.
pub const PRIORITY_CAPACITY: usize = 64;

/// What a client's writer is told through its stream queue.
pub enum Outgoing {
    /// One encoded line, shared by every client it goes to.
    Line(Arc<[u8]>),
    /// A reply is waiting in the priority queue.
    Wake,
    /// Write what is queued, then close the sending side.
    Close,
    /// Write what is queued, then close the connection (the server dropped it).
    CloseNow,
}

/// What the reader of every client shares.
pub struct Shared {
    pub token: Arc<ControlToken>,
    pub handler: Arc<dyn ControlHandler>,
    pub throttle: Arc<AuthThrottle>,
    pub log: ServerLog,
}

/// One client's state that its threads and the server share.
#[derive(Clone)]
pub struct Link {
    pub peer: SocketAddr,
    pub sender: SyncSender<Outgoing>,
    pub priority: SyncSender<Arc<[u8]>>,
    /// Stream lines queued and not yet written.
    pub pending: Arc<AtomicUsize>,
    /// The client proved the token.
    pub authenticated: Arc<AtomicBool>,
    /// The server dropped the client: serve nothing more.
    pub evicted: Arc<AtomicBool>,
}

impl Link {
    /// Queues a reply ahead of the stream; waits only when this client already has
    /// [`PRIORITY_CAPACITY`] replies unwritten.
    pub fn send_reply(&self, reply: ControlReply) -> Result<(), ()> {
        let line = encode_line(&StreamMessage::Reply(reply)).map_err(|_| ())?;
        self.priority.send(line.into()).map_err(|_| ())?;
        // The writer may be waiting on the stream queue: wake it. A full queue means it is
        // busy and looks at the replies before its next line anyway.
        let _ = self.sender.try_send(Outgoing::Wake);
        Ok(())
    }
}

/// Writes queued lines, replies first, until the queue is closed, a write fails or times out
/// (then the whole connection is shut down, which also ends the reader), or `Close`.
pub fn writer_loop(
    mut stream: TcpStream,
    receiver: &Receiver<Outgoing>,
    priority: &Receiver<Arc<[u8]>>,
    pending: &AtomicUsize,
) {
    let write_replies = |stream: &mut TcpStream| -> Result<(), ()> {
        loop {
            match priority.try_recv() {
                Ok(line) => stream.write_all(&line).map_err(|_| ())?,
                Err(TryRecvError::Empty | TryRecvError::Disconnected) => return Ok(()),
            }
        }
    };
    while let Ok(item) = receiver.recv() {
        if write_replies(&mut stream).is_err() {
            break;
        }
        match item {
            Outgoing::Line(line) => {
                if stream.write_all(&line).is_err() {
                    break;
                }
                pending.fetch_sub(1, Ordering::SeqCst);
            }
            Outgoing::Wake => {}
            Outgoing::Close => {
                let _ = stream.flush();
                let _ = stream.shutdown(Shutdown::Write);
                return;
            }
            Outgoing::CloseNow => {
                let _ = stream.flush();
                break;
            }
        }
    }
    let _ = stream.shutdown(Shutdown::Both);
}

/// Reads request lines and queues their replies. Ends at end of input, on a read error,
/// after an over-long line, after too many failed authentications, or once evicted.
pub fn reader_loop(stream: TcpStream, link: &Link, shared: &Shared) {
    let mut reader = BufReader::new(stream);
    let mut failures_here = 0u32;
    let policy = *shared.throttle.policy();
    loop {
        let read = read_line_capped(&mut reader, MAX_LINE_BYTES);
        if link.evicted.load(Ordering::SeqCst) {
            return;
        }
        let line = match read {
            Ok(LineRead::Line(line)) if line.iter().all(u8::is_ascii_whitespace) => continue,
            Ok(LineRead::Line(line)) => line,
            Ok(LineRead::TooLong) => {
                let reply = ControlReply::error(
                    None,
                    ErrorCode::LineTooLong,
                    format!("lines are limited to {MAX_LINE_BYTES} bytes; closing"),
                );
                close_with(reader.get_mut(), link, reply);
                return;
            }
            // End of input: a read-only client may close its sending side and keep reading.
            Ok(LineRead::Eof) | Err(_) => return,
        };
        let served = serve_request(&line, &shared.token, shared.handler.as_ref());
        if served.stop_all {
            shared.log.line(format!(
                "stop_all from {} (no token needed): {}",
                link.peer, served.reply.message
            ));
        }
        match served.auth {
            AuthOutcome::NotAsked => {}
            AuthOutcome::Proved => {
                if !link.authenticated.swap(true, Ordering::SeqCst) {
                    shared.throttle.success(link.peer.ip());
                    shared
                        .log
                        .line(format!("{} proved the control token", link.peer));
                }
            }
            AuthOutcome::Failed => {
                failures_here += 1;
                let failure = shared.throttle.failure(link.peer.ip(), Instant::now());
                shared.log.line(format!(
                    "authentication failed from {} ({} in a row from {}, {} on this \
                     connection; answered after {} ms)",
                    link.peer,
                    failure.failures_from_peer,
                    link.peer.ip(),
                    failures_here,
                    failure
                        .answer_at
                        .saturating_duration_since(Instant::now())
                        .as_millis()
                ));
                sleep_until(failure.answer_at);
                if failures_here >= policy.max_failures_per_connection {
                    shared.log.line(format!(
                        "closing {}: {failures_here} failed authentications on one connection",
                        link.peer
                    ));
                    let _ = link.send_reply(served.reply);
                    let reply = ControlReply::error(
                        None,
                        ErrorCode::TooManyFailures,
                        format!("{failures_here} failed authentications; closing"),
                    );
                    close_with(reader.get_mut(), link, reply);
                    return;
                }
            }
        }
        if link.send_reply(served.reply).is_err() {
            return;
        }
    }
}

fn sleep_until(at: Instant) {
    let now = Instant::now();
    if at > now {
        std::thread::sleep(at - now);
    }
}

/// Sends `reply`, closes the sending side after it and drains what the client still sends,
/// so that closing does not reset the connection before the client has read the reply.
fn close_with(stream: &mut TcpStream, link: &Link, reply: ControlReply) {
    let _ = link.send_reply(reply);
    let _ = link.sender.send(Outgoing::Close);
    drain_before_close(stream);
}

/// Reads and discards what the client is still sending (at most [`DRAIN_BYTES`], waiting at
/// most [`DRAIN_WAIT`] per read).
fn drain_before_close(stream: &mut TcpStream) {
    use std::io::Read;
    if stream.set_read_timeout(Some(DRAIN_WAIT)).is_err() {
        return;
    }
    let mut scratch = [0u8; 8192];
    let mut total = 0;
    while total < DRAIN_BYTES {
        match stream.read(&mut scratch) {
            Ok(0) | Err(_) => return,
            Ok(n) => total += n,
        }
    }
}

/// See [`drain_before_close`].
const DRAIN_BYTES: usize = 1 << 20;
/// See [`drain_before_close`].
const DRAIN_WAIT: Duration = Duration::from_millis(500);
