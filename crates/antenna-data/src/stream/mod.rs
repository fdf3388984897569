//! The live stream and control protocol: newline-delimited JSON over TCP, documented with
//! examples in `docs/stream-protocol.md`.
//!
//! The server sends [`StreamMessage`]s, one per line; a client may send control requests
//! ([`ControlRequest`], read by a server with [`RequestEnvelope`]) and gets a
//! [`StreamMessage::Reply`] for each. The server itself (sockets, the token, who may connect)
//! is `antennad`'s (`host_daemon::net`).
//!
//! # Example
//!
//! ```
//! use antenna_data::stream::{ControlCommand, Request, RequestEnvelope};
//!
//! let envelope = RequestEnvelope::parse(br#"{"id":1,"cmd":"stop_all"}"#)?;
//! assert!(!envelope.needs_token());
//! assert_eq!(envelope.command()?, Request::Control(ControlCommand::StopAll));
//! # Ok::<(), antenna_data::stream::ControlReply>(())
//! ```

mod framing;
mod message;
mod request;

pub use framing::{LineRead, MAX_LINE_BYTES, encode_line, read_line_capped};
pub use message::{
    ControlReply, ErrorCode, EstimateMessage, PROTOCOL_VERSION, PollingStatus, RigInfo,
    SegmentSample, SegmentStatus, StreamMessage,
};
pub use request::{
    COMMAND_NAMES, ControlCommand, ControlRequest, Request, RequestEnvelope, STOP_ALL, StageTarget,
    WireCommand,
};
