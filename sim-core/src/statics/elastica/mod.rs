//! Reference solver for the planar inextensible Euler-Bernoulli cantilever (the elastica)
//! under a dead tip force (docs/model.md section 5).
//!
//! The beam has length `L`, bending stiffness `EI(s)` (N m^2) along the arc length `s`, is
//! clamped at the origin at angle `theta0` and carries a dead force `F = (Fx, Fy)` at its free
//! tip. With `M(s)` the bending moment that the part beyond `s` exerts on the section (the
//! moment of the tip force about the section, `M(s) = (x_L - x(s)) Fy - (y_L - y(s)) Fx`):
//!
//! ```text
//! x' = cos theta,  y' = sin theta,  theta' = M / EI(s),  M' = Fx sin theta - Fy cos theta,
//! x(0) = y(0) = 0,  theta(0) = theta0,  M(L) = 0.
//! ```
//!
//! [`solve`] shoots on the unknown clamp moment `M(0)`: Newton's method (with backtracking,
//! and load continuation as a fallback) on the residual `M(L)`, whose derivative comes from
//! the variational equations integrated alongside. The integrator is a Gragg-Bulirsch-Stoer
//! extrapolation method (modified midpoint rule with step counts 2, 4, ..., 12 and
//! Aitken-Neville extrapolation in `h^2`, order 12) with adaptive step-size control; it
//! reaches the default `1e-13` relative local tolerance in tens of steps. Breakpoints of
//! `EI` (piecewise-constant sections, or ones declared for a closure) and shape sample
//! points are hit exactly, so a jump in `EI` never sits inside a step.
//!
//! For a uniform beam loaded perpendicular to the clamp direction the classical closed form
//! by elliptic integrals (Bisshopp & Drucker 1945) is in [`perpendicular_load_closed_form`];
//! the two agree to better than `1e-10` (see the tests).
//!
//! A chain of rigid links with joint springs `k_j = EI(x_j) / l` (joint `j` at arc length
//! `x_j`, links of length `l`) approximates this beam; as the number of links grows its
//! equilibria converge to the elastica's, which is what this solver is the reference for.

use std::f64::consts::FRAC_PI_2;
use std::fmt;
use std::sync::Arc;

/// Number of columns of the extrapolation tableau (step counts 2, 4, ..., 2K).
const GBS_COLUMNS: usize = 6;
/// State: x, y, theta, M, d theta / d M0, d M / d M0.
type State = [f64; 6];

/// Errors from the elastica solver and the closed form.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ElasticaError {
    /// `length_m` is not finite and positive.
    #[error("length_m = {value_m} m is not finite and positive")]
    InvalidLength {
        /// The offending length, m.
        value_m: f64,
    },
    /// A tip force component is not finite.
    #[error("tip_force_n[{index}] = {value_n} N is not finite")]
    InvalidForce {
        /// 0 for `Fx`, 1 for `Fy`.
        index: usize,
        /// The offending value, N.
        value_n: f64,
    },
    /// `clamp_angle_rad` is not finite.
    #[error("clamp_angle_rad = {value_rad} rad is not finite")]
    InvalidClampAngle {
        /// The offending angle, rad.
        value_rad: f64,
    },
    /// A bending stiffness (a constant, a section value, or a closure's value at `s_m`) is not
    /// finite and positive.
    #[error("bending stiffness at s = {s_m} m is {value_n_m2} N m^2, not finite and positive")]
    InvalidStiffness {
        /// Arc length where it was evaluated (a section's start for piecewise values), m.
        s_m: f64,
        /// The offending value, N m^2.
        value_n_m2: f64,
    },
    /// A breakpoint is not strictly inside (0, L) or not strictly increasing.
    #[error("breakpoints_m[{index}] = {value_m} m is not strictly increasing inside (0, length_m)")]
    InvalidBreakpoint {
        /// Index into the breakpoints.
        index: usize,
        /// The offending value, m.
        value_m: f64,
    },
    /// Piecewise-constant stiffness needs one value more than breakpoints.
    #[error("{values} stiffness value(s) for {breakpoints} breakpoint(s); need breakpoints + 1")]
    SectionCountMismatch {
        /// Number of breakpoints.
        breakpoints: usize,
        /// Number of values.
        values: usize,
    },
    /// A solver option is out of its domain.
    #[error("option {field} = {value} is out of range ({expected})")]
    InvalidOption {
        /// Option name.
        field: &'static str,
        /// The offending value.
        value: f64,
        /// The domain, in words.
        expected: &'static str,
    },
    /// The adaptive integrator's step fell below `1e-14 L`.
    #[error("integration step size underflow at s = {s_m} m")]
    StepSizeUnderflow {
        /// Arc length reached, m.
        s_m: f64,
    },
    /// Newton's method (and load continuation) did not bring `M(L)` to zero.
    #[error(
        "shooting did not converge after {iterations} iterations: |M(L)| = {residual_n_m} N m at M(0) = {base_moment_n_m} N m"
    )]
    NotConverged {
        /// Newton iterations spent.
        iterations: usize,
        /// Best residual `|M(L)|` reached, N m.
        residual_n_m: f64,
        /// The clamp moment at that residual, N m.
        base_moment_n_m: f64,
    },
    /// `alpha` for the closed form is not finite.
    #[error("alpha = {value} is not finite")]
    InvalidAlpha {
        /// The offending value.
        value: f64,
    },
}

/// Bending stiffness `EI(s)` along the beam, N m^2.
#[derive(Clone)]
pub enum BendingStiffness {
    /// The same `EI` everywhere.
    Uniform {
        /// `EI`, N m^2.
        ei_n_m2: f64,
    },
    /// Constant on each section between breakpoints: `ei_n_m2[i]` on
    /// `(breakpoints_m[i-1], breakpoints_m[i])` with `breakpoints_m[-1] = 0`,
    /// `breakpoints_m[len] = L`.
    PiecewiseConstant {
        /// Interior breakpoints, m, strictly increasing inside (0, L).
        breakpoints_m: Vec<f64>,
        /// One value per section, N m^2 (`breakpoints_m.len() + 1` of them).
        ei_n_m2: Vec<f64>,
    },
    /// A function of arc length (m) returning N m^2, smooth between the given breakpoints
    /// (which the integrator never steps across; at a breakpoint the closure is evaluated
    /// there, so give it the one-sided value you mean or keep it continuous).
    Function {
        /// `EI(s)`, N m^2.
        ei_n_m2: Arc<dyn Fn(f64) -> f64 + Send + Sync>,
        /// Interior breakpoints, m, strictly increasing inside (0, L).
        breakpoints_m: Vec<f64>,
    },
}

impl BendingStiffness {
    /// A closure `EI(s)` with no breakpoints.
    pub fn function(ei_n_m2: impl Fn(f64) -> f64 + Send + Sync + 'static) -> Self {
        Self::Function {
            ei_n_m2: Arc::new(ei_n_m2),
            breakpoints_m: Vec::new(),
        }
    }

