//! The base servo: the [`Servo`] trait (the Pololu Maestro in [`crate::hardware::maestro`], the
//! in-memory [`crate::FakeServo`]) and the linear pulse-to-angle [`PulseCalibration`].

/// A hobby servo positioned by angle, radians.
///
/// Contract: the implementation owns its port or model. [`Servo::set_angle_rad`] returns once
/// the target has been handed over (the servo may still be moving); an angle the servo cannot
/// reach is an error and nothing is sent. [`Servo::angle_rad`] is where the servo is
/// commanded to be now (for the Maestro, its position including any speed ramp).
pub trait Servo {
    /// What can go wrong talking to the servo.
    type Error: core::error::Error + 'static;

    /// Sets the target angle, radians.
    fn set_angle_rad(&mut self, angle_rad: f64) -> Result<(), Self::Error>;
    /// The current angle, radians.
    fn angle_rad(&mut self) -> Result<f64, Self::Error>;
}

pub use crate::config::geometry::{CalibrationError, PulseCalibration};
