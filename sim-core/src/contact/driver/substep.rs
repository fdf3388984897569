//! One (sub)step: the pairs that take part, the semismooth Newton solve (or, where it fails
//! with friction, the fixed point on the normal forces), pairs missed (by a solve that
//! converged or one that failed) or let go re-solved,
//! hairs anchored or let go, and the jump test.

use nalgebra::Vector2;

use super::QuasiStatic;
use crate::contact::broad_phase::Inputs;
use crate::contact::certifier::FORCE_ZERO_N;
use crate::contact::pair::{Pair, PairKey};
use crate::contact::posture::Pose;
use crate::contact::report::StepReport;
use crate::contact::step_solver::STALL_ITERATIONS;
use crate::contact::step_solver::{Proximal, StepProblem};

/// Why one attempt at a (sub)step was not accepted.
pub(super) enum Reject {
    /// Newton did not converge.
    NoConvergence,
    /// It converged, but a joint moved more than its jump threshold.
    Jump,
}

/// An accepted (sub)step, not yet committed.
pub(crate) struct Accepted {
    pub x: Vec<f64>,
    pub hair_links: Vec<usize>,
    pub pairs: Vec<Pair>,
    pub residual_m: f64,
    pub hand_force_n: Vector2<f64>,
}

/// Rounds of re-solving (pairs missed or let go, hairs anchoring) before a (sub)step is
/// refined instead.
const ROUNDS: usize = 8;

/// Newton iterations of a quick attempt (one plain solve with friction after a step where
/// friction locked the antenna): a step that can stick again converges in a few.
const QUICK_ITERATIONS: usize = 12;

/// A quick attempt whose best merit has not halved in this many Newton iterations has
/// stalled: friction still locks the antenna, and the step drops it at once. A step that
/// sticks again converges without such a stall: over 20 s of the thesis's walls under 4
/// links (90 mm links; friction locks the antenna in 787-1,529 of 2,000 steps), 4 drops
/// friction in as many steps on each wall as 14 ([`STALL_ITERATIONS`]) does, and the median
/// step takes 6 Newton iterations instead of 14 (the failing quick attempt spent 12 of
/// them).
const QUICK_STALL_ITERATIONS: usize = 4;

/// Whether the last four rounds left two sets of pairs in turn (`A B A B`).
fn taking_turns(round_keys: &[Vec<PairKey>]) -> bool {
    match round_keys {
        [.., a, b, c, d] => a == c && b == d && a != b,
        _ => false,
    }
}

/// Records the pairs a round leaves for the next (`round_keys`, sorted keys) and whether
/// the rounds now take turns ([`taking_turns`]).
fn taking_turns_with(round_keys: &mut Vec<Vec<PairKey>>, pairs: &[Pair]) -> bool {
    let mut keys: Vec<PairKey> = pairs.iter().map(|q| q.key).collect();
    keys.sort_unstable();
    round_keys.push(keys);
    taking_turns(round_keys)
}

impl QuasiStatic {
    /// Whether the joint angles `x` (`theta_1..theta_n`) change some joint from the committed
    /// posture by more than its jump threshold ([`super::ContactSettings::jump_threshold_rad`]:
    /// scaled with the links by default, a bound on the change of curvature).
    fn jumps(&self, x: &[f64]) -> bool {
        let lengths = self.world.chain().link_lengths_m();
        let settings = self.world.settings();
        x.iter()
            .zip(&self.committed.theta()[1..])
            .enumerate()
            .any(|(i, (x, t))| (x - t).abs() > settings.jump_threshold_rad(lengths, i + 1))
    }

