//! `antenna solve`: a [`Scene`] through sim-core's equilibrium solver, reported exactly as
//! `docs/scene-format.md` says ([`SolveReport`]), or as a short human summary.
//!
//! sim-core works relative to the base attachment point; the report is in the ground frame,
//! so the base position (`[base] position_m`) is added to every point and subtracted from
//! the pin.

use std::fmt::Write as _;

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};
use sim_core::{
    Equilibrium, EquilibriumError, EquilibriumProblem, Frame, InitialGuess, KinematicsError,
    LimitSide, MinimaSearch, SolveOptions, all_minima, frame_poses, solve_equilibrium,
};

use antenna_scene::{Scene, Start};

/// The JSON object `antenna solve --json` prints (field names fixed by docs/scene-format.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SolveReport {
    /// The `n + 1` joint angles, radians, `theta_0` first.
    pub theta_rad: Vec<f64>,
    /// Positions of frames `0..=n` (`n + 1` points `[x, y]`), ground frame, metres.
    pub joints_m: Vec<[f64; 2]>,
    /// The tip position `[x, y]`, ground frame, metres.
    pub tip_m: [f64; 2],
    /// Joint spring energy `U`, joules.
    pub energy_j: f64,
    /// The force the tip exerts on what holds it (minus the pin's force on the tip), newtons;
    /// zero when nothing holds it.
    pub tip_force_n: [f64; 2],
    /// Solver iterations.
    pub iterations: usize,
    /// Final KKT residual.
    pub residual: f64,
    /// Whether the residual is within the tolerance.
    pub converged: bool,
    /// Sign changes of the flexible joint angles (angles under 1e-6 rad ignored).
    pub inflections: usize,
    /// Whether the equilibrium is a strict local minimum.
    pub stable: bool,
}

/// What the solver acts on: the chain, the load and the pin relative to the base.
pub fn problem(scene: &Scene) -> EquilibriumProblem<'_> {
    EquilibriumProblem {
        chain: &scene.chain,
        tip_force_n: scene.tip_force_n,
        tip_pin_m: scene.tip_pin_relative_m(),
    }
}

/// The solver's start for a scene's `initial`.
pub fn initial_guess(start: &Start) -> InitialGuess {
    match start {
        Start::Straight => InitialGuess::Straight,
        Start::C => InitialGuess::C,
        Start::S => InitialGuess::S,
        Start::MirrorC => InitialGuess::C.mirrored(),
        Start::MirrorS => InitialGuess::S.mirrored(),
        Start::AnglesRad(a) => InitialGuess::Angles(a.clone()),
    }
}

/// The scene's solver options, the solver's defaults where the scene is silent.
pub fn solve_options(scene: &Scene) -> SolveOptions {
    let defaults = SolveOptions::default();
    SolveOptions {
        tolerance: scene.solver.tolerance.unwrap_or(defaults.tolerance),
        max_iterations: scene
            .solver
            .max_iterations
            .unwrap_or(defaults.max_iterations),
    }
}

/// Why a solve produced no answer.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    /// The solver refused the input (an unreachable pin, a bad start, ...).
    #[error("{0}")]
    Input(EquilibriumError),
    /// The iteration broke down.
    #[error("{0}")]
    Breakdown(EquilibriumError),
    /// Positions of the answer could not be computed (a bug: the answer has the wrong shape).
    #[error("positions of the equilibrium: {0}")]
    Kinematics(#[from] KinematicsError),
}

impl From<EquilibriumError> for SolveError {
    fn from(e: EquilibriumError) -> Self {
        match e {
            EquilibriumError::NumericalBreakdown { .. } => SolveError::Breakdown(e),
            other => SolveError::Input(other),
        }
    }
}

