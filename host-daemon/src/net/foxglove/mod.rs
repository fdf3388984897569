//! The Foxglove WebSocket server (issue #48): the antenna live in Foxglove, view-only.
//!
//! The hub hands every stream message to [`FoxgloveLive::publish`] beside the TCP server;
//! the server itself is being written (this module is its place in the layering).

use antenna_data::stream::StreamMessage;

/// A running Foxglove server.
#[derive(Debug)]
pub struct FoxgloveLive {}

impl FoxgloveLive {
    /// Publishes one stream message on the channels it feeds (never blocks).
    pub fn publish(&mut self, message: &StreamMessage) {
        let _ = message;
    }
}
