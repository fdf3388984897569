//! Following a snap downhill: where the posture's branch of equilibria ends under the moving
//! base (the antenna flips or springs forward), the posture follows the friction-aware
//! gradient flow by implicit (proximal) steps until a plain solve from where it got to
//! converges without a jump (model.md 6: "follow the downhill path, not jump to whatever
//! minimum a Newton step lands in").

use nalgebra::Vector2;

use super::ContactError;
use super::quasistatic::QuasiStatic;
use super::report::StepReport;

impl QuasiStatic {
    /// Follows a vanished branch downhill at the base position `goal`: implicit steps of the
    /// friction-aware gradient flow (proximal solves, the proximal weight `gamma` halved
    /// after each success and quadrupled after each failure), until a plain solve from the
    /// posture reached converges without a jump.
    pub(super) fn follow_snap(
        &mut self,
        goal: Vector2<f64>,
        budget: usize,
        report: &mut StepReport,
    ) -> Result<(), ContactError> {
        report.snapped = true;
        self.secant = None;
        let mut gamma = 1.0;
        for _ in 0..self.settings.max_snap_steps {
            if report.iterations > budget {
                break;
            }
            report.snap_steps += 1;
            let x_prev = self.coordinates();
            let r = self.attempt(goal, Some((gamma, &x_prev)), report);
            match r {
                Ok(accepted) => {
                    let moved = accepted
                        .x
                        .iter()
                        .zip(&x_prev)
                        .take(self.chain.n())
                        .fold(0.0_f64, |a, (x, y)| a.max((x - y).abs()));
                    report.note_residual(accepted.residual_m, &self.settings);
                    self.commit(goal, accepted);
                    if (moved < 1e-7 || gamma < 1e-6)
                        && let Ok(plain) = self.attempt(goal, None, report)
                    {
                        report.note_residual(plain.residual_m, &self.settings);
                        self.commit(goal, plain);
                        return Ok(());
                    }
                    gamma = (gamma * 0.5).max(1e-8);
                }
                Err(_) => {
                    gamma *= 4.0;
                    if gamma > 1e12 {
                        break;
                    }
                }
            }
        }
        Err(ContactError::no_convergence(
            goal,
            "the downhill path did not come to rest",
            report.iterations,
        ))
    }
}
