//! Closed-loop wall following: a robot running along walls, turned by a controller that
//! knows the wall only through its antenna (Cowan, Lee and Full 2006, "Task-level control
//! of rapid wall following in the American cockroach", J Exp Biol 209:1617; thesis 4.2.1).
//!
//! # Frames and signs
//! - **Ground frame**: the scene's frame; `heading_rad` is the body's heading in it,
//!   counter-clockwise.
//! - **Body frame**: origin at the point of rotation (POR), x ahead, y toward the wall.
//! - `theta` (the body's angle to the wall), the turning rate `omega` and the moment `u`
//!   are positive turning **away** from the wall. A run with the wall on the right
//!   ([`WallSide::Right`]) is solved as the mirror image of a left-wall run and reported
//!   back in the scene's frame.
//!
//! # What is where
//! - [`config`]: the robot, the controller and the run ([`FollowConfig`]).
//! - [`body`]: the template body and the wheeled robot, integrated by RK4.
//! - [`theory`]: the template's linearization about the setpoint and its stability boundary.
//! - [`footprint`]: the body's rectangle against the walls (collisions).
//! - [`estimate`]: the estimators (contact line, bend, ideal preview) and odometry.
//! - [`sensed`]: the contact-line and bend estimators fed sample by sample ([`SensedWall`]),
//!   the one implementation behind the loop and antennad's live estimate.
//! - [`control`]: the PD controller, its delay and the search turn.
//! - [`run`]: the loop ([`Follow`], a [`FollowStep`] per step).
//! - [`summary`]: how a run went ([`FollowSummary`], [`FollowStatus`]).
//! - [`error`]: why a run could not start or go on ([`FollowError`]).

pub mod body;
pub mod config;
pub mod control;
pub mod error;
pub mod estimate;
pub mod footprint;
pub mod run;
pub mod sensed;
pub mod summary;
pub mod theory;

pub use config::{
    BodyModel, Controller, ESTIMATOR_NAMES, Estimator, FollowConfig, FollowSettings, Robot,
    WallSide,
};
pub use control::Command;
pub use error::FollowError;
pub use estimate::{BendTable, Estimate, NoEstimate};
pub use run::{Follow, FollowStep, MAX_TURN_PER_STEP_RAD, calibrate_bend, calibrate_bend_at};
pub use sensed::SensedWall;
pub use summary::{FollowStatus, FollowSummary, STATUS_NAMES};
