//! The elastica problem: the beam ([`ElasticaProblem`], its [`BendingStiffness`]), the solver's
//! options ([`ElasticaOptions`]), the answer ([`ElasticaSolution`], [`ShapePoint`]), and the
//! checks of a problem and its options.

use std::fmt;
use std::sync::Arc;

use super::ElasticaError;

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
    pub(super) fn at(&self, s_m: f64, section: usize) -> Result<f64, ElasticaError> {
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

/// The equilibrium found by [`solve`](super::solve).
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

pub(super) fn validate(
    problem: &ElasticaProblem,
    options: &ElasticaOptions,
) -> Result<(), ElasticaError> {
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
pub(super) fn section_knots(problem: &ElasticaProblem) -> Vec<f64> {
    let mut knots = problem.bending_stiffness.breakpoints_m().to_vec();
    knots.push(problem.length_m);
    knots
}
