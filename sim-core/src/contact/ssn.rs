//! The semismooth Newton method on a step's equations ([`super::equations`]), with the
//! exact Newton system of [`super::newton_system`].
//!
//! Globalization: a non-monotone backtracking line search on `|Phi|^2 / 2` (Grippo,
//! Lampariello and Lucidi: a step is accepted against the largest merit of the last few
//! iterations, so that the modes can settle where a constraint is degenerate), a cap on the
//! change of any coordinate per iteration, and Levenberg-Marquardt damping of the Newton
//! matrix, raised when no step is accepted and lowered again after successes (it changes
//! the path, never the solution: `Phi` itself is never regularized). A solve that does not
//! converge is reported; the caller refines the step.

use super::equations::{Equations, StepProblem};
use super::newton_system::NewtonSystem;
use super::pair::Pair;
use nalgebra::{DMatrix, Vector2};

/// How a solve ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct SsnOutcome {
    pub converged: bool,
    pub iterations: usize,
    /// `max |Phi|`, metres.
    pub residual_m: f64,
    /// The hand's force on the tip, newtons (zero without a hand).
    pub hand_force_n: Vector2<f64>,
}

/// The solver's scratch space, reused from step to step.
#[derive(Debug, Default)]
pub(crate) struct Ssn {
    pub eq: Equations,
    pub system: NewtonSystem,
    dz: Vec<f64>,
    z_prev: Vec<f64>,
    trial: Vec<Pair>,
}

/// How many past merits the non-monotone line search compares against.
const NONMONOTONE_MEMORY: usize = 6;

/// The largest change of a coordinate in one iteration, radians.
const MAX_CHANGE_RAD: f64 = 0.25;

/// The first damping tried after a failure, and the limits of the damping.
const MIN_DAMPING: f64 = 1e-8;
const MAX_DAMPING: f64 = 1e4;

fn next_damping(damping: f64) -> f64 {
    if damping < MIN_DAMPING {
        MIN_DAMPING
    } else {
        damping * 100.0
    }
}

impl Ssn {
    /// Solves the step: `x` (the coordinates) and the pairs' forces are the start and
    /// receive the answer (the best point reached if it did not converge).
    pub fn solve(&mut self, p: &StepProblem<'_>, x: &mut [f64], pairs: &mut [Pair]) -> SsnOutcome {
        self.eq.prepare(p);
        self.eq.load(x, pairs);
        let m = x.len();
        let n = p.chain.n();
        let mut merit = self.eq.evaluate(p, pairs);
        let mut outcome = SsnOutcome {
            converged: false,
            iterations: 0,
            residual_m: self.eq.residual_m(),
            hand_force_n: Vector2::zeros(),
        };
        let mut damping = 0.0_f64;
        let mut recent = [merit; NONMONOTONE_MEMORY];
        while (outcome.residual_m > p.tolerance_m || outcome.residual_m.is_nan())
            && outcome.iterations < p.max_iterations
        {
            let reference = recent.iter().copied().fold(merit, f64::max);
            outcome.iterations += 1;
            let mut dz = std::mem::take(&mut self.dz);
            let direction = self.system.direction(&self.eq, p, pairs, damping, &mut dz);
            if direction.is_none() {
                self.dz = dz;
                damping = next_damping(damping);
                if damping > MAX_DAMPING {
                    break;
                }
                continue;
            }
            // Cap the change of the coordinates per iteration (a trust region in angle).
            let max_dx = dz[..m].iter().fold(0.0_f64, |a, v| a.max(v.abs()));
            let mut alpha = if max_dx > MAX_CHANGE_RAD {
                MAX_CHANGE_RAD / max_dx
            } else {
                1.0
            };
            self.z_prev.clone_from(&self.eq.z);
            let mut accepted = false;
            while alpha > 1e-6 {
                for (i, (z, z0)) in self.eq.z.iter_mut().zip(&self.z_prev).enumerate() {
                    *z = z0 + alpha * dz[i];
                }
                for a in 0..m {
                    self.eq.z[a] = self.eq.z[a].clamp(self.eq.lo[a], self.eq.hi[a]);
                }
                self.trial.clear();
                self.trial.extend_from_slice(pairs);
                let mut trial = std::mem::take(&mut self.trial);
                let trial_merit = self.eq.evaluate(p, &mut trial);
                if trial_merit.is_finite() && trial_merit <= (1.0 - 2e-4 * alpha) * reference {
                    pairs.copy_from_slice(&trial);
                    self.trial = trial;
                    merit = trial_merit;
                    accepted = true;
                    break;
                }
                self.trial = trial;
                alpha *= 0.5;
            }
            self.dz = dz;
            if !accepted {
                // Back to the current point (the trials overwrote the evaluation).
                self.eq.z.clone_from(&self.z_prev);
                merit = self.eq.evaluate(p, pairs);
                damping = next_damping(damping);
                if damping > MAX_DAMPING {
                    break;
                }
                continue;
            }
            damping = if damping > MIN_DAMPING {
                damping * 0.01
            } else {
                0.0
            };
            recent[outcome.iterations % NONMONOTONE_MEMORY] = merit;
            outcome.residual_m = self.eq.residual_m();
            if (0..n).any(|a| (self.eq.z[a] - x[a]).abs() > p.max_departure_rad) {
                break;
            }
        }
        // A solve that stalls at a degenerate point (a contact touching with N = 0 and
        // gap = 0: the modes trade places and Newton's method stops improving) is accepted
        // within the acceptable residual.
        outcome.converged = outcome.residual_m <= p.tolerance_m.max(p.acceptable_m);
        x.copy_from_slice(&self.eq.z[..m]);
        outcome.hand_force_n = self.eq.hand_force_n;
        outcome
    }

