//! The semismooth Newton method on a step's equations ([`super::equations`]), with the
//! exact Newton system of [`super::newton_system`].
//!
//! The first Newton step keeps the contacts the last step ended pressed pressed (and a
//! stuck one stuck): read at the start, the last posture carried with the base lifts them
//! off their walls by the base's displacement. A sliding one's mode is read at the start (a
//! contact that may stick or slide takes the branch its first step points to, and a kept
//! slide would carry a tip off a corner where friction holds it). Convergence is always
//! judged with the modes read at the point.
//!
//! Globalization: a non-monotone backtracking line search on `|Phi|^2 / 2` (Grippo,
//! Lampariello and Lucidi: a step is accepted against the largest merit of the last few
//! iterations, so that the modes can settle where a constraint is degenerate), a cap on the
//! change of any coordinate per iteration, and Levenberg-Marquardt damping of the Newton
//! matrix, raised when no step is accepted and lowered again after successes (it changes
//! the path, never the solution: `Phi` itself is never regularized). A plain solve whose
//! best merit stops halving (two wrong mode sets taking turns, which the non-monotone
//! search allows, or steps shrunk to nothing) stops after a few iterations at its best
//! point instead of spending its budget. A solve that stalls within a micrometre of an
//! answer (but above the acceptable residual: one within it is accepted as it stands, and
//! reported) tries the other mode of each joint on a stop, each pressed contact and each
//! sliding one in turn ([`Ssn::repair`]): a wrong mode there makes the Newton matrix
//! singular. A solve that does not converge is reported; the caller refines the step.

use super::equations::{Equations, Forced, StepProblem, bound_of};
use super::newton_system::NewtonSystem;
use crate::contact::feature::Slip;
use crate::contact::pair::Pair;
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
    /// Whether the answer came from a repair of a stalled solve ([`Ssn::repair`]): the
    /// same equations, solved on other modes.
    pub repaired: bool,
}

/// The solver's scratch space, reused from step to step.
#[derive(Debug, Default)]
pub(super) struct Ssn {
    pub(super) eq: Equations,
    pub(super) system: NewtonSystem,
    dz: Vec<f64>,
    z_prev: Vec<f64>,
    trial: Vec<Pair>,
    z_best: Vec<f64>,
    pairs_best: Vec<Pair>,
    /// The part whose other mode settled the last repaired solve, tried first by the next
    /// repair ([`Ssn::repair`]).
    last_repair: Option<RepairedPart>,
    /// Parts of repairs, counted over the solver's life, whose other mode converged to an
    /// answer that mode does not keep (a contact stuck beyond its friction cone, or one
    /// whose plain modes, from where it was let go or stuck, do not converge): a substep
    /// that fails while adding to it found no equilibrium in reach of its start in any mode
    /// set its repairs tried ([`Ssn::refused_repairs`]).
    refused_repairs: usize,
}

/// A part of the equations a repair gave its other mode, named so that the next solve (with
/// its own pair indices) can find it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum RepairedPart {
    Free(usize),
    LetGo(crate::contact::pair::PairKey),
    Stuck(crate::contact::pair::PairKey),
}

impl RepairedPart {
    fn of(part: Forced, pairs: &[Pair]) -> RepairedPart {
        match part {
            Forced::Free(a) => RepairedPart::Free(a),
            Forced::LetGo(k) => RepairedPart::LetGo(pairs[k].key),
            Forced::Stuck(k) => RepairedPart::Stuck(pairs[k].key),
        }
    }
}

/// How many past merits the non-monotone line search compares against.
const NONMONOTONE_MEMORY: usize = 6;

