//! `antenna-monitor`: the egui desktop monitor for live, recorded and simulated antenna
//! chains.
//!
//! It connects to antennad's stream ([`client`], `docs/stream-protocol.md`), opens a
//! recorded MCAP trial ([`recording`]), runs a scene file's simulated sweep on a worker
//! thread ([`sweep_run`]) or plays a closed-loop wall-following run ([`follow`]: a follow
//! scene run by sim-core's loop, or the lines of `antenna follow --jsonl`), keeps a bounded
//! [`history`] of every poll, and draws ([`panels`])
//! the chain with its touches, walls, base and stage, sim-core's prediction for the same
//! base pose ([`prediction`]) and the difference, antennad's live wall estimate over the chain
//! and its distance against time ([`estimate`]), joint-angle time series, a touch raster,
//! segment health, stage and servo state, and the controls (with the daemon's token). The
//! view ([`view`]) pauses, zooms and scrubs while acquisition goes on, follows the newest
//! sample, plays a recording or a sweep, and exports ([`export`]) the visible range to CSV
//! and the view to PNG or SVG.
//!
//! The chain panel draws only [`frame::ChainFrame`], whatever the source: live samples and
//! recorded polls become frames through [`rig::RigGeometry`], a sweep's steps through
//! [`sweep::frame_from_step`], a follow run's through [`follow::FollowRunState::frame_at`]
//! (with the robot's body and the path of its moving, turning base). A sweep's wall map ([`mapping`]: the contact points the
//! robot estimates, the wall passed shaded by how well they cover it) is drawn over the walls.
//!
//! # Example: a history and its frame
//!
//! ```
//! use antenna_monitor::history::{Health, History, Sample, SegmentReading};
//! use antenna_monitor::rig::RigGeometry;
//!
//! // Three 40 mm segments on a 40 mm base link, mounted at 30 degrees.
//! let rig = RigGeometry::with_links(vec![0.04; 4], 30f64.to_radians(), "example")?;
//! let mut history = History::new(3, 60_000); // one minute at 1 kHz
//! for i in 0..2000 {
//!     let touching = i > 1500;
//!     history.push(&Sample {
//!         seq: Some(i),
//!         t_s: i as f64 * 1e-3,
//!         segments: vec![
//!             SegmentReading { angle_rad: Some(0.1), touch_bits: Some(0), health: Health::Ok };
//!             3
//!         ]
//!         .into_iter()
//!         .enumerate()
//!         .map(|(k, mut s)| {
//!             if k == 2 && touching {
//!                 s.touch_bits = Some(0b1000);
//!             }
//!             s
//!         })
//!         .collect(),
//!         stage_position_m: Some(0.1),
//!         servo_angle_rad: Some(0.0),
//!     })?;
//! }
//! // The last second, reduced to 100 screen columns.
//! let columns = history.envelope(0, 1.0, 2.0, 100);
//! assert_eq!(columns.len(), 100);
//! assert_eq!(history.touch_spans(2, 1.0, 2.0, 100).len(), 1);
//! // The chain at the newest sample: base at the stage, tip touching.
//! let frame = rig.frame_at(&history, history.len() - 1)?;
//! assert_eq!(frame.base_m, [0.1, 0.0]);
//! assert!(frame.segments[2].touched());
//! # Ok::<(), antenna_monitor::error::MonitorError>(())
//! ```

pub mod app;
pub mod client;
pub mod error;
pub mod estimate;
pub mod export;
pub mod follow;
pub mod frame;
pub mod history;
pub mod mapping;
pub mod panels;
pub mod prediction;
pub mod recording;
pub mod rig;
pub mod screenshot;
pub mod sweep;
pub mod sweep_run;
pub mod view;

pub use app::{AppOptions, MonitorApp, is_software_gl, tune_for_software_gl};
pub use error::MonitorError;
