//! Static equilibria of the chain (thesis 2.3.2, docs/model.md 3, 4, 6): KKT points of
//!
//! ```text
//! minimize   P(theta) = U(theta) - F . p_n(theta)      over theta_1..theta_n (theta_0 fixed)
//! subject to cw_j <= theta_j <= ccw_j                  (joint limits)
//!            p_n(theta) = P                            (optional: tip pinned, free to rotate)
//! ```
//!
//! with `U = 1/2 sum k_j (theta_j - rest_j)^2` (rest angles from the chain).
//!
//! # Method
//! - **Newton with analytic derivatives.** Gradient `K (theta - rest) - J^T f` and Hessian
//!   `K + [f . (p_n - p_(max(i,j)-1))]` ([`crate::statics::energy::Potential`]), `J` the tip Jacobian.
//! - **`O(n)` per iteration.** The Hessian is diagonal plus a `max(i,j)`-semiseparable
//!   matrix; it is factored by elimination from the tip inwards in `O(n)`
//!   ([`structured`]). The pin adds a 2-column term handled by the Woodbury identity
//!   (two more `O(n)` solves and a 2 x 2 system). The workspace is allocated once per solve.
//!   A dense `O(n^3)` path ([`LinearSolver::Dense`]) is kept as the test reference.
//! - **Globalization that cannot diverge.** A projected Armijo line search on the merit
//!   (the potential without a pin) along a descent direction: the Newton direction when the
//!   Newton matrix is positive definite, a Levenberg-shifted Newton direction (`H + sigma I`,
//!   `sigma` found with the `O(n)` inertia count) when it is not, a negative-curvature step
//!   off a saddle ([`escape`]), the scaled projected gradient as a last resort. Every accepted step
//!   decreases the merit; [`solve_equilibrium_with`] can record the history
//!   ([`SolveTrace`]). See [`newton`].
//! - **Joint limits** by projected Newton with an epsilon-active set (Bertsekas): the answer
//!   is a KKT point, and a joint on a limit reports its stop torque with the sign of a
//!   valid multiplier ([`Equilibrium::limit_torques_nm`]).
//! - **Pinned tip** by a homotopy of the target from the start's own tip position to `P`
//!   and an augmented-Lagrangian outer loop with projected-Newton inner solves
//!   ([`pinned`]).
//! - **Stability** from the inertia of the structured factorization and a 2 x 2 Schur
//!   complement ([`stability`]); **all minima** by a seeded multi-start search
//!   ([`minima`]).
//!
//! # Example: a cantilever under a tip load
//! ```
//! use nalgebra::Vector2;
//! use sim_core::{Chain, EquilibriumProblem, InitialGuess, SolveOptions, solve_equilibrium};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let chain = Chain::builder(8).stiffness_nm_per_rad(0.05).build()?;
//! let problem = EquilibriumProblem::new(&chain).with_tip_force_n(Vector2::new(0.0, -0.2));
//! let eq = solve_equilibrium(&problem, &InitialGuess::Straight, &SolveOptions::default())?;
//! assert!(eq.converged && eq.stable && eq.kkt_residual <= 1e-10);
//! assert!(eq.theta_rad[1..].iter().all(|&t| t < 0.0)); // bent downwards, a C
//! assert_eq!(eq.inflections, 0);
//! # Ok(())
//! # }
//! ```

pub(crate) mod bordered;
pub mod error;
pub mod escape;
pub mod minima;
pub mod newton;
pub mod options;
pub mod pinned;
pub mod problem;
pub mod report;
mod solve;
pub mod stability;
pub mod structured;
mod workspace;

pub use error::EquilibriumError;
pub use minima::{SAME_EQUILIBRIUM_RAD, all_minima};
pub use options::{LinearSolver, MinimaSearch, SolveOptions, SolverSettings};
pub use problem::{EquilibriumProblem, InitialGuess};
pub use report::{Equilibrium, LimitSide, SolveTrace, TraceStep, count_inflections};
pub use solve::{solve_equilibrium, solve_equilibrium_with};
pub use structured::{Inertia, SemiseparableFactor, SemiseparableMatrix};