/// A plain solve whose best merit has not halved for this many iterations has stalled (it
/// cycles between modes, or creeps at tiny steps) and stops at its best point (until
/// 2026-11, only above the acceptable residual). Chosen by the stress soak (seed 4221,
/// 2,000 sweeps): 14 finished 1,872 with a Newton p99 of 44 per step; 12 finished 1,869
/// (p99 39), 24 1,862 (p99 61), and no stop (the whole budget of 60) 1,847-1,854 (p99
/// 116); with the repair trying sliding contacts stuck, 14 finished 1,871 (p99 41;
/// BENCHMARKS.md, "Contact stress soak"). Over the CI sample, 230 of some 26,000 plain
/// solves converged after such a stall of 12 or more iterations, and 3,835 did not converge
/// at all.
pub(crate) const STALL_ITERATIONS: usize = 14;

/// A plain solve whose last this many accepted steps were all along a Newton step so large
/// that the cap on a coordinate's change ([`MAX_CHANGE_RAD`]) cut it to at most
/// [`CREEP_STEP`] of itself, with no halving of its best merit over them, creeps along a
/// direction of a nearly singular Newton matrix (a stuck tip whose slip the joints can
/// barely move, 150 links, replay `soak:4221:1102`, where the step would change the joint angles by
/// some 2,000 rad) and stops there at its best point, as a stall. Counting any step the
/// line search shrank that far instead stopped solves that creep towards a repairable
/// stall (`a_stall_between_two_walls_one_joint_cannot_both_touch_is_repaired`) and a tip
/// pushed onto a wedge's apex, where friction holds it, short of sticking there
/// (`a_tip_pushed_onto_a_convex_corner_slips_off_it_unless_friction_holds_it`).
const CREEP_ITERATIONS: usize = 4;

/// The fraction of its Newton step at or below which the cap cuts a step to count it as
/// huge.
const CREEP_STEP: f64 = 1e-3;

/// How far (relative) a repaired stuck contact's shear force may exceed its bound `mu N`
/// and still count as inside its cone (rounding; the certificate's own tolerance is
/// looser).
const CONE_SLACK: f64 = 1e-9;

/// The factor by which the best merit must fall to count as progress.
const STALL_FACTOR: f64 = 0.5;

/// The largest change of a coordinate in one iteration, radians.
const MAX_CHANGE_RAD: f64 = 0.25;

/// A stalled solve whose residual is at most this, metres, tries the other modes of its
/// degenerate parts ([`Ssn::repair`]).
const REPAIR_BELOW_M: f64 = 1e-6;

/// Newton iterations of each repair.
const REPAIR_ITERATIONS: usize = 20;

/// Newton iterations a repair spends in all before it gives up (the caller then falls back
/// to the fixed point or refines the step): a chain lying along a wall has a part to try
/// for each of its contacts, some 14 iterations each (150 links, replay `soak:4221:988`: 172 parts, 2,463
/// iterations, none settling it; the fixed point then took 20). A snap's proximal step is
/// held to it too: one that fails had tried every part, up to some 600 Newton iterations
/// a failure (150 links with hairs along a line wall with mu = 1, replay `soak:4221:375`: its flows
/// 21,790 -> 20,668 Newton iterations for the sweep, 7.4 s -> 6.2 s alone; the CI sample
/// 37,034 -> 36,946). Tried at 40d476c, the same budget failed the snap of replay `soak:4221:138` ("did not
/// come to rest"); since a substep at a fold snaps without halving to the end
/// (`QuasiStatic::advance`), the soak finishes every sweep with it.
const REPAIR_BUDGET: usize = 100;

/// A repair tries the sliding contacts stuck before letting any go where at most this many
/// slide ([`Ssn::repair`]): a few contacts on a link flat on a wall, not a whole chain
/// lying along it (replay `soak:4221:1371`: 56 sliding contacts, each tried stuck first, took twice the
/// Newton iterations of letting the contacts go first). 2 gave a Newton p99 of 24 and 96
/// at 72 and 150 links over the soak; 4 and 8 gave 22 and 93.
const FEW_SLIDING: usize = 4;

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

