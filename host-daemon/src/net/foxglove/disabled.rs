//! [`FoxgloveLive`] in an antennad built without the cargo feature `foxglove`: a type with no
//! value, so the hub's `Option<FoxgloveLive>` is always `None` and costs nothing.

use super::error::FoxgloveError;
use crate::config::Config;
use antenna_data::stream::StreamMessage;
use std::net::SocketAddr;

/// No Foxglove server: this antennad was built without it (it cannot be started).
#[derive(Debug)]
pub enum FoxgloveLive {}

impl FoxgloveLive {
    /// Always [`FoxgloveError::NotBuilt`].
    ///
    /// # Errors
    /// Always.
    pub fn start(config: &Config, unix_origin_ns: u64) -> Result<Self, FoxgloveError> {
        let _ = (config, unix_origin_ns);
        Err(FoxgloveError::NotBuilt)
    }

    /// Never called (there is no value).
    pub fn local_addr(&self) -> SocketAddr {
        match *self {}
    }

    /// Never called (there is no value).
    pub fn client_count(&self) -> usize {
        match *self {}
    }

    /// Never called (there is no value).
    pub fn publish(&mut self, message: &StreamMessage) {
        let _ = message;
        match *self {}
    }

    /// Never called (there is no value).
    pub fn stop(self) {
        match self {}
    }
}
