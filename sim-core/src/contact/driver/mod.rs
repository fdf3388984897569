//! The quasi-static state of a chain among walls, and the stepping of its base: substeps
//! where a step fails or jumps, snaps followed downhill ([`super::snap`]), each (sub)step
//! solved by [`super::substep`].

use nalgebra::Vector2;

use super::ContactError;
use super::broad_phase::BroadPhase;
use super::certifier::{Certifier, CertifyTolerances, EquilibriumCheck};
use super::committed::Committed;
use super::feature::Contact;
use super::posture::Pose;
use super::report::StepReport;
use super::settings::ContactSettings;
use super::step_solver::StepSolver;
use super::world::World;
use crate::{Chain, Wall};

mod anchoring;
mod jam;
mod snap;
mod stability;
mod substep;
#[cfg(test)]
mod turn_tests;

pub use jam::{Jam, JammedContact};
pub(super) use substep::Accepted;

/// A chain moving quasi-statically against walls with friction and hairs (docs/model.md 6-7).
///
/// The state carries from step to step: joint and hair angles, and every contact with its
/// forces and friction state (anchored hairs stay anchored). See the
/// [module documentation](super) for the method.
///
/// It is the driver of four stages, each owning its state (private to its module): the
/// world (chain, walls, loads, settings), the committed state, the broad phase (its
/// postures) and the step solver (its scratch space and repair memory); the certifier keeps
/// none (see [the stages](super#the-stages)). The driver owns only what steering the steps
/// needs (the secant, friction dropped or locked, anchoring blocked) and passes values
/// between the stages.
#[derive(Debug)]
pub struct QuasiStatic {
    world: World,
    committed: Committed,
    broad_phase: BroadPhase,
    step_solver: StepSolver,
    /// No hair anchors during the rest of this step (set after anchors were torn out).
    anchoring_blocked: bool,
    /// The last plain (sub)step's base displacement, turn and change of the joint angles.
    secant: Option<Secant>,
    /// Friction is off for the rest of this step (see [`StepReport::friction_dropped`]).
    friction_off: bool,
    /// Friction was dropped in the last step.
    friction_locked: bool,
    /// One solve only: no fixed point on the normal forces where it fails.
    quick_attempt: bool,
}

/// How many times a step that fails its check is halved before it is refused.
const CERTIFY_SPLITS: usize = 3;

/// Failed substeps in a row whose repairs found other modes converging only to answers
/// those modes refuse ([`StepSolver::refused_repairs`]), after which a substep is not
/// halved again but followed downhill as a snap (see [`QuasiStatic::advance`]).
const FOLD_FAILURES: usize = 2;

/// The last plain (sub)step's change: the base's displacement and turn, and the change of
/// the joint angles `theta_1..theta_n` (the secant predictor, [`QuasiStatic::secant_prediction`]).
#[derive(Clone, Debug)]
struct Secant {
    delta_m: Vector2<f64>,
    turn_rad: f64,
    dtheta_rad: Vec<f64>,
}

/// The state a step changes ([`QuasiStatic::step_to_pose`] takes a refused step again from
/// it).
struct SavedState {
    committed: Committed,
    secant: Option<Secant>,
    friction_locked: bool,
    anchoring_blocked: bool,
}

