//! The TCP server: one accept thread, and per client a reader thread (control requests) and a
//! writer thread draining a bounded queue, so that [`StreamServer::publish`] never touches a
//! socket.
//!
//! # Who may connect, and who may control
//!
//! Watching needs nothing. Every command needs the token except `stop_all`, which anyone
//! connected may send and which the daemon carries out ahead of any other work. Failed
//! authentications are slowed per address and logged with it, and a connection that fails
//! [`super::AuthPolicy::max_failures_per_connection`] times is closed
//! ([`super::auth_throttle`]). The number of connections is capped, in all and per address;
//! when a cap is reached, a new connection takes the place of the oldest one that never
//! proved the token, so an operator can always connect and control however many readers
//! there are ([`super::admission`]).

use std::io::{self, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::{TrySendError, sync_channel};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::{self, JoinHandle};
use std::time::{Duration, Instant};

use antenna_data::stream::{
    ControlReply, ErrorCode, PROTOCOL_VERSION, RigInfo, StreamMessage, encode_line,
};

use super::admission::{Admission, Occupant, admit};
use super::auth_throttle::{AuthPolicy, AuthThrottle};
use super::connection::{self, Link, Outgoing, PRIORITY_CAPACITY};
use super::control::ControlHandler;
use super::server_log::ServerLog;
use crate::config::token::ControlToken;

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
    /// Connections at most (default 32); see the module documentation for who makes room.
    pub max_clients: usize,
    /// Connections from one address at most (default 16).
    pub max_clients_per_peer: usize,
    /// How failed authentications are slowed.
    pub auth: AuthPolicy,
    /// Sent in [`StreamMessage::Hello`].
    pub segment_addresses: Vec<u8>,
    /// Sent in [`StreamMessage::Hello`], e.g. `"antennad 0.1.0"`.
    pub daemon: String,
    /// Sent in [`StreamMessage::Hello`]: the rig's geometry, if known.
    pub rig: Option<RigInfo>,
    /// Where the server's notices go (failed authentications, `stop_all`, connections
    /// dropped or refused), each naming the peer's address.
    pub log: ServerLog,
}