    /// `EI` at arc length `s_m`, N m^2. A piecewise-constant stiffness gives the value of the
    /// section that starts at or before `s_m` (at a breakpoint, the distal section's value).
    ///
    /// # Errors
    /// [`ElasticaError::InvalidStiffness`] when the value there is not finite and positive.
    pub fn at_n_m2(&self, s_m: f64) -> Result<f64, ElasticaError> {
        let section = self.breakpoints_m().partition_point(|&b| b <= s_m);
        self.at(s_m, section)
    }

    /// Interior breakpoints, m (empty for a uniform beam).
    pub fn breakpoints_m(&self) -> &[f64] {
        match self {
            Self::Uniform { .. } => &[],
            Self::PiecewiseConstant { breakpoints_m, .. }
            | Self::Function { breakpoints_m, .. } => breakpoints_m,
        }
    }

    /// `EI` at `s_m` in section `section`, validated.
    fn at(&self, s_m: f64, section: usize) -> Result<f64, ElasticaError> {
        let value = match self {
            Self::Uniform { ei_n_m2 } => *ei_n_m2,
            Self::PiecewiseConstant { ei_n_m2, .. } => {
                ei_n_m2.get(section).copied().unwrap_or(f64::NAN)
            }
            Self::Function { ei_n_m2, .. } => ei_n_m2(s_m),
        };
        if value.is_finite() && value > 0.0 {
            Ok(value)
        } else {
            Err(ElasticaError::InvalidStiffness {
                s_m,
                value_n_m2: value,
            })
        }
    }
}

impl fmt::Debug for BendingStiffness {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Uniform { ei_n_m2 } => {
                f.debug_struct("Uniform").field("ei_n_m2", ei_n_m2).finish()
            }
            Self::PiecewiseConstant {
                breakpoints_m,
                ei_n_m2,
            } => f
                .debug_struct("PiecewiseConstant")
                .field("breakpoints_m", breakpoints_m)
                .field("ei_n_m2", ei_n_m2)
                .finish(),
            Self::Function { breakpoints_m, .. } => f
                .debug_struct("Function")
                .field("breakpoints_m", breakpoints_m)
                .finish_non_exhaustive(),
        }
    }
}

/// A clamped beam with a dead tip force.
#[derive(Debug, Clone)]
pub struct ElasticaProblem {
    /// Beam length `L`, m.
    pub length_m: f64,
    /// `EI(s)`.
    pub bending_stiffness: BendingStiffness,
    /// Clamp direction, rad from the x-axis, counter-clockwise positive.
    pub clamp_angle_rad: f64,
    /// Dead force at the tip `(Fx, Fy)`, N.
    pub tip_force_n: [f64; 2],
}

/// Solver options; [`Default`] gives the reference accuracy.
#[derive(Debug, Clone, PartialEq)]
pub struct ElasticaOptions {
    /// Relative local error tolerance of the integrator (default `1e-13`).
    pub integration_tolerance: f64,
    /// Convergence threshold on `|M(L)| / (|F| L)` (default `1e-12`).
    pub residual_tolerance: f64,
    /// Newton iterations allowed per load level (default 50).
    pub max_newton_iterations: usize,
    /// Starting clamp moment, N m; `None` uses the straight beam's `M(0)`. Pick a different
    /// start to reach another equilibrium (e.g. a buckled one under compression).
    pub initial_base_moment_n_m: Option<f64>,
    /// Number of shape samples, uniformly spaced in arc length from clamp to tip inclusive:
    /// 0 for none, otherwise at least 2.
    pub shape_samples: usize,
}

impl Default for ElasticaOptions {
    fn default() -> Self {
        Self {
            integration_tolerance: 1e-13,
            residual_tolerance: 1e-12,
            max_newton_iterations: 50,
            initial_base_moment_n_m: None,
            shape_samples: 0,
        }
    }
}

/// One sample of the deformed shape.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShapePoint {
    /// Arc length from the clamp, m.
    pub arc_length_m: f64,
    /// Position `(x, y)`, m.
    pub position_m: [f64; 2],
    /// Tangent angle, rad from the x-axis.
    pub angle_rad: f64,
    /// Bending moment `M(s)`, N m.
    pub moment_n_m: f64,
}

/// The equilibrium found by [`solve`].
#[derive(Debug, Clone, PartialEq)]
pub struct ElasticaSolution {
    /// Tip position `(x_L, y_L)`, m.
    pub tip_position_m: [f64; 2],
    /// Tip tangent angle, rad.
    pub tip_angle_rad: f64,
    /// Clamp moment `M(0)`, N m.
    pub base_moment_n_m: f64,
    /// `|M(L)|` of the reported solution (should be 0), N m.
    pub moment_residual_n_m: f64,
    /// Newton iterations spent in total (over all load levels).
    pub newton_iterations: usize,
    /// Shape samples (empty unless asked for).
    pub shape: Vec<ShapePoint>,
}

/// Closed-form large deflection of a uniform cantilever under a tip load perpendicular to the
/// clamp direction (Bisshopp & Drucker 1945), in units of `L` and in the clamp's frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PerpendicularLoadClosedForm {
    /// `alpha = P L^2 / EI` (signed: positive loads toward the counter-clockwise side).
    pub alpha: f64,
    /// Tip angle relative to the clamp direction, rad.
    pub tip_angle_rad: f64,
    /// Tip coordinate along the clamp direction, divided by `L`.
    pub tip_along_over_length: f64,
    /// Tip coordinate across the clamp direction (the deflection), divided by `L`.
    pub tip_transverse_over_length: f64,
}

/// Solves the elastica by shooting on the clamp moment.
///
/// # Errors
/// [`ElasticaError`] for invalid geometry, load, stiffness or options; a non-positive or
/// non-finite `EI` met during integration; step-size underflow; or
/// [`ElasticaError::NotConverged`] with the best residual when shooting fails.
pub fn solve(
    problem: &ElasticaProblem,
    options: &ElasticaOptions,
) -> Result<ElasticaSolution, ElasticaError> {
    validate(problem, options)?;
    let length_m = problem.length_m;
    let [fx, fy] = problem.tip_force_n;
    let force_n = fx.hypot(fy);
    let moment_scale_n_m = force_n * length_m;
    let mut shooter = Shooter {
        problem,
        tolerance: options.integration_tolerance,
        moment_scale_n_m,
        step_hint_m: length_m / 4.0,
        knots: section_knots(problem),
    };
    let (theta0, l) = (problem.clamp_angle_rad, length_m);
    let straight_m0 = l * (theta0.cos() * fy - theta0.sin() * fx);
    let start_m0 = options.initial_base_moment_n_m.unwrap_or(straight_m0);
    let threshold = options.residual_tolerance * moment_scale_n_m;

    let (base_moment_n_m, newton_iterations) = if force_n == 0.0 {
        (0.0, 0)
    } else {
        match newton(&mut shooter, 1.0, start_m0, threshold, options) {
            Ok(found) => found,
            Err(NewtonFailure::Hard(e)) => return Err(e),
            Err(NewtonFailure::Soft(its, residual, at)) => continuation(
                &mut shooter,
                start_m0,
                threshold,
                options,
                (its, residual, at),
            )?,
        }
    };

    // Final pass at the full load, hitting the sample points exactly.
    let samples = options.shape_samples;
    let sample_s: Vec<f64> = (0..samples)
        .map(|i| length_m * i as f64 / (samples - 1) as f64)
        .collect();
    let mut shape = Vec::with_capacity(samples);
    if samples > 0 {
        shape.push(ShapePoint {
            arc_length_m: 0.0,
            position_m: [0.0, 0.0],
            angle_rad: theta0,
            moment_n_m: base_moment_n_m,
        });
    }
    let end = shooter.integrate(1.0, base_moment_n_m, &sample_s, |s, y| {
        if s > 0.0 {
            shape.push(ShapePoint {
                arc_length_m: s,
                position_m: [y[0], y[1]],
                angle_rad: y[2],
                moment_n_m: y[3],
            });
        }
    })?;
    let residual = end[3].abs();
    if force_n != 0.0 && (residual.is_nan() || residual > 10.0 * threshold) {
        return Err(ElasticaError::NotConverged {
            iterations: newton_iterations,
            residual_n_m: residual,
            base_moment_n_m,
        });
    }
    Ok(ElasticaSolution {
        tip_position_m: [end[0], end[1]],
        tip_angle_rad: end[2],
        base_moment_n_m,
        moment_residual_n_m: residual,
        newton_iterations,
        shape,
    })
}