impl QuasiStatic {
    /// A chain at `theta_rad` (`n + 1` entries, `theta_0` the base angle) with its base pivot
    /// at `base_m`, among `walls`. Hairs start open (at [`crate::Hair::rest_angle_rad`]). No contact forces act yet: call
    /// [`Self::settle`] to let a posture touching a wall come to rest.
    ///
    /// The walls are kept without the polyline vertices that lie within the penetration
    /// tolerance of the chord replacing them ([`crate::Polyline::without_flat_vertices`]):
    /// such a vertex is not a corner. A wall scanned or digitized finely, its points
    /// rounded, has turns of `1e-13..1e-12` rad between collinear points, which tested
    /// against 0 made hundreds of spurious corners (contacts, snaps, and a sweep that
    /// depended on how finely the wall was sampled). Dropping them moves the wall by at most
    /// the penetration tolerance; contacts are reported, and every step certified, against
    /// these walls ([`Self::walls`]), the vertices kept and their arclengths the given
    /// walls'.
    ///
    /// # Errors
    /// [`ContactError::WrongLength`], [`ContactError::NotFinite`],
    /// [`ContactError::OutsideLimits`], [`ContactError::BadSetting`], and
    /// [`ContactError::BaseInsideWall`] or [`ContactError::StartInsideWall`] if the posture
    /// is inside a wall by more than the penetration tolerance.
    pub fn new(
        chain: Chain,
        walls: Vec<Wall>,
        base_m: Vector2<f64>,
        theta_rad: &[f64],
        settings: ContactSettings,
    ) -> Result<QuasiStatic, ContactError> {
        settings.validate()?;
        if theta_rad.len() != chain.dof() {
            return Err(ContactError::WrongLength {
                argument: "theta_rad",
                expected: chain.dof(),
                actual: theta_rad.len(),
            });
        }
        finite("base_m", &[base_m.x, base_m.y])?;
        finite("theta_rad", theta_rad)?;
        for (j, (&t, lim)) in theta_rad
            .iter()
            .zip(chain.joint_limits())
            .enumerate()
            .skip(1)
        {
            if !lim.contains(t) {
                return Err(ContactError::OutsideLimits {
                    joint: j,
                    angle_rad: t,
                    cw_rad: lim.cw_rad,
                    ccw_rad: lim.ccw_rad,
                });
            }
        }
        let mut theta = theta_rad.to_vec();
        theta[0] = chain.base_angle_rad();
        let beta: Vec<f64> = chain
            .hairs()
            .iter()
            .map(|h| h.map_or(0.0, |h| h.rest_angle_rad()))
            .collect();
        let mut sim = QuasiStatic {
            world: World::new(chain, &walls, settings),
            committed: Committed::new(base_m, theta, beta),
            broad_phase: BroadPhase::default(),
            step_solver: StepSolver::default(),
            anchoring_blocked: false,
            secant: None,
            friction_off: false,
            friction_locked: false,
            quick_attempt: false,
        };
        sim.broad_phase.check_start(&sim.world, &sim.committed)?;
        Ok(sim)
    }

    /// A dead load at the tip (ground frame, newtons) from now on.
    pub fn set_tip_force_n(&mut self, tip_force_n: Vector2<f64>) {
        self.world.set_tip_force_n(tip_force_n);
    }

    /// The dead load at the tip, newtons.
    pub fn tip_force_n(&self) -> Vector2<f64> {
        self.world.tip_force_n()
    }

    /// Holds the tip near `offset_m` from the base pivot (a hand moving and turning with the
    /// base, for placing the antenna: the offset is in the ground frame at the current base
    /// angle, and turns about the pivot as the base turns) by a stiff spring, or lets go
    /// (`None`). While held, [`Self::hand_force_n`] is the hand's force on the tip.
    pub fn hold_tip(&mut self, offset_m: Option<Vector2<f64>>) {
        self.world.hold_tip(offset_m, self.committed.theta()[0]);
        if offset_m.is_none() {
            self.committed.let_go_of_tip();
        }
    }

    /// The force of the hand on the tip after the last step, newtons.
    pub fn hand_force_n(&self) -> Vector2<f64> {
        self.committed.hand_force_n()
    }

    /// The chain; its base angle ([`Chain::base_angle_rad`]) is the current one,
    /// `theta_rad()[0]`.
    pub fn chain(&self) -> &Chain {
        self.world.chain()
    }

    /// The walls, without their flat vertices (see [`Self::new`]).
    pub fn walls(&self) -> &[Wall] {
        self.world.walls()
    }

    /// The base pivot, ground frame, metres.
    pub fn base_m(&self) -> Vector2<f64> {
        self.committed.base_m()
    }

    /// The base link's angle `theta_0` from the ground x-axis, radians (`theta_rad()[0]`).
    pub fn base_angle_rad(&self) -> f64 {
        self.committed.theta()[0]
    }

    /// The farthest a point of the chain can be from the base pivot, metres: the sum of the
    /// link lengths and the longest reach of a hair past its link. A turn of the base by
    /// `a` radians moves no point by more than `reach_m() * a`, and
    /// [`Self::step_to_pose`] measures a step by `max(|d base|, reach_m() |d angle|)`.
    pub fn reach_m(&self) -> f64 {
        self.world.reach_m()
    }

