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
//! Aitken-Neville extrapolation in `h^2`, order 12; the crate's `numerics::gbs`) with
//! adaptive step-size control; it reaches the default `1e-13` relative local tolerance in tens
//! of steps. Breakpoints of `EI` (piecewise-constant sections, or ones declared for a closure)
//! and shape sample points are hit exactly, so a jump in `EI` never sits inside a step.
//!
//! For a uniform beam loaded perpendicular to the clamp direction the classical closed form
//! by elliptic integrals (Bisshopp & Drucker 1945; Carlson's symmetric forms, the crate's
//! `numerics::elliptic`) is in [`perpendicular_load_closed_form`]; the two agree to better
//! than `1e-10` (see the tests).
//!
//! A chain of rigid links with joint springs `k_j = EI(x_j) / l` (joint `j` at arc length
//! `x_j`, links of length `l`) approximates this beam; as the number of links grows its
//! equilibria converge to the elastica's, which is what this solver is the reference for.
//!
//! # Files
//! - `error.rs`: [`ElasticaError`].
//! - `problem.rs`: the problem ([`ElasticaProblem`], [`BendingStiffness`]), the options
//!   ([`ElasticaOptions`]) and the answer ([`ElasticaSolution`], [`ShapePoint`]), and the
//!   validation of a problem.
//! - `shooting.rs`: [`solve`], Newton's method on the clamp moment with load continuation, and
//!   the integration of the beam's equations.
//! - `closed_form.rs`: [`perpendicular_load_closed_form`] ([`PerpendicularLoadClosedForm`]).

mod closed_form;
mod error;
mod problem;
mod shooting;
#[cfg(test)]
mod tests;

pub use closed_form::{PerpendicularLoadClosedForm, perpendicular_load_closed_form};
pub use error::ElasticaError;
pub use problem::{
    BendingStiffness, ElasticaOptions, ElasticaProblem, ElasticaSolution, ShapePoint,
};
pub use shooting::solve;