/// The Bisshopp-Drucker closed form for `alpha = P L^2 / EI` (any sign; `alpha = 0` is the
/// straight beam). Reproduces the classical table, e.g. `alpha = 1`: transverse `0.30172`,
/// along `0.94357` (horizontal shortening `0.05643`), tip angle `0.46135` rad.
///
/// # Errors
/// [`ElasticaError::InvalidAlpha`] for a non-finite `alpha`.
pub fn perpendicular_load_closed_form(
    alpha: f64,
) -> Result<PerpendicularLoadClosedForm, ElasticaError> {
    if !alpha.is_finite() {
        return Err(ElasticaError::InvalidAlpha { value: alpha });
    }
    if alpha == 0.0 {
        return Ok(PerpendicularLoadClosedForm {
            alpha,
            tip_angle_rad: 0.0,
            tip_along_over_length: 1.0,
            tip_transverse_over_length: 0.0,
        });
    }
    let a = alpha.abs();
    let root_a = a.sqrt();
    // Tip angle phi0 solves sqrt(alpha) = K(m) - F(psi1 | m), m = (1 + sin phi0) / 2,
    // sin psi1 = 1 / sqrt(1 + sin phi0). g is increasing in phi0, -sqrt(alpha) at 0 and +inf
    // at pi/2: bisect to the last bit.
    let parts = |phi0: f64| {
        let sin_phi0 = phi0.sin();
        let m = 0.5 * (1.0 + sin_phi0);
        let psi1 = (1.0 / (1.0 + sin_phi0).sqrt()).asin();
        (m, psi1)
    };
    let g = |phi0: f64| {
        let (m, psi1) = parts(phi0);
        if m >= 1.0 {
            return f64::INFINITY;
        }
        complete_elliptic_k(m) - elliptic_f(psi1, m) - root_a
    };
    let (mut lo, mut hi) = (0.0f64, FRAC_PI_2);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if g(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let phi0 = 0.5 * (lo + hi);
    let (m, psi1) = parts(phi0);
    let along = (2.0 * phi0.sin() / a).sqrt();
    let transverse = 1.0 - 2.0 / root_a * (complete_elliptic_e(m) - elliptic_e(psi1, m));
    let sign = alpha.signum();
    Ok(PerpendicularLoadClosedForm {
        alpha,
        tip_angle_rad: sign * phi0,
        tip_along_over_length: along,
        tip_transverse_over_length: sign * transverse,
    })
}

fn validate(problem: &ElasticaProblem, options: &ElasticaOptions) -> Result<(), ElasticaError> {
    let l = problem.length_m;
    if !(l.is_finite() && l > 0.0) {
        return Err(ElasticaError::InvalidLength { value_m: l });
    }
    for (index, &value_n) in problem.tip_force_n.iter().enumerate() {
        if !value_n.is_finite() {
            return Err(ElasticaError::InvalidForce { index, value_n });
        }
    }
    if !problem.clamp_angle_rad.is_finite() {
        return Err(ElasticaError::InvalidClampAngle {
            value_rad: problem.clamp_angle_rad,
        });
    }
    let stiffness = &problem.bending_stiffness;
    let mut previous = 0.0;
    for (index, &value_m) in stiffness.breakpoints_m().iter().enumerate() {
        if !(value_m.is_finite() && value_m > previous && value_m < l) {
            return Err(ElasticaError::InvalidBreakpoint { index, value_m });
        }
        previous = value_m;
    }
    match stiffness {
        BendingStiffness::Uniform { ei_n_m2 } => {
            stiffness
                .at(0.0, 0)
                .map_err(|_| ElasticaError::InvalidStiffness {
                    s_m: 0.0,
                    value_n_m2: *ei_n_m2,
                })?;
        }
        BendingStiffness::PiecewiseConstant {
            breakpoints_m,
            ei_n_m2,
        } => {
            if ei_n_m2.len() != breakpoints_m.len() + 1 {
                return Err(ElasticaError::SectionCountMismatch {
                    breakpoints: breakpoints_m.len(),
                    values: ei_n_m2.len(),
                });
            }
            for (i, &value) in ei_n_m2.iter().enumerate() {
                if !(value.is_finite() && value > 0.0) {
                    let s_m = if i == 0 { 0.0 } else { breakpoints_m[i - 1] };
                    return Err(ElasticaError::InvalidStiffness {
                        s_m,
                        value_n_m2: value,
                    });
                }
            }
        }
        BendingStiffness::Function { .. } => {
            // Probe the ends; interior values are checked as they are met.
            stiffness.at(0.0, 0)?;
            stiffness.at(l, 0)?;
        }
    }
    let tol = options.integration_tolerance;
    if !(tol.is_finite() && (1e-15..=1e-3).contains(&tol)) {
        return Err(ElasticaError::InvalidOption {
            field: "integration_tolerance",
            value: tol,
            expected: "in [1e-15, 1e-3]",
        });
    }
    let rtol = options.residual_tolerance;
    if !(rtol.is_finite() && rtol > 0.0) {
        return Err(ElasticaError::InvalidOption {
            field: "residual_tolerance",
            value: rtol,
            expected: "finite and positive",
        });
    }
    if options.max_newton_iterations == 0 {
        return Err(ElasticaError::InvalidOption {
            field: "max_newton_iterations",
            value: 0.0,
            expected: "at least 1",
        });
    }
    if let Some(m0) = options.initial_base_moment_n_m
        && !m0.is_finite()
    {
        return Err(ElasticaError::InvalidOption {
            field: "initial_base_moment_n_m",
            value: m0,
            expected: "finite",
        });
    }
    if options.shape_samples == 1 {
        return Err(ElasticaError::InvalidOption {
            field: "shape_samples",
            value: 1.0,
            expected: "0 or at least 2",
        });
    }
    Ok(())
}

/// Section ends (breakpoints, then `L`), in order.
fn section_knots(problem: &ElasticaProblem) -> Vec<f64> {
    let mut knots = problem.bending_stiffness.breakpoints_m().to_vec();
    knots.push(problem.length_m);
    knots
}

/// Why Newton stopped short.
enum NewtonFailure {
    /// A problem error (e.g. `EI` invalid where it was met): give up at once.
    Hard(ElasticaError),
    /// No convergence: (iterations, best residual, its M0).
    Soft(usize, f64, f64),
}

/// Integrates, sorting errors into hard (bad problem) and soft (step-size underflow).
fn shoot(shooter: &mut Shooter<'_>, lambda: f64, m0: f64) -> Result<Option<State>, ElasticaError> {
    match shooter.integrate(lambda, m0, &[], |_, _| {}) {
        Ok(end) => Ok(Some(end)),
        Err(ElasticaError::StepSizeUnderflow { .. }) => Ok(None),
        Err(e) => Err(e),
    }
}

/// Safeguarded Newton on `M(L)` at load factor `lambda`.
///
/// Every equilibrium has `|M(0)| = |p_L x F| <= |F| L = B`, so iterates stay in `[-B, B]`.
/// Points where `M(L) < 0` and `> 0` are remembered; once both exist they bracket a root and
/// a Newton step leaving the bracket, or one that fails to halve `|M(L)|`, is replaced by
/// bisection. The first time a step fails to halve `|M(L)|`, `M(L)` is probed at `+-B` to
/// find a bracket. Without a bracket, steps are backtracked until `|M(L)|` decreases.
fn newton(
    shooter: &mut Shooter<'_>,
    lambda: f64,
    start_m0: f64,
    threshold: f64,
    options: &ElasticaOptions,
) -> Result<(f64, usize), NewtonFailure> {
    let threshold = threshold * lambda;
    let bound = lambda * shooter.moment_scale_n_m;
    let mut m0 = start_m0.clamp(-bound, bound);
    let Some(mut end) = shoot(shooter, lambda, m0).map_err(NewtonFailure::Hard)? else {
        return Err(NewtonFailure::Soft(0, f64::INFINITY, m0));
    };
    let (mut negative, mut positive): (Option<f64>, Option<f64>) = (None, None);
    let record = |m: f64, r: f64, neg: &mut Option<f64>, pos: &mut Option<f64>| {
        if r < 0.0 {
            *neg = Some(m);
        } else if r > 0.0 {
            *pos = Some(m);
        }
    };
    record(m0, end[3], &mut negative, &mut positive);
    let mut probed = false;
    let mut slow = false;
    for it in 1..=options.max_newton_iterations {
        let residual = end[3];
        if residual.abs() <= threshold {
            return Ok((m0, it - 1));
        }
        let slope = end[5];
        let newton_m0 = if slope.is_finite() && slope != 0.0 {
            (m0 - residual / slope).clamp(-bound, bound)
        } else {
            f64::NAN
        };
        if let (Some(a), Some(b)) = (negative, positive) {
            let (lo, hi) = (a.min(b), a.max(b));
            let candidate = if !slow && newton_m0 > lo && newton_m0 < hi {
                newton_m0
            } else {
                0.5 * (lo + hi)
            };
            let Some(trial) = shoot(shooter, lambda, candidate).map_err(NewtonFailure::Hard)?
            else {
                return Err(NewtonFailure::Soft(it, residual.abs(), m0));
            };
            record(candidate, trial[3], &mut negative, &mut positive);
            slow = trial[3].abs() > 0.5 * residual.abs();
            if hi - lo <= 4.0 * f64::EPSILON * bound.max(hi.abs()) {
                // The bracket has collapsed to rounding level.
                return if trial[3].abs().min(residual.abs()) <= 10.0 * threshold {
                    Ok((candidate, it))
                } else {
                    Err(NewtonFailure::Soft(it, trial[3].abs(), candidate))
                };
            }
            m0 = candidate;
            end = trial;
            continue;
        }
        if !newton_m0.is_finite() {
            return Err(NewtonFailure::Soft(it, residual.abs(), m0));
        }
        let mut accepted = false;
        let mut t = 1.0;
        for _ in 0..40 {
            let trial_m0 = m0 + t * (newton_m0 - m0);
            if let Some(trial) = shoot(shooter, lambda, trial_m0).map_err(NewtonFailure::Hard)? {
                record(trial_m0, trial[3], &mut negative, &mut positive);
                if trial[3].abs() < residual.abs() {
                    let halved = trial[3].abs() <= 0.5 * residual.abs();
                    m0 = trial_m0;
                    end = trial;
                    accepted = true;
                    if !halved && !probed {
                        probed = true;
                        for edge in [-bound, bound] {
                            if let Some(e) =
                                shoot(shooter, lambda, edge).map_err(NewtonFailure::Hard)?
                            {
                                record(edge, e[3], &mut negative, &mut positive);
                            }
                        }
                    }
                    break;
                }
                if negative.is_some() && positive.is_some() {
                    // A bracket appeared: let the bracketed branch take over.
                    accepted = true;
                    break;
                }
            }
            t *= 0.5;
        }
        if !accepted {
            // No decrease: either converged to rounding level or stuck.
            return if residual.abs() <= 10.0 * threshold {
                Ok((m0, it))
            } else {
                Err(NewtonFailure::Soft(it, residual.abs(), m0))
            };
        }
    }
    if end[3].abs() <= threshold {
        Ok((m0, options.max_newton_iterations))
    } else {
        Err(NewtonFailure::Soft(
            options.max_newton_iterations,
            end[3].abs(),
            m0,
        ))
    }
}

/// Load continuation from the unloaded beam in 4, then 16, then 64 equal steps.
fn continuation(
    shooter: &mut Shooter<'_>,
    start_m0: f64,
    threshold: f64,
    options: &ElasticaOptions,
    direct: (usize, f64, f64),
) -> Result<(f64, usize), ElasticaError> {
    let (mut total, mut best_residual, mut best_m0) = direct;
    'levels: for levels in [4usize, 16, 64] {
        let mut m0 = 0.0;
        let mut previous_lambda = 0.0;
        for i in 1..=levels {
            let lambda = i as f64 / levels as f64;
            // M(0) scales with the load to first order.
            let guess = if i == 1 {
                start_m0 * lambda
            } else {
                m0 * lambda / previous_lambda
            };
            match newton(shooter, lambda, guess, threshold, options) {
                Ok((found, its)) => {
                    total += its;
                    m0 = found;
                    previous_lambda = lambda;
                }
                Err(NewtonFailure::Hard(e)) => return Err(e),
                Err(NewtonFailure::Soft(its, residual, at)) => {
                    total += its;
                    if lambda == 1.0 && residual < best_residual {
                        best_residual = residual;
                        best_m0 = at;
                    }
                    continue 'levels;
                }
            }
        }
        return Ok((m0, total));
    }
    Err(ElasticaError::NotConverged {
        iterations: total,
        residual_n_m: best_residual,
        base_moment_n_m: best_m0,
    })
}