    /// The joint angles `theta_0..theta_n`, radians.
    pub fn theta_rad(&self) -> &[f64] {
        self.committed.theta()
    }

    /// The hair angles per link (`n + 1`; `0` on links without a hair), radians: the open
    /// angle ([`crate::Hair::rest_angle_rad`]) unless a contact folds the hair (or bends a
    /// compliant one past its stop).
    pub fn hair_angles_rad(&self) -> &[f64] {
        self.committed.beta()
    }

    /// The settings.
    pub fn settings(&self) -> &ContactSettings {
        self.world.settings()
    }

    /// Replaces the settings for the steps to come.
    ///
    /// # Errors
    /// [`ContactError::BadSetting`] naming the first setting out of range (the settings are
    /// then unchanged).
    pub fn set_settings(&mut self, settings: ContactSettings) -> Result<(), ContactError> {
        settings.validate()?;
        self.world.set_settings(settings);
        Ok(())
    }

    /// The contacts after the last step, ordered by link then kind.
    pub fn contacts(&self) -> Vec<Contact> {
        let mut out = Vec::with_capacity(self.committed.pairs().len());
        self.contacts_into(&mut out);
        out
    }

    /// [`Self::contacts`] into a caller's buffer (cleared first).
    pub fn contacts_into(&self, out: &mut Vec<Contact>) {
        self.committed
            .contacts_into(&self.world.pieces().piece_of, out);
    }

    /// The tolerances [`Self::step_to`] certifies every step against
    /// (the certifier's): ten times what the solver's acceptable residual
    /// ([`ContactSettings::acceptable_m`]) allows, in each unit (torques through the
    /// stiffest joint over the mean link length, forces through the contact scale
    /// `k_mean / L^2`), and the penetration tolerance.
    pub fn certify_tolerances(&self) -> CertifyTolerances {
        self.certifier().tolerances()
    }

    /// Re-derives the equilibrium conditions of the current state independently of the
    /// solver (the certifier, `certifier.rs`): the torque balance at every joint and hair from the
    /// contact forces reported by [`Self::contacts`] (and the tip load), the joint-limit
    /// multipliers' signs, non-penetration of every link and hair tip, the friction cone,
    /// Coulomb's law (stuck contacts do not slip, slipping ones are at the limit against
    /// their slip, recomputed from the committed state the last step started from) and the
    /// complementarity of forces and gaps.
    pub fn check(&self) -> EquilibriumCheck {
        self.certifier().check()
    }

