//! Seed 4.2.2: wall shape against wall following. Sinusoidal walls of spatial frequency
//! 2.8, 4.2, 6.3, 9.5 and 14.2 1/m, and the trapezoid; a distally decreasing profile against
//! the constant one; the contact points the robot would estimate from its 12-bit joint
//! angles and touch bits, scored against the true wall (mean spatial error, mm).
//! `examples/mapping_4_2_2.toml` is the base scene of the sinusoids (its wall's frequency and
//! the profile are varied here), `examples/mapping_trapezoid_4_2_2.toml` the trapezoid's.

use sim_core::sweep::{Sweep, SweepScene};
use sim_core::{
    MappingAccumulator, Sinusoid, StiffnessProfile, TouchLayout, Wall, WallShape,
    estimate_contacts, sensed_theta_rad,
};

use super::{ReproduceError, with_profile};

/// The seed's wall frequencies, 1/m.
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
    )
}

/// Runs `profile` along the trapezoid of `base` (`examples/mapping_trapezoid_4_2_2.toml`).
///
/// # Errors
/// As [`run`].
pub fn run_trapezoid(
    base: &SweepScene,
    profile: StiffnessProfile,
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
    )
}

/// Sweeps `scene`, estimating the contacts from what the robot senses at every step.
fn map(
    label: String,
    scene: SweepScene,
    profile: StiffnessProfile,
    frequency_per_m: Option<f64>,
) -> Result<MappingRun, ReproduceError> {
    let walls = scene.walls.clone();
    let chain = scene.chain.clone();
    let mut sweep = Sweep::new(scene).map_err(|source| ReproduceError::Sweep {
        label: label.clone(),
        source,
    })?;
    let mut acc = MappingAccumulator::default();
    let mut sensed = vec![0.0; chain.dof()];
    let mut estimates = Vec::new();
    let mut out = MappingRun {
        profile,
        frequency_per_m,
        mean_error_mm: f64::NAN,
        points: 0,
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
        let ok = sensed_theta_rad(&step.theta_rad, &mut sensed).and_then(|()| {
            estimates.clear();
            estimate_contacts(
                &chain,
                &step.base_m,
                &sensed,
                &step.touch_bits,
                &TouchLayout::default(),
                &mut estimates,
            )
        });
        if ok.is_err() {
            continue;
        }
        acc.add(&walls, &estimates);
        out.estimates_m
            .extend(estimates.iter().map(|e| [e.point_m.x, e.point_m.y]));
    }
    let score = acc.score();
    out.mean_error_mm = score.mean_error_mm.unwrap_or(f64::NAN);
    out.points = score.count;
    Ok(out)
}
