//! Errors of recording and reading trials.

use std::path::PathBuf;

/// Why a trial could not be recorded or read.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// The file could not be created, written or read.
    #[error("{path}: {source}")]
    Io {
        /// The trial file.
        path: PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
    /// The MCAP writer failed.
    #[error("{path}: MCAP: {source}")]
    Mcap {
        /// The trial file.
        path: PathBuf,
        /// What the MCAP library said.
        source: mcap::McapError,
    },
    /// A message could not be encoded or decoded as JSON.
    #[error("{path}: {topic}: {source}")]
    Json {
        /// The trial file.
        path: PathBuf,
        /// The channel.
        topic: String,
        /// What serde_json said.
        source: serde_json::Error,
    },
    /// A Foxglove message could not be encoded.
    #[error("{path}: {topic}: {source}")]
    Foxglove {
        /// The trial file.
        path: PathBuf,
        /// The channel.
        topic: String,
        /// What the encoder said.
        source: crate::foxglove::EncodeError,
    },
    /// A time stamp was negative or not finite (or a start time not a Unix time).
    #[error("{path}: time {t_s} s is not a finite time since the trial started")]
    BadTime {
        /// The trial file.
        path: PathBuf,
        /// The offending time, s.
        t_s: f64,
    },
    /// The recorder was already finished (it failed while finishing).
    #[error("{path}: the recording is already closed")]
    Finished {
        /// The trial file.
        path: PathBuf,
    },
    /// The file does not start like an MCAP file.
    #[error("{path}: not an MCAP file (no MCAP magic at the start)")]
    NotMcap {
        /// The file.
        path: PathBuf,
    },
}
