//! The messages of a trial recording, one struct per MCAP channel. They are serialized as JSON
//! (`serde_json`) and described in the file by the JSON schemas of [`super::schema`].

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::stream::RigInfo;

/// One segment's part of one poll (`/antenna/segments`).
///
/// When the poll failed (`ok` false) the sample fields are `None` (JSON `null`) and the flag
/// says why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SegmentSample {
    /// The segment's 7-bit I2C address.
    pub address: u8,
    /// The raw angle, 0..=4095 counts per turn; `None` when the poll failed.
    pub angle_counts: Option<u16>,
    /// The joint angle from the segment's calibration, rad; `None` when the poll failed.
    pub angle_rad: Option<f64>,
    /// The touch bits (bit i: hair i touched), 0..=15; `None` when the poll failed.
    pub touch: Option<u8>,
    /// The poll returned a valid, PEC-checked sample.
    pub ok: bool,
    /// The segment did not acknowledge its address.
    pub nack: bool,
    /// The read came back with a wrong PEC (the sample was dropped, not recorded).
    pub pec_error: bool,
    /// Another bus error.
    pub bus_error: bool,
    /// The sample is valid but its sequence did not advance since the last poll (a stuck
    /// segment), as judged by the acquisition.
    pub stale: bool,
}

/// One poll of every segment (`/antenna/segments`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SegmentsMessage {
    /// The poll's number on the daemon's clock: +1 per poll, so a gap means skipped poll
    /// deadlines, never a lost sample (files written before this field have none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seq: Option<u64>,
    /// Monotonic time since the trial started, s.
    pub t_s: f64,
    /// The segments in polling order (base first).
    pub segments: Vec<SegmentSample>,
}

/// The linear stage's position (`/antenna/stage`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StageMessage {
    /// Monotonic time since the trial started, s (the same clock as the segments).
    pub t_s: f64,
    /// Stage position, m.
    pub position_m: f64,
}

/// The base servo's angle (`/antenna/servo`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ServoMessage {
    /// Monotonic time since the trial started, s (the same clock as the segments).
    pub t_s: f64,
    /// Base angle, rad.
    pub base_angle_rad: f64,
}

/// What a [`PhysicsStepMessage`] was.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PhysicsStepKind {
    /// The scene's placement, done afresh with the base at the message's pose (a trial
    /// starting).
    Place,
    /// One quasi-static step from the previous posture to the message's pose.
    Step,
}

/// One placement or step of the simulated rig's physics (`/sim/physics`): the base pose it
/// was for and the joint angles it gave, so a trial can be replayed through sim-core's
/// stepper from its scene (the metadata's `rig.scene_toml`). Recorded only by the simulated
/// rig; files from before it existed have none.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PhysicsStepMessage {
    /// Monotonic time since the trial started, s (the same clock as the segments): when the
    /// step was made.
    pub t_s: f64,
    /// A placement or a step.
    pub kind: PhysicsStepKind,
    /// The stage position it was for, m (fractional: where the stage was at that instant).
    pub stage_m: f64,
    /// The base pivot, ground frame, m.
    pub base_x_m: f64,
    /// See [`Self::base_x_m`].
    pub base_y_m: f64,
    /// The base link's angle from the ground x-axis, rad (the scene's base angle plus the
    /// servo angle).
    pub base_angle_rad: f64,
    /// The joint angles `theta_1..theta_n` the physics gave, rad.
    pub joint_angles_rad: Vec<f64>,
}

/// One wall estimate (`/antenna/estimate`): what the daemon's estimator made of the polls up
/// to `seq`, in the carriage frame (origin at the base pivot, `x` along the stage's travel,
/// `y` toward the wall; see [`crate::foxglove::EstimatedWall`]), and on the simulated rig the
/// true wall at the same instant beside it.
///
/// (The Rust field of the angle is `wall_angle_rad`, written `angle_rad`: a struct with both
/// `distance_m` and `angle_rad` reads as a scene's wall description, which only
/// `antenna-scene` holds.)
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EstimateMessage {
    /// Monotonic time since the trial started, s (the same clock as the segments): the newest
    /// poll's.
    pub t_s: f64,
    /// The newest poll's `seq`.
    pub seq: u64,
    /// The estimator (`contact-line`, `bend`, `ideal-preview`).
    pub estimator: String,
    /// The wall's distance from the travel at `x = preview_m`, m; `None` when there is no
    /// estimate (`reason` says why).
    pub distance_m: Option<f64>,
    /// The wall's angle to the travel, rad; `None` for an estimator that gives none (`bend`)
    /// or when there is no estimate.
    #[serde(rename = "angle_rad")]
    pub wall_angle_rad: Option<f64>,
    /// Where along the travel the distance is estimated, m from the base pivot.
    pub preview_m: Option<f64>,
    /// Why there is no estimate (e.g. no contact in the window).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// The true distance at the same place (the simulated rig only), m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub true_distance_m: Option<f64>,
    /// The true angle (the simulated rig only), rad.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub true_angle_rad: Option<f64>,
}

/// Something the daemon said during the trial (`/trial/log`): a stage or servo device
/// vanishing or coming back, a move refused, a segment's counter stopping, ...
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LogMessage {
    /// Monotonic time since the trial started, s (the same clock as the segments).
    pub t_s: f64,
    /// What happened, for humans.
    pub text: String,
}

/// What the trial was (`/trial/metadata`, written once, first; also an MCAP Metadata record
/// named `trial`).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct TrialMetadata {
    /// The trial's name.
    pub trial: String,
    /// Wall-clock start, seconds since the Unix epoch (UTC).
    pub started_unix_s: f64,
    /// The same instant exactly, nanoseconds since the Unix epoch: every message's MCAP log
    /// time is this plus its `t_s` (absent in files written before it was added).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub started_unix_ns: Option<u64>,
    /// The daemon configuration in force, as free text (TOML).
    pub config: String,
    /// Free-text notes such as `wall` and `hairs`, sorted by key.
    pub notes: BTreeMap<String, String>,
    /// The rig's geometry as the stream's `hello` describes it (the antenna, the wall, the
    /// stage's soft limits), so a reader can draw the chain without the daemon's
    /// configuration format; `None` in files written before it was added.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rig: Option<RigInfo>,
}

impl TrialMetadata {
    /// Unix-epoch nanoseconds of the trial's start: [`Self::started_unix_ns`], else
    /// [`Self::started_unix_s`] rounded; `None` for a start that is not a Unix time.
    pub fn start_unix_ns(&self) -> Option<u64> {
        self.started_unix_ns.or_else(|| {
            let ns = (self.started_unix_s * 1e9).round();
            (ns.is_finite() && ns >= 0.0 && ns < u64::MAX as f64).then_some(ns as u64)
        })
    }

    /// The metadata as MCAP Metadata key/value strings.
    pub fn to_key_values(&self) -> BTreeMap<String, String> {
        let mut map = BTreeMap::new();
        map.insert("trial".to_string(), self.trial.clone());
        map.insert(
            "started_unix_s".to_string(),
            format!("{}", self.started_unix_s),
        );
        if let Some(ns) = self.started_unix_ns {
            map.insert("started_unix_ns".to_string(), ns.to_string());
        }
        map.insert("config".to_string(), self.config.clone());
        for (k, v) in &self.notes {
            map.insert(format!("notes.{k}"), v.clone());
        }
        if let Some(rig) = &self.rig
            && let Ok(json) = serde_json::to_string(rig)
        {
            map.insert("rig".to_string(), json);
        }
        map
    }
}
