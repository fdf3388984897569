//! Statics of the chain and of the beam it stands for (thesis 2.3.2, 3.2.2; docs/model.md 3-6):
//! the potential energy, static equilibria, the tip force at a posture, Castigliano's
//! deflection, chains as beams, and the elastica they converge to.
//!
//! - [`energy`]: spring energy and tip load with gradient and Hessian, in `theta` and `q`.
//! - [`equilibrium`]: KKT points of the potential under joint limits and an optional pinned
//!   tip, their stability, and all minima.
//! - [`tip_force`](mod@tip_force): the tip force at a posture (least squares `J^T F = -tau`,
//!   and the free-body system with stop torques, base reaction and servo torque).
//! - [`castigliano`]: the deflection `K^-1 J^T (F, M)` of a small tip load (thesis 3.2.2).
//! - [`beam`]: chains that stand for a beam (the first-order equal-links and the
//!   second-order Hencky layouts) and Richardson extrapolation over the number of links.
//! - [`elastica`]: the reference solver for the clamped inextensible beam under a tip load.

pub mod beam;
pub mod castigliano;
pub mod elastica;
pub mod energy;
pub mod equilibrium;
pub mod tip_force;