struct Shooter<'a> {
    problem: &'a ElasticaProblem,
    tolerance: f64,
    moment_scale_n_m: f64,
    step_hint_m: f64,
    /// Section ends: breakpoints then `L`.
    knots: Vec<f64>,
}

impl Shooter<'_> {
    /// Integrates from the clamp with `M(0) = m0` under `lambda` times the load to `L`,
    /// calling `on_sample` at each of `samples` (sorted, in [0, L]) and returning the tip
    /// state.
    fn integrate(
        &mut self,
        lambda: f64,
        m0: f64,
        samples: &[f64],
        mut on_sample: impl FnMut(f64, &State),
    ) -> Result<State, ElasticaError> {
        let p = self.problem;
        let (fx, fy) = (lambda * p.tip_force_n[0], lambda * p.tip_force_n[1]);
        let l = p.length_m;
        let mut y: State = [0.0, 0.0, p.clamp_angle_rad, m0, 0.0, 1.0];
        let scale: [f64; 4] = [
            self.tolerance * l,
            self.tolerance * l,
            self.tolerance,
            self.tolerance * self.moment_scale_n_m.max(f64::MIN_POSITIVE),
        ];
        let mut s = 0.0;
        let mut sample_iter = samples.iter().copied().filter(|&v| v > 0.0).peekable();
        for section in 0..self.knots.len() {
            let section_end = self.knots[section];
            while s < section_end {
                let target = match sample_iter.peek() {
                    Some(&v) if v < section_end => v,
                    _ => section_end,
                };
                let rhs = Rhs {
                    fx,
                    fy,
                    stiffness: &p.bending_stiffness,
                    section,
                };
                y = self.advance(&rhs, s, target, y, &scale)?;
                s = target;
                if sample_iter.peek().is_some_and(|&v| v <= target) {
                    sample_iter.next();
                    on_sample(s, &y);
                }
            }
        }
        Ok(y)
    }

    /// Adaptive GBS steps from `s0` to exactly `s1`.
    fn advance(
        &mut self,
        rhs: &Rhs<'_>,
        s0: f64,
        s1: f64,
        mut y: State,
        scale: &[f64; 4],
    ) -> Result<State, ElasticaError> {
        let l = self.problem.length_m;
        let mut s = s0;
        let mut h = self.step_hint_m.min(s1 - s0);
        let mut steps = 0usize;
        while s < s1 {
            let remaining = s1 - s;
            let capped = h >= remaining;
            if capped {
                h = remaining;
            }
            let (y_new, err) = gbs_step(rhs, s, h, &y, scale)?;
            let exponent = 1.0 / (2 * GBS_COLUMNS - 1) as f64;
            let fac = if err > 0.0 {
                (0.94 * (0.65 / err).powf(exponent)).clamp(0.2, 4.0)
            } else {
                4.0
            };
            if err <= 1.0 {
                s = if capped { s1 } else { s + h };
                y = y_new;
                // A step cut short to land on s1 says nothing about a longer one failing.
                self.step_hint_m = if capped {
                    self.step_hint_m.max(h * fac)
                } else {
                    h * fac
                };
                h = self.step_hint_m;
            } else {
                h *= fac;
                self.step_hint_m = h;
            }
            steps += 1;
            if h < 1e-14 * l || steps > 1_000_000 {
                return Err(ElasticaError::StepSizeUnderflow { s_m: s });
            }
        }
        Ok(y)
    }
}

