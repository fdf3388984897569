//! The TCP interface: a stream of samples to any number of read-only clients, and control
//! commands guarded by a token.
//!
//! The wire format is newline-delimited JSON, documented with examples in
//! `docs/stream-protocol.md`: the server sends [`StreamMessage`]s, a client may send
//! [`ControlRequest`]s and gets a [`StreamMessage::Reply`] for each. The types here do not
//! depend on the daemon's internals; the daemon converts its samples into
//! [`StreamMessage::Samples`], hands them to [`StreamServer::publish`] (which never blocks on
//! a socket) and implements [`ControlHandler`].
//!
//! # Example
//!
//! ```
//! use std::sync::Arc;
//! use host_daemon::net::{ControlToken, RecordingHandler, StreamMessage, StreamServer};
//!
//! let token = ControlToken::new("s3cret").expect("non-empty");
//! let server = StreamServer::bind("127.0.0.1:0", token, Arc::new(RecordingHandler::new()))
//!     .expect("bind");
//! let queued = server.publish(&StreamMessage::Lagged { dropped: 0 });
//! assert_eq!(queued, 0); // nobody is connected yet
//! server.shutdown();
//! ```

mod control;
mod fake_handler;
mod framing;
mod message;
mod server;
mod token;

pub use control::{
    COMMAND_NAMES, ControlCommand, ControlHandler, ControlRequest, StageTarget, WireCommand,
    serve_request,
};
pub use fake_handler::RecordingHandler;
pub use framing::{LineRead, MAX_LINE_BYTES, encode_line, read_line_capped};
pub use message::{
    ControlReply, ErrorCode, PROTOCOL_VERSION, RigInfo, RigWall, SegmentSample, SegmentStatus,
    StreamMessage,
};
pub use server::{DEFAULT_BIND, ServerError, ServerOptions, StreamServer};
pub use token::{ControlToken, EmptyToken};
