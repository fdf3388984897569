//! The wall map of a simulated sweep (thesis 4.2.2, Figures 4.15 and 4.16): the contact points
//! the robot estimates from what it senses, and the wall section it passed shaded by how well
//! those points cover it.
//!
//! [`SweepMapping`] gathers, step by step as the sweep's thread hands the steps over, the
//! estimated points (sim-core's [`estimate_contacts`] on the joint angles and touch bits as
//! [`Sensors`] read them) and the section of each wall passed (the true contacts' extent along
//! the motion, [`CoverageAccumulator`]). Both are kept per step, so the coverage *up to any
//! step* is one call of sim-core's [`wall_coverage`] ([`SweepMapping::coverage`]), made only
//! when the step drawn changes and at most every [`CoverageCache::MIN_INTERVAL`]
//! ([`CoverageCache`]), never per frame.
//!
//! [`coverage_colour`] is the map's colour scale, from [`CAPTURED_COLOUR`] (error 0) through
//! [`MIDWAY_COLOUR`] to [`MISSED_COLOUR`] (error at or beyond the completeness threshold):
//! Okabe and Ito's bluish green, yellow and vermillion, told apart with the common colour
//! vision deficiencies, the hue moving one way from one end to the other.
//!
//! ```
//! use antenna_monitor::mapping::{CAPTURED_COLOUR, MISSED_COLOUR, coverage_colour};
//! assert_eq!(coverage_colour(Some(0.0), 5.0), CAPTURED_COLOUR);
//! assert_eq!(coverage_colour(Some(7.5), 5.0), MISSED_COLOUR);
//! // No estimated point at all: missed.
//! assert_eq!(coverage_colour(None, 5.0), MISSED_COLOUR);
//! ```

use std::time::{Duration, Instant};

use egui::Color32;
use nalgebra::Vector2;
use sim_core::sweep::SweepStep;
use sim_core::{
    Chain, Coverage, CoverageAccumulator, CoverageError, CoverageSettings, EstimatedContact,
    MappingError, Section, SensorSettings, Sensors, Wall, estimate_contacts, wall_coverage,
};

use crate::error::MonitorError;

/// A wall sample at the estimated points (coverage error 0): Okabe-Ito bluish green.
pub const CAPTURED_COLOUR: Color32 = Color32::from_rgb(0, 158, 115);
/// Halfway to the threshold: Okabe-Ito yellow.
pub const MIDWAY_COLOUR: Color32 = Color32::from_rgb(240, 228, 66);
/// A wall sample at or beyond the threshold (or with no estimated point at all):
/// Okabe-Ito vermillion.
pub const MISSED_COLOUR: Color32 = Color32::from_rgb(213, 94, 0);

/// The map's colour for a wall sample `error_mm` from the nearest estimated point, with
/// `complete_within_mm` the completeness threshold: [`CAPTURED_COLOUR`] at 0,
/// [`MIDWAY_COLOUR`] at half the threshold, [`MISSED_COLOUR`] at the threshold and beyond,
/// linear in between. `None` (no point at all) and NaN are missed; a threshold that is not
/// positive (or NaN) captures only an error of 0 (or below).
pub fn coverage_colour(error_mm: Option<f64>, complete_within_mm: f64) -> Color32 {
    let Some(error_mm) = error_mm.filter(|e| !e.is_nan()) else {
        return MISSED_COLOUR;
    };
    let fraction = if complete_within_mm > 0.0 {
        error_mm / complete_within_mm
    } else if error_mm <= 0.0 {
        0.0
    } else {
        1.0
    };
    colour_at_fraction(fraction)
}

/// The scale at `fraction` of the threshold (clamped to `0..=1`).
fn colour_at_fraction(fraction: f64) -> Color32 {
    let f = if fraction.is_nan() {
        1.0
    } else {
        fraction.clamp(0.0, 1.0)
    };
    if f <= 0.0 {
        CAPTURED_COLOUR
    } else if f >= 1.0 {
        MISSED_COLOUR
    } else if f <= 0.5 {
        lerp_colour(CAPTURED_COLOUR, MIDWAY_COLOUR, f * 2.0)
    } else {
        lerp_colour(MIDWAY_COLOUR, MISSED_COLOUR, (f - 0.5) * 2.0)
    }
}