struct Rhs<'a> {
    fx: f64,
    fy: f64,
    stiffness: &'a BendingStiffness,
    section: usize,
}

impl Rhs<'_> {
    fn eval(&self, s: f64, y: &State) -> Result<State, ElasticaError> {
        let ei = self.stiffness.at(s, self.section)?;
        let (sin_t, cos_t) = y[2].sin_cos();
        Ok([
            cos_t,
            sin_t,
            y[3] / ei,
            self.fx * sin_t - self.fy * cos_t,
            y[5] / ei,
            (self.fx * cos_t + self.fy * sin_t) * y[4],
        ])
    }
}

/// One Gragg-Bulirsch-Stoer step of size `h`: returns the extrapolated state and the scaled
/// error estimate (max over x, y, theta, M of |T_KK - T_K,K-1| / tolerance). `scale` holds
/// the absolute tolerances of x, y, theta, M; theta's (`scale[2]`) is also the relative one.
fn gbs_step(
    rhs: &Rhs<'_>,
    s: f64,
    h: f64,
    y: &State,
    scale: &[f64; 4],
) -> Result<(State, f64), ElasticaError> {
    let f0 = rhs.eval(s, y)?;
    let mut table = [[0.0f64; 6]; GBS_COLUMNS];
    let mut counts = [0usize; GBS_COLUMNS];
    let mut last_two = ([0.0f64; 6], [0.0f64; 6]);
    for j in 0..GBS_COLUMNS {
        let n = 2 * (j + 1);
        counts[j] = n;
        let hs = h / n as f64;
        // Modified midpoint rule with n substeps.
        let mut z_prev = *y;
        let mut z = add_scaled(y, &f0, hs);
        for m in 1..n {
            let f = rhs.eval(s + m as f64 * hs, &z)?;
            let z_next = add_scaled(&z_prev, &f, 2.0 * hs);
            z_prev = z;
            z = z_next;
        }
        // Aitken-Neville in h^2: row j of the tableau, overwriting in place.
        let mut current = z;
        for k in 1..=j {
            let ratio = (counts[j] as f64 / counts[j - k] as f64).powi(2);
            let previous = table[k - 1];
            table[k - 1] = current;
            let mut next = [0.0; 6];
            for c in 0..6 {
                next[c] = current[c] + (current[c] - previous[c]) / (ratio - 1.0);
            }
            if j == GBS_COLUMNS - 1 && k == j {
                last_two = (current, next);
            }
            current = next;
        }
        table[j] = current;
    }
    let (lower, best) = last_two;
    let rtol = scale[2];
    let mut err = 0.0f64;
    for c in 0..4 {
        let tol = scale[c] + rtol * y[c].abs().max(best[c].abs());
        err = err.max((best[c] - lower[c]).abs() / tol);
    }
    Ok((best, err))
}

fn add_scaled(a: &State, b: &State, h: f64) -> State {
    let mut out = *a;
    for (o, v) in out.iter_mut().zip(b) {
        *o += h * v;
    }
    out
}

