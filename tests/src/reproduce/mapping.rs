//! Thesis 4.2.2: wall shape against wall following. Sinusoidal walls of spatial frequency
//! 2.8, 4.2, 6.3, 9.5 and 14.2 1/m, and the trapezoid; a distally decreasing profile against
//! the constant one; the contact points the robot would estimate from its 12-bit joint
//! angles and touch bits through a scene's `[sensors]` (ideal, or the robot's of
//! `examples/mapping_4_2_2_sensors.toml`), scored against the true wall two ways: each
//! estimated point's distance to the wall (the point error), and each point of the wall
//! section passed to its nearest estimated point (the coverage, `sim_core::sensing::coverage`: what
//! the thesis's "mean spatial error from the ground truth" grows with).
//! `examples/mapping_4_2_2.toml` is the base scene of the sinusoids (its wall's frequency and
//! the profile are varied here), `examples/mapping_trapezoid_4_2_2.toml` the trapezoid's.

use sim_core::sweep::{Sweep, SweepScene};
use sim_core::{
    CoverageAccumulator, MappingAccumulator, SensorSettings, Sensors, Sinusoid, StiffnessProfile,
    Wall, WallSample, WallShape, estimate_contacts,
};

use super::{ReproduceError, with_profile};

/// The thesis's wall frequencies, 1/m.
pub const FREQUENCIES_PER_M: [f64; 5] = [2.8, 4.2, 6.3, 9.5, 14.2];

/// One run: a profile against a wall frequency.
#[derive(Clone, Debug)]
pub struct MappingRun {
    /// The profile.
    pub profile: StiffnessProfile,
    /// The sinusoid's spatial frequency, 1/m (`None`: the trapezoid).
    pub frequency_per_m: Option<f64>,
    /// The mean spatial error of the estimated contact points, mm.
    pub mean_error_mm: f64,
    /// How many estimated points it averages.
    pub points: usize,
    /// The wall section passed: each sample's mean distance to the nearest estimated
    /// point, mm (`NaN` without points).
    pub coverage_error_mm: f64,
    /// Its 90th percentile, mm.
    pub coverage_p90_mm: f64,
    /// The fraction of the section within 5 mm of an estimated point.
    pub completeness: f64,
    /// The wall samples and their coverage error, for the figure.
    pub wall_samples: Vec<WallSample>,
    /// Estimated contact points (ground frame, m), for the figure.
    pub estimates_m: Vec<[f64; 2]>,
    /// Steps that snapped.
    pub snaps: usize,
    /// Steps run.
    pub steps: usize,
    /// Why the sweep stopped early (the score is then over the steps before), if it did.
    pub failure: Option<String>,
}

/// The base scene's sinusoid with another frequency.
fn with_frequency(base: &SweepScene, frequency_per_m: f64) -> Result<Vec<Wall>, ReproduceError> {
    let mut walls = base.walls.clone();
    let Some(wall) = walls.first_mut() else {
        return Err(ReproduceError::Scene {
            path: "mapping".into(),
            message: "the base scene has no wall".into(),
        });
    };
    let WallShape::Sinusoid(s) = &wall.shape else {
        return Err(ReproduceError::Scene {
            path: "mapping".into(),
            message: "the base scene's wall 0 is not a sinusoid".into(),
        });
    };
    wall.shape = WallShape::Sinusoid(Sinusoid::new(
        s.baseline_point_m(),
        s.direction_rad(),
        s.amplitude_m(),
        frequency_per_m,
        s.phase_rad(),
        s.solid_side(),
    )?);
    Ok(walls)
}

/// Runs `profile` against the wall at `frequency_per_m`.
///
/// # Errors
/// [`ReproduceError`] for an invalid scene; a step that fails ends the run early (see
/// [`MappingRun::failure`]).
pub fn run(
    base: &SweepScene,
    profile: StiffnessProfile,
    frequency_per_m: f64,
    sensors: &SensorSettings,
) -> Result<MappingRun, ReproduceError> {
    let scene = SweepScene {
        chain: with_profile(&base.chain, profile.clone())?,
        walls: with_frequency(base, frequency_per_m)?,
        ..base.clone()
    };
    map(
        format!("4.2.2 {} {frequency_per_m} 1/m", profile.name()),
        scene,
        profile,
        Some(frequency_per_m),
        sensors,
    )
}

