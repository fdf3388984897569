//! The devices' geometry as the configuration fixes it: the stage's scale and soft limits
//! ([`StageGeometry`]) and which limit switch it homes against ([`HomingDirection`]), the
//! servo's pulse calibration ([`PulseCalibration`]). Plain values, checked when built, so the
//! configuration can refuse what the drivers could not use; the drivers
//! (`crate::hardware::stage`, `crate::hardware::servo`, which re-export them) use them.

/// Which limit switch a stage homes against: the one at its near end, where the soft
/// limits' `min_mm` is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum HomingDirection {
    /// The limit switch in the negative direction (the VXM's `I1M-0`).
    Negative,
    /// The limit switch in the positive direction (the VXM's `I1M0`).
    Positive,
}

/// Invalid stage geometry.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum GeometryError {
    /// Steps per millimetre must be finite and positive.
    #[error("steps per mm must be finite and positive, got {0}")]
    StepsPerMm(f64),
    /// The soft limits must be finite with min below max, and each within the i32 step range.
    #[error("soft limits must be finite with min < max, got {min_mm} mm to {max_mm} mm")]
    Limits {
        /// Lower limit, millimetres.
        min_mm: f64,
        /// Upper limit, millimetres.
        max_mm: f64,
    },
}

/// The stage's scale and soft limits. Step zero is where the stage was homed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StageGeometry {
    steps_per_mm: f64,
    min_steps: i32,
    max_steps: i32,
}

impl StageGeometry {
    /// A stage with `steps_per_mm` motor steps per millimetre that may travel from `min_mm` to
    /// `max_mm` (relative to home). The step limits are rounded inward.
    pub fn new(steps_per_mm: f64, min_mm: f64, max_mm: f64) -> Result<Self, GeometryError> {
        if !(steps_per_mm.is_finite() && steps_per_mm > 0.0) {
            return Err(GeometryError::StepsPerMm(steps_per_mm));
        }
        let min_steps = (min_mm * steps_per_mm).ceil();
        let max_steps = (max_mm * steps_per_mm).floor();
        let range = f64::from(i32::MIN)..=f64::from(i32::MAX);
        if !(min_mm < max_mm
            && range.contains(&min_steps)
            && range.contains(&max_steps)
            && min_steps <= max_steps)
        {
            return Err(GeometryError::Limits { min_mm, max_mm });
        }
        Ok(Self {
            steps_per_mm,
            min_steps: min_steps as i32,
            max_steps: max_steps as i32,
        })
    }

    /// Motor steps per millimetre.
    pub fn steps_per_mm(&self) -> f64 {
        self.steps_per_mm
    }

    /// The soft limits in steps, inclusive.
    pub fn limits_steps(&self) -> (i32, i32) {
        (self.min_steps, self.max_steps)
    }

    /// Millimetres to the nearest step, or `None` if not finite or beyond i32 steps.
    pub fn steps_for_mm(&self, mm: f64) -> Option<i64> {
        let steps = (mm * self.steps_per_mm).round();
        (steps.is_finite() && steps.abs() <= f64::from(i32::MAX)).then_some(steps as i64)
    }

    /// Steps to millimetres.
    pub fn mm_for_steps(&self, steps: i32) -> f64 {
        f64::from(steps) / self.steps_per_mm
    }
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
