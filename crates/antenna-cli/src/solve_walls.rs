//! `antenna solve` on a scene with walls: the antenna placed as `[start]` says and settled
//! with friction (step 0 of the scene's sweep) is the equilibrium, reported with exactly the
//! fields of docs/scene-format.md ([`SolveReport`]).
//!
//! - `tip_force_n` is the force the tip exerts on what holds it: minus the walls' force on
//!   the tip when the tip (the distal end of link `n`) is a contact, zero otherwise.
//! - `iterations` and `residual` are the placement's Newton iterations and the final
//!   residual of its equations (metres); `converged` says the residual is within
//!   `[contact] tolerance_m` (or the solver's acceptable residual at a degenerate contact).
//! - `stable`: sim-core's stability test of the contact state (`Sweep::is_stable`: the
//!   Hessian of the Lagrangian positive definite on the tangent space of the active
//!   constraints).

use std::fmt::Write as _;

use sim_core::contact::Feature;
use sim_core::statics::equilibrium::count_inflections;
use sim_core::sweep::{Sweep, SweepStep};
use sim_core::{Frame, frame_poses, strain_energy_j};

use crate::solve::SolveReport;
use crate::sweep::record::ContactRecord;
use antenna_scene::{Scene, SweepFailure};

/// The settled posture of a scene with walls.
#[derive(Debug, Clone)]
pub struct WallEquilibrium {
    /// The report `antenna solve --json` prints.
    pub report: SolveReport,
    /// The placed state (step 0 of the sweep).
    pub placed: SweepStep,
    /// What the placement did, in words.
    pub note: String,
}

/// Places and settles the antenna of `scene` against its walls.
///
/// # Errors
/// [`SweepFailure`]: bad input (a start inside a wall, a wall the tip cannot reach), no
/// equilibrium found, or a numerical breakdown, each with the file and the key.
pub fn solve_wall_scene(scene: &Scene) -> Result<WallEquilibrium, SweepFailure> {
    let mut sweep =
        Sweep::new(scene.sweep_scene()?).map_err(|e| SweepFailure::from_sweep_error(scene, e))?;
    let stable = sweep.is_stable();
    let Some(placed) = sweep.placed().cloned() else {
        return Err(SweepFailure::Breakdown(format!(
            "{}: the sweep has no placed state",
            scene.locations.path
        )));
    };
    let sim = sweep.sim();
    let chain = sim.chain();
    let n = chain.n();
    let theta = &placed.theta_rad;
    let kinematics = |e: sim_core::KinematicsError| {
        SweepFailure::Breakdown(format!(
            "{}: positions of the settled posture: {e}",
            scene.locations.path
        ))
    };
    let poses = frame_poses(chain, theta, Frame::GROUND).map_err(kinematics)?;
    let base = placed.base_m;
    let joints_m: Vec<[f64; 2]> = (0..=n)
        .map(|i| {
            let p = poses.position_m(Frame::link(i)).unwrap_or_default() + base;
            [p.x, p.y]
        })
        .collect();
    let tip_m = joints_m.last().copied().unwrap_or([base.x, base.y]);
    let on_tip = placed
        .contacts
        .iter()
        .filter(|c| c.feature == Feature::Vertex { link: n })
        .fold(nalgebra::Vector2::zeros(), |sum, c| sum + c.force_n());
    let energy_j = strain_energy_j(chain, theta).map_err(kinematics)?;
    let residual = placed.report.residual_m;
    let report = SolveReport {
        theta_rad: theta.clone(),
        joints_m,
        tip_m,
        energy_j,
        tip_force_n: [-on_tip.x + 0.0, -on_tip.y + 0.0],
        iterations: placed.report.iterations,
        residual,
        converged: residual <= scene.contact.tolerance_m.max(scene.contact.acceptable_m),
        inflections: count_inflections(&theta[1..]),
        stable,
    };
    Ok(WallEquilibrium {
        report,
        placed,
        note: sweep.placement_note().to_string(),
    })
}

/// A short human summary of the settled posture: what the placement did, convergence,
/// stability, energy, the tip and its force on the wall, the contacts and the joint angles.
pub fn wall_summary(scene: &Scene, eq: &WallEquilibrium) -> String {
    let r = &eq.report;
    let yes_no = |b: bool| if b { "yes" } else { "no" };
    let mut out = String::new();
    let _ = writeln!(out, "placement: {}", eq.note);
    let _ = writeln!(
        out,
        "converged: {} ({} Newton iterations, residual {:.3e} m); stable: {}; inflections: {}",
        yes_no(r.converged),
        r.iterations,
        r.residual,
        yes_no(r.stable),
        r.inflections
    );
    let _ = writeln!(
        out,
        "energy U = {:.6e} J; tip at [{:.6}, {:.6}] m; the tip pushes on the wall with [{:.6e}, {:.6e}] N",
        r.energy_j, r.tip_m[0], r.tip_m[1], r.tip_force_n[0], r.tip_force_n[1]
    );
    let _ = writeln!(out, "contacts: {}", eq.placed.contacts.len());
    for c in &eq.placed.contacts {
        let record = ContactRecord::new(c);
        let _ = writeln!(
            out,
            "  link {:<3} {:<6} wall {} at [{:.6}, {:.6}] m: N = {:.4e} N, T = {:.4e} N, {}{}",
            record.link,
            record.kind,
            record.wall,
            record.point_m[0],
            record.point_m[1],
            record.normal_force_n,
            record.shear_force_n,
            record.state,
            if record.anchored { ", anchored" } else { "" }
        );
    }
    let _ = writeln!(out, "joint angles (deg):");
    let limits = scene.chain.joint_limits();
    for (j, theta) in r.theta_rad.iter().enumerate() {
        let note = match limits.get(j) {
            _ if j == 0 => " (base, fixed)",
            Some(l) if j > 0 && *theta <= l.cw_rad => " (on its clockwise limit)",
            Some(l) if j > 0 && *theta >= l.ccw_rad => " (on its counter-clockwise limit)",
            _ => "",
        };
        let _ = writeln!(out, "  theta_{j:<3} {:>10.4}{note}", theta.to_degrees());
    }
    out
}
