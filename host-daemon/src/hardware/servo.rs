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

/// An invalid calibration.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("a calibration needs two distinct finite angles and distinct finite positive pulse widths")]
pub struct CalibrationError;

/// Pulse width as a linear function of angle, fixed by two points (angle in radians, pulse
/// width in microseconds), e.g. 1000 us at -pi/2 and 2000 us at +pi/2.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PulseCalibration {
    angle_a_rad: f64,
    pulse_a_us: f64,
    angle_b_rad: f64,
    pulse_b_us: f64,
}

impl PulseCalibration {
    /// The line through (`angle_a_rad`, `pulse_a_us`) and (`angle_b_rad`, `pulse_b_us`).
    pub fn new(
        angle_a_rad: f64,
        pulse_a_us: f64,
        angle_b_rad: f64,
        pulse_b_us: f64,
    ) -> Result<Self, CalibrationError> {
        let finite = [angle_a_rad, pulse_a_us, angle_b_rad, pulse_b_us]
            .iter()
            .all(|v| v.is_finite());
        if !finite
            || angle_a_rad == angle_b_rad
            || pulse_a_us == pulse_b_us
            || pulse_a_us <= 0.0
            || pulse_b_us <= 0.0
        {
            return Err(CalibrationError);
        }
        Ok(Self {
            angle_a_rad,
            pulse_a_us,
            angle_b_rad,
            pulse_b_us,
        })
    }

    fn us_per_rad(&self) -> f64 {
        (self.pulse_b_us - self.pulse_a_us) / (self.angle_b_rad - self.angle_a_rad)
    }

    /// The pulse width for `angle_rad`, microseconds.
    pub fn pulse_us(&self, angle_rad: f64) -> f64 {
        self.pulse_a_us + (angle_rad - self.angle_a_rad) * self.us_per_rad()
    }

    /// The angle for `pulse_us`, radians.
    pub fn angle_rad(&self, pulse_us: f64) -> f64 {
        self.angle_a_rad + (pulse_us - self.pulse_a_us) / self.us_per_rad()
    }
}
