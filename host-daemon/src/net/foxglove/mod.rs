//! The Foxglove WebSocket server (issue #48): the antenna live in Foxglove, view-only
//! (`docs/foxglove.md`).
//!
//! The hub hands every stream message to [`FoxgloveLive::publish`] beside the TCP server.
//! The server (the Foxglove SDK's, cargo feature `foxglove`, on by default) runs on a runtime
//! of its own and advertises no capability: clients subscribe, and cannot publish, call
//! services or set parameters (control stays on the token-protected TCP port). Its channels:
//!
//! | topic | encoding, schema | what |
//! |---|---|---|
//! | `/antenna/transforms` | protobuf, `foxglove.FrameTransforms` | `world` -> `carriage` -> `link_0` .. `link_n`, at `[foxglove] scene_hz` |
//! | `/antenna/scene` | protobuf, `foxglove.SceneUpdate` | the links, their touch switches (coloured when closed), the walls (simulated rig), the estimated wall: whole to a new subscriber and every 2 s, between at `scene_hz` what changed |
//! | `/antenna/samples` | json, [`schemas::SAMPLES_SCHEMA`] | every poll: the stream's `samples` line |
//! | `/antenna/status` | json, [`schemas::STATUS_SCHEMA`] | the stream's `status` line |
//! | `/antenna/estimate` | json, [`schemas::ESTIMATE_SCHEMA`] | the stream's `estimate` line |
//!
//! Every message's log time and time stamp is the Unix-epoch time of its poll (the daemon's
//! clock origin plus its `t_ns`), so a poll's samples and its transforms carry the same log
//! time. A message is encoded only for a channel somebody subscribed to. The frames and the
//! scene are `antenna_data::foxglove`'s, the same as the recordings carry; the chain is
//! [`chain_model`] of the configuration.
//!
//! Built without the feature, [`FoxgloveLive`] has no value and [`FoxgloveLive::start`]
//! fails with [`FoxgloveError::NotBuilt`].

#[cfg(feature = "foxglove")]
mod channels;
#[cfg(not(feature = "foxglove"))]
mod disabled;
mod error;
mod model;
pub mod schemas;
#[cfg(feature = "foxglove")]
mod server;

#[cfg(not(feature = "foxglove"))]
pub use disabled::FoxgloveLive;
pub use error::FoxgloveError;
pub use model::chain_model;
#[cfg(feature = "foxglove")]
pub use server::{FoxgloveLive, MESSAGE_BACKLOG};

/// Whether this antennad was built with the Foxglove server (cargo feature `foxglove`).
pub const BUILT: bool = cfg!(feature = "foxglove");
