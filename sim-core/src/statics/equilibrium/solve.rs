//! The entry points [`solve_equilibrium`] and [`solve_equilibrium_with`]: validation, the
//! start, the dead-load or pinned solve, and the report.

use nalgebra::Vector2;

use super::newton::{Recorder, minimize};
use super::options::{LinearSolver, SolveOptions, SolverSettings};
use super::pinned::solve_pinned;
use super::report::{Equilibrium, LimitSide, SolveTrace, count_inflections};
use super::stability::is_stable;
use super::workspace::{Merit, Workspace};
use super::{EquilibriumError, EquilibriumProblem, InitialGuess};

/// The equilibrium reached from `initial`: a KKT point of
/// `min U(theta) - F . p_n(theta)` over the flexible joints, subject to the joint limits and,
/// with a pin, `p_n(theta) = P`. See the [module documentation](super) for the method.
///
/// Returns `Ok` with `converged: false` when the iteration budget runs out.
///
/// # Errors
/// [`EquilibriumError`]: bad input (wrong lengths, NaN, an explicit start outside the
/// limits, invalid options), an unreachable pin target, a pin the limits keep out of reach,
/// or a numerical breakdown.
pub fn solve_equilibrium(
    problem: &EquilibriumProblem<'_>,
    initial: &InitialGuess,
    options: &SolveOptions,
) -> Result<Equilibrium, EquilibriumError> {
    solve_equilibrium_with(problem, initial, options, &SolverSettings::default()).map(|(e, _)| e)
}

/// [`solve_equilibrium`] with [`SolverSettings`]: the dense reference linear algebra, and the
/// merit history of every accepted step (a test hook).
///
/// # Errors
/// As [`solve_equilibrium`].
pub fn solve_equilibrium_with(
    problem: &EquilibriumProblem<'_>,
    initial: &InitialGuess,
    options: &SolveOptions,
    settings: &SolverSettings,
) -> Result<(Equilibrium, SolveTrace), EquilibriumError> {
    options.validate()?;
    problem.check()?;
    let chain = problem.chain;
    if let Some(pin) = problem.tip_pin_m {
        check_reach(chain, pin)?;
    }
    let x0 = initial.resolve(chain, problem.tip_pin_m)?;
    let mut ws = Workspace::new(chain, x0);
    let mut trace = SolveTrace::default();
    let mut iterations = 0;
    let linear = settings.linear_solver;
    let mut restarted_from = None;
    let mu = {
        let mut rec = Recorder {
            trace: settings.record_trace.then_some(&mut trace),
            segment: 0,
        };
        match problem.tip_pin_m {
            None => {
                let merit = Merit::dead_load(problem.tip_force_n);
                minimize(
                    &mut ws,
                    &merit,
                    options.tolerance,
                    options.max_iterations,
                    &mut iterations,
                    linear,
                    true,
                    &mut rec,
                )?;
                Vector2::zeros()
            }
            Some(pin) => {
                let mut restarts = RESTARTS
                    .iter()
                    .map(|make| make())
                    .filter(|start| start != initial);
                let mut starts = 1;
                let mut closest_m = f64::INFINITY;
                loop {
                    let solved = solve_pinned(
                        &mut ws,
                        problem.tip_force_n,
                        pin,
                        options.tolerance,
                        options.max_iterations,
                        linear,
                        &mut iterations,
                        &mut rec,
                    );
                    // The given start's answer stands as it is (converged or out of
                    // budget); a restart stands only if it meets the pin, else it is one
                    // more start that failed.
                    let gap_m = match solved {
                        Ok(mu) if restarted_from.is_none() => break mu,
                        Ok(mu) => {
                            let gap_m = (ws.tip - pin).norm();
                            if gap_m <= options.tolerance * ws.l_flex {
                                break mu;
                            }
                            gap_m
                        }
                        Err(EquilibriumError::PinInfeasible { gap_m, .. }) => gap_m,
                        Err(e) => return Err(e),
                    };
                    closest_m = closest_m.min(gap_m);
                    match restarts.next() {
                        Some(start) if iterations < options.max_iterations => {
                            ws = Workspace::new(chain, start.resolve(chain, Some(pin))?);
                            restarted_from = Some(start);
                            starts += 1;
                        }
                        _ => {
                            return Err(EquilibriumError::PinInfeasible {
                                gap_m: closest_m,
                                starts,
                                iterations,
                            });
                        }
                    }
                }
            }
        }
    };
    let mut eq = report(&mut ws, problem, mu, iterations, options.tolerance, linear)?;
    eq.restarted_from = restarted_from;
    Ok((eq, trace))
}

