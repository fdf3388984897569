//! Trial recording: every trial to one MCAP file.
//!
//! MCAP (the format rosbag2 moved to) is append-only and carries its schemas: the file opens
//! in Foxglove and PlotJuggler. Channels with JSON messages described by JSON schemas:
//!
//! | topic | message | rate |
//! |---|---|---|
//! | `/trial/metadata` | [`TrialMetadata`] (also an MCAP Metadata record `trial`) | once, first |
//! | `/antenna/segments` | [`SegmentsMessage`]: `t_s` and per segment address, angle counts, `angle_rad`, touch bits, ok/nack/pec/bus/stale flags | every poll |
//! | `/antenna/stage` | [`StageMessage`]: `t_s`, `position_m` | the stage's rate |
//! | `/antenna/servo` | [`ServoMessage`]: `t_s`, `base_angle_rad` | the servo's rate |
//! | `/sim/physics` | [`PhysicsStepMessage`]: `t_s`, `kind` (`place`/`step`), `stage_m`, the base pose (`base_x_m`, `base_y_m`, `base_angle_rad`) and the `joint_angles_rad` it gave (simulated rig only; added with issue #46, older files have none) | every physics step |
//! | `/trial/log` | [`LogMessage`]: `t_s`, `text` (a device vanished or came back, a move refused, a counter stopped) | when it happens |
//! | `/antenna/estimate` | [`EstimateMessage`]: `t_s`, `seq`, `estimator`, the wall's `distance_m`, `angle_rad` and `preview_m` in the carriage frame (or a `reason`), the true ones on the simulated rig | the estimator's rate (added with issue #48) |
//!
//! and, beside them, Foxglove's standard schemas (protobuf, [`crate::foxglove`]), so that the
//! file shows the antenna in 3D and plays it in Foxglove:
//!
//! | topic | message | rate |
//! |---|---|---|
//! | `/antenna/transforms` | `foxglove.FrameTransforms`: `world` -> `carriage` -> `link_0` -> ... -> `link_n` | [`FoxgloveOptions::scene_hz`] (50 Hz) |
//! | `/antenna/scene` | `foxglove.SceneUpdate`: the links, their touch switches (red when closed), the walls (every [`WALLS_INTERVAL_S`]), the newest estimated wall | the same |
//!
//! The recorder draws them itself, at the first poll due, from the newest poll, stage
//! position, servo angle and estimate it recorded (the stage and servo at 0 until their
//! first message) and the chain's model ([`FoxgloveOptions::chain`], else the metadata's rig;
//! a file with neither has no Foxglove channels). They are derived data: [`TrialReader`]
//! counts them ([`Trial::foxglove_messages`]) and reads the JSON channels as before.
//!
//! Segment polls carry `seq`, the poll's number on the daemon's clock (+1 per poll deadline),
//! so a reader can tell that none is missing. While the stage's (or servo's) serial device is
//! gone, no stage (servo) samples are recorded, and `/trial/log` says when it vanished and
//! came back.
//!
//! `t_s` is monotonic time since the trial started, on one clock for all topics. Each
//! message's MCAP log time (and publish time) is that instant in Unix-epoch nanoseconds:
//! [`TrialMetadata::started_unix_ns`] plus `t_s`, so a trial lines up with video and other
//! logs.
//!
//! # Size
//!
//! Messages go into zstd-compressed chunks ([`ChunkCompression`], MCAP's own compression that
//! every reader undoes), one per flush: the default trial's JSON shrinks about 25 times
//! (BENCHMARKS.md, "Recordings"). The Foxglove channels at 50 Hz add about 14 kB/s to the
//! default trial (8 segments at 1 kHz, measured with issue #48: 47 kB/s of JSON channels with
//! the estimates at 100 Hz, 61 kB/s with the Foxglove channels; 57 kB/s at 25 Hz).
//!
//! # Crash safety
//!
//! [`TrialRecorder`] closes its chunk and flushes the file at least every 100 ms of trial
//! time ([`FLUSH_INTERVAL_S`]), and each flush leaves the file a complete MCAP file (without
//! a summary: [`sealed_file`]), so a process killed with `kill -9` leaves a file that
//! standard readers (Python's `mcap`, the Rust `mcap` crate, Foxglove) open as it is, with
//! every message up to the last flush. The file is synced to the disk every
//! [`RecorderOptions::sync_interval_s`] (1 s by default) and at the end. [`TrialReader`]
//! also reads older files cut inside a chunk, up to their last whole record (chunk CRCs
//! checked), and says where and why a file stopped ([`Trial::truncated`]).
//!
//! # Example
//!
//! ```
//! use antenna_data::record::{TrialReader, TrialRecorder, synthetic_metadata, synthetic_segments};
//!
//! let path = std::env::temp_dir().join(format!("doc-record-{}.mcap", std::process::id()));
//! let mut recorder = TrialRecorder::create(&path, &synthetic_metadata("doc"))?;
//! for i in 0..250 {
//!     recorder.record_segments(&synthetic_segments(i, 3))?;
//! }
//! recorder.finish()?;
//! let trial = TrialReader::read(&path)?;
//! assert_eq!(trial.segments.len(), 250);
//! assert!(trial.truncated.is_none());
//! # std::fs::remove_file(&path).ok();
//! # Ok::<(), antenna_data::record::RecordError>(())
//! ```

mod error;
mod messages;
mod reader;
pub mod schema;
pub mod sealed_file;
mod synthetic;
mod writer;

pub use error::RecordError;
pub use messages::{
    EstimateMessage, LogMessage, PhysicsStepKind, PhysicsStepMessage, SegmentSample,
    SegmentsMessage, ServoMessage, StageMessage, TrialMetadata,
};
pub use reader::{Trial, TrialReader};
pub use synthetic::{
    SYNTHETIC_POLL_PERIOD_S, synthetic_estimate, synthetic_metadata, synthetic_rig,
    synthetic_segments, synthetic_servo, synthetic_stage,
};
pub use writer::{
    ChunkCompression, DEFAULT_SCENE_HZ, FLUSH_INTERVAL_S, FoxgloveOptions, RecordCounts,
    RecorderOptions, TrialRecorder, WALLS_INTERVAL_S,
};
