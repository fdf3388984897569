//! Model.md 6's fixed point on the normal forces, for the steps Coulomb's law makes hard.
//!
//! Coulomb's law makes a step's equations non-monotone (the friction of a sliding contact
//! can drive it into the wall). Where the semismooth Newton method on them fails, the step
//! is solved as a sequence of Tresca problems instead, the shear bounds `mu N` held at the
//! normal forces of the previous solve, started from the last step's forces, until the
//! normal forces stop changing: then the answer is Coulomb's. Where the iteration does not
//! settle, the contacts whose normal force keeps growing are **jammed** (a frictional
//! paradox: sliding needs ever more normal force the more friction it has): they slide
//! without friction for the step, which is reported ([`crate::contact::StepReport::jams`], counted
//! by the attempt that accepts the answer).

use super::equations::StepProblem;
use super::ssn::{Ssn, SsnOutcome};
use crate::contact::pair::Pair;
use crate::contact::report::StepReport;

/// Fixed-point iterations on the normal forces before a step is given up.
const TRESCA_ITERATIONS: usize = 30;
/// When the held normal forces count as settled, relative.
const TRESCA_TOLERANCE_N: f64 = 1e-10;

/// Solves the step by the fixed point (see the module docs); `x` and the pairs are the
/// start and receive the answer.
pub(super) fn solve_by_fixed_point(
    ssn: &mut Ssn,
    problem: &StepProblem<'_>,
    x: &mut [f64],
    pairs: &mut [Pair],
    report: &mut StepReport,
) -> SsnOutcome {
    for c in pairs.iter_mut() {
        c.tresca_n = Some(c.normal_force_n.max(0.0));
        c.relaxed_bound_n = None;
    }
    let mut outcome = SsnOutcome::not_converged();
    for round in 0..TRESCA_ITERATIONS {
        outcome = ssn.solve(problem, x, pairs);
        report.iterations += outcome.iterations;
        if !outcome.converged && round == 0 {
            // The first Tresca problem does not solve either: the iteration tells nothing of
            // normal forces that keep growing, so nothing is called jammed (a failed solve's
            // drift was, before: 150 links on a digitized wall (replay `soak:4221:1982`), whose whole steps
            // then failed at 60 Newton iterations where their halves took 3 each). The
            // caller refines the step.
            for c in pairs.iter_mut() {
                c.tresca_n = None;
            }
            return outcome;
        }
        if !outcome.converged {
            break;
        }
        let mut settled = true;
        for c in pairs.iter_mut() {
            let held = c.tresca_n.unwrap_or(0.0);
            let now = c.normal_force_n.max(0.0);
            if (now - held).abs() > TRESCA_TOLERANCE_N * (1.0 + now) {
                settled = false;
            }
            c.tresca_n = Some(now);
        }
        if settled {
            report.fixed_point_solves += 1;
            for c in pairs.iter_mut() {
                c.tresca_n = None;
            }
            return outcome;
        }
    }
    // No fixed point: a jam. The jamming contacts (whose normal force kept growing) slide
    // without friction for this step; the others keep Coulomb's law, or, where the step
    // does not converge with it, the bound of their last normal force. Every bound that is
    // not Coulomb's is recorded on its contact and the step reports the jam.
    let mut jammed = 0;
    let held: Vec<f64> = pairs.iter().map(|c| c.tresca_n.unwrap_or(0.0)).collect();
    for (c, &h) in pairs.iter_mut().zip(&held) {
        if (c.normal_force_n.max(0.0) - h).abs() > 1e-3 * (1e-9 + h) {
            c.tresca_n = Some(0.0);
            jammed += 1;
        } else {
            c.tresca_n = None;
        }
    }
    if jammed == 0 {
        for c in pairs.iter_mut() {
            c.tresca_n = None;
        }
        outcome.converged = false;
        return outcome;
    }
    outcome = ssn.solve(problem, x, pairs);
    report.iterations += outcome.iterations;
    if !outcome.converged {
        // Coulomb's law for the others does not settle either: hold their bounds too.
        for (c, &h) in pairs.iter_mut().zip(&held) {
            if c.tresca_n.is_none() {
                c.tresca_n = Some(h.min(c.normal_force_n.max(0.0)));
            }
        }
        // Any contact whose held bound exceeds mu N loses its friction, until every
        // contact is inside its cone.
        for _ in 0..=pairs.len() {
            outcome = ssn.solve(problem, x, pairs);
            report.iterations += outcome.iterations;
            if !outcome.converged {
                break;
            }
            let mut outside = false;
            for c in pairs.iter_mut() {
                let bound = c.law.shear_bound(c.normal_force_n).0;
                if c.shear_force_n.abs() > bound + 1e-12 && c.tresca_n != Some(0.0) {
                    c.tresca_n = Some(0.0);
                    outside = true;
                }
            }
            if !outside {
                break;
            }
        }
    }
    for c in pairs.iter_mut() {
        c.relaxed_bound_n = c.tresca_n.map(|held| c.law.shear_bound(held).0);
        c.tresca_n = None;
    }
    outcome
}
