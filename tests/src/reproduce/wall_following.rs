//! Thesis 4.2.1 / Table 4.1: the stiffness profile against wall following. Nine segments of
//! 40 mm (`links = 9`: a base link and 8 flexible joints), base angle 30 deg, a smooth wall
//! at 8 deg closing from 20 to 9 cm over the run, 16.7 mm/s for 50 s sampled at 100 Hz,
//! starting bent backwards with the tip on the wall (`examples/wall_following_4_2_1.toml`),
//! once per profile.

use std::panic::{AssertUnwindSafe, catch_unwind};

use nalgebra::Vector2;
use rayon::prelude::*;
use sim_core::sweep::{Sweep, SweepScene};
use sim_core::{StiffnessProfile, pearson_correlation, spearman_correlation};

use super::{ReproduceError, mean_sd_median, with_profile};

/// One profile's run.
#[derive(Clone, Debug)]
pub struct ProfileRun {
    /// The profile.
    pub profile: StiffnessProfile,
    /// What the placement did.
    pub placement: String,
    /// Per step: time, s.
    pub t_s: Vec<f64>,
    /// Per step: the base pivot's distance to the wall, m.
    pub wall_distance_m: Vec<f64>,
    /// Per step: the preview distance, m (`NaN` without contact).
    pub preview_m: Vec<f64>,
    /// Per step: the point of bend (joint number).
    pub bend_joint: Vec<f64>,
    /// Per step: the point of contact (point number; `NaN` without contact).
    pub contact_joint: Vec<f64>,
    /// Chain snapshots (ground-frame points base..tip) every 5 s, with the time.
    pub snapshots: Vec<(f64, Vec<Vector2<f64>>)>,
    /// Steps that snapped.
    pub snaps: usize,
    /// Wall-clock time of the sweep, seconds.
    pub elapsed_s: f64,
}

/// Table 4.1's columns for one profile.
#[derive(Clone, Copy, Debug)]
pub struct Table41Row {
    /// Pearson (point of bend, wall distance); `None` when undefined (a constant series).
    pub bend_pearson: Option<f64>,
    /// Spearman (point of bend, wall distance).
    pub bend_spearman: Option<f64>,
    /// Pearson (point of contact, wall distance).
    pub contact_pearson: Option<f64>,
    /// Spearman (point of contact, wall distance).
    pub contact_spearman: Option<f64>,
    /// Preview distance mean, cm.
    pub preview_mean_cm: f64,
    /// Preview distance standard deviation, cm.
    pub preview_sd_cm: f64,
    /// Preview distance median, cm.
    pub preview_median_cm: f64,
}

impl ProfileRun {
    /// The Table 4.1 row of this run (steps with a contact).
    pub fn table_row(&self) -> Table41Row {
        let mut d = Vec::new();
        let mut bend = Vec::new();
        let mut contact = Vec::new();
        let mut preview = Vec::new();
        for i in 0..self.t_s.len() {
            if self.contact_joint[i].is_finite() {
                d.push(self.wall_distance_m[i]);
                bend.push(self.bend_joint[i]);
                contact.push(self.contact_joint[i]);
                preview.push(self.preview_m[i] * 100.0);
            }
        }
        let (preview_mean_cm, preview_sd_cm, preview_median_cm) = mean_sd_median(&preview);
        Table41Row {
            bend_pearson: pearson_correlation(&bend, &d),
            bend_spearman: spearman_correlation(&bend, &d),
            contact_pearson: pearson_correlation(&contact, &d),
            contact_spearman: spearman_correlation(&contact, &d),
            preview_mean_cm,
            preview_sd_cm,
            preview_median_cm,
        }
    }
}

/// Runs the sweep of `base` with `profile`.
///
/// # Errors
/// [`ReproduceError`] when the chain cannot be built or a step fails.
pub fn run_profile(
    base: &SweepScene,
    profile: StiffnessProfile,
) -> Result<ProfileRun, ReproduceError> {
    let label = format!("4.2.1 {}", profile.name());
    let scene = SweepScene {
        chain: with_profile(&base.chain, profile.clone())?,
        ..base.clone()
    };
    let started = std::time::Instant::now();
    let mut sweep = Sweep::new(scene).map_err(|source| ReproduceError::Sweep {
        label: label.clone(),
        source,
    })?;
    let placement = sweep.placement_note().to_owned();
    let mut run = ProfileRun {
        profile,
        placement,
        t_s: Vec::new(),
        wall_distance_m: Vec::new(),
        preview_m: Vec::new(),
        bend_joint: Vec::new(),
        contact_joint: Vec::new(),
        snapshots: Vec::new(),
        snaps: 0,
        elapsed_s: 0.0,
    };
    let snapshot_every = (5.0 / sweep.motion().step_s).round() as usize;
    while let Some(step) = sweep.next_step() {
        let step = step.map_err(|source| ReproduceError::Sweep {
            label: label.clone(),
            source,
        })?;
        let sim = sweep.sim();
        let distance = sim
            .walls()
            .iter()
            .map(|w| w.signed_distance(&step.base_m).gap_m)
            .fold(f64::INFINITY, f64::min);
        run.t_s.push(step.t_s);
        run.wall_distance_m.push(distance);
        run.preview_m.push(step.preview_m.unwrap_or(f64::NAN));
        run.bend_joint
            .push(step.bend_joint.map_or(f64::NAN, |j| j as f64));
        run.contact_joint
            .push(step.contact_joint.map_or(f64::NAN, |j| j as f64));
        if step.report.snapped {
            run.snaps += 1;
        }
        if step.step % snapshot_every.max(1) == 0 || step.step == 1 {
            run.snapshots.push((step.t_s, chain_points(sim)));
        }
    }
    run.elapsed_s = started.elapsed().as_secs_f64();
    Ok(run)
}

/// The chain's points (base pivot, then every link end) in the ground frame.
pub fn chain_points(sim: &sim_core::contact::QuasiStatic) -> Vec<Vector2<f64>> {
    let base = sim.base_m();
    let mut out = vec![base];
    if let Ok(poses) = sim_core::frame_poses(sim.chain(), sim.theta_rad(), sim_core::Frame::GROUND)
    {
        for link in 0..=sim.chain().n() {
            if let Some(p) = poses.position_m(sim_core::Frame::link(link)) {
                out.push(base + p);
            }
        }
    }
    out
}

/// Runs every profile of [`super::TABLE_4_1_PROFILES`] (in parallel, on rayon's pool).
///
/// # Errors
/// The first run's error.
pub fn run_all(base: &SweepScene) -> Result<Vec<ProfileRun>, ReproduceError> {
    let runs: Vec<Result<ProfileRun, ReproduceError>> = super::TABLE_4_1_PROFILES
        .par_iter()
        .map(|p| {
            catch_unwind(AssertUnwindSafe(|| run_profile(base, p.clone()))).unwrap_or_else(|_| {
                Err(ReproduceError::Scene {
                    path: "4.2.1".into(),
                    message: "a run panicked".into(),
                })
            })
        })
        .collect();
    runs.into_iter().collect()
}