fn lerp_colour(a: Color32, b: Color32, t: f64) -> Color32 {
    let channel = |x: u8, y: u8| {
        let v = f64::from(x) + (f64::from(y) - f64::from(x)) * t;
        v.round().clamp(0.0, 255.0) as u8
    };
    Color32::from_rgb(
        channel(a.r(), b.r()),
        channel(a.g(), b.g()),
        channel(a.b(), b.b()),
    )
}

/// The number of colour bands the map is drawn in (consecutive wall samples in one band are
/// drawn as one line): [`coverage_band`].
pub const COLOUR_BANDS: usize = 32;

/// The band of `error_mm` (`0..=COLOUR_BANDS`; the last is "missed"), and its colour (the
/// scale at the band's lower edge, so band 0 is [`CAPTURED_COLOUR`] and the last
/// [`MISSED_COLOUR`]).
pub fn coverage_band(error_mm: Option<f64>, complete_within_mm: f64) -> (usize, Color32) {
    let band = match error_mm.filter(|e| !e.is_nan()) {
        None => COLOUR_BANDS,
        Some(e) if complete_within_mm > 0.0 => {
            let f = (e / complete_within_mm).clamp(0.0, 1.0);
            ((f * COLOUR_BANDS as f64).floor() as usize).min(COLOUR_BANDS)
        }
        Some(e) => {
            if e <= 0.0 {
                0
            } else {
                COLOUR_BANDS
            }
        }
    };
    (band, colour_at_fraction(band as f64 / COLOUR_BANDS as f64))
}

/// The map's numbers in one line, e.g. `wall map: coverage mean 2.1 mm, p90 4.4 mm, 87 %
/// within 5 mm, 5123 points` (`-` for a number there is none of).
pub fn coverage_summary(coverage: &Coverage, points: usize, complete_within_mm: f64) -> String {
    let mm = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |v| format!("{v:.1} mm"));
    let completeness = coverage
        .completeness
        .map_or_else(|| "-".to_owned(), |c| format!("{:.0} %", c * 100.0));
    format!(
        "wall map: coverage mean {}, p90 {}, {completeness} within {complete_within_mm} mm, \
         {points} points",
        mm(coverage.mean_error_mm),
        mm(coverage.p90_error_mm),
    )
}

/// What the map gathered at one step: the estimated points so far (their count) and the
/// sections passed so far.
#[derive(Debug, Clone, PartialEq)]
pub struct MappedStep {
    /// The estimated points of this step and every one before it: the first this many of
    /// [`SweepMapping::all_points_m`].
    pub points_end: usize,
    /// The sections of the walls passed up to this step (one per wall touched).
    pub sections: Vec<Section>,
}

/// A sweep's wall map, step by step (see the module documentation).
#[derive(Debug, Clone)]
pub struct SweepMapping {
    sensors: Sensors,
    direction_rad: f64,
    accumulator: CoverageAccumulator,
    steps: Vec<MappedStep>,
    sensed_theta_rad: Vec<f64>,
    touch_bits: Vec<u8>,
    estimates: Vec<EstimatedContact>,
    unmapped_steps: usize,
    first_failure: Option<String>,
}

impl SweepMapping {
    /// An empty map of a sweep of `chain` past `walls` walls, moving along `direction_rad`
    /// (radians from the ground x-axis, sim-core's `Motion::direction_rad`), sensed by sensors
    /// as `settings` describe them ([`SensorSettings::IDEAL`]: the 12-bit angles and the true
    /// touch bits at every step). The one place the monitor makes its [`Sensors`].
    ///
    /// # Errors
    /// [`MonitorError::Sweep`] if `settings` do not fit the chain
    /// ([`SensorSettings::validate`]).
    pub fn new(
        settings: &SensorSettings,
        chain: &Chain,
        walls: usize,
        direction_rad: f64,
    ) -> Result<SweepMapping, MonitorError> {
        let sensors = Sensors::new(settings, chain.n())
            .map_err(|e| MonitorError::Sweep(format!("sensors: {e}")))?;
        let links = chain.n() + 1;
        Ok(SweepMapping {
            sensors,
            direction_rad,
            accumulator: CoverageAccumulator::new(direction_rad, walls),
            steps: Vec::new(),
            sensed_theta_rad: vec![0.0; links],
            touch_bits: vec![0; links],
            estimates: Vec::new(),
            unmapped_steps: 0,
            first_failure: None,
        })
    }