/// Runs `profile` along the trapezoid of `base` (`examples/mapping_trapezoid_4_2_2.toml`).
///
/// # Errors
/// As [`run`].
pub fn run_trapezoid(
    base: &SweepScene,
    profile: StiffnessProfile,
    sensors: &SensorSettings,
) -> Result<MappingRun, ReproduceError> {
    let scene = SweepScene {
        chain: with_profile(&base.chain, profile.clone())?,
        ..base.clone()
    };
    map(
        format!("4.2.2 {} trapezoid", profile.name()),
        scene,
        profile,
        None,
        sensors,
    )
}

/// Sweeps `scene`, estimating the contacts from what `sensors` read at every step.
fn map(
    label: String,
    scene: SweepScene,
    profile: StiffnessProfile,
    frequency_per_m: Option<f64>,
    sensors: &SensorSettings,
) -> Result<MappingRun, ReproduceError> {
    let walls = scene.walls.clone();
    let chain = scene.chain.clone();
    let direction_rad = scene.motion.direction_rad();
    let mut sensors = Sensors::new(sensors, chain.n()).map_err(|e| ReproduceError::Scene {
        path: label.clone(),
        message: e.to_string(),
    })?;
    let mut sweep = Sweep::new(scene).map_err(|source| ReproduceError::Sweep {
        label: label.clone(),
        source,
    })?;
    let mut acc = MappingAccumulator::default();
    let mut coverage = CoverageAccumulator::new(direction_rad, walls.len());
    let mut sensed = vec![0.0; chain.dof()];
    let mut touch = vec![0; chain.dof()];
    let mut estimates = Vec::new();
    let mut out = MappingRun {
        profile,
        frequency_per_m,
        mean_error_mm: f64::NAN,
        points: 0,
        coverage_error_mm: f64::NAN,
        coverage_p90_mm: f64::NAN,
        completeness: f64::NAN,
        wall_samples: Vec::new(),
        estimates_m: Vec::new(),
        snaps: 0,
        steps: 0,
        failure: None,
    };
    while let Some(step) = sweep.next_step() {
        let step = match step {
            Ok(step) => step,
            Err(e) => {
                out.failure = Some(e.to_string());
                break;
            }
        };
        out.steps += 1;
        if step.report.snapped {
            out.snaps += 1;
        }
        coverage.pass(&step.contacts);
        if !sensors.is_sample_due(step.t_s) {
            continue;
        }
        let ok = sensors
            .sense_angles_rad(&step.theta_rad, &mut sensed)
            .and_then(|()| sensors.sense_touch(&step.contacts, &mut touch))
            .and_then(|()| {
                estimates.clear();
                estimate_contacts(
                    &chain,
                    &step.base_m,
                    &sensed,
                    &touch,
                    &sensors.touch_layout(),
                    &mut estimates,
                )
            });
        if ok.is_err() {
            continue;
        }
        acc.add(&walls, &estimates);
        coverage.estimate(estimates.iter().map(|e| e.point_m));
        out.estimates_m
            .extend(estimates.iter().map(|e| [e.point_m.x, e.point_m.y]));
    }
    let score = acc.score();
    out.mean_error_mm = score.mean_error_mm.unwrap_or(f64::NAN);
    out.points = score.count;
    let c = coverage
        .coverage(&walls, &antenna_cli::sweep::coverage_settings())
        .map_err(|e| ReproduceError::Scene {
            path: label,
            message: e.to_string(),
        })?;
    out.coverage_error_mm = c.mean_error_mm.unwrap_or(f64::NAN);
    out.coverage_p90_mm = c.p90_error_mm.unwrap_or(f64::NAN);
    out.completeness = c.completeness.unwrap_or(f64::NAN);
    out.wall_samples = c.samples;
    Ok(out)
}
