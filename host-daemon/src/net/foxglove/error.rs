//! [`FoxgloveError`]: why the Foxglove server did not start.

/// Why [`super::FoxgloveLive::start`] failed.
#[derive(Debug, thiserror::Error)]
pub enum FoxgloveError {
    /// antennad was built without the cargo feature `foxglove`.
    #[error(
        "this antennad was built without the Foxglove server (cargo feature `foxglove`, on by \
         default; the board builds of scripts/cross without it); leave `[foxglove] enabled` out \
         or set it to false"
    )]
    NotBuilt,
    /// `[foxglove] listen` is not an address and port.
    #[error("not an address:port, got {0:?}")]
    Address(String),
    /// The server's runtime (its worker thread) could not be made.
    #[error("starting the Foxglove server's thread: {0}")]
    Runtime(#[source] std::io::Error),
    /// The port could not be bound (in use, not an address of this machine, not allowed).
    #[error("cannot listen on {listen}: {reason}")]
    Bind {
        /// The address asked for.
        listen: String,
        /// What the operating system or the server said.
        reason: String,
    },
    /// A channel could not be made.
    #[error("the Foxglove channel {topic}: {reason}")]
    Channel {
        /// Its topic.
        topic: String,
        /// What the SDK said.
        reason: String,
    },
}