impl SsnOutcome {
    /// A solve not made (or that did not converge), with nothing spent.
    pub fn not_converged() -> SsnOutcome {
        SsnOutcome {
            converged: false,
            iterations: 0,
            residual_m: f64::INFINITY,
            hand_force_n: Vector2::zeros(),
            repaired: false,
        }
    }
}

impl Ssn {
    /// Solves the step: `x` (the coordinates) and the pairs' forces are the start and
    /// receive the answer (the best point reached if it did not converge).
    pub fn solve(&mut self, p: &StepProblem<'_>, x: &mut [f64], pairs: &mut [Pair]) -> SsnOutcome {
        self.eq.prepare(p);
        self.eq.load(x, pairs);
        self.eq.forced = None;
        // The first Newton step keeps the pairs pressed in the last step pressed: the last
        // posture carried with the base lifts a pressed contact off its wall by the base's
        // displacement, and the mode read there would let it go for one step, a step a
        // soft antenna's free posture makes huge (the line search then takes it in
        // slivers, and the modes take turns). Likewise an unloaded pair the carried
        // posture pushes slightly into its wall stays let go for that step.
        self.eq.keep_last_modes = true;
        // `descend` reads the residual at the start.
        let mut outcome = SsnOutcome::not_converged();
        self.descend(p, x, pairs, p.max_iterations, &mut outcome);
        // A solve stalled within the acceptable residual is accepted (and reported) as it
        // stands: a repair there seldom reached the tolerance (over the soak's 150-link
        // sweeps, 340 of 736 such repairs, at some 70 Newton iterations each).
        if outcome.residual_m > p.tolerance_m.max(p.acceptable_m)
            && outcome.residual_m <= REPAIR_BELOW_M
        {
            self.repair(p, x, pairs, &mut outcome);
        }
        // A solve that stalls at a degenerate point (a contact touching with N = 0 and
        // gap = 0: the modes trade places and Newton's method stops improving) is accepted
        // within the acceptable residual.
        outcome.converged = outcome.residual_m <= p.tolerance_m.max(p.acceptable_m);
        let m = x.len();
        x.copy_from_slice(&self.eq.z[..m]);
        outcome.hand_force_n = self.eq.hand_force_n;
        outcome
    }

