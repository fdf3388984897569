//! Solver options ([`SolveOptions`]), the multi-start search ([`MinimaSearch`]) and the
//! settings used by tests and benchmarks ([`SolverSettings`]).

use super::EquilibriumError;

/// Options of one solve (validated when the solve starts).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolveOptions {
    /// Tolerance on the KKT residual (dimensionless, see [`Equilibrium::kkt_residual`]);
    /// default `1e-10`.
    ///
    /// [`Equilibrium::kkt_residual`]: super::Equilibrium::kkt_residual
    pub tolerance: f64,
    /// Budget of Newton iterations, summed over every stage of the solve; default 200.
    pub max_iterations: usize,
}

impl Default for SolveOptions {
    fn default() -> Self {
        SolveOptions {
            tolerance: 1e-10,
            max_iterations: 200,
        }
    }
}

impl SolveOptions {
    /// Checks the options: `tolerance` finite and `> 0`, `max_iterations >= 1`.
    ///
    /// # Errors
    /// [`EquilibriumError::InvalidOption`] naming the first bad option.
    pub fn validate(&self) -> Result<(), EquilibriumError> {
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(EquilibriumError::InvalidOption {
                option: "tolerance",
                value: self.tolerance,
            });
        }
        if self.max_iterations == 0 {
            return Err(EquilibriumError::InvalidOption {
                option: "max_iterations",
                value: 0.0,
            });
        }
        Ok(())
    }
}

/// The multi-start search of [`all_minima`](super::all_minima).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MinimaSearch {
    /// Random starts on top of the fixed ones (straight, C, S and the mirrors); default 64.
    pub random_starts: usize,
    /// Seed of the random starts (SplitMix64); default 1.
    pub seed: u64,
}

impl Default for MinimaSearch {
    fn default() -> Self {
        MinimaSearch {
            random_starts: 64,
            seed: 1,
        }
    }
}

/// How the Newton system is solved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LinearSolver {
    /// The `O(n)` elimination along the chain ([`super::structured`]); the default.
    #[default]
    Structured,
    /// Dense `O(n^3)` factorizations with nalgebra (Cholesky, or a symmetric eigen
    /// decomposition with eigenvalues made positive when the matrix is indefinite), and a dense
    /// bordered-matrix inertia for stability. The reference the structured path is tested
    /// against; not for large `n`.
    Dense,
}

/// Settings beyond [`SolveOptions`], for tests and benchmarks
/// ([`solve_equilibrium_with`](super::solve_equilibrium_with)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SolverSettings {
    /// Which linear algebra to use.
    pub linear_solver: LinearSolver,
    /// Record the merit after every accepted step in the returned
    /// [`SolveTrace`](super::SolveTrace) (a test hook; costs an allocation per step).
    pub record_trace: bool,
}
