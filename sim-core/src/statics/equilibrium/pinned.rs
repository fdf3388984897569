//! The pinned tip: `p_n(theta) = P`, the tip free to rotate, with joint limits.
//!
//! # Method: homotopy in the target, augmented Lagrangian, projected Newton inside
//! The equilibrium reached "from a start" is defined by this search, and the search says
//! what it does:
//! 1. **Homotopy.** The pin target moves in `K` equal steps on the straight segment from
//!    the start's own tip position to `P` (`K = ceil(|P - tip_start| / (0.2 L))`, 1 to 10,
//!    `L` the flexible length). Each intermediate target is solved to `max(tol, 1e-6)`
//!    with at most 30 Newton iterations; the last to the requested tolerance. Moving the
//!    target slowly keeps the search on the branch of equilibria that starts at the start
//!    posture (a C stays a C, an S an S) unless that branch folds or snaps, in which case
//!    the search follows the descent wherever it goes: it is a search, not a guarantee.
//! 2. **Augmented Lagrangian.** For one target, minimize over the box of limits
//!    `L_A = U - F . p_n - mu . c + rho/2 |c|^2`, `c = p_n - P`, by projected Newton
//!    ([`super::newton`]); then `mu <- mu - rho c`. `mu` is the force the pin exerts on the
//!    tip (the least-squares `J^T mu = grad U - J^T F` at the start, to begin with).
//!    `rho` starts at `1e3 T / L^2` (`T` the torque scale) and grows tenfold whenever the
//!    gap `|c|` fails to shrink fourfold, up to `1e8` times its start; if the gap still
//!    stagnates (three updates in a row, or the descent stalls or runs out of budget with
//!    the penalty at its cap and the gap not shrinking fourfold) on the final target the
//!    pin is declared infeasible within the limits ([`EquilibriumError::PinInfeasible`]).
//!    Within one Newton stage the merit `L_A` never increases; each multiplier update or
//!    target move starts a new merit (a new [`TraceStep::segment`](super::TraceStep)).
//! 3. **Near-singular Jacobian.** A target near full reach (0.9999 L, the chain almost
//!    straight) makes `J` nearly rank one; the penalty term `rho J^T J` and the Woodbury
//!    solve with an inertia check stay well defined there, and the multiplier update
//!    converges linearly with a small rate once `rho` is large.

use nalgebra::{Matrix2, Vector2};

use super::EquilibriumError;
use super::escape::escape_saddle;
use super::newton::{Recorder, Status, minimize};
use super::options::LinearSolver;
use super::stability::is_stable;
use super::workspace::{Merit, Workspace};

/// The least-squares pin force `mu`: `min |J^T mu - (grad U - J^T F)|`, regularized.
fn least_squares_force(ws: &mut Workspace, force: Vector2<f64>) -> Vector2<f64> {
    ws.kinematics();
    ws.gradient(force);
    let mut jjt = Matrix2::zeros();
    let mut jg = Vector2::zeros();
    for j in 0..ws.n {
        let col = Vector2::new(-ws.qy[j], ws.qx[j]);
        jjt += col * col.transpose();
        jg += col * ws.g[j];
    }
    let reg = 1e-12 * jjt.trace().max(f64::MIN_POSITIVE);
    (jjt + Matrix2::identity() * reg)
        .try_inverse()
        .map_or_else(Vector2::zeros, |inv| inv * jg)
}

/// Solves the pinned problem from `ws.x`; returns the pin force `mu`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve_pinned(
    ws: &mut Workspace,
    force: Vector2<f64>,
    target: Vector2<f64>,
    tolerance: f64,
    max_iterations: usize,
    linear: LinearSolver,
    iterations: &mut usize,
    rec: &mut Recorder<'_>,
) -> Result<Vector2<f64>, EquilibriumError> {
    let length = ws.l_flex.max(f64::MIN_POSITIVE);
    let start_tip = ws.tip_of(&ws.x);
    let stages = ((target - start_tip).norm() / (0.2 * length))
        .ceil()
        .clamp(1.0, 10.0) as usize;
    let mut mu = least_squares_force(ws, force);
    let ts = ws.torque_scale(force + mu);
    let rho0 = 1e3 * ts / (length * length);
    let rho_max = 1e8 * rho0;
    let mut rho = rho0;
    let mut reached = true;
    for stage in 1..=stages {
        let last = stage == stages;
        // An intermediate target the limits keep out of reach (or a stage out of budget)
        // leaves a multiplier and penalty inflated for a point the chain cannot hold:
        // start the next stage afresh from the least-squares force instead.
        if !reached {
            mu = least_squares_force(ws, force);
            rho = rho0;
        }
        reached = false;
        let goal = start_tip + (target - start_tip) * (stage as f64 / stages as f64);
        let tol = if last { tolerance } else { tolerance.max(1e-6) };
        let budget = if last {
            max_iterations
        } else {
            max_iterations.min(*iterations + 30)
        };
        let mut prev_gap = f64::INFINITY;
        let mut stagnant = 0;
        let mut escapes = 0;
        loop {
            let merit = Merit {
                force,
                mu,
                rho,
                target: Some(goal),
            };
            let (status, _) = minimize(ws, &merit, tol, budget, iterations, linear, false, rec)?;
            // A stationary point of the merit that is a saddle of the pinned problem
            // (the straight start with the target on its axis): step off it first.
            if status == Status::Converged
                && escapes < 10
                && !is_stable(ws, force + mu - rho * (ws.tip - goal), true, linear)
                && escape_saddle(ws, &merit, linear, iterations, rec).is_some()
            {
                escapes += 1;
                continue;
            }
            let c = ws.tip - goal;
            mu -= rho * c;
            let gap = c.norm() / length;
            if !gap.is_finite() {
                return Err(EquilibriumError::NumericalBreakdown {
                    iteration: *iterations,
                    reason: "non-finite pin gap",
                });
            }
            if status == Status::Converged && gap <= tol {
                reached = true;
                break;
            }
            let stopped = status == Status::Stalled || *iterations >= budget;
            let shrinking = gap <= 0.25 * prev_gap;
            if !stopped && !shrinking {
                if rho < rho_max {
                    rho = (rho * 10.0).min(rho_max);
                    stagnant = 0;
                } else {
                    stagnant += 1;
                }
            }
            // The gap stagnates with the penalty at its cap (three updates in a row, or the
            // descent stopped there): the chain is jammed against its limits.
            let jammed = !shrinking && rho >= rho_max && (stopped || stagnant >= 3);
            if jammed && last {
                return Err(EquilibriumError::PinInfeasible {
                    gap_m: gap * length,
                    starts: 1,
                    iterations: *iterations,
                });
            }
            if jammed || stopped {
                break;
            }
            prev_gap = gap;
        }
    }
    Ok(mu)
}
