//! What `antennad` writes for others to read, with no dependency on the daemon itself:
//!
//! - [`record`]: trial recordings, one MCAP file per trial (schemas, messages, the writer and
//!   the reader),
//! - [`stream`]: the live stream and control protocol, newline-delimited JSON over TCP
//!   (`docs/stream-protocol.md`), and
//! - [`foxglove`]: the antenna in Foxglove's standard schemas (its frames and a 3D scene),
//!   which the recordings carry and antennad's live Foxglove server sends.
//!
//! `antennad` (`host-daemon`) writes both; `antenna export` (`antenna-cli`) and
//! `antenna-monitor` read them through this crate.
//!
//! # Example
//!
//! ```
//! use antenna_data::record::{TrialReader, TrialRecorder, synthetic_metadata, synthetic_segments};
//! use antenna_data::stream::{StreamMessage, encode_line};
//!
//! let path = std::env::temp_dir().join(format!("doc-data-{}.mcap", std::process::id()));
//! let mut recorder = TrialRecorder::create(&path, &synthetic_metadata("doc"))?;
//! recorder.record_segments(&synthetic_segments(0, 3))?;
//! recorder.finish()?;
//! assert_eq!(TrialReader::read(&path)?.segments.len(), 1);
//! # std::fs::remove_file(&path).ok();
//!
//! let lagged = StreamMessage::Lagged { dropped: 3, samples_dropped: 2 };
//! let line = encode_line(&lagged).expect("encodes");
//! assert_eq!(line, b"{\"type\":\"lagged\",\"dropped\":3,\"samples_dropped\":2}\n");
//! # Ok::<(), antenna_data::record::RecordError>(())
//! ```

pub mod foxglove;
pub mod record;
pub mod stream;
