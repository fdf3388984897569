//! The stage and the servo as the daemon's rig drives them, whatever they are: the Velmex VXM
//! and the Pololu Maestro on their serial ports ([`crate::hardware::vxm_device`],
//! [`crate::hardware::maestro_device`]) or the simulated ones (`crate::sim::devices`), as
//! trait objects ([`StageDevice`], [`ServoDevice`]) with one error ([`DeviceError`]).
//!
//! A stage is always driven through [`LimitedStage`] behind a [`HomingStage`]: the soft limits
//! hold whatever a trial or a client asks, and no move is made before the stage is homed.

use crate::hardware::homing::{HomingEvent, HomingStage, HomingState};
use crate::hardware::stage::{Homed, LimitedStage, Stage, StageError};
use crate::hardware::vxm::VxmKill;
use std::time::{Duration, Instant};

/// What went wrong with a device.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DeviceError {
    /// The device's serial port is gone; it is being reopened.
    #[error("the {part} is unavailable ({path}: {reason})")]
    Unavailable {
        /// `"stage"` or `"servo"`.
        part: &'static str,
        /// The configured port.
        path: String,
        /// Why.
        reason: String,
    },
    /// The stage is not homed yet (homing starts or is under way); nothing moved.
    #[error("the stage is not homed yet ({0})")]
    NotHomed(String),
    /// Homing failed; nothing moves until it is tried again.
    #[error("the stage is not homed: homing failed ({0})")]
    HomingFailed(String),
    /// A move beyond the soft limits, a speed or angle out of range, a device error.
    #[error("{0}")]
    Refused(String),
}

/// A stage move: by a distance from where the stage is, or to a position from home.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StageMove {
    /// By this many millimetres.
    By(f64),
    /// To this many millimetres from home.
    To(f64),
}

impl StageMove {
    /// Starts the move at `speed_mm_per_s` on the homed `stage`.
    pub fn start<S: Stage>(
        self,
        stage: &mut LimitedStage<S, Homed>,
        speed_mm_per_s: f64,
    ) -> Result<(), StageError<S::Error>> {
        stage.set_speed_mm_per_s(speed_mm_per_s)?;
        match self {
            Self::By(distance_mm) => stage.start_relative_mm(distance_mm),
            Self::To(position_mm) => stage.start_absolute_mm(position_mm),
        }
    }
}

/// A linear stage as the rig drives it: homed against its limit switch before it moves,
/// within its soft limits.
pub trait StageDevice: Send {
    /// `"simulated stage"` or `"VXM on /dev/ttyUSB0"`.
    fn description(&self) -> String;
    /// Whether the stage answers (a simulated one always does).
    fn available(&self) -> bool {
        true
    }
    /// A line that stops the stage from any thread without waiting for the one driving it
    /// (the VXM's kill), if it has one.
    fn kill_line(&self) -> Option<VxmKill> {
        None
    }
    /// Where the homing is.
    fn homing_state(&self) -> HomingState;
    /// A failed homing is tried again at the next step.
    fn retry_homing(&mut self);
    /// Why the stage lost its home (a power cycle) since the last call, if it did.
    fn take_home_lost(&mut self) -> Option<String> {
        None
    }
    /// A simulated stage moves until `now` (time since the rig's clock started) and says
    /// where it is, millimetres from where it started; a real one moves by itself (`None`).
    fn advance(&mut self, _now: Duration) -> Option<f64> {
        None
    }
    /// Steps the homing (starts it when not homed, finishes it when the stage has stopped).
    fn step_homing(&mut self, now: Instant) -> Result<Option<HomingEvent>, DeviceError>;
    /// Starts `to` at `speed_mm_per_s`; refused unless homed, or beyond the soft limits.
    fn start_move(&mut self, to: StageMove, speed_mm_per_s: f64) -> Result<(), DeviceError>;
    /// Whether the motor is moving (a move or homing).
    fn is_moving(&mut self) -> Result<bool, DeviceError>;
    /// The position, millimetres from home; refused before the stage is homed.
    fn position_mm(&mut self) -> Result<f64, DeviceError>;
    /// Stops the motor at once; a homing under way fails.
    fn kill(&mut self) -> Result<(), DeviceError>;
}

/// The base servo as the rig drives it.
pub trait ServoDevice: Send {
    /// `"simulated servo"` or `"Maestro on /dev/ttyACM0"`.
    fn description(&self) -> String;
    /// Whether the servo answers (a simulated one always does).
    fn available(&self) -> bool {
        true
    }
    /// A simulated servo moves until `now` and says its angle, radians; a real one moves by
    /// itself (`None`).
    fn advance(&mut self, _now: Duration) -> Option<f64> {
        None
    }
    /// Sets the target angle, radians.
    fn set_angle_rad(&mut self, angle_rad: f64) -> Result<(), DeviceError>;
    /// The angle, radians.
    fn angle_rad(&mut self) -> Result<f64, DeviceError>;
}

/// A stage's own error as the rig reports it.
pub fn stage_error<E: core::error::Error>(e: StageError<E>) -> DeviceError {
    DeviceError::Refused(match e {
        StageError::Device(e) => format!("stage: {e}"),
        other => other.to_string(),
    })
}

/// The homed stage, or why moves are refused.
pub fn homed<S: Stage>(
    stage: &mut HomingStage<S>,
) -> Result<&mut LimitedStage<S, Homed>, DeviceError> {
    stage.homed().map_err(|state| match state {
        HomingState::Failed(why) => DeviceError::HomingFailed(why),
        HomingState::Homing => DeviceError::NotHomed("homing under way".to_owned()),
        _ => DeviceError::NotHomed("homing starts at the next stage sample".to_owned()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stage_failure_is_a_refusal_naming_the_stage() {
        let e = stage_error(StageError::<std::io::Error>::Device(std::io::Error::other(
            "gone",
        )));
        assert_eq!(e, DeviceError::Refused("stage: gone".to_owned()));
        let e = stage_error(StageError::<std::io::Error>::InvalidNumber {
            what: "speed mm/s",
            value: f64::NAN,
        });
        assert_eq!(e.to_string(), "speed mm/s of NaN is not a usable number");
    }
}