    /// The secant predictor of the joint angles `theta_1..theta_n` with the base at
    /// `goal`: the last plain step's change, scaled to this step's change of the base pose
    /// (up to twice the last one; displacement and turn weighed together, the turn by the
    /// chain's reach), within the joint limits; `None` without a last plain step or where
    /// the changes do not point the same way.
    fn secant_prediction(&self, goal: Pose) -> Option<Vec<f64>> {
        let secant = self.secant.as_ref()?;
        let (delta, dtheta) = (&secant.delta_m, &secant.dtheta_rad);
        // A turn weighs as the displacement of a point at the chain's reach. Without turns
        // both terms are zero and this is the projection on the displacement alone, bit
        // for bit.
        let reach_m = self.world.reach_m();
        let w = reach_m * reach_m;
        let theta = self.committed.theta();
        let d2 = delta.norm_squared() + w * secant.turn_rad * secant.turn_rad;
        let scale = if d2 > 0.0 {
            ((goal.base_m - self.committed.base_m()).dot(delta)
                + w * (goal.angle_rad - theta[0]) * secant.turn_rad)
                / d2
        } else {
            0.0
        };
        if !(scale > 0.0 && scale <= 2.0) {
            return None;
        }
        let limits = self.world.chain().joint_limits();
        Some(
            theta[1..]
                .iter()
                .zip(dtheta)
                .zip(&limits[1..])
                .map(|((t, d), l)| (t + scale * d).clamp(l.cw_rad, l.ccw_rad))
                .collect(),
        )
    }