/// Carlson's symmetric integral `R_F(x, y, z)` (duplication; truncation error ~ 1e-4^6).
fn carlson_rf(x: f64, y: f64, z: f64) -> f64 {
    const ERRTOL: f64 = 1e-4;
    let (mut xt, mut yt, mut zt) = (x, y, z);
    let (mut ave, mut dx, mut dy, mut dz);
    let mut iterations = 0;
    loop {
        let (sx, sy, sz) = (xt.sqrt(), yt.sqrt(), zt.sqrt());
        let lambda = sx * (sy + sz) + sy * sz;
        xt = 0.25 * (xt + lambda);
        yt = 0.25 * (yt + lambda);
        zt = 0.25 * (zt + lambda);
        ave = (xt + yt + zt) / 3.0;
        dx = (ave - xt) / ave;
        dy = (ave - yt) / ave;
        dz = (ave - zt) / ave;
        iterations += 1;
        if dx.abs().max(dy.abs()).max(dz.abs()) <= ERRTOL || iterations > 100 {
            break;
        }
    }
    let e2 = dx * dy - dz * dz;
    let e3 = dx * dy * dz;
    (1.0 + (e2 / 24.0 - 0.1 - 3.0 / 44.0 * e3) * e2 + e3 / 14.0) / ave.sqrt()
}

/// Carlson's symmetric integral `R_D(x, y, z)`.
fn carlson_rd(x: f64, y: f64, z: f64) -> f64 {
    const ERRTOL: f64 = 1e-4;
    const C1: f64 = 3.0 / 14.0;
    const C2: f64 = 1.0 / 6.0;
    const C3: f64 = 9.0 / 22.0;
    const C4: f64 = 3.0 / 26.0;
    const C5: f64 = 0.25 * C3;
    const C6: f64 = 1.5 * C4;
    let (mut xt, mut yt, mut zt) = (x, y, z);
    let (mut sum, mut fac) = (0.0, 1.0);
    let (mut ave, mut dx, mut dy, mut dz);
    let mut iterations = 0;
    loop {
        let (sx, sy, sz) = (xt.sqrt(), yt.sqrt(), zt.sqrt());
        let lambda = sx * (sy + sz) + sy * sz;
        sum += fac / (sz * (zt + lambda));
        fac *= 0.25;
        xt = 0.25 * (xt + lambda);
        yt = 0.25 * (yt + lambda);
        zt = 0.25 * (zt + lambda);
        ave = 0.2 * (xt + yt + 3.0 * zt);
        dx = (ave - xt) / ave;
        dy = (ave - yt) / ave;
        dz = (ave - zt) / ave;
        iterations += 1;
        if dx.abs().max(dy.abs()).max(dz.abs()) <= ERRTOL || iterations > 100 {
            break;
        }
    }
    let ea = dx * dy;
    let eb = dz * dz;
    let ec = ea - eb;
    let ed = ea - 6.0 * eb;
    let ee = ed + ec + ec;
    3.0 * sum
        + fac
            * (1.0
                + ed * (-C1 + C5 * ed - C6 * dz * ee)
                + dz * (C2 * ee + dz * (-C3 * ec + dz * C4 * ea)))
            / (ave * ave.sqrt())
}

/// Incomplete elliptic integral of the first kind `F(phi | m)`, `0 <= phi <= pi/2`, `m < 1`.
fn elliptic_f(phi: f64, m: f64) -> f64 {
    let (s, c) = phi.sin_cos();
    s * carlson_rf(c * c, 1.0 - m * s * s, 1.0)
}

/// Incomplete elliptic integral of the second kind `E(phi | m)`, `0 <= phi <= pi/2`, `m <= 1`.
fn elliptic_e(phi: f64, m: f64) -> f64 {
    let (s, c) = phi.sin_cos();
    let (cc, q) = (c * c, 1.0 - m * s * s);
    s * carlson_rf(cc, q, 1.0) - m * s * s * s / 3.0 * carlson_rd(cc, q, 1.0)
}

/// `K(m)`.
fn complete_elliptic_k(m: f64) -> f64 {
    carlson_rf(0.0, 1.0 - m, 1.0)
}

/// `E(m)`.
fn complete_elliptic_e(m: f64) -> f64 {
    carlson_rf(0.0, 1.0 - m, 1.0) - m / 3.0 * carlson_rd(0.0, 1.0 - m, 1.0)
}

