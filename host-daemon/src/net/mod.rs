//! The TCP server of the stream and control protocol (`antenna_data::stream`,
//! `docs/stream-protocol.md`): a stream of samples to any number of read-only clients, and
//! control commands guarded by a token ([`ControlToken`]): failed tries slowed per address
//! ([`auth_throttle`]), `stop_all` open to anyone connected, and room for an operator
//! however many readers there are ([`admission`]).
//!
//! The daemon converts its samples into [`StreamMessage::Samples`], hands them to
//! [`StreamServer::publish`] (which never blocks on a socket) and implements
//! [`ControlHandler`].
//!
//! # Example
//!
//! ```
//! use std::sync::Arc;
//! use antenna_data::stream::StreamMessage;
//! use host_daemon::net::{ControlToken, RecordingHandler, StreamServer};
//!
//! let token = ControlToken::new("s3cret-s3cret-s3cret").expect("long enough");
//! let server = StreamServer::bind("127.0.0.1:0", token, Arc::new(RecordingHandler::new()))
//!     .expect("bind");
//! let queued = server.publish(&StreamMessage::Lagged { dropped: 0, samples_dropped: 0 });
//! assert_eq!(queued, 0); // nobody is connected yet
//! server.shutdown();
//! ```
//!
//! [`StreamMessage::Samples`]: antenna_data::stream::StreamMessage::Samples

pub mod admission;
pub mod auth_throttle;
mod connection;
mod control;
mod fake_handler;
pub mod foxglove;
mod server;
mod server_log;

pub use crate::config::token::{ControlToken, GENERATED_TOKEN_BYTES, MIN_TOKEN_CHARS, TokenError};
pub use auth_throttle::AuthPolicy;
pub use control::{AuthOutcome, ControlHandler, Served, serve_request};
pub use fake_handler::RecordingHandler;
pub use server::{DEFAULT_BIND, ServerError, ServerOptions, StreamServer};
pub use server_log::ServerLog;