/// The standard starts a pinned search restarts from when the given start jams against the
/// joint limits short of the target, in this order.
const RESTARTS: [fn() -> InitialGuess; 5] = [
    || InitialGuess::Straight,
    || InitialGuess::C,
    || InitialGuess::C.mirrored(),
    || InitialGuess::S,
    || InitialGuess::S.mirrored(),
];

/// The distance from the first flexible joint to the pin target, if reachable.
fn check_reach(chain: &crate::Chain, pin: Vector2<f64>) -> Result<(), EquilibriumError> {
    let lengths = &chain.link_lengths_m()[1..];
    let reach: f64 = lengths.iter().sum();
    let longest = lengths.iter().copied().fold(0.0, f64::max);
    let min_reach = (2.0 * longest - reach).max(0.0);
    let (l0, t0) = (chain.link_lengths_m()[0], chain.base_angle_rad());
    let d = (pin - Vector2::new(l0 * t0.cos(), l0 * t0.sin())).norm();
    let slack = 1e-12 * reach;
    if d > reach + slack || d < min_reach - slack {
        return Err(EquilibriumError::Unreachable {
            distance_m: d,
            reach_m: reach,
            min_reach_m: min_reach,
        });
    }
    Ok(())
}

/// The report at `ws.x` with pin force `mu`.
fn report(
    ws: &mut Workspace,
    problem: &EquilibriumProblem<'_>,
    mu: Vector2<f64>,
    iterations: usize,
    tolerance: f64,
    linear: LinearSolver,
) -> Result<Equilibrium, EquilibriumError> {
    ws.kinematics();
    let f = problem.tip_force_n + mu;
    ws.gradient(f);
    let ts = ws.torque_scale(f);
    let mut residual = ws.stationarity(ts);
    if let Some(pin) = problem.tip_pin_m {
        residual = residual.max((ws.tip - pin).norm() / ws.l_flex.max(f64::MIN_POSITIVE));
    }
    if !residual.is_finite() || ws.x.iter().any(|t| !t.is_finite()) {
        return Err(EquilibriumError::NumericalBreakdown {
            iteration: iterations,
            reason: "non-finite result",
        });
    }
    let mut limit_sides = vec![LimitSide::Free; ws.n + 1];
    let mut limit_torques_nm = vec![0.0; ws.n + 1];
    for j in 0..ws.n {
        let (x, lo, hi, g) = (ws.x[j], ws.lo[j], ws.hi[j], ws.g[j]);
        let (side, torque) = if lo >= hi {
            if g >= 0.0 {
                (LimitSide::Clockwise, g)
            } else {
                (LimitSide::CounterClockwise, g)
            }
        } else if x <= lo {
            (LimitSide::Clockwise, g.max(0.0))
        } else if x >= hi {
            (LimitSide::CounterClockwise, g.min(0.0))
        } else {
            (LimitSide::Free, 0.0)
        };
        limit_sides[j + 1] = side;
        limit_torques_nm[j + 1] = torque;
    }
    let energy_j = ws.strain(&ws.x);
    let total_potential_j = energy_j - problem.tip_force_n.dot(&ws.tip);
    let stable = is_stable(ws, f, problem.tip_pin_m.is_some(), linear);
    Ok(Equilibrium {
        theta_rad: ws.theta(),
        energy_j,
        total_potential_j,
        iterations,
        kkt_residual: residual,
        converged: residual <= tolerance,
        stable,
        inflections: count_inflections(&ws.x),
        pin_force_n: mu,
        limit_sides,
        limit_torques_nm,
        restarted_from: None,
    })
}