    /// A stalled solve near an answer: the modes of its degenerate parts may be wrong. A
    /// joint held on its stop that should leave it, or a contact pressed where it should
    /// let go, makes the active piece's equations singular (more touching contacts than
    /// free joints can satisfy: a link across two nearly collinear vertices of a digitized
    /// wall, two joints on one edge with the joint between them on its stop) and Newton's
    /// method stalls at their least-squares compromise, nanometres inside the wall. A
    /// contact sliding at the edge of its friction cone with next to no slip may be one of
    /// two on a link lying flat on a wall, whose slips are the same and whose shear forces
    /// are determined only summed: they take opposite slide modes, and each mode set's
    /// Newton step leads into the other. Each such part in turn is given the other mode
    /// (the sliding contact stuck, the contact let go, the joint free) and the piece
    /// solved; an answer is kept only where the modes it settles in are its own (the plain
    /// equations hold there to the tolerance). Otherwise the stalled point stands.
    ///
    /// The order is by measurement. Over the stress soak (seed 4221, all 2,000 sweeps) a
    /// repair was tried some 38,000 times; a freed joint settled 75 of them in 31,000
    /// tries, a let-go contact 6,200 in 79,000, a stuck one 1,000 in 26,000. Joints, tried
    /// first until then, now come last; a few sliding contacts ([`FEW_SLIDING`]) stuck
    /// come first: over the soak's sweeps of 72 and 150 links, that gave a Newton p99 per
    /// step of 22 and 93 (joints first: 58 and 137; contacts let go before stuck: 28 and
    /// 105).
    fn repair(
        &mut self,
        p: &StepProblem<'_>,
        x_start: &[f64],
        pairs: &mut [Pair],
        outcome: &mut SsnOutcome,
    ) {
        let m = x_start.len();
        let c = pairs.len();
        // The pressed contacts that slide with friction: sliding at the edge of the cone
        // with next to no slip, a pair of contacts on one link flat on a wall can take
        // opposite slide modes (their slips are the same, their shear forces only summed
        // are determined), and each mode set's Newton step leads into the other.
        let stuck: Vec<Forced> = (0..c)
            .filter(|&k| {
                pairs[k].normal_active
                    && pairs[k].slip != Slip::Stuck
                    && bound_of(&pairs[k]).0 > 0.0
            })
            .map(Forced::Stuck)
            .collect();
        // The pressed contacts, those with the least normal force first (the likeliest to
        // let go).
        let mut pressed: Vec<usize> = (0..c)
            .filter(|&k| pairs[k].normal_active && pairs[k].law.min_normal_n() == 0.0)
            .collect();
        pressed.sort_by(|&a, &b| {
            pairs[a]
                .normal_force_n
                .abs()
                .total_cmp(&pairs[b].normal_force_n.abs())
        });
        // The ends of each piece's run of pressed contacts first (stably, so by force among
        // themselves): a chain lying along a wall lifts off at the ends of its run (soak
        // 1371, 72 links: the tip let go settled the stall as the 54th part of 113, after
        // some 850 Newton iterations; it is now among the first).
        let along = |k: usize| pairs[k].geo.link as f64 + pairs[k].geo.s;
        let mut runs: Vec<(usize, f64, f64)> = Vec::new();
        for &k in &pressed {
            let piece = pairs[k].key.piece;
            match runs.iter_mut().find(|r| r.0 == piece) {
                Some(run) => {
                    run.1 = run.1.min(along(k));
                    run.2 = run.2.max(along(k));
                }
                None => runs.push((piece, along(k), along(k))),
            }
        }
        pressed.sort_by_key(|&k| {
            !runs
                .iter()
                .any(|r| r.0 == pairs[k].key.piece && (along(k) == r.1 || along(k) == r.2))
        });
        let let_go = pressed.into_iter().map(Forced::LetGo);
        let mut parts: Vec<Forced> = Vec::new();
        if stuck.len() <= FEW_SLIDING {
            parts.extend(stuck);
            parts.extend(let_go);
        } else {
            parts.extend(let_go);
            parts.extend(stuck);
        }
        parts.extend(
            (0..m)
                .filter(|&a| self.eq.held[a].is_some())
                .map(Forced::Free),
        );
        if parts.is_empty() {
            return;
        }
        // The part that settled the last repair first: the next step's stall is most often
        // the same one (150 links on a digitized trapezoid, replay `soak:4221:426`: the last of three
        // sliding contacts stuck, step after step, after 35 iterations on the other two).
        if let Some(last) = self.last_repair
            && let Some(i) = parts
                .iter()
                .position(|&q| RepairedPart::of(q, pairs) == last)
        {
            parts[..=i].rotate_right(1);
        }
        // The row with the largest residual may be a part that none of the above holds: a
        // hair tip let go whose normal force the stall left nonzero (touching with next to
        // no force, its normal row taking turns between pressed and let go). Its letting
        // go is tried first (150 links with distal hairs on a digitized line, replay `soak:4221:1911`:
        // 43,108 -> 29,897 Newton iterations). Only for hair tips: for any pair it cost the
        // CI sample 49,972 -> 51,003 and the 150-link 4.2.1 sweep (no hairs) a p99 of 58
        // -> 80; and moved ahead of the parts above as well, the CI sample 51,952.
        if let Some(worst) = self.worst_row_part(pairs)
            && !parts.contains(&worst)
        {
            parts.insert(0, worst);
        }
        let z_stalled = self.eq.z.clone();
        let pairs_stalled = pairs.to_vec();
        let residual_stalled = outcome.residual_m;
        let spent_before = outcome.iterations;
        for part in parts {
            if outcome.iterations - spent_before >= REPAIR_BUDGET {
                break;
            }
            self.eq.z.clone_from(&z_stalled);
            pairs.copy_from_slice(&pairs_stalled);
            if let Forced::LetGo(k) = part {
                self.eq.z[m + k] = 0.0;
                self.eq.z[m + c + k] = 0.0;
            }
            self.eq.forced = Some(part);
            self.descend(p, x_start, pairs, REPAIR_ITERATIONS, outcome);
            self.eq.forced = None;
            if outcome.residual_m.is_nan() || outcome.residual_m > p.tolerance_m {
                continue;
            }
            // A contact stuck by force whose shear force lies outside its cone is no answer
            // of Coulomb's law: the plain modes would slide it again, back to the stall, so
            // the plain solve from there is not tried (the 150-link 4.2.1 sweep's contact
            // rolling to the next joint: a stuck answer needing 103% of `mu N`, then 20
            // iterations of the plain solve to fail; its worst step 73 -> 58 Newton
            // iterations, the CI sample 49,972 -> 49,430).
            if let Forced::Stuck(k) = part
                && self.eq.z[m + c + k].abs() > bound_of(&pairs[k]).0 * (1.0 + CONE_SLACK)
            {
                self.refused_repairs += 1;
                continue;
            }
            // The plain modes at the repaired answer: converged there, or a few more
            // iterations from it.
            self.descend(p, x_start, pairs, REPAIR_ITERATIONS, outcome);
            if outcome.residual_m <= p.tolerance_m {
                outcome.repaired = true;
                self.last_repair = Some(RepairedPart::of(part, &pairs_stalled));
                return;
            }
            self.refused_repairs += 1;
        }
        self.eq.z.clone_from(&z_stalled);
        pairs.copy_from_slice(&pairs_stalled);
        self.eq.evaluate(p, pairs);
        outcome.residual_m = residual_stalled;
    }