    /// Tries one (sub)step from the committed state to the base at `goal` (with a proximal
    /// term when following a snap). The start posture (where the contacts' material points
    /// were, their slips measured from there) is the committed pose, pivot and angle; the
    /// probe (the last posture carried to the goal), the broad phase and the predictor use
    /// the goal's.
    pub(super) fn attempt(
        &mut self,
        goal: Pose,
        proximal: Option<(f64, &[f64])>,
        report: &mut StepReport,
    ) -> Result<Accepted, Reject> {
        let n = self.world.chain().n();
        let inputs = Inputs {
            world: &self.world,
            committed: &self.committed,
            friction_off: self.friction_off,
        };
        // The secant prediction at `goal` (the broad phase's, and each round's start).
        let predicted = self.secant_prediction(goal);
        let mut pairs = self
            .broad_phase
            .candidates(inputs, goal, predicted.as_deref())
            .map_err(|_| Reject::NoConvergence)?;
        // A solve gives up where its joint angles wander farther than twice the largest jump
        // threshold from its start: a plain step's answer there would be refused as a jump.
        // A snap's pseudo-time step (proximal) starts off equilibrium, where Newton's first
        // iterates swing out and come back: it keeps at least twice `jump_rad` (the bound
        // before the threshold was scaled to the link; at 0.05 rad the flow of a held 18-link
        // antenna brought onto a digitized wall failed to come to rest, CI sample 2).
        let settings = self.world.settings();
        let largest_rad = settings.max_jump_threshold_rad(self.world.chain().link_lengths_m());
        let departure_rad = match proximal {
            Some(_) => 2.0 * largest_rad.max(settings.jump_rad),
            None => 2.0 * largest_rad,
        };
        let mut anchoring = super::anchoring::AnchorRounds::default();
        let mut handed_over = Vec::new();
        // The pairs each round left for the next.
        let mut round_keys: Vec<Vec<PairKey>> = Vec::new();
        // The joint angles the last round's solve reached, where the next round starts
        // from them (see where it is set).
        let mut warm: Option<Vec<f64>> = None;
        for _round in 0..ROUNDS {
            let mut hair_links: Vec<usize> =
                pairs.iter().filter_map(|c| c.key.hair_link()).collect();
            hair_links.sort_unstable();
            hair_links.dedup();
            // The last round's answer where it hands one on (below), else the committed
            // angles.
            let warmed = warm.is_some();
            let beta = self.committed.beta();
            let mut x: Vec<f64> = warm
                .take()
                .unwrap_or_else(|| self.committed.theta()[1..].to_vec());
            // A round that starts afresh starts from the secant predictor.
            if proximal.is_none()
                && !warmed
                && let Some(predicted) = &predicted
            {
                x.copy_from_slice(predicted);
            }
            x.extend(hair_links.iter().map(|&l| beta[l]));
            let prox_x: Vec<f64>;
            let prox = match proximal {
                Some((gamma, x_prev)) => {
                    prox_x = x_prev
                        .iter()
                        .copied()
                        .chain(hair_links.iter().map(|&l| beta[l]))
                        .collect();
                    Some(Proximal {
                        gamma,
                        x_prev: &prox_x,
                    })
                }
                None => None,
            };
            let problem = StepProblem {
                chain: self.world.chain(),
                pieces: &self.world.pieces().walls,
                tip_force_n: self.world.tip_force_n(),
                base_m: goal.base_m,
                base_angle_rad: goal.angle_rad,
                hair_links: &hair_links,
                hair_beta_rad: beta,
                proximal: prox,
                hand_m: self.world.hand_target(goal),
                tolerance_m: settings.tolerance_m,
                // A pseudo-time step of a snap is held to the same residual as a step: a
                // looser one lets the flow creep by stalled solves where a contact sits on
                // the edge of its friction cone, and never come to rest.
                acceptable_m: settings.acceptable_m,
                max_departure_rad: departure_rad,
                max_iterations: if self.quick_attempt {
                    QUICK_ITERATIONS.min(settings.max_iterations)
                } else {
                    settings.max_iterations
                },
                // A snap's step (proximal) keeps its whole budget above the acceptable
                // residual: its flow stops where its solves fail. A quick attempt only
                // asks whether the step sticks again.
                stall_after: match (proximal, self.quick_attempt) {
                    (Some(_), _) => None,
                    (None, true) => Some(QUICK_STALL_ITERATIONS),
                    (None, false) => Some(STALL_ITERATIONS),
                },
            };
            // A bound relaxed by a fixed point of an earlier round does not carry over: this
            // round solves Coulomb's law again (and records its own relaxations).
            for pair in &mut pairs {
                pair.relaxed_bound_n = None;
            }
            let x_start = x.clone();
            let pairs_start = pairs.clone();
            let mut outcome = self.step_solver.solve(&problem, &mut x, &mut pairs);
            report.iterations += outcome.iterations;
            if !outcome.converged && self.quick_attempt {
                return Err(Reject::NoConvergence);
            }
            if !outcome.converged {
                // A solve that failed where something is inside a wall that no pair holds
                // may have failed for want of that pair: the round is solved again from its
                // start with it, as after a solve that converged (the 14.2 cycles/m
                // sinusoid at N = 72: a crest's contact crossing a joint, Newton p99 per
                // step over 20 s 46 -> 25).
                let missed =
                    self.broad_phase
                        .missed_after_failure(inputs, goal, &x, &hair_links, &pairs);
                if !missed.is_empty() {
                    pairs = pairs_start;
                    pairs.extend(missed);
                    report.resolves += 1;
                    // Rounds whose solves fail for want of a pair that the next round's
                    // answer lets go again take turns too (the sinusoid under 150 links:
                    // a crest handed to joints 106 and 107, whose failed solve puts it
                    // inside link 107, whose pair then hands it back; 33,973 -> 32,099
                    // Newton iterations over 20 s).
                    if taking_turns_with(&mut round_keys, &pairs) {
                        return Err(Reject::NoConvergence);
                    }
                    continue;
                }
            }
            if !outcome.converged && !pairs.iter().any(Pair::has_friction) {
                // Without friction the fixed point's Tresca problems are this very problem:
                // it would only solve it again (up to hundreds of iterations per attempt in
                // a frictionless snap, replay `soak:4221:1747`, kept by `soak_sweeps_fixed_since_still_finish`), so the attempt fails here.
                return Err(Reject::NoConvergence);
            }
            // A solve with friction that stalled within the acceptable residual, leaving a
            // pair with a force off its wall by more than the certificate allows (a stall
            // cycling between modes: Coulomb's law), takes the fixed point's answer where
            // the fixed point converges (replay `soak:4221:939`: a tip of 150 links crossing
            // a digitized wall's concave corner with 2 uN, left 1.2 um off it).
            if outcome.converged
                && outcome.residual_m > settings.tolerance_m
                && pairs.iter().any(Pair::has_friction)
            {
                let length_m = self.certifier().tolerances().length_m;
                if pairs
                    .iter()
                    .any(|q| q.force_n().norm() > FORCE_ZERO_N && q.geo.gap_m.abs() > length_m)
                {
                    let stalled = (x.clone(), pairs.clone(), outcome);
                    x.clone_from(&x_start);
                    pairs.clone_from(&pairs_start);
                    let fixed = self
                        .step_solver
                        .solve_by_fixed_point(&problem, &mut x, &mut pairs, report);
                    if fixed.converged {
                        outcome = fixed;
                    } else {
                        (x, pairs, outcome) = stalled;
                    }
                }
            }
            if !outcome.converged {
                // Coulomb's law makes the step's equations non-monotone: solve the Tresca
                // problems of the fixed point instead (`step_solver/tresca.rs`).
                x.clone_from(&x_start);
                pairs.clone_from(&pairs_start);
                outcome = self
                    .step_solver
                    .solve_by_fixed_point(&problem, &mut x, &mut pairs, report);
                if !outcome.converged {
                    return Err(Reject::NoConvergence);
                }
            }
            // Pairs that are no longer what touches (a feature's foot past its link's end)
            // let go, and any point now inside a wall joins: the step is solved again.
            let revision = self.broad_phase.revise(
                inputs,
                goal,
                &x,
                &hair_links,
                &mut pairs,
                &mut handed_over,
            );
            let (mut changed, none_missed) = (revision.changed, revision.none_missed);
            // Hair anchoring on rough surfaces (docs/model.md 7).
            changed |= self.update_anchors(&x, &hair_links, &mut pairs, &mut anchoring);
            if changed {
                // Rounds that take turns between two sets of pairs (a crest's force handed
                // from a link's end to its joint, whose next solve pushes the link into the
                // crest again) do not settle: the attempt fails after two such turns, and the
                // step is refined, as after all its rounds.
                if taking_turns_with(&mut round_keys, &pairs) {
                    return Err(Reject::NoConvergence);
                }
                report.resolves += 1;
                // The next round starts from this round's answer where it only changed
                // which pairs hold the same contacts (a crest's force handed from a link's
                // end to its joint, a pair let go) and is not itself a jump: that answer is
                // next to the next one, and the step's start may be a snap away from it
                // (the 14.2 cycles/m sinusoid under 150 links: 47 -> 38 steps over 40 Newton
                // iterations of 2,000, 17 -> 15 snaps). Where a point was found inside a
                // wall, the answer that put it there is no start (replay `soak:4221:1361`: a swing of
                // the distal links through a corner, 661 -> 18,095 Newton iterations when
                // started from it), nor is one that jumped. A snap's proximal steps start
                // afresh: started there, the flow of CI sample 4's placement took another
                // path to another posture (204 -> 10,582 Newton iterations for the sweep).
                if proximal.is_none() && none_missed && !self.jumps(&x[..n]) {
                    warm = Some(x[..n].to_vec());
                }
                continue;
            }
            if self.jumps(&x[..n]) {
                return Err(Reject::Jump);
            }
            if self.friction_off {
                for pair in &mut pairs {
                    if pair.law.shear_bound(pair.normal_force_n.max(0.0)).0 > 0.0 {
                        pair.relaxed_bound_n = Some(0.0);
                    }
                }
            } else {
                // The jams of the fixed point that gave this answer (not of earlier rounds).
                report.jams += pairs.iter().filter(|p| p.relaxed_bound_n.is_some()).count();
            }
            return Ok(Accepted {
                x,
                hair_links,
                pairs,
                residual_m: outcome.residual_m,
                hand_force_n: outcome.hand_force_n,
            });
        }
        Err(Reject::NoConvergence)
    }
}