    /// Adds the next step of the sweep (in time order, the placement first): its true
    /// contacts widen the sections passed, and if the sensors sample it, the points estimated
    /// from their reading join the map. A step whose reading cannot be mapped maps no points
    /// and is counted ([`Self::unmapped_steps`]).
    pub fn push(&mut self, chain: &Chain, step: &SweepStep) {
        if self.sensors.is_sample_due(step.t_s) {
            match self.estimate(chain, step) {
                Ok(()) => self
                    .accumulator
                    .estimate(self.estimates.iter().map(|e| e.point_m)),
                Err(e) => {
                    self.unmapped_steps += 1;
                    self.first_failure
                        .get_or_insert_with(|| format!("step {}: {e}", step.step));
                }
            }
        }
        self.accumulator.pass(&step.contacts);
        self.steps.push(MappedStep {
            points_end: self.accumulator.points_m().len(),
            sections: self.accumulator.sections(),
        });
    }

    /// The points estimated from the sensors' reading of `step` into `self.estimates`.
    fn estimate(&mut self, chain: &Chain, step: &SweepStep) -> Result<(), MappingError> {
        self.estimates.clear();
        self.sensors
            .sense_angles_rad(&step.theta_rad, &mut self.sensed_theta_rad)?;
        self.sensors
            .sense_touch(&step.contacts, &mut self.touch_bits)?;
        estimate_contacts(
            chain,
            &step.base_m,
            &self.sensed_theta_rad,
            &self.touch_bits,
            &self.sensors.touch_layout(),
            &mut self.estimates,
        )
        .inspect_err(|_| self.estimates.clear())
    }

    /// The sensors' settings.
    pub fn sensor_settings(&self) -> &SensorSettings {
        self.sensors.settings()
    }

    /// The motion's direction, radians from the ground x-axis.
    pub fn direction_rad(&self) -> f64 {
        self.direction_rad
    }

    /// The motion's direction as a unit vector (as sim-core's [`CoverageAccumulator`] makes
    /// it from [`Self::direction_rad`]).
    pub fn direction(&self) -> Vector2<f64> {
        let (sin, cos) = self.direction_rad.sin_cos();
        Vector2::new(cos, sin)
    }

    /// The steps mapped (one per step pushed).
    pub fn steps(&self) -> &[MappedStep] {
        &self.steps
    }

    /// Every point estimated so far, step by step, ground frame, metres.
    pub fn all_points_m(&self) -> &[Vector2<f64>] {
        self.accumulator.points_m()
    }

    /// The points estimated up to step `index` (of those pushed; the placement is 0),
    /// ground frame, metres; empty for a step not pushed.
    pub fn points_m(&self, index: usize) -> &[Vector2<f64>] {
        let end = self.steps.get(index).map_or(0, |s| s.points_end);
        self.all_points_m().get(..end).unwrap_or_default()
    }

    /// Steps whose sensed reading could not be mapped (none with a valid sweep).
    pub fn unmapped_steps(&self) -> usize {
        self.unmapped_steps
    }

    /// Why the first of [`Self::unmapped_steps`] was not mapped.
    pub fn first_failure(&self) -> Option<&str> {
        self.first_failure.as_deref()
    }

    /// The coverage of `walls` (the sweep's) by the points estimated up to step `index`, over
    /// the sections passed up to it ([`wall_coverage`]); `None` for a step not pushed.
    ///
    /// # Errors
    /// As [`wall_coverage`].
    pub fn coverage(
        &self,
        walls: &[Wall],
        index: usize,
        settings: &CoverageSettings,
    ) -> Result<Option<Coverage>, CoverageError> {
        let Some(step) = self.steps.get(index) else {
            return Ok(None);
        };
        wall_coverage(
            walls,
            &self.direction(),
            &step.sections,
            self.points_m(index),
            settings,
        )
        .map(Some)
    }
}

