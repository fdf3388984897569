//! What a solve reports: [`Equilibrium`], [`LimitSide`], and the per-step merit history
//! [`SolveTrace`].

use nalgebra::Vector2;

use super::InitialGuess;

/// Which side of its range a joint rests on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LimitSide {
    /// Strictly inside its limits (and the base joint).
    Free,
    /// On its clockwise (lower) limit `cw_rad`.
    Clockwise,
    /// On its counter-clockwise (upper) limit `ccw_rad`.
    CounterClockwise,
}

/// The answer of one solve.
#[derive(Clone, Debug, PartialEq)]
pub struct Equilibrium {
    /// `n + 1` joint angles, radians, `theta_0` (the base angle) first.
    pub theta_rad: Vec<f64>,
    /// Joint spring energy `U` only, joules.
    pub energy_j: f64,
    /// `U - F . p_n`, joules: what is minimized (with a pin, on the pinned set).
    pub total_potential_j: f64,
    /// Newton iterations, summed over every stage.
    pub iterations: usize,
    /// The KKT residual, dimensionless: the larger of
    /// - the projected-gradient stationarity `max_j |theta_j - clamp(theta_j - g_j / T, cw_j, ccw_j)|`
    ///   over the flexible joints, where `g = K (theta - rest) - J^T (F + lambda)` is the
    ///   gradient of the Lagrangian (`lambda` the pin force, zero without a pin) and
    ///   `T = max_j k_j + |F + lambda| L` a torque scale (N m/rad; `L` the flexible length).
    ///   Inside the limits this is `|g_j| / T`; on a limit it is zero exactly when the stop
    ///   pushes the right way;
    /// - the pin gap `|p_n - P| / L` (zero without a pin).
    pub kkt_residual: f64,
    /// Whether `kkt_residual <= tolerance`.
    pub converged: bool,
    /// A strict local minimum: the Hessian of the Lagrangian is positive definite on the
    /// tangent space of the active constraints (the joints on a limit held fixed, and the
    /// null space of the pin Jacobian). See [`super::stability`].
    pub stable: bool,
    /// Sign changes along `theta_1..theta_n`, angles with `|theta| < 1e-6` rad ignored.
    pub inflections: usize,
    /// The force the pin exerts ON the tip, newtons, ground frame (zero without a pin).
    pub pin_force_n: Vector2<f64>,
    /// `n + 1` entries; entry 0 (the base) is [`LimitSide::Free`].
    pub limit_sides: Vec<LimitSide>,
    /// `n + 1` entries: the torque the stop exerts on joint `j`, N m (0 when free). A clockwise
    /// stop pushes counter-clockwise (`>= 0`), a counter-clockwise stop pushes clockwise
    /// (`<= 0`).
    pub limit_torques_nm: Vec<f64>,
    /// `None` when the answer was reached from the given start. With a pin, the search from
    /// the given start can jam against the joint limits short of the target; it then
    /// restarts from the standard starts in turn (straight, C, mirrored C, S, mirrored S)
    /// and this names the one it was reached from.
    pub restarted_from: Option<InitialGuess>,
}

/// One entry of a [`SolveTrace`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceStep {
    /// Which merit function: it changes when the pin target moves (homotopy stage) or the
    /// augmented-Lagrangian multiplier or penalty is updated. Within one segment the merit
    /// never increases.
    pub segment: usize,
    /// The merit after the step, joules: the starting value of the segment plus the sum of
    /// the accepted changes.
    pub merit_j: f64,
    /// The change of the merit over the step, joules, evaluated as an accurate difference
    /// (not as a difference of two rounded totals); `<= 0` for every accepted step, `0` for
    /// the first entry of a segment.
    pub change_j: f64,
    /// The step length `alpha` of the projected line search (0 for the first entry of a
    /// segment).
    pub step_length: f64,
    /// The stationarity residual of the merit before the step.
    pub residual: f64,
    /// Whether the Newton matrix had to be shifted or modified (it was indefinite) to get a
    /// descent direction, or the step was a negative-curvature escape from a saddle.
    pub modified: bool,
}

/// The merit history of a solve (a test hook: recorded only when
/// [`SolverSettings::record_trace`](super::SolverSettings::record_trace) is set).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SolveTrace {
    /// One entry at the start of each segment, then one per accepted step.
    pub steps: Vec<TraceStep>,
}

impl SolveTrace {
    /// Whether the merit never increased within a segment.
    pub fn is_monotone(&self) -> bool {
        self.steps.windows(2).all(|w| {
            w[1].segment != w[0].segment || (w[1].merit_j <= w[0].merit_j && w[1].change_j <= 0.0)
        })
    }
}

/// Sign changes along `theta_1..theta_n`, ignoring `|theta| < 1e-6` rad.
pub fn count_inflections(flexible_rad: &[f64]) -> usize {
    let mut last = 0.0_f64;
    let mut count = 0;
    for &t in flexible_rad {
        if t.abs() < 1e-6 {
            continue;
        }
        if last != 0.0 && (t > 0.0) != (last > 0.0) {
            count += 1;
        }
        last = t;
    }
    count
}
