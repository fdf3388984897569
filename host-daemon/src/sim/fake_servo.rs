//! An in-memory servo that slews toward its target at a set rate in simulated time: the base
//! servo of the simulated rig and of tests that need no serial port.

use crate::hardware::servo::Servo;
use std::time::Duration;

/// An angle the fake servo cannot reach.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("{angle_rad} rad is outside {min_rad}..={max_rad} rad")]
pub struct FakeServoError {
    /// The angle asked for, radians.
    pub angle_rad: f64,
    /// Lower limit, radians.
    pub min_rad: f64,
    /// Upper limit, radians.
    pub max_rad: f64,
}

/// A servo in memory with a range and a slew rate. Its clock only moves when told
/// ([`FakeServo::advance`]).
#[derive(Debug, Clone, PartialEq)]
pub struct FakeServo {
    min_rad: f64,
    max_rad: f64,
    slew_rad_per_s: f64,
    angle_rad: f64,
    target_rad: f64,
}

impl Default for FakeServo {
    fn default() -> Self {
        Self::new()
    }
}

impl FakeServo {
    /// At zero, range -pi/2..=pi/2, slewing at 60 degrees per 0.15 s (a typical hobby servo).
    pub fn new() -> Self {
        Self {
            min_rad: -core::f64::consts::FRAC_PI_2,
            max_rad: core::f64::consts::FRAC_PI_2,
            slew_rad_per_s: core::f64::consts::FRAC_PI_3 / 0.15,
            angle_rad: 0.0,
            target_rad: 0.0,
        }
    }

    /// The same with range `min_rad..=max_rad` (min below max, both finite).
    pub fn with_range_rad(mut self, min_rad: f64, max_rad: f64) -> Option<Self> {
        (min_rad.is_finite() && max_rad.is_finite() && min_rad < max_rad).then(|| {
            self.min_rad = min_rad;
            self.max_rad = max_rad;
            self.angle_rad = self.angle_rad.clamp(min_rad, max_rad);
            self.target_rad = self.angle_rad;
            self
        })
    }

    /// The same slewing at `slew_rad_per_s` (infinity: instantly; must be positive).
    pub fn with_slew_rate_rad_per_s(mut self, slew_rad_per_s: f64) -> Option<Self> {
        (slew_rad_per_s > 0.0).then(|| {
            self.slew_rad_per_s = slew_rad_per_s;
            self
        })
    }

    /// The target angle, radians.
    pub fn target_rad(&self) -> f64 {
        self.target_rad
    }

    /// Lets `dt` of simulated time pass.
    pub fn advance(&mut self, dt: Duration) {
        let step = self.slew_rad_per_s * dt.as_secs_f64();
        let gap = self.target_rad - self.angle_rad;
        self.angle_rad = if gap.abs() <= step {
            self.target_rad
        } else {
            self.angle_rad + step.copysign(gap)
        };
    }
}

impl Servo for FakeServo {
    type Error = FakeServoError;

    fn set_angle_rad(&mut self, angle_rad: f64) -> Result<(), FakeServoError> {
        if !(self.min_rad..=self.max_rad).contains(&angle_rad) {
            return Err(FakeServoError {
                angle_rad,
                min_rad: self.min_rad,
                max_rad: self.max_rad,
            });
        }
        self.target_rad = angle_rad;
        if self.slew_rad_per_s.is_infinite() {
            self.angle_rad = angle_rad;
        }
        Ok(())
    }

    fn angle_rad(&mut self) -> Result<f64, FakeServoError> {
        Ok(self.angle_rad)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slews_at_its_rate_and_refuses_out_of_range() {
        let mut servo = FakeServo::new().with_slew_rate_rad_per_s(1.0).unwrap();
        servo.set_angle_rad(0.5).unwrap();
        servo.advance(Duration::from_millis(200));
        assert!((servo.angle_rad().unwrap() - 0.2).abs() < 1e-12);
        servo.advance(Duration::from_secs(1));
        assert_eq!(servo.angle_rad().unwrap(), 0.5);
        assert!(servo.set_angle_rad(2.0).is_err());
        assert_eq!(servo.target_rad(), 0.5);
        let mut instant = FakeServo::new()
            .with_slew_rate_rad_per_s(f64::INFINITY)
            .unwrap();
        instant.set_angle_rad(-1.0).unwrap();
        assert_eq!(instant.angle_rad().unwrap(), -1.0);
    }
}
