//! Why a closed-loop run could not start or go on.

use crate::contact::ContactError;
use crate::sweep::SweepError;

/// Why a closed-loop run could not start or go on.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FollowError {
    /// A value of the run's description is out of range.
    #[error("[{table}] {key}: {reason}")]
    Invalid {
        /// The scene table (without brackets).
        table: &'static str,
        /// The key.
        key: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// The robot's footprint overlaps a wall at the start.
    #[error(
        "the robot's footprint overlaps wall {wall} at the start (by {depth_m:.4} m): move \
         [follow] pose_m away from the wall or make [robot] footprint_m smaller"
    )]
    StartsInWall {
        /// The wall.
        wall: usize,
        /// How deep the footprint's deepest corner is inside it, m.
        depth_m: f64,
    },
    /// The antenna could not be placed at the start.
    #[error("the antenna could not be placed at the start: {0}")]
    Placement(SweepError),
    /// The sensors could not be set up.
    #[error("the sensors: {0}")]
    Sensors(String),
    /// The bend estimator's calibration table could not be made.
    #[error("the bend estimator's calibration: {0}")]
    Calibration(String),
    /// The antenna's solver refused a step (the run ends there, with what it has).
    #[error("at t = {t_s:.3} s: {source}")]
    Contact {
        /// The time of the step.
        t_s: f64,
        /// The solver's error.
        source: ContactError,
    },
}
