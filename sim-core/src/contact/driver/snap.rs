//! Following a snap downhill: where the posture's branch of equilibria ends under the moving
//! base (the antenna flips or springs forward), the posture follows the friction-aware
//! gradient flow by implicit (proximal) steps until a plain solve from where it got to
//! converges without a jump (docs/model.md 6: "follow the downhill path, not jump to whatever
//! minimum a Newton step lands in").

use super::QuasiStatic;
use crate::contact::ContactError;
use crate::contact::posture::Pose;
use crate::contact::report::StepReport;

/// A pseudo-time step that changes no joint angle by more than this, radians, has come to
/// rest: a plain solve from there ends the snap.
const REST_RAD: f64 = 1e-7;

/// A pseudo-time step whose proximal solve took at most this many Newton iterations is
/// followed by a longer one (`gamma` halved); a harder one keeps `gamma`.
const EASY_ITERATIONS: usize = 40;

/// After this many hard pseudo-time steps in a row (each over [`EASY_ITERATIONS`]), the
/// next is longer all the same. A flow whose every solve is hard kept a tiny step for good:
/// the placement of replay `soak:4221:329` (36 links let go on a polyline, the flow at `gamma` = 5e5) crept 3
/// micro-radians per step for 2,000 steps, 101,159 Newton iterations; it now comes to rest
/// after 5,332 (3,230 with the repair's cone test of `step_solver/ssn.rs` since). By measurement on
/// the two settles it changes most: after 3 hard steps, 4,912 and replay `soak:4221:73`'s 61,885 (a
/// longer step failing there at some 1,000 iterations a time); after 6, 5,332 and 31,134;
/// after 10, 5,893 and 44,051; never, 101,159 and 42,538.
const HARD_IN_A_ROW: usize = 6;

impl QuasiStatic {
    /// Follows a vanished branch downhill at the base position `goal`: implicit steps of the
    /// friction-aware gradient flow (proximal solves, the proximal weight `gamma` halved
    /// after each success that took at most [`EASY_ITERATIONS`] and quadrupled after each
    /// failure), until a plain solve from the posture reached converges without a jump.
    pub(super) fn follow_snap(
        &mut self,
        goal: Pose,
        budget: usize,
        report: &mut StepReport,
    ) -> Result<(), ContactError> {
        report.snapped = true;
        self.secant = None;
        let mut gamma = 1.0;
        // The posture before the last accepted pseudo-time step.
        let mut x_before_last: Option<Vec<f64>> = None;
        let mut hard_in_a_row = 0_usize;
        for _ in 0..self
            .world
            .settings()
            .snap_step_budget(self.world.chain().n())
        {
            if report.iterations > budget {
                break;
            }
            report.snap_steps += 1;
            let x_prev = self.committed.coordinates();
            let spent_before = report.iterations;
            let r = self.attempt(goal, Some((gamma, &x_prev)), report);
            let easy = report.iterations - spent_before <= EASY_ITERATIONS;
            match r {
                Ok(accepted) => {
                    let n = self.world.chain().n();
                    let distance = |to: &[f64]| {
                        accepted
                            .x
                            .iter()
                            .zip(to)
                            .take(n)
                            .fold(0.0_f64, |a, (x, y)| a.max((x - y).abs()))
                    };
                    let moved = distance(&x_prev);
                    // Back where the step before this one started: two pseudo-time steps
                    // taking turns about a rest point that a stalled solve accepted within
                    // the acceptable residual (a contact touching with no force), which
                    // the flow would otherwise circle for its whole budget.
                    let circling = x_before_last
                        .as_deref()
                        .is_some_and(|x| distance(x) < REST_RAD);
                    report.note_residual(accepted.residual_m, self.world.settings());
                    self.commit(goal, accepted);
                    x_before_last = Some(x_prev);
                    let resting = moved < REST_RAD || circling || gamma < 1e-6;
                    if resting && let Ok(plain) = self.attempt(goal, None, report) {
                        report.note_residual(plain.residual_m, self.world.settings());
                        self.commit(goal, plain);
                        return Ok(());
                    }
                    // A solve that came easily takes a longer pseudo-time step next; one
                    // that was hard keeps its step, rather than fail at a longer one, unless
                    // the flow came to rest where no plain solve converges, or the last
                    // [`HARD_IN_A_ROW`] were all hard.
                    hard_in_a_row = if easy { 0 } else { hard_in_a_row + 1 };
                    if easy || resting || hard_in_a_row >= HARD_IN_A_ROW {
                        hard_in_a_row = 0;
                        gamma = (gamma * 0.5).max(1e-8);
                    }
                }
                Err(_) => {
                    hard_in_a_row = 0;
                    gamma *= 4.0;
                    if gamma > 1e12 {
                        break;
                    }
                }
            }
        }
        Err(ContactError::no_convergence(
            goal.base_m,
            "the downhill path did not come to rest",
            report.iterations,
        ))
    }
}