/// The coverage last computed for the step drawn, recomputed when that step changes but at
/// most every [`Self::MIN_INTERVAL`] (see the module documentation).
#[derive(Debug, Default)]
pub struct CoverageCache {
    /// The sweep (the app's count of sweeps opened) and the step computed for.
    key: Option<(u64, usize)>,
    coverage: Option<Result<Coverage, String>>,
    computed_at: Option<Instant>,
}

impl CoverageCache {
    /// The least time between two computations (scrubbing, or a sweep being solved, changes
    /// the step drawn every frame).
    pub const MIN_INTERVAL: Duration = Duration::from_millis(100);

    /// Makes the coverage that of step `index` of sweep `sweep` with `compute` (called only
    /// if the step is not the one held, and the last computation is at least
    /// [`Self::MIN_INTERVAL`] before `now`, or was of another sweep). Returns whether the step
    /// held is not yet `index` (the caller asks for a frame after [`Self::MIN_INTERVAL`]).
    pub fn refresh(
        &mut self,
        sweep: u64,
        index: usize,
        now: Instant,
        compute: impl FnOnce() -> Result<Option<Coverage>, CoverageError>,
    ) -> bool {
        if self.key == Some((sweep, index)) {
            return false;
        }
        let same_sweep = self.key.is_some_and(|(s, _)| s == sweep);
        let recent = self
            .computed_at
            .is_some_and(|t| now.saturating_duration_since(t) < Self::MIN_INTERVAL);
        if same_sweep && recent {
            return true;
        }
        self.coverage = match compute() {
            Ok(Some(c)) => Some(Ok(c)),
            Ok(None) => None,
            Err(e) => Some(Err(e.to_string())),
        };
        self.key = Some((sweep, index));
        self.computed_at = Some(now);
        false
    }

    /// The step held (`(sweep, step)`), if any.
    pub fn key(&self) -> Option<(u64, usize)> {
        self.key
    }

    /// The coverage held, or why it could not be computed.
    pub fn coverage(&self) -> Option<&Result<Coverage, String>> {
        self.coverage.as_ref()
    }

    /// Forgets the coverage held.
    pub fn clear(&mut self) {
        *self = Self::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cache_computes_once_per_step_and_not_faster_than_its_interval() {
        let mut cache = CoverageCache::default();
        let t0 = Instant::now();
        let mut calls = 0;
        let mut compute = || {
            calls += 1;
            Ok(Some(Coverage::default()))
        };
        assert!(!cache.refresh(1, 3, t0, &mut compute));
        assert!(!cache.refresh(1, 3, t0 + Duration::from_secs(1), &mut compute));
        // Another step too soon: held back.
        assert!(cache.refresh(1, 4, t0 + Duration::from_millis(10), &mut compute));
        assert_eq!(cache.key(), Some((1, 3)));
        // Another sweep: at once.
        assert!(!cache.refresh(2, 4, t0 + Duration::from_millis(20), &mut compute));
        assert!(!cache.refresh(2, 5, t0 + Duration::from_millis(200), &mut compute));
        assert_eq!(cache.key(), Some((2, 5)));
        assert_eq!(calls, 3);
        assert!(matches!(cache.coverage(), Some(Ok(_))));
    }

    #[test]
    fn bands_start_captured_and_end_missed() {
        assert_eq!(coverage_band(Some(0.0), 5.0), (0, CAPTURED_COLOUR));
        assert_eq!(coverage_band(Some(5.0), 5.0), (COLOUR_BANDS, MISSED_COLOUR));
        assert_eq!(coverage_band(None, 5.0), (COLOUR_BANDS, MISSED_COLOUR));
        assert_eq!(coverage_band(Some(f64::NAN), 5.0).0, COLOUR_BANDS);
        assert_eq!(coverage_band(Some(0.0), 0.0).0, 0);
        assert_eq!(coverage_band(Some(0.1), 0.0).0, COLOUR_BANDS);
        assert_eq!(coverage_band(Some(2.5), 5.0).1, MIDWAY_COLOUR);
    }
}