    /// How many parts of repairs so far converged in their other mode to an answer that
    /// mode does not keep (see the field): compared before and after a substep's attempt,
    /// it tells a step that ends at a fold of its branch of equilibria from one that only
    /// went too far.
    pub fn refused_repairs(&self) -> usize {
        self.refused_repairs
    }

    /// Linear solves, over the solver's life, that fell back to the dense factorization.
    pub fn dense_solves(&self) -> usize {
        self.system.dense_solves
    }

    /// The part a repair can force on the row of `Phi` with the largest magnitude: its
    /// coordinate freed (if held), its hair tip's pair let go (a hair tip's normal row), or
    /// stuck (the shear row of a pressed contact sliding with friction). `None` for a free
    /// coordinate's row, another pair's normal row, or a shear row that sticking cannot
    /// change.
    fn worst_row_part(&self, pairs: &[Pair]) -> Option<Forced> {
        let m = self.eq.m();
        let c = pairs.len();
        let mut worst = None;
        let mut largest = -1.0_f64;
        for (i, v) in self.eq.phi.iter().enumerate() {
            if v.abs() > largest {
                largest = v.abs();
                worst = Some(i);
            }
        }
        let i = worst?;
        if i < m {
            self.eq.held[i].is_some().then_some(Forced::Free(i))
        } else if i < m + c {
            let k = i - m;
            pairs.get(k)?.key.hair_link().map(|_| Forced::LetGo(k))
        } else {
            let k = i - m - c;
            let pair = pairs.get(k)?;
            (pair.normal_active && pair.slip != Slip::Stuck && bound_of(pair).0 > 0.0)
                .then_some(Forced::Stuck(k))
        }
    }