impl Default for ServerOptions {
    fn default() -> Self {
        Self {
            queue_capacity: 1024,
            write_timeout: Duration::from_secs(5),
            max_clients: 32,
            max_clients_per_peer: 16,
            auth: AuthPolicy::default(),
            segment_addresses: Vec::new(),
            daemon: format!("antennad {}", env!("CARGO_PKG_VERSION")),
            rig: None,
            log: ServerLog::default(),
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

struct Client {
    /// Smaller is older.
    id: u64,
    link: Link,
    stream: TcpStream,
    connected_at: Instant,
    /// Messages dropped since the last one queued for this client.
    dropped: u64,
    /// How many of those were samples (the `seq` gap the client sees).
    samples_dropped: u64,
    /// When a message was first dropped, if the queue has not drained to half since.
    lagging_since: Option<Instant>,
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
/// disconnected. Control replies are never dropped, and go out ahead of the stream lines
/// queued before them.
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
        if options.max_clients == 0 || options.max_clients_per_peer == 0 {
            return Err(ServerError::Options(
                "max_clients and max_clients_per_peer must be at least 1",
            ));
        }
        if options.auth.max_failures_per_connection == 0 {
            return Err(ServerError::Options(
                "auth.max_failures_per_connection must be at least 1",
            ));
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
                connection: Arc::new(connection::Shared {
                    token: Arc::new(token),
                    handler,
                    throttle: Arc::new(AuthThrottle::new(options.auth)),
                    log: options.log.clone(),
                }),
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
        let samples = matches!(message, StreamMessage::Samples { .. });
        let mut queued = 0;
        for client in self.shared.clients().iter_mut() {
            if client.disconnected {
                continue;
            }
            if client.dropped > 0 {
                let notice = StreamMessage::Lagged {
                    dropped: client.dropped,
                    samples_dropped: client.samples_dropped,
                };
                let Ok(notice) = encode_line(&notice) else {
                    continue;
                };
                match self.try_queue(client, notice.into()) {
                    Ok(()) => {
                        client.dropped = 0;
                        client.samples_dropped = 0;
                    }
                    Err(_) => {
                        self.lag(client, samples);
                        continue;
                    }
                }
            }
            match self.try_queue(client, Arc::clone(&line)) {
                Ok(()) => queued += 1,
                Err(TrySendError::Full(())) => self.lag(client, samples),
                Err(TrySendError::Disconnected(())) => {} // reaped by the accept thread
            }
        }
        queued
    }

    /// Queues one line without blocking; a lagging client counts as caught up once its queue
    /// has drained to half its capacity.
    fn try_queue(&self, client: &mut Client, line: Arc<[u8]>) -> Result<(), TrySendError<()>> {
        let before = client.link.pending.fetch_add(1, Ordering::SeqCst);
        match client.link.sender.try_send(Outgoing::Line(line)) {
            Ok(()) => {
                if before <= self.queue_capacity / 2 {
                    client.lagging_since = None;
                }
                Ok(())
            }
            Err(e) => {
                client.link.pending.fetch_sub(1, Ordering::SeqCst);
                Err(match e {
                    TrySendError::Full(_) => TrySendError::Full(()),
                    TrySendError::Disconnected(_) => TrySendError::Disconnected(()),
                })
            }
        }
    }

    /// Counts a dropped message; disconnects the client once it has been lagging for the
    /// write timeout (`shutdown` is a non-blocking system call; the writer then ends).
    fn lag(&self, client: &mut Client, samples: bool) {
        client.dropped += 1;
        client.samples_dropped += u64::from(samples);
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

    /// How many connected clients have proved the token.
    pub fn operator_count(&self) -> usize {
        self.shared
            .clients()
            .iter()
            .filter(|c| !c.disconnected && c.link.authenticated.load(Ordering::SeqCst))
            .count()
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
    connection: Arc<connection::Shared>,
    options: Arc<ServerOptions>,
}

fn accept_loop(listener: &TcpListener, shared: &Shared, ctx: &ClientContext) {
    let mut finishing: Vec<JoinHandle<()>> = Vec::new();
    let mut next_id = 0u64;
    while !shared.stop.load(Ordering::SeqCst) {
        match listener.accept() {
            Ok((stream, peer)) => {
                next_id += 1;
                admit_client(stream, peer, next_id, shared, ctx);
                // Under a flood of connections too, dropped ones leave the list.
                reap(shared, &mut finishing);
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
        drop(client.link);
        finishing.push(client.writer);
        finishing.push(client.reader);
    }
    for handle in finishing {
        let _ = handle.join();
    }
}

/// Lets a new connection in, dropping another for it if a cap is reached, or refuses it.
fn admit_client(
    stream: TcpStream,
    peer: SocketAddr,
    id: u64,
    shared: &Shared,
    ctx: &ClientContext,
) {
    let log = &ctx.connection.log;
    let mut clients = shared.clients();
    let occupants: Vec<Occupant> = clients
        .iter()
        .filter(|c| !c.disconnected)
        .map(|c| Occupant {
            id: c.id,
            ip: c.link.peer.ip(),
            authenticated: c.link.authenticated.load(Ordering::SeqCst),
        })
        .collect();
    let options = &ctx.options;
    match admit(
        &occupants,
        peer.ip(),
        options.max_clients,
        options.max_clients_per_peer,
    ) {
        Admission::Admit => {}
        Admission::Evict(victim) => {
            if let Some(client) = clients.iter_mut().find(|c| c.id == victim) {
                log.notice(format!(
                    "dropped {} (connected {:.1} s, no token proved) to make room for {peer}",
                    client.link.peer,
                    client.connected_at.elapsed().as_secs_f64()
                ));
                evict(client, peer);
            }
        }
        Admission::Refuse(why) => {
            drop(clients);
            log.notice(format!("refused {peer}: {why}"));
            refuse(stream, &why);
            return;
        }
    }
    // Threads are started without the list locked (publish never waits for a spawn); only
    // this thread adds clients, so the admission stands.
    drop(clients);
    match start_client(stream, peer, id, ctx) {
        Ok(client) => shared.clients().push(client),
        Err(e) => log.notice(format!("could not serve {peer}: {e}")),
    }
}

/// Tells a client why it is dropped and closes its connection.
fn evict(client: &mut Client, for_peer: SocketAddr) {
    client.link.evicted.store(true, Ordering::SeqCst);
    client.disconnected = true;
    let reply = StreamMessage::Reply(ControlReply::error(
        None,
        ErrorCode::Evicted,
        format!(
            "the server is full: this connection, the oldest that never proved the token, \
             makes room for {for_peer}; closing"
        ),
    ));
    let queued = encode_line(&reply).is_ok_and(|line| {
        client.link.priority.try_send(line.into()).is_ok()
            && client.link.sender.try_send(Outgoing::CloseNow).is_ok()
    });
    if !queued {
        let _ = client.stream.shutdown(Shutdown::Both);
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

fn refuse(mut stream: TcpStream, why: &str) {
    let reply = StreamMessage::Reply(ControlReply::error(
        None,
        ErrorCode::TooManyClients,
        format!("{why}; closing"),
    ));
    let _ = stream.set_nonblocking(true);
    if let Ok(line) = encode_line(&reply) {
        let _ = stream.write_all(&line);
    }
    let _ = stream.shutdown(Shutdown::Both);
}

fn start_client(
    stream: TcpStream,
    peer: SocketAddr,
    id: u64,
    ctx: &ClientContext,
) -> io::Result<Client> {
    stream.set_nonblocking(false)?;
    stream.set_nodelay(true)?;
    stream.set_write_timeout(Some(ctx.options.write_timeout))?;
    let (sender, receiver) = sync_channel(ctx.options.queue_capacity);
    let (priority, priority_receiver) = sync_channel(PRIORITY_CAPACITY);
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
    let link = Link {
        peer,
        sender,
        priority,
        pending: Arc::clone(&pending),
        authenticated: Arc::new(AtomicBool::new(false)),
        evicted: Arc::new(AtomicBool::new(false)),
    };
    let write_half = stream.try_clone()?;
    let read_half = stream.try_clone()?;
    let writer = thread::Builder::new()
        .name("net-writer".into())
        .spawn(move || {
            connection::writer_loop(write_half, &receiver, &priority_receiver, &pending)
        })?;
    let reader = {
        let reader_link = link.clone();
        let shared = Arc::clone(&ctx.connection);
        thread::Builder::new()
            .name("net-reader".into())
            .spawn(move || connection::reader_loop(read_half, &reader_link, &shared))
    };
    let reader = match reader {
        Ok(r) => r,
        Err(e) => {
            let _ = stream.shutdown(Shutdown::Both);
            drop(link);
            let _ = writer.join();
            return Err(e);
        }
    };
    Ok(Client {
        id,
        link,
        stream,
        connected_at: Instant::now(),
        dropped: 0,
        samples_dropped: 0,
        lagging_since: None,
        disconnected: false,
        writer,
        reader,
    })
}