/// The report of one equilibrium of `scene`.
///
/// # Errors
/// [`KinematicsError`] if the answer does not fit the chain.
pub fn report(scene: &Scene, eq: &Equilibrium) -> Result<SolveReport, KinematicsError> {
    let poses = frame_poses(&scene.chain, &eq.theta_rad, Frame::GROUND)?;
    let b = scene.base_position_m;
    let joints_m: Vec<[f64; 2]> = (0..=scene.n())
        .map(|i| {
            let p = poses
                .position_m(Frame::link(i))
                .unwrap_or_else(Vector2::zeros)
                + b;
            [p.x, p.y]
        })
        .collect();
    let tip_m = joints_m.last().copied().unwrap_or([b.x, b.y]);
    let on_holder = -eq.pin_force_n;
    Ok(SolveReport {
        theta_rad: eq.theta_rad.clone(),
        joints_m,
        tip_m,
        energy_j: eq.energy_j,
        tip_force_n: [on_holder.x + 0.0, on_holder.y + 0.0],
        iterations: eq.iterations,
        residual: eq.kkt_residual,
        converged: eq.converged,
        inflections: eq.inflections,
        stable: eq.stable,
    })
}

/// Solves the scene from its `initial` start.
///
/// # Errors
/// [`SolveError`] when the solver refuses the input or breaks down (running out of
/// iterations is not an error: the answer has `converged: false`).
pub fn solve_scene(scene: &Scene) -> Result<(Equilibrium, SolveReport), SolveError> {
    let eq = solve_equilibrium(
        &problem(scene),
        &initial_guess(&scene.solver.initial),
        &solve_options(scene),
    )?;
    let r = report(scene, &eq)?;
    Ok((eq, r))
}

/// Every distinct stable equilibrium the multi-start search finds, lowest total potential
/// first (the scene's `initial` is not used: the search has its own starts).
///
/// # Errors
/// As [`solve_scene`].
pub fn all_minima_of_scene(
    scene: &Scene,
    search: &MinimaSearch,
) -> Result<Vec<(Equilibrium, SolveReport)>, SolveError> {
    let minima = all_minima(&problem(scene), &solve_options(scene), search)?;
    minima
        .into_iter()
        .map(|eq| {
            let r = report(scene, &eq)?;
            Ok((eq, r))
        })
        .collect()
}

fn yes_no(b: bool) -> &'static str {
    if b { "yes" } else { "no" }
}

/// A short human summary of one equilibrium: angles in degrees, tip, energy, iterations,
/// residual, convergence, stability, inflections.
pub fn summary(scene: &Scene, eq: &Equilibrium, r: &SolveReport) -> String {
    let mut out = String::new();
    let shape = match r.inflections {
        0 => "C-like",
        1 => "S-like",
        _ => "wavy",
    };
    let _ = writeln!(
        out,
        "converged: {} ({} iterations, KKT residual {:.3e}); stable: {}; inflections: {} ({shape})",
        yes_no(r.converged),
        r.iterations,
        r.residual,
        yes_no(r.stable),
        r.inflections
    );
    let _ = writeln!(
        out,
        "energy U = {:.6e} J; tip at [{:.6}, {:.6}] m",
        r.energy_j, r.tip_m[0], r.tip_m[1]
    );
    if scene.tip_pin_m.is_some() {
        let _ = writeln!(
            out,
            "tip pushes on the pin with [{:.6e}, {:.6e}] N",
            r.tip_force_n[0], r.tip_force_n[1]
        );
    }
    let _ = writeln!(out, "joint angles (deg):");
    for (j, theta) in r.theta_rad.iter().enumerate() {
        let note = if j == 0 {
            " (base, fixed)"
        } else {
            match eq.limit_sides.get(j) {
                Some(LimitSide::Clockwise) => " (on its clockwise limit)",
                Some(LimitSide::CounterClockwise) => " (on its counter-clockwise limit)",
                _ => "",
            }
        };
        let _ = writeln!(out, "  theta_{j:<3} {:>10.4}{note}", theta.to_degrees());
    }
    out
}