    /// The Hessian of the Lagrangian at `x` with the pairs' forces, reduced to the tangent
    /// space of the active constraints: coordinates strictly inside their range, moved so
    /// that every pair carrying a force keeps touching (and a stuck one does not slide).
    /// Returns `Z^T H Z` for an orthonormal basis `Z` of that space (`0 x 0` when nothing can
    /// move); `H` is symmetrized (friction's terms are not a potential's).
    pub fn tangent_hessian(
        &mut self,
        p: &StepProblem<'_>,
        x: &[f64],
        pairs: &mut [Pair],
    ) -> DMatrix<f64> {
        self.eq.prepare(p);
        self.eq.load(x, pairs);
        self.eq.evaluate(p, pairs);
        let m = x.len();
        let free: Vec<usize> = (0..m)
            .filter(|&a| x[a] > self.eq.lo[a] + 1e-12 && x[a] < self.eq.hi[a] - 1e-12)
            .collect();
        let f = free.len();
        let hess = self.system.dense_hessian(&self.eq, p, pairs);
        let rows = self.system.active_constraint_rows(&self.eq, p, pairs);
        // The null space of the constraint rows: eigenvectors of A^T A with (relatively)
        // zero eigenvalue.
        let mut ata = DMatrix::<f64>::zeros(f, f);
        for row in &rows {
            for i in 0..f {
                for j in 0..f {
                    ata[(i, j)] += row[free[i]] * row[free[j]];
                }
            }
        }
        let eig = ata.symmetric_eigen();
        let top = eig.eigenvalues.iter().copied().fold(0.0_f64, f64::max);
        let null: Vec<usize> = (0..f)
            .filter(|&i| eig.eigenvalues[i] <= 1e-10 * top.max(f64::MIN_POSITIVE))
            .collect();
        let mut basis = DMatrix::<f64>::zeros(f, null.len());
        for (col, &i) in null.iter().enumerate() {
            basis.set_column(col, &eig.eigenvectors.column(i));
        }
        let mut h = DMatrix::<f64>::zeros(f, f);
        for (i, &a) in free.iter().enumerate() {
            for (j, &b) in free.iter().enumerate() {
                h[(i, j)] = 0.5 * (hess[(a, b)] + hess[(b, a)]);
            }
        }
        basis.transpose() * h * basis
    }
}