#[cfg(test)]
#[allow(clippy::excessive_precision)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    // mpmath digits kept beyond f64 precision on purpose (they are the reference).
    /// Bisshopp-Drucker values computed independently with mpmath at 30 digits:
    /// (alpha, tip angle, along / L, transverse / L).
    const GOLDEN_BD: [(f64, f64, f64, f64); 5] = [
        (
            0.5,
            0.24453364713321830851,
            0.98408103752916250338,
            0.16214357565836960515,
        ),
        (
            1.0,
            0.46135194971187896071,
            0.94356676371662311691,
            0.30172077379981352954,
        ),
        (
            2.0,
            0.78174983155654304442,
            0.83935827917483276379,
            0.49345748039671182041,
        ),
        (
            5.0,
            1.2153681176116810959,
            0.61237163927557012814,
            0.71379152361191272809,
        ),
        (
            10.0,
            1.430285538803857529,
            0.44500440224624873043,
            0.81060902488029645323,
        ),
    ];

    fn uniform(length_m: f64, ei: f64, theta0: f64, force: [f64; 2]) -> ElasticaProblem {
        ElasticaProblem {
            length_m,
            bending_stiffness: BendingStiffness::Uniform { ei_n_m2: ei },
            clamp_angle_rad: theta0,
            tip_force_n: force,
        }
    }

    /// The problem with a perpendicular load of given alpha, in a rotated frame.
    fn perpendicular(alpha: f64, length_m: f64, ei: f64, theta0: f64) -> ElasticaProblem {
        let p = alpha * ei / (length_m * length_m);
        uniform(length_m, ei, theta0, [-p * theta0.sin(), p * theta0.cos()])
    }

    #[test]
    fn elliptic_integrals_match_mpmath() {
        let cases = [
            (complete_elliptic_k(0.5), 1.8540746773013719184),
            (complete_elliptic_e(0.5), 1.3506438810476755025),
            (elliptic_f(0.7, 0.8), 0.74951647592744153974),
            (elliptic_e(0.7, 0.8), 0.65610742990242828839),
            (elliptic_f(1.2, 0.95), 1.6135859897147038081),
            (elliptic_e(1.2, 0.95), 0.9500177125460177028),
            (carlson_rf(1.0, 2.0, 0.0), 1.3110287771460599052),
            (carlson_rd(0.0, 2.0, 1.0), 1.7972103521033883112),
        ];
        for (got, want) in cases {
            assert!((got - want).abs() < 2e-15 * want, "{got} vs {want}");
        }
    }

    #[test]
    fn closed_form_matches_literature_and_mpmath() {
        // The classical table (alpha = 1): 0.30172 and 0.05643 to five decimals.
        let one = perpendicular_load_closed_form(1.0).unwrap();
        assert!((one.tip_transverse_over_length - 0.30172).abs() < 5e-6);
        assert!((1.0 - one.tip_along_over_length - 0.05643).abs() < 5e-6);
        for (alpha, angle, along, transverse) in GOLDEN_BD {
            let cf = perpendicular_load_closed_form(alpha).unwrap();
            assert!((cf.tip_angle_rad - angle).abs() < 1e-14, "{alpha}");
            assert!((cf.tip_along_over_length - along).abs() < 1e-14, "{alpha}");
            assert!(
                (cf.tip_transverse_over_length - transverse).abs() < 1e-14,
                "{alpha}"
            );
        }
        // A negative alpha mirrors the shape.
        let neg = perpendicular_load_closed_form(-2.0).unwrap();
        assert!((neg.tip_transverse_over_length + GOLDEN_BD[2].3).abs() < 1e-14);
        assert!((neg.tip_angle_rad + GOLDEN_BD[2].1).abs() < 1e-14);
        assert!((neg.tip_along_over_length - GOLDEN_BD[2].2).abs() < 1e-14);
        assert_eq!(
            perpendicular_load_closed_form(0.0)
                .unwrap()
                .tip_along_over_length,
            1.0
        );
    }

    #[test]
    fn shooting_matches_closed_form_to_1e_10() {
        let mut worst = 0.0f64;
        for (alpha, ..) in GOLDEN_BD {
            for theta0 in [0.0, 0.7, -2.0] {
                let (l, ei) = (0.36, 0.02);
                let sol = solve(
                    &perpendicular(alpha, l, ei, theta0),
                    &ElasticaOptions::default(),
                )
                .unwrap();
                let cf = perpendicular_load_closed_form(alpha).unwrap();
                let (c, s) = (theta0.cos(), theta0.sin());
                let want = [
                    l * (c * cf.tip_along_over_length - s * cf.tip_transverse_over_length),
                    l * (s * cf.tip_along_over_length + c * cf.tip_transverse_over_length),
                ];
                let dx = (sol.tip_position_m[0] - want[0]).abs() / l;
                let dy = (sol.tip_position_m[1] - want[1]).abs() / l;
                let da = (sol.tip_angle_rad - theta0 - cf.tip_angle_rad).abs();
                worst = worst.max(dx).max(dy).max(da);
                assert!(
                    dx < 1e-10 && dy < 1e-10 && da < 1e-10,
                    "alpha {alpha} theta0 {theta0}: {dx:e} {dy:e} {da:e}"
                );
                assert!(sol.moment_residual_n_m <= 1e-11 * alpha * ei / l);
            }
        }
        eprintln!("elastica vs closed form: worst |difference| / L (or rad) = {worst:.2e}");
    }

    #[test]
    fn small_load_matches_linear_theory() {
        let (l, ei, p) = (0.5, 0.3, 1e-6);
        let sol = solve(&uniform(l, ei, 0.0, [0.0, p]), &ElasticaOptions::default()).unwrap();
        let delta = p * l.powi(3) / (3.0 * ei);
        let slope = p * l * l / (2.0 * ei);
        // Nonlinear corrections are O(alpha^2) relative, alpha = 8.3e-7 here.
        assert!((sol.tip_position_m[1] / delta - 1.0).abs() < 1e-9);
        assert!((sol.tip_angle_rad / slope - 1.0).abs() < 1e-9);
        assert!((sol.tip_position_m[0] - l).abs() < 1e-12 * l);
    }

    #[test]
    fn piecewise_small_load_matches_linear_theory() {
        // y_L = P int (L - s)^2 / EI ds, theta_L = P int (L - s) / EI ds, section by section.
        let l = 0.36;
        let breaks = vec![0.04, 0.12, 0.2, 0.3];
        let eis = vec![0.08, 0.03, 0.01, 0.004, 0.001];
        let p = 1e-7;
        let problem = ElasticaProblem {
            length_m: l,
            bending_stiffness: BendingStiffness::PiecewiseConstant {
                breakpoints_m: breaks.clone(),
                ei_n_m2: eis.clone(),
            },
            clamp_angle_rad: 0.0,
            tip_force_n: [0.0, p],
        };
        let sol = solve(&problem, &ElasticaOptions::default()).unwrap();
        let mut ends = vec![0.0];
        ends.extend(&breaks);
        ends.push(l);
        let (mut y_lin, mut t_lin) = (0.0, 0.0);
        for (w, ei) in ends.windows(2).zip(&eis) {
            y_lin += p * ((l - w[0]).powi(3) - (l - w[1]).powi(3)) / (3.0 * ei);
            t_lin += p * ((l - w[0]).powi(2) - (l - w[1]).powi(2)) / (2.0 * ei);
        }
        assert!(
            (sol.tip_position_m[1] / y_lin - 1.0).abs() < 1e-8,
            "{} vs {y_lin}",
            sol.tip_position_m[1]
        );
        assert!((sol.tip_angle_rad / t_lin - 1.0).abs() < 1e-8);
    }

    #[test]
    fn piecewise_equal_and_function_constant_agree_with_uniform() {
        let (l, ei, theta0, f) = (0.3, 0.05, 0.4, [0.2, -0.9]);
        let base = solve(&uniform(l, ei, theta0, f), &ElasticaOptions::default()).unwrap();
        let piecewise = ElasticaProblem {
            bending_stiffness: BendingStiffness::PiecewiseConstant {
                breakpoints_m: vec![0.1, 0.25],
                ei_n_m2: vec![ei; 3],
            },
            ..uniform(l, ei, theta0, f)
        };
        let function = ElasticaProblem {
            bending_stiffness: BendingStiffness::function(move |_| ei),
            ..uniform(l, ei, theta0, f)
        };
        for other in [piecewise, function] {
            let sol = solve(&other, &ElasticaOptions::default()).unwrap();
            for k in 0..2 {
                assert!((sol.tip_position_m[k] - base.tip_position_m[k]).abs() < 1e-12 * l);
            }
            assert!((sol.tip_angle_rad - base.tip_angle_rad).abs() < 1e-12);
        }
    }

    #[test]
    fn tapered_function_is_between_its_bounds() {
        // EI decreasing from 0.08 to 0.004: tip deflection lies between the two uniform ones.
        let (l, f) = (0.36, [0.0, 0.05]);
        let tapered = ElasticaProblem {
            bending_stiffness: BendingStiffness::function(move |s| {
                0.004 + 0.076 * (-(s / l) * 3.0).exp()
            }),
            ..uniform(l, 1.0, 0.0, f)
        };
        let sol = solve(&tapered, &ElasticaOptions::default()).unwrap();
        let stiff = solve(&uniform(l, 0.08, 0.0, f), &ElasticaOptions::default()).unwrap();
        let soft = solve(&uniform(l, 0.004, 0.0, f), &ElasticaOptions::default()).unwrap();
        assert!(sol.tip_position_m[1] > stiff.tip_position_m[1]);
        assert!(sol.tip_position_m[1] < soft.tip_position_m[1]);
        assert!(sol.moment_residual_n_m <= 1e-12 * 0.05 * l);
    }

    #[test]
    fn shape_samples_satisfy_moment_balance_and_end_at_tip() {
        let (l, ei) = (0.36, 0.01);
        let problem = uniform(l, ei, 0.3, [-0.05, 0.12]);
        let sol = solve(
            &problem,
            &ElasticaOptions {
                shape_samples: 37,
                ..ElasticaOptions::default()
            },
        )
        .unwrap();
        assert_eq!(sol.shape.len(), 37);
        let [fx, fy] = problem.tip_force_n;
        let [xl, yl] = sol.tip_position_m;
        for (i, p) in sol.shape.iter().enumerate() {
            assert!((p.arc_length_m - l * i as f64 / 36.0).abs() < 1e-15);
            // M is integrated from its own ODE; the algebraic balance checks it independently.
            let balance = (xl - p.position_m[0]) * fy - (yl - p.position_m[1]) * fx;
            assert!(
                (p.moment_n_m - balance).abs() < 1e-12 * 0.13 * l,
                "sample {i}"
            );
        }
        let last = sol.shape[36];
        assert_eq!(last.position_m, sol.tip_position_m);
        assert_eq!(last.angle_rad, sol.tip_angle_rad);
        assert_eq!(sol.shape[0].angle_rad, 0.3);
        // Inextensible: chords are shorter than arcs but not by much for smooth shapes.
        let chord: f64 = sol
            .shape
            .windows(2)
            .map(|w| {
                (w[1].position_m[0] - w[0].position_m[0])
                    .hypot(w[1].position_m[1] - w[0].position_m[1])
            })
            .sum();
        assert!(chord < l && chord > l * (1.0 - 1e-3));
    }

    #[test]
    fn zero_and_axial_loads_leave_the_beam_straight() {
        let l = 0.2;
        for force in [[0.0, 0.0], [3.0, 0.0], [-0.1, 0.0]] {
            // Compression -0.1 N is below the buckling load pi^2 EI / (4 L^2) = 0.62 N.
            let sol = solve(&uniform(l, 0.01, 0.0, force), &ElasticaOptions::default()).unwrap();
            assert!((sol.tip_position_m[0] - l).abs() < 1e-14);
            assert!(sol.tip_position_m[1].abs() < 1e-14);
            assert!(sol.tip_angle_rad.abs() < 1e-14);
        }
    }

    #[test]
    fn bad_input_gives_typed_errors() {
        let ok = uniform(0.3, 0.01, 0.0, [0.0, 0.1]);
        let opts = ElasticaOptions::default();
        let with = |f: &dyn Fn(&mut ElasticaProblem)| {
            let mut p = ok.clone();
            f(&mut p);
            solve(&p, &opts)
        };
        assert!(matches!(
            with(&|p| p.length_m = -1.0),
            Err(ElasticaError::InvalidLength { .. })
        ));
        assert!(matches!(
            with(&|p| p.tip_force_n[1] = f64::NAN),
            Err(ElasticaError::InvalidForce { index: 1, .. })
        ));
        assert!(matches!(
            with(&|p| p.clamp_angle_rad = f64::INFINITY),
            Err(ElasticaError::InvalidClampAngle { .. })
        ));
        assert!(matches!(
            with(&|p| p.bending_stiffness = BendingStiffness::Uniform { ei_n_m2: 0.0 }),
            Err(ElasticaError::InvalidStiffness { .. })
        ));
        assert!(matches!(
            with(
                &|p| p.bending_stiffness = BendingStiffness::PiecewiseConstant {
                    breakpoints_m: vec![0.2, 0.1],
                    ei_n_m2: vec![0.01; 3]
                }
            ),
            Err(ElasticaError::InvalidBreakpoint { index: 1, .. })
        ));
        assert!(matches!(
            with(
                &|p| p.bending_stiffness = BendingStiffness::PiecewiseConstant {
                    breakpoints_m: vec![0.1],
                    ei_n_m2: vec![0.01; 3]
                }
            ),
            Err(ElasticaError::SectionCountMismatch {
                breakpoints: 1,
                values: 3
            })
        ));
        assert!(matches!(
            with(
                &|p| p.bending_stiffness = BendingStiffness::PiecewiseConstant {
                    breakpoints_m: vec![0.1],
                    ei_n_m2: vec![0.01, -1.0]
                }
            ),
            Err(ElasticaError::InvalidStiffness { .. })
        ));
        // A closure that goes negative mid-beam is caught where it is met.
        let err = with(&|p| {
            p.bending_stiffness =
                BendingStiffness::function(|s| if (0.1..0.2).contains(&s) { -1.0 } else { 0.01 })
        });
        assert!(
            matches!(err, Err(ElasticaError::InvalidStiffness { s_m, .. }) if (0.1..0.2).contains(&s_m))
        );
        assert!(matches!(
            solve(
                &ok,
                &ElasticaOptions {
                    shape_samples: 1,
                    ..ElasticaOptions::default()
                }
            ),
            Err(ElasticaError::InvalidOption {
                field: "shape_samples",
                ..
            })
        ));
        assert!(matches!(
            solve(
                &ok,
                &ElasticaOptions {
                    integration_tolerance: 0.0,
                    ..ElasticaOptions::default()
                }
            ),
            Err(ElasticaError::InvalidOption {
                field: "integration_tolerance",
                ..
            })
        ));
        assert!(matches!(
            perpendicular_load_closed_form(f64::NAN),
            Err(ElasticaError::InvalidAlpha { .. })
        ));
    }

    #[test]
    fn non_convergence_reports_the_residual() {
        // One Newton iteration cannot reach 1e-12 from the straight start at alpha = 10, and
        // continuation with one iteration per level cannot either.
        let problem = perpendicular(10.0, 0.3, 0.01, 0.0);
        let err = solve(
            &problem,
            &ElasticaOptions {
                max_newton_iterations: 1,
                ..ElasticaOptions::default()
            },
        )
        .unwrap_err();
        match err {
            ElasticaError::NotConverged { residual_n_m, .. } => {
                assert!(residual_n_m.is_finite() && residual_n_m > 0.0)
            }
            other => panic!("unexpected {other:?}"),
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        /// Rotating the clamp and the force together rotates the solution rigidly.
        #[test]
        fn rotation_equivariance(
            fx in -0.3f64..0.3,
            fy in -0.3f64..0.3,
            rot in -PI_F..PI_F,
        ) {
            let (l, ei) = (0.36, 0.02);
            let a = solve(&uniform(l, ei, 0.0, [fx, fy]), &ElasticaOptions::default()).unwrap();
            let (c, s) = (rot.cos(), rot.sin());
            let b = solve(&uniform(l, ei, rot, [c * fx - s * fy, s * fx + c * fy]), &ElasticaOptions::default()).unwrap();
            let [x, y] = a.tip_position_m;
            prop_assert!((b.tip_position_m[0] - (c * x - s * y)).abs() < 1e-11 * l);
            prop_assert!((b.tip_position_m[1] - (s * x + c * y)).abs() < 1e-11 * l);
            prop_assert!((b.tip_angle_rad - rot - a.tip_angle_rad).abs() < 1e-11);
        }
    }

    const PI_F: f64 = std::f64::consts::PI;
}