    /// The certifier of the committed state.
    fn certifier(&self) -> Certifier<'_> {
        Certifier::new(&self.world, &self.committed)
    }

    /// Replaces the posture (joint angles), dropping every contact: for placing the antenna
    /// by hand before a sweep. The same checks as [`Self::new`].
    ///
    /// # Errors
    /// As [`Self::new`].
    pub fn set_posture(
        &mut self,
        base_m: Vector2<f64>,
        theta_rad: &[f64],
    ) -> Result<(), ContactError> {
        let fresh = QuasiStatic::new(
            self.world.chain().clone(),
            self.world.walls().to_vec(),
            base_m,
            theta_rad,
            *self.world.settings(),
        )?;
        self.committed.place(fresh.committed);
        Ok(())
    }

    /// Lets the current posture come to rest where it is (the base does not move): a step of
    /// length zero. A posture that is not an equilibrium follows its downhill path.
    ///
    /// # Errors
    /// As [`Self::step_to`].
    pub fn settle(&mut self) -> Result<StepReport, ContactError> {
        self.step_to(self.committed.base_m())
    }

    /// Moves the base pivot to `base_m`, the base angle kept ([`Self::step_to_pose`] at the
    /// current angle), and solves the equilibrium there with friction remembered from the
    /// last step. A step that does not converge, or jumps, is split in
    /// halves (up to `2^max_substep_depth` substeps); where the posture's branch of
    /// equilibria ends, the posture follows the downhill path to the next one (a snap).
    ///
    /// Every step is certified by [`Self::check`]; a step whose answer fails the check is
    /// taken again from where it started in two halves (each certified, down to an eighth
    /// of the step) before it is refused.
    ///
    /// # Errors
    /// [`ContactError::NotFinite`], [`ContactError::BaseInsideWall`],
    /// [`ContactError::NoConvergence`] (the state is then that of the last substep solved),
    /// [`ContactError::Jammed`], or [`ContactError::Uncertified`] (the state is the one
    /// that failed the check).
    pub fn step_to(&mut self, base_m: Vector2<f64>) -> Result<StepReport, ContactError> {
        self.step_to_pose(base_m, self.committed.theta()[0])
    }

    /// Moves the base pivot to `base_m` and turns the base link to `base_angle_rad` (its
    /// angle `theta_0` from the ground x-axis) together, and solves the equilibrium there
    /// with friction remembered from the last step: a mobile robot's antenna, whose base
    /// moves and turns at every step. The joint angles `theta_1..theta_n` are relative, so
    /// the chain turns with its base; the contacts slip (or stick) from where they were.
    ///
    /// The turn is the difference of the angles as given (no wrapping: from `3.1` to
    /// `-3.1` radians is a turn of `-6.2`). The step is measured by
    /// `max(|d base|, reach |d angle|)` ([`Self::reach_m`]); a step that fails or jumps is
    /// split in halves of both the displacement and the turn, a pure turn too. A held tip
    /// ([`Self::hold_tip`]) turns with the base. `step_to_pose(b, self.base_angle_rad())`
    /// is [`Self::step_to`]`(b)`, bit for bit.
    ///
    /// # Errors
    /// As [`Self::step_to`]; [`ContactError::NotFinite`] for a base position or angle that
    /// is not finite. After an error the state (and the chain's base angle) is that of the
    /// last substep solved.
    pub fn step_to_pose(
        &mut self,
        base_m: Vector2<f64>,
        base_angle_rad: f64,
    ) -> Result<StepReport, ContactError> {
        finite("base_m", &[base_m.x, base_m.y])?;
        finite("base_angle_rad", &[base_angle_rad])?;
        let goal = Pose {
            base_m,
            angle_rad: base_angle_rad,
        };
        let result = self.step_certified(goal, CERTIFY_SPLITS);
        self.world.turn_chain_to(self.committed.theta()[0]);
        result
    }

    /// [`Self::step_to_pose`] with `splits` halvings left for a step that fails its check.
    fn step_certified(&mut self, goal: Pose, splits: usize) -> Result<StepReport, ContactError> {
        let from = self.committed.pose();
        if splits == 0 || from.distance_m(&goal, self.world.reach_m()) == 0.0 {
            return self.step_once(goal);
        }
        let saved = self.saved_state();
        match self.step_once(goal) {
            Err(refused @ ContactError::Uncertified { .. }) => {
                self.restore_state(saved);
                let mid = from.midway(&goal);
                let mut report = match self.step_certified(mid, splits - 1) {
                    Ok(r) => r,
                    Err(ContactError::Uncertified { .. }) => return Err(refused),
                    Err(other) => return Err(other),
                };
                let second = self.step_certified(goal, splits - 1)?;
                report.accumulate(&second);
                report.certificate = second.certificate;
                report.dense_solves += second.dense_solves;
                Ok(report)
            }
            other => other,
        }
    }

    /// What a step changes, to take it again.
    fn saved_state(&self) -> SavedState {
        SavedState {
            committed: self.committed.clone(),
            secant: self.secant.clone(),
            friction_locked: self.friction_locked,
            anchoring_blocked: self.anchoring_blocked,
        }
    }

    fn restore_state(&mut self, saved: SavedState) {
        self.committed = saved.committed;
        self.secant = saved.secant;
        self.friction_locked = saved.friction_locked;
        self.anchoring_blocked = saved.anchoring_blocked;
        self.friction_off = false;
        self.quick_attempt = false;
    }

    /// One step to `goal`, certified (see [`Self::step_to_pose`]).
    fn step_once(&mut self, goal: Pose) -> Result<StepReport, ContactError> {
        let base_m = goal.base_m;
        let mut report = StepReport::default();
        // No wall, no contact: the posture is the free equilibrium under the tip load, which
        // the base's translation does not change (nor its turn, unloaded). So too where
        // every wall is clear of the unloaded antenna at rest by more than the candidate
        // margin at the new base pose (the broad phase: a wall never reached costs a bound
        // per link, not a solve).
        let unloaded_at_rest = self.world.tip_force_n() == Vector2::zeros()
            && !self.world.holds_tip()
            && self.at_rest();
        if unloaded_at_rest
            && (self.world.walls().is_empty()
                || self
                    .broad_phase
                    .clear_of_walls(&self.world, &self.committed, goal))
        {
            self.committed.move_base_to(goal);
            report.substeps = 1;
            self.certify(&mut report)?;
            return Ok(report);
        }
        if self.world.walls().is_empty() {
            self.committed.move_pivot_to(base_m);
        }
        let dense_before = self.step_solver.dense_solves();
        // Where friction locked the antenna in the last step, one plain solve with friction
        // is tried before friction is dropped again (and where the step fails without
        // friction too, it is taken with friction in full, below).
        let locked_from = self.friction_locked.then(|| self.saved_state());
        let mut result = if self.friction_locked {
            self.friction_locked = false;
            self.quick_attempt = true;
            let quick = self.attempt(goal, None, &mut report);
            self.quick_attempt = false;
            match quick {
                Ok(accepted) => {
                    report.note_residual(accepted.residual_m, self.world.settings());
                    self.commit(goal, accepted);
                    report.substeps += 1;
                    Ok(())
                }
                Err(_) => Err(ContactError::no_convergence(
                    base_m,
                    "friction still locks the antenna",
                    report.iterations,
                )),
            }
        } else {
            self.advance(goal, self.world.step_budget(), &mut report)
        };
        if let Err(first) = result {
            // No frictional equilibrium nearby (friction locks the antenna: sliding would
            // need ever more normal force). Friction is dropped at every contact for the rest
            // of the step, which the step reports; without friction either, it failed.
            result = if self.world.has_friction() {
                self.friction_off = true;
                let retry = self.advance(goal, self.world.step_budget(), &mut report);
                self.friction_off = false;
                match retry {
                    Ok(()) => {
                        report.friction_dropped = true;
                        self.friction_locked = true;
                        Ok(())
                    }
                    Err(_) => Err(first),
                }
            } else {
                Err(first)
            };
        }
        if result.is_err()
            && let Some(saved) = locked_from
        {
            // Friction locked the last step, and neither the quick solve with friction nor
            // the step without it went through: the step is taken again from its start with
            // friction, in full (substeps, the fixed point, snaps), before it fails.
            self.restore_state(saved);
            self.friction_locked = false;
            result = self.advance(goal, self.world.step_budget(), &mut report);
        }
        report.dense_solves = self.step_solver.dense_solves() - dense_before;
        if let Err(e) = result {
            return Err(self.diagnose_failure(goal, e));
        }
        self.certify(&mut report)?;
        Ok(report)
    }

    /// Moves the base to `target` in substeps (halving a step that fails or jumps, its
    /// displacement and its turn, following a snap downhill where the smallest substep
    /// fails); the state is that of the last substep solved.
    fn advance(
        &mut self,
        target: Pose,
        budget_iterations: usize,
        report: &mut StepReport,
    ) -> Result<(), ContactError> {
        let reach_m = self.world.reach_m();
        let full_m = self.committed.pose().distance_m(&target, reach_m);
        let min_m = full_m / f64::powi(2.0, self.world.settings().max_substep_depth as i32);
        let mut goals = vec![target];
        let budget = report.iterations + budget_iterations;
        // Failed substeps in a row whose repairs found other modes converging only to
        // answers those modes refuse.
        let mut refused_in_a_row = 0_usize;
        while let Some(&goal) = goals.last() {
            if report.iterations > budget {
                return Err(ContactError::no_convergence(
                    goal.base_m,
                    "the step took more Newton iterations than its budget (max_step_iterations, scaled with the joints)",
                    report.iterations,
                ));
            }
            let refused_before = self.step_solver.refused_repairs();
            let attempted = self.attempt(goal, None, report);
            refused_in_a_row = match attempted {
                Err(_) if self.step_solver.refused_repairs() > refused_before => {
                    refused_in_a_row + 1
                }
                _ => 0,
            };
            match attempted {
                Ok(accepted) => {
                    report.note_residual(accepted.residual_m, self.world.settings());
                    let delta_m = goal.base_m - self.committed.base_m();
                    let theta = self.committed.theta();
                    let turn_rad = goal.angle_rad - theta[0];
                    let dtheta_rad: Vec<f64> = accepted.x[..self.world.chain().n()]
                        .iter()
                        .zip(&theta[1..])
                        .map(|(a, b)| a - b)
                        .collect();
                    let moved = self.committed.pose().distance_m(&goal, reach_m) > 0.0;
                    self.secant = moved.then_some(Secant {
                        delta_m,
                        turn_rad,
                        dtheta_rad,
                    });
                    self.commit(goal, accepted);
                    report.substeps += 1;
                    goals.pop();
                }
                Err(_) => {
                    let d = self.committed.pose().distance_m(&goal, reach_m);
                    // A substep that fails at a fold of its branch (its stalled solves'
                    // repairs find other modes that converge, but only to answers those
                    // modes refuse: a tip stuck beyond its friction cone, or let go where
                    // its plain modes press it again) fails again however short: the
                    // halvings creep towards the fold, each failing the same way, and the
                    // snap comes at the end all the same (replay `soak:4221:375`, 150 links with distal
                    // hairs on a line wall with mu = 1: 14 halvings of some 235 Newton
                    // iterations each before each of six snaps). After two such failures
                    // in a row the snap is followed from where the posture stands: soak
                    // 375 38,050 -> 21,790 Newton iterations, the CI sample 40,577 ->
                    // 37,034 (before the snap's repair budget, `ssn::REPAIR_BUDGET`). At
                    // the first such failure it was 19,957 and 39,663, but a 4-link sweep
                    // along a digitized wall with mu = 0.6 (CI sample 38) took 13,440 ->
                    // 18,554: a stall one halving clears as often as not.
                    let at_fold = refused_in_a_row >= FOLD_FAILURES;
                    if d > min_m && d > 0.0 && !at_fold {
                        goals.push(self.committed.pose().midway(&goal));
                    } else {
                        let followed = match self.follow_snap(goal, budget, report) {
                            Err(e) if self.release_anchors(report) => {
                                let retry = self.follow_snap(goal, budget, report);
                                retry.map_err(|_| e)
                            }
                            other => other,
                        };
                        self.anchoring_blocked = false;
                        followed?;
                        report.substeps += 1;
                        goals.pop();
                    }
                }
            }
        }
        Ok(())
    }

    /// Runs the independent check on the state reached and refuses it if it fails.
    fn certify(&self, report: &mut StepReport) -> Result<(), ContactError> {
        let certifier = self.certifier();
        let check = certifier.check();
        report.certificate = check;
        let tolerances = certifier.tolerances();
        if check.holds_within(&tolerances) {
            Ok(())
        } else {
            let base_m = self.committed.base_m();
            Err(ContactError::Uncertified {
                base_x_m: base_m.x,
                base_y_m: base_m.y,
                failures: check.failures(&tolerances).join("; "),
                check: Box::new(check),
            })
        }
    }

    /// Whether every joint sits at its rest angle within its limits (the free equilibrium
    /// without loads).
    fn at_rest(&self) -> bool {
        self.world
            .chain()
            .rest_theta()
            .iter()
            .zip(self.committed.theta())
            .skip(1)
            .all(|(r, t)| r == t)
    }

    /// Makes an accepted (sub)step the state (the base at `goal`, pivot and angle); the
    /// state it started from is kept as the committed state's start.
    fn commit(&mut self, goal: Pose, accepted: Accepted) {
        self.committed.commit(self.world.chain(), goal, accepted);
    }

    /// The stages, for a test to look at what they hold.
    #[cfg(test)]
    pub(super) fn committed(&self) -> &Committed {
        &self.committed
    }

    /// The world, for a test to certify a tampered state in.
    #[cfg(test)]
    pub(super) fn world(&self) -> &World {
        &self.world
    }
}

fn finite(argument: &'static str, values: &[f64]) -> Result<(), ContactError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(ContactError::NotFinite {
            argument,
            index,
            value: values[index],
        }),
        None => Ok(()),
    }
}
