//! [`FoxgloveLive`]: the Foxglove SDK's WebSocket server on its own runtime, view-only.

use super::channels::{ChannelSettings, Channels};
use super::error::FoxgloveError;
use super::model::chain_model;
use super::schemas::SCENE_TOPIC;
use crate::config::{Config, WallSideName};
use antenna_data::stream::StreamMessage;
use foxglove::websocket::{ChannelView, Client, ServerListener};
use foxglove::{Context, WebSocketServerHandle};
use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// Messages queued per client before its oldest are dropped (a client that does not read
/// loses messages, never the daemon's time): about half a second of samples at 1 kHz.
pub const MESSAGE_BACKLOG: usize = 512;
/// How long stopping waits for the clients' tasks to end before aborting them.
const STOP_WAIT: Duration = Duration::from_secs(1);

/// Flags the walls as due when a client subscribes to the scene.
struct SceneSubscriptions(Arc<AtomicBool>);

impl ServerListener for SceneSubscriptions {
    fn on_subscribe(&self, _client: Client, channel: ChannelView) {
        if channel.topic() == SCENE_TOPIC {
            self.0.store(true, Ordering::Relaxed);
        }
    }
}

/// A running Foxglove WebSocket server: view-only (no capability advertised: clients cannot
/// publish, call services or set parameters), its channels in a context of their own, on a
/// runtime of its own (one worker thread, `antennad-foxglove`), never on the polling thread.
/// [`FoxgloveLive::publish`] never blocks: a slow client's queue drops its oldest messages.
pub struct FoxgloveLive {
    runtime: Option<tokio::runtime::Runtime>,
    server: Option<WebSocketServerHandle>,
    local_addr: SocketAddr,
    channels: Channels,
    /// The channels' context: the server holds it weakly (it must outlive the server).
    context: Arc<Context>,
}

impl std::fmt::Debug for FoxgloveLive {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FoxgloveLive")
            .field("local_addr", &self.local_addr)
            .finish_non_exhaustive()
    }
}

impl FoxgloveLive {
    /// Starts the server of `config`'s `[foxglove]` on `listen` (port 0: any free port, see
    /// [`Self::local_addr`]), drawing `config`'s chain ([`super::chain_model`]);
    /// `unix_origin_ns` is the Unix-epoch time of the daemon's clock origin (the messages'
    /// time stamps are this plus their `t_ns`).
    ///
    /// # Errors
    /// The address is not one, the port cannot be bound, or the runtime cannot be made.
    pub fn start(config: &Config, unix_origin_ns: u64) -> Result<Self, FoxgloveError> {
        let listen = &config.foxglove.listen;
        let addr: SocketAddr = listen
            .parse()
            .map_err(|_| FoxgloveError::Address(listen.clone()))?;
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .max_blocking_threads(1)
            .thread_name("antennad-foxglove")
            .enable_all()
            .build()
            .map_err(FoxgloveError::Runtime)?;
        let context = Context::new();
        let walls_due = Arc::new(AtomicBool::new(true));
        let scene_hz = config.foxglove.scene_hz;
        let channels = Channels::new(
            &context,
            ChannelSettings {
                model: chain_model(config),
                unix_origin_ns,
                scene_period_ns: if scene_hz.is_finite() && scene_hz > 0.0 {
                    (1e9 / scene_hz) as u64
                } else {
                    0
                },
                wall_on_left: config.estimate.wall_side == WallSideName::Left,
            },
            Arc::clone(&walls_due),
        )?;
        let host = match addr {
            SocketAddr::V4(v4) => v4.ip().to_string(),
            SocketAddr::V6(v6) => format!("[{}]", v6.ip()),
        };
        let server = context
            .websocket_server()
            .name("antennad")
            .bind(host, addr.port())
            .capabilities([])
            .message_backlog_size(MESSAGE_BACKLOG)
            .listener(Arc::new(SceneSubscriptions(walls_due)));
        let handle = runtime
            .block_on(server.start())
            .map_err(|e| FoxgloveError::Bind {
                listen: listen.clone(),
                reason: e.to_string(),
            })?;
        let local_addr = SocketAddr::new(addr.ip(), handle.port());
        Ok(Self {
            runtime: Some(runtime),
            server: Some(handle),
            local_addr,
            channels,
            context,
        })
    }

    /// The address actually bound.
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    /// Clients connected now.
    pub fn client_count(&self) -> usize {
        self.server
            .as_ref()
            .map_or(0, WebSocketServerHandle::client_count)
    }

    /// Publishes one stream message on the channels it feeds (never blocks; encodes only
    /// for channels somebody subscribed to).
    pub fn publish(&mut self, message: &StreamMessage) {
        self.channels.publish(message);
    }

    /// Stops the server: the channels closed, the clients told and, after at most a second,
    /// their tasks aborted; then the runtime's thread ends.
    pub fn stop(mut self) {
        self.shut_down();
    }

    fn shut_down(&mut self) {
        self.channels.close();
        let Some(runtime) = self.runtime.take() else {
            return;
        };
        if let Some(server) = self.server.take() {
            let shutdown = server.stop();
            let _ =
                runtime.block_on(async { tokio::time::timeout(STOP_WAIT, shutdown.wait()).await });
        }
        runtime.shutdown_timeout(STOP_WAIT);
        // The channels leave the context with it.
        let _ = &self.context;
    }
}

impl Drop for FoxgloveLive {
    fn drop(&mut self) {
        self.shut_down();
    }
}
