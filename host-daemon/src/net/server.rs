//! The TCP server: one accept thread, and per client a reader thread (control requests) and a
//! writer thread draining a bounded queue, so that [`StreamServer::publish`] never touches a
//! socket.

use std::io::{self, BufReader, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::{self, JoinHandle};
use std::time::{Duration, Instant};

use antenna_data::stream::{
    ControlReply, ErrorCode, LineRead, MAX_LINE_BYTES, PROTOCOL_VERSION, RigInfo, StreamMessage,
    encode_line, read_line_capped,
};

use super::control::{ControlHandler, serve_request};
use super::token::ControlToken;

/// The address the daemon listens on unless configured otherwise: loopback only.
pub const DEFAULT_BIND: &str = "127.0.0.1:7878";

/// How often the accept thread looks for new clients and for the stop flag.
const ACCEPT_POLL: Duration = Duration::from_millis(20);

/// Server settings; `Default` gives the documented values.
#[derive(Debug, Clone)]
pub struct ServerOptions {
    /// Messages queued per client before further ones are dropped for it (default 1024).
    pub queue_capacity: usize,
    /// A client that stays behind for this long is disconnected (default 5 s): its socket
    /// accepted no bytes, or messages were dropped for it and its queue has not drained to
    /// half its capacity since.
    pub write_timeout: Duration,
    /// Connections beyond this many are refused with an error line (default 32).
    pub max_clients: usize,
    /// Sent in [`StreamMessage::Hello`].
    pub segment_addresses: Vec<u8>,
    /// Sent in [`StreamMessage::Hello`], e.g. `"antennad 0.1.0"`.
    pub daemon: String,
    /// Sent in [`StreamMessage::Hello`]: the rig's geometry, if known.
    pub rig: Option<RigInfo>,
}

impl Default for ServerOptions {
    fn default() -> Self {
        Self {
            queue_capacity: 1024,
            write_timeout: Duration::from_secs(5),
            max_clients: 32,
            segment_addresses: Vec::new(),
            daemon: format!("antennad {}", env!("CARGO_PKG_VERSION")),
            rig: None,
        }
    }
}

/// Errors starting the server.
#[derive(Debug, thiserror::Error)]
pub enum ServerError {
    /// Binding or configuring the listening socket failed.
    #[error("cannot listen on {addr}: {source}")]
    Bind {
        /// The requested address.
        addr: String,
        /// The underlying error.
        source: io::Error,
    },
    /// A thread could not be spawned.
    #[error("cannot start the server thread: {0}")]
    Spawn(io::Error),
    /// Invalid options.
    #[error("invalid server option: {0}")]
    Options(&'static str),
}

/// What a client's writer sends.
enum Outgoing {
    /// One encoded line, shared by every client it goes to.
    Line(Arc<[u8]>),
    /// Flush and close the connection.
    Close,
}

struct Client {
    sender: SyncSender<Outgoing>,
    stream: TcpStream,
    /// Messages dropped since the last one queued for this client.
    dropped: u64,
    /// When a message was first dropped, if the queue has not drained to half since.
    lagging_since: Option<Instant>,
    /// Lines queued and not yet written (shared with the writer and reader threads).
    pending: Arc<AtomicUsize>,
    /// Set once the server has shut this connection down; it is reaped soon after.
    disconnected: bool,
    writer: JoinHandle<()>,
    reader: JoinHandle<()>,
}

struct Shared {
    clients: Mutex<Vec<Client>>,
    stop: AtomicBool,
}

impl Shared {
    fn clients(&self) -> MutexGuard<'_, Vec<Client>> {
        // A panic while holding the lock leaves the list consistent (every step is a single
        // push, remove or counter update), so a poisoned lock is still usable.
        self.clients.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// A running server. Dropping it shuts it down, as does [`StreamServer::shutdown`].
///
/// Policy for slow clients: each client has a queue of [`ServerOptions::queue_capacity`]
/// messages. When it is full, further messages are dropped for that client only and counted;
/// the count reaches the client as a [`StreamMessage::Lagged`] line just before the next message
/// it does get. A client that stays behind for [`ServerOptions::write_timeout`] (its socket
/// accepts no bytes, or it keeps losing messages without its queue draining to half) is
/// disconnected. Control replies are never dropped.
pub struct StreamServer {
    local_addr: SocketAddr,
    write_timeout: Duration,
    queue_capacity: usize,
    shared: Arc<Shared>,
    accept: Option<JoinHandle<()>>,
}

impl std::fmt::Debug for StreamServer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StreamServer")
            .field("local_addr", &self.local_addr)
            .finish_non_exhaustive()
    }
}

impl StreamServer {
    /// Listens on `addr` with [`ServerOptions::default`].
    ///
    /// # Errors
    /// See [`StreamServer::bind_with`].
    pub fn bind(
        addr: impl ToSocketAddrs + std::fmt::Debug,
        token: ControlToken,
        handler: Arc<dyn ControlHandler>,
    ) -> Result<Self, ServerError> {
        Self::bind_with(addr, token, handler, ServerOptions::default())
    }

    /// Listens on `addr` (use [`DEFAULT_BIND`] unless configured otherwise) and starts the
    /// accept thread.
    ///
    /// # Errors
    /// [`ServerError::Bind`] if the address cannot be bound, [`ServerError::Options`] for a zero
    /// queue capacity, write timeout or client limit, [`ServerError::Spawn`] if no thread starts.
    pub fn bind_with(
        addr: impl ToSocketAddrs + std::fmt::Debug,
        token: ControlToken,
        handler: Arc<dyn ControlHandler>,
        options: ServerOptions,
    ) -> Result<Self, ServerError> {
        if options.queue_capacity == 0 {
            return Err(ServerError::Options("queue_capacity must be at least 1"));
        }
        if options.write_timeout.is_zero() {
            return Err(ServerError::Options("write_timeout must be positive"));
        }
        if options.max_clients == 0 {
            return Err(ServerError::Options("max_clients must be at least 1"));
        }
        let bind_err = |source| ServerError::Bind {
            addr: format!("{addr:?}"),
            source,
        };
        let listener = TcpListener::bind(&addr).map_err(bind_err)?;
        listener.set_nonblocking(true).map_err(bind_err)?;
        let local_addr = listener.local_addr().map_err(bind_err)?;
        let shared = Arc::new(Shared {
            clients: Mutex::new(Vec::new()),
            stop: AtomicBool::new(false),
        });
        let write_timeout = options.write_timeout;
        let queue_capacity = options.queue_capacity;
        let accept = {
            let shared = Arc::clone(&shared);
            let ctx = ClientContext {
                token: Arc::new(token),
                handler,
                options: Arc::new(options),
            };
            thread::Builder::new()
                .name("net-accept".into())
                .spawn(move || accept_loop(&listener, &shared, &ctx))
                .map_err(ServerError::Spawn)?
        };
        Ok(Self {
            local_addr,
            write_timeout,
            queue_capacity,
            shared,
            accept: Some(accept),
        })
    }

    /// The address actually bound (useful with port 0).
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    /// Queues `message` for every connected client. Never blocks on a socket: it encodes the
    /// message once and does one non-blocking queue push per client. Returns how many clients
    /// it was queued for.
    pub fn publish(&self, message: &StreamMessage) -> usize {
        let Ok(line) = encode_line(message) else {
            // Unreachable for these types (serde_json writes non-finite floats as null).
            return 0;
        };
        let line: Arc<[u8]> = line.into();
        let mut queued = 0;
        for client in self.shared.clients().iter_mut() {
            if client.disconnected {
                continue;
            }
            if client.dropped > 0 {
                let notice = StreamMessage::Lagged {
                    dropped: client.dropped,
                };
                let Ok(notice) = encode_line(&notice) else {
                    continue;
                };
                match self.try_queue(client, notice.into()) {
                    Ok(()) => client.dropped = 0,
                    Err(_) => {
                        self.lag(client);
                        continue;
                    }
                }
            }
            match self.try_queue(client, Arc::clone(&line)) {
                Ok(()) => queued += 1,
                Err(TrySendError::Full(())) => self.lag(client),
                Err(TrySendError::Disconnected(())) => {} // reaped by the accept thread
            }
        }
        queued
    }

    /// Queues one line without blocking; a lagging client counts as caught up once its queue
    /// has drained to half its capacity.
    fn try_queue(&self, client: &mut Client, line: Arc<[u8]>) -> Result<(), TrySendError<()>> {
        let before = client.pending.fetch_add(1, Ordering::SeqCst);
        match client.sender.try_send(Outgoing::Line(line)) {
            Ok(()) => {
                if before <= self.queue_capacity / 2 {
                    client.lagging_since = None;
                }
                Ok(())
            }
            Err(e) => {
                client.pending.fetch_sub(1, Ordering::SeqCst);
                Err(match e {
                    TrySendError::Full(_) => TrySendError::Full(()),
                    TrySendError::Disconnected(_) => TrySendError::Disconnected(()),
                })
            }
        }
    }

    /// Counts a dropped message; disconnects the client once it has been lagging for the
    /// write timeout (`shutdown` is a non-blocking system call; the writer then ends).
    fn lag(&self, client: &mut Client) {
        client.dropped += 1;
        let since = *client.lagging_since.get_or_insert_with(Instant::now);
        if since.elapsed() > self.write_timeout {
            let _ = client.stream.shutdown(Shutdown::Both);
            client.disconnected = true;
        }
    }

    /// How many clients are connected (including ones about to be reaped).
    pub fn client_count(&self) -> usize {
        self.shared.clients().len()
    }

    /// Stops accepting, disconnects every client and joins all the server's threads.
    pub fn shutdown(mut self) {
        self.stop_and_join();
    }

    fn stop_and_join(&mut self) {
        self.shared.stop.store(true, Ordering::SeqCst);
        if let Some(accept) = self.accept.take() {
            // The accept thread disconnects and joins every client before it returns.
            let _ = accept.join();
        }
    }
}

impl Drop for StreamServer {
    fn drop(&mut self) {
        self.stop_and_join();
    }
}

struct ClientContext {
    token: Arc<ControlToken>,
    handler: Arc<dyn ControlHandler>,
    options: Arc<ServerOptions>,
}

fn accept_loop(listener: &TcpListener, shared: &Shared, ctx: &ClientContext) {
    let mut finishing: Vec<JoinHandle<()>> = Vec::new();
    while !shared.stop.load(Ordering::SeqCst) {
        match listener.accept() {
            Ok((stream, _peer)) => {
                let full = shared.clients().len() >= ctx.options.max_clients;
                if full {
                    refuse(stream, ctx.options.max_clients);
                } else if let Ok(client) = start_client(stream, ctx) {
                    shared.clients().push(client);
                }
                continue; // look for more pending connections right away
            }
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => {}
            Err(_) => {} // e.g. ECONNABORTED or EMFILE: keep serving the others
        }
        reap(shared, &mut finishing);
        thread::sleep(ACCEPT_POLL);
    }
    let clients = std::mem::take(&mut *shared.clients());
    for client in clients {
        let _ = client.stream.shutdown(Shutdown::Both);
        drop(client.sender);
        finishing.push(client.writer);
        finishing.push(client.reader);
    }
    for handle in finishing {
        let _ = handle.join();
    }
}

/// Removes clients whose threads have both ended (the connection is over) and joins threads.
fn reap(shared: &Shared, finishing: &mut Vec<JoinHandle<()>>) {
    {
        let mut clients = shared.clients();
        let mut i = 0;
        while i < clients.len() {
            if clients[i].writer.is_finished() && clients[i].reader.is_finished() {
                let client = clients.swap_remove(i);
                finishing.push(client.writer);
                finishing.push(client.reader);
            } else {
                i += 1;
            }
        }
    }
    let mut i = 0;
    while i < finishing.len() {
        if finishing[i].is_finished() {
            let _ = finishing.swap_remove(i).join();
        } else {
            i += 1;
        }
    }
}

fn refuse(mut stream: TcpStream, max_clients: usize) {
    let reply = StreamMessage::Reply(ControlReply::error(
        None,
        ErrorCode::TooManyClients,
        format!("the server already has {max_clients} clients"),
    ));
    let _ = stream.set_nonblocking(true);
    if let Ok(line) = encode_line(&reply) {
        let _ = stream.write_all(&line);
    }
    let _ = stream.shutdown(Shutdown::Both);
}

fn start_client(stream: TcpStream, ctx: &ClientContext) -> io::Result<Client> {
    stream.set_nonblocking(false)?;
    stream.set_nodelay(true)?;
    stream.set_write_timeout(Some(ctx.options.write_timeout))?;
    let (sender, receiver) = sync_channel(ctx.options.queue_capacity);
    let pending = Arc::new(AtomicUsize::new(0));
    let hello = StreamMessage::Hello {
        protocol_version: PROTOCOL_VERSION,
        daemon: ctx.options.daemon.clone(),
        segment_count: ctx.options.segment_addresses.len(),
        segment_addresses: ctx.options.segment_addresses.clone(),
        rig: ctx.options.rig.clone(),
    };
    if let Ok(line) = encode_line(&hello) {
        // The queue is empty and has room for at least one message.
        pending.fetch_add(1, Ordering::SeqCst);
        let _ = sender.try_send(Outgoing::Line(line.into()));
    }
    let write_half = stream.try_clone()?;
    let read_half = stream.try_clone()?;
    let writer = {
        let pending = Arc::clone(&pending);
        thread::Builder::new()
            .name("net-writer".into())
            .spawn(move || writer_loop(write_half, &receiver, &pending))?
    };
    let reader = {
        let sender = sender.clone();
        let token = Arc::clone(&ctx.token);
        let handler = Arc::clone(&ctx.handler);
        let pending = Arc::clone(&pending);
        thread::Builder::new()
            .name("net-reader".into())
            .spawn(move || reader_loop(read_half, &sender, &pending, &token, handler.as_ref()))
    };
    let reader = match reader {
        Ok(r) => r,
        Err(e) => {
            let _ = stream.shutdown(Shutdown::Both);
            drop(sender);
            let _ = writer.join();
            return Err(e);
        }
    };
    Ok(Client {
        sender,
        stream,
        dropped: 0,
        lagging_since: None,
        pending,
        disconnected: false,
        writer,
        reader,
    })
}

/// Writes queued lines until the queue is closed, a write fails or times out (then the whole
/// connection is shut down, which also ends the reader), or `Close` (then only the sending
/// side is closed, after everything queued before it).
fn writer_loop(mut stream: TcpStream, receiver: &Receiver<Outgoing>, pending: &AtomicUsize) {
    while let Ok(item) = receiver.recv() {
        match item {
            Outgoing::Line(line) => {
                if stream.write_all(&line).is_err() {
                    break;
                }
                pending.fetch_sub(1, Ordering::SeqCst);
            }
            Outgoing::Close => {
                let _ = stream.flush();
                let _ = stream.shutdown(Shutdown::Write);
                return;
            }
        }
    }
    let _ = stream.shutdown(Shutdown::Both);
}

/// Reads request lines and queues their replies (blocking only this client when its queue is
/// full). Ends at end of input, on a read error, or after an over-long line.
fn reader_loop(
    stream: TcpStream,
    sender: &SyncSender<Outgoing>,
    pending: &AtomicUsize,
    token: &ControlToken,
    handler: &dyn ControlHandler,
) {
    let mut reader = BufReader::new(stream);
    loop {
        let reply = match read_line_capped(&mut reader, MAX_LINE_BYTES) {
            Ok(LineRead::Line(line)) if line.iter().all(u8::is_ascii_whitespace) => continue,
            Ok(LineRead::Line(line)) => serve_request(&line, token, handler),
            Ok(LineRead::TooLong) => {
                let reply = ControlReply::error(
                    None,
                    ErrorCode::LineTooLong,
                    format!("lines are limited to {MAX_LINE_BYTES} bytes; closing"),
                );
                let _ = send_reply(sender, pending, reply);
                let _ = sender.send(Outgoing::Close);
                drain_before_close(reader.get_mut());
                return;
            }
            // End of input: a read-only client may close its sending side and keep reading.
            Ok(LineRead::Eof) | Err(_) => return,
        };
        if send_reply(sender, pending, reply).is_err() {
            return;
        }
    }
}

fn send_reply(
    sender: &SyncSender<Outgoing>,
    pending: &AtomicUsize,
    reply: ControlReply,
) -> Result<(), ()> {
    let line = encode_line(&StreamMessage::Reply(reply)).map_err(|_| ())?;
    pending.fetch_add(1, Ordering::SeqCst);
    sender.send(Outgoing::Line(line.into())).map_err(|_| {
        pending.fetch_sub(1, Ordering::SeqCst);
    })
}

/// Reads and discards what the client is still sending (at most [`DRAIN_BYTES`], waiting at
/// most [`DRAIN_WAIT`] per read), so that closing the socket does not reset the connection and
/// destroy the error reply before the client has read it.
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