#[cfg(test)]
mod tests {
    use super::taking_turns;
    use crate::contact::pair::{ChainPoint, PairKey};
    use crate::walls::ConvexFeature;

    /// Rounds that hand a crest's force from link 102's end to joint 102 and back take
    /// turns (`A B A B`); rounds that change their pairs each time, or keep them, do not.
    #[test]
    fn rounds_take_turns_only_between_two_sets_of_pairs() {
        let link = vec![PairKey::link(102, ConvexFeature::Crest { index: 4 }, 0)];
        let joint = vec![PairKey::point(ChainPoint::Vertex(102), 0)];
        let both = vec![link[0], joint[0]];
        let (a, b) = (link.clone(), joint.clone());
        assert!(taking_turns(&[a.clone(), b.clone(), a.clone(), b.clone()]));
        assert!(taking_turns(&[
            both.clone(),
            a.clone(),
            b.clone(),
            a.clone(),
            b.clone()
        ]));
        assert!(!taking_turns(&[a.clone(), b.clone(), a.clone()]));
        assert!(!taking_turns(&[
            a.clone(),
            b.clone(),
            a.clone(),
            both.clone()
        ]));
        assert!(!taking_turns(&[a.clone(), a.clone(), a.clone(), a.clone()]));
        assert!(!taking_turns(&[b.clone(), a.clone(), both, a.clone(), b]));
    }
}