    /// Newton iterations from the current `z` until the residual is within the tolerance,
    /// `budget` iterations are spent, no step is accepted at the largest damping, or the
    /// joint angles wander past the departure limit from `x_start`.
    fn descend(
        &mut self,
        p: &StepProblem<'_>,
        x_start: &[f64],
        pairs: &mut [Pair],
        budget: usize,
        outcome: &mut SsnOutcome,
    ) {
        let m = x_start.len();
        let n = p.chain.n();
        let mut merit = self.eq.evaluate(p, pairs);
        if self.eq.keep_last_modes {
            self.eq.keep_last_modes = false;
            if self.eq.residual_m() <= p.tolerance_m {
                // Converged only with the kept modes: judged with its own.
                merit = self.eq.evaluate(p, pairs);
            }
        }
        outcome.residual_m = self.eq.residual_m();
        let mut damping = 0.0_f64;
        let mut recent = [merit; NONMONOTONE_MEMORY];
        let mut spent = 0;
        // The best point so far (by merit) and the iteration at which the best merit last
        // halved. A plain solve that stops making progress is cycling between modes (the
        // non-monotone search lets it take turns between two wrong mode sets) or creeping
        // at tiny steps: it stops there, at its best point, rather than spend its budget
        // (the caller falls back to the fixed point or refines the step). A problem without
        // `stall_after` (a snap's step) keeps its whole budget above the acceptable residual
        // (within it, it stops where it stands: below).
        let mut best_merit = if merit.is_finite() {
            merit
        } else {
            f64::INFINITY
        };
        let mut progress_at = 0_usize;
        let mut stalled = false;
        // Accepted steps in a row along a huge Newton step (see [`CREEP_ITERATIONS`]).
        let mut creeping = 0_usize;
        // The stop fires below the acceptable residual too: a solve creeping there between
        // mode sets at a degenerate point (a contact touching with no force) would spend
        // its whole budget to end where it stood (150 links, replay `soak:4221:545`: 60 iterations per
        // step at 1e-11 m).
        let can_stall = p.stall_after.is_some();
        if can_stall {
            self.z_best.clone_from(&self.eq.z);
            self.pairs_best.clear();
            self.pairs_best.extend_from_slice(pairs);
        }
        while (outcome.residual_m > p.tolerance_m || outcome.residual_m.is_nan()) && spent < budget
        {
            let since_progress = spent - progress_at;
            if let Some(stall_after) = p.stall_after
                && (since_progress >= stall_after
                    || (creeping >= CREEP_ITERATIONS && since_progress >= CREEP_ITERATIONS))
            {
                stalled = true;
                break;
            }
            // A snap's step stalled within the acceptable residual is accepted there rather
            // than spend its budget to end where it stands (replay `soak:4221:73`: a placement settling
            // with friction took 100,199 Newton iterations over 324 pseudo-time steps, many
            // of their solves 60 iterations at an acceptable residual).
            if !can_stall
                && since_progress >= STALL_ITERATIONS
                && outcome.residual_m <= p.acceptable_m
            {
                break;
            }
            let reference = recent.iter().copied().fold(merit, f64::max);
            outcome.iterations += 1;
            spent += 1;
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
            let huge = alpha <= CREEP_STEP;
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
                    creeping = if huge { creeping + 1 } else { 0 };
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
            if merit < best_merit {
                if merit <= STALL_FACTOR * best_merit {
                    progress_at = spent;
                }
                best_merit = merit;
                if can_stall {
                    self.z_best.clone_from(&self.eq.z);
                    self.pairs_best.clear();
                    self.pairs_best.extend_from_slice(pairs);
                }
            }
            if (0..n).any(|a| (self.eq.z[a] - x_start[a]).abs() > p.max_departure_rad) {
                break;
            }
        }
        // A stalled solve returns its best point (the non-monotone search may have left it).
        if stalled && (best_merit < merit || merit.is_nan()) {
            self.eq.z.clone_from(&self.z_best);
            pairs.copy_from_slice(&self.pairs_best);
            self.eq.evaluate(p, pairs);
            outcome.residual_m = self.eq.residual_m();
        }
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

#[cfg(test)]
mod tests {
    //! The repair of a stalled solve, on a problem whose wrong modes make the Newton
    //! system singular.
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::contact::feature::FrictionLaw;
    use crate::contact::pair::{ChainPoint, PairKey};
    use crate::{Chain, Line, SolidSide, Surface, SurfaceMap, Wall};

    /// A plain step (no proximal term, the stall stop on) of `chain` against `pieces` with the
    /// default tolerances, its base at the origin and no hairs.
    fn plain_problem<'a>(chain: &'a Chain, pieces: &'a [Wall]) -> StepProblem<'a> {
        StepProblem {
            chain,
            pieces,
            tip_force_n: Vector2::zeros(),
            base_m: Vector2::zeros(),
            base_angle_rad: chain.base_angle_rad(),
            hair_links: &[],
            hair_beta_rad: &[0.0, 0.0],
            proximal: None,
            hand_m: None,
            tolerance_m: 1e-12,
            acceptable_m: 1e-9,
            max_departure_rad: 1.0,
            max_iterations: 60,
            stall_after: Some(STALL_ITERATIONS),
        }
    }

    /// The row with the largest residual names the part a repair tries first when no other
    /// part holds it: a hair tip let go whose normal force is not zero (touching with next
    /// to no force, as in replay `soak:4221:1911`) is let go; another pair, or a free joint, names none.
    #[test]
    fn the_worst_row_of_a_let_go_pair_with_a_force_is_its_letting_go() {
        let length_m = 0.05;
        let chain = Chain::builder(1)
            .link_length_m(length_m)
            .stiffness_nm_per_rad(0.01)
            .build()
            .unwrap();
        let tip = Vector2::new(2.0 * length_m, 0.0);
        let surface = || SurfaceMap::uniform(Surface::Smooth { mu: 0.0 }).unwrap();
        // Two walls clear of the tip, beyond it.
        let pieces: Vec<Wall> = [1e-3, 2e-3]
            .iter()
            .map(|d| {
                Wall::new(
                    Line::new(tip + Vector2::new(0.0, *d), 0.0, SolidSide::Left).unwrap(),
                    surface(),
                )
            })
            .collect();
        let law = FrictionLaw::Coulomb { mu: 0.0 };
        let mut pairs: Vec<Pair> = (0..2)
            .map(|piece| {
                Pair::new(
                    PairKey::point(ChainPoint::Vertex(1), piece),
                    law,
                    1,
                    1.0,
                    tip,
                )
            })
            .collect();
        // Pair 1 let go with a pull left on it, pair 0 let go with none.
        pairs[1].normal_force_n = -0.02;
        let problem = plain_problem(&chain, &pieces);
        let mut ssn = Ssn::default();
        ssn.eq.prepare(&problem);
        ssn.eq.load(&[0.0], &pairs);
        ssn.eq.evaluate(&problem, &mut pairs);
        assert!(!pairs[1].normal_active);
        // A chain point's pair: not a part of its own (the repair's order stands).
        assert_eq!(ssn.worst_row_part(&pairs), None);
        // A hair tip's pair with the same rows: its letting go.
        pairs[1].key = PairKey::point(ChainPoint::HairTip(1), 1);
        assert_eq!(ssn.worst_row_part(&pairs), Some(Forced::LetGo(1)));
        // A joint held on its stop whose row is the largest: freed.
        ssn.eq.phi.iter_mut().for_each(|v| *v = 0.0);
        ssn.eq.phi[0] = 1.0;
        ssn.eq.held[0] = Some(0.0);
        assert_eq!(ssn.worst_row_part(&pairs), Some(Forced::Free(0)));
        ssn.eq.held[0] = None;
        assert_eq!(ssn.worst_row_part(&pairs), None);
    }

    /// One flexible joint, its tip pressed by wall A to `theta*` and wall B `delta`
    /// behind the tip there (tilted, not touching): started with both pressing, the two
    /// gap rows depend on the one angle alone and cannot both vanish. Newton's method
    /// stalls at their compromise, a fraction of `delta` inside B; the repair lets B go
    /// and finds the equilibrium on A alone, which the plain equations accept.
    #[test]
    fn a_stall_between_two_walls_one_joint_cannot_both_touch_is_repaired() {
        let length_m = 0.05;
        let k = 0.01;
        let chain = Chain::builder(1)
            .link_length_m(length_m)
            .stiffness_nm_per_rad(k)
            .build()
            .unwrap();
        let theta_star = 0.5_f64;
        let along = Vector2::new(theta_star.cos(), theta_star.sin());
        let tip = Vector2::new(length_m, 0.0) + along * length_m;
        // The tip's direction of motion as theta grows.
        let ahead = Vector2::new(-along.y, along.x);
        let surface = || SurfaceMap::uniform(Surface::Smooth { mu: 0.0 }).unwrap();
        let delta_m = 1e-7;
        let pieces = vec![
            Wall::new(
                Line::new(tip, theta_star, SolidSide::Right).unwrap(),
                surface(),
            ),
            Wall::new(
                Line::new(tip - ahead * delta_m, theta_star + 0.3, SolidSide::Right).unwrap(),
                surface(),
            ),
        ];
        let law = FrictionLaw::Coulomb { mu: 0.0 };
        let force_n = k * theta_star / length_m;
        let mut pairs: Vec<Pair> = (0..2)
            .map(|piece| {
                let key = PairKey::point(ChainPoint::Vertex(1), piece);
                let mut pair = Pair::new(key, law, 1, 1.0, tip);
                pair.normal_force_n = 0.5 * force_n;
                pair.normal_active = true;
                pair
            })
            .collect();
        let problem = plain_problem(&chain, &pieces);
        let mut x = vec![theta_star];
        let mut ssn = Ssn::default();
        let pairs_start = pairs.clone();
        let outcome = ssn.solve(&problem, &mut x, &mut pairs);
        assert!(outcome.converged, "{outcome:?}");
        assert!(
            outcome.repaired,
            "the plain solve did not stall: {outcome:?}"
        );
        assert!(outcome.residual_m <= 1e-12, "{outcome:?}");
        assert!(
            (x[0] - theta_star).abs() < 1e-9,
            "theta {} vs {theta_star}",
            x[0]
        );
        // A carries the spring's torque; B is let go, clear of the tip, and the next repair
        // tries letting B go first.
        assert_eq!(ssn.last_repair, Some(RepairedPart::LetGo(pairs[1].key)));
        assert!(pairs[0].normal_active);
        assert!((pairs[0].normal_force_n - force_n).abs() < 1e-9 * force_n.max(1.0));
        assert!(!pairs[1].normal_active);
        assert_eq!(pairs[1].normal_force_n, 0.0);
        assert!(
            pairs[1].geo.gap_m > 0.5 * delta_m,
            "gap {}",
            pairs[1].geo.gap_m
        );
        // The plain solve takes turns at the compromise: stopped once its best merit no
        // longer halves, it reaches the same answer by the repair in half the iterations of
        // a solve that spends its whole budget there (40 against 81).
        let patient = StepProblem {
            stall_after: None,
            ..problem
        };
        let mut x_patient = vec![theta_star];
        let mut pairs_patient = pairs_start;
        let slow = Ssn::default().solve(&patient, &mut x_patient, &mut pairs_patient);
        assert!(slow.converged && slow.repaired, "{slow:?}");
        assert!((x_patient[0] - x[0]).abs() < 1e-12);
        assert!(
            outcome.iterations + 20 < slow.iterations,
            "stopped at a stall: {} iterations, patient: {}",
            outcome.iterations,
            slow.iterations
        );
    }
}
