//! The step solver: one (sub)step's equations for a given set of pairs, solved. Its input
//! is a [`StepProblem`] (the chain, the wall pieces, the loads, the goal pose, the hairs
//! taking part and the solve's limits), the start `x` and the pairs (their forces and
//! friction state as the start); its output the answer in `x` and the pairs, and an
//! [`SsnOutcome`].
//!
//! - `equations.rs`: the nonlinear complementarity problem (the Alart-Curnier form of
//!   Coulomb contact), its unknowns, residual and modes;
//! - `newton_system.rs`: the exact Newton system of the active piece (a bordered system);
//! - `ssn.rs`: the semismooth Newton method on it, globalized, with repairs of stalls;
//! - `tresca.rs`: the fixed point on the normal forces (Tresca problems) where Coulomb's law
//!   makes the equations non-monotone.
//!
//! Its state (the scratch space reused from solve to solve, the last repair, the counters)
//! is its own: private to this module, read through [`StepSolver`]'s methods.

mod equations;
mod newton_system;
mod ssn;
mod tresca;

pub(super) use equations::{Proximal, StepProblem};
pub(super) use ssn::{STALL_ITERATIONS, SsnOutcome};

use nalgebra::DMatrix;

use super::pair::Pair;
use super::report::StepReport;
use ssn::Ssn;

/// The step solver's state: the semismooth Newton method's scratch space and memory (see
/// the module docs).
#[derive(Debug, Default)]
pub(super) struct StepSolver {
    ssn: Ssn,
}

impl StepSolver {
    /// Solves `problem` by the semismooth Newton method from `x` and `pairs` (the start;
    /// they receive the answer).
    pub fn solve(
        &mut self,
        problem: &StepProblem<'_>,
        x: &mut [f64],
        pairs: &mut [Pair],
    ) -> SsnOutcome {
        self.ssn.solve(problem, x, pairs)
    }

    /// Solves `problem` by the fixed point on the normal forces (Tresca problems), for a
    /// step whose semismooth Newton solve failed with friction; jammed contacts are
    /// reported through the pairs' relaxed bounds.
    pub fn solve_by_fixed_point(
        &mut self,
        problem: &StepProblem<'_>,
        x: &mut [f64],
        pairs: &mut [Pair],
        report: &mut StepReport,
    ) -> SsnOutcome {
        tresca::solve_by_fixed_point(&mut self.ssn, problem, x, pairs, report)
    }

    /// The Hessian of the step's Lagrangian at `x` on the tangent space of the active
    /// constraints (see [`Ssn::tangent_hessian`]).
    pub fn tangent_hessian(
        &mut self,
        problem: &StepProblem<'_>,
        x: &[f64],
        pairs: &mut [Pair],
    ) -> DMatrix<f64> {
        self.ssn.tangent_hessian(problem, x, pairs)
    }

    /// Repairs, over the solver's life, that found another mode converging only to an
    /// answer that mode refuses ([`Ssn::refused_repairs`]).
    pub fn refused_repairs(&self) -> usize {
        self.ssn.refused_repairs()
    }

    /// Linear solves, over the solver's life, that fell back to the dense factorization.
    pub fn dense_solves(&self) -> usize {
        self.ssn.dense_solves()
    }
}
