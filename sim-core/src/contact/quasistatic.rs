//! The quasi-static state of a chain among walls, and the stepping of its base: substeps
//! where a step fails or jumps, snaps followed downhill ([`super::snap`]), each (sub)step
//! solved by [`super::substep`].

use nalgebra::Vector2;

use super::ContactError;
use super::check::FORCE_ZERO_N;
use super::feature::{Contact, FrictionLaw};
use super::pair::Pair;
use super::pieces::Pieces;
use super::posture::{Pose, Posture};
use super::report::StepReport;
use super::settings::ContactSettings;
use super::ssn::Ssn;
use super::substep::Accepted;
use crate::{Chain, Wall};

/// A chain moving quasi-statically against walls with friction and hairs (docs/model.md 6-7).
///
/// The state carries from step to step: joint and hair angles, and every contact with its
/// forces and friction state (anchored hairs stay anchored). See the
/// [module documentation](super) for the method.
#[derive(Debug)]
pub struct QuasiStatic {
    pub(super) chain: Chain,
    pub(super) walls: Vec<Wall>,
    /// The walls as the contacts see them ([`Pieces`]); contacts are reported against
    /// `walls`.
    pub(super) pieces: Pieces,
    pub(super) tip_force_n: Vector2<f64>,
    pub(super) settings: ContactSettings,
    pub(super) base_m: Vector2<f64>,
    pub(super) theta: Vec<f64>,
    pub(super) beta: Vec<f64>,
    /// The contacts of the last step (touching pairs only).
    pub(super) pairs: Vec<Pair>,
    pub(super) ssn: Ssn,
    /// The posture at the start of the (sub)step, and carried to its goal.
    pub(super) start: Posture,
    pub(super) probe: Posture,
    /// A hand holding the tip at this offset from the base pivot, given with the base link
    /// at `hand_angle_rad` (the offset turns with the base).
    pub(super) hand_offset_m: Option<Vector2<f64>>,
    pub(super) hand_angle_rad: f64,
    pub(super) hand_force_n: Vector2<f64>,
    /// No hair anchors during the rest of this step (set after anchors were torn out).
    pub(super) anchoring_blocked: bool,
    /// The last plain (sub)step's base displacement, turn and change of the joint angles.
    pub(super) secant: Option<Secant>,
    /// The state the last committed (sub)step started from (what its contacts' slips are
    /// measured from: [`Self::check`] recomputes them).
    pub(super) step_start: StepStart,
    /// The farthest a point of the chain can be from the base pivot, metres: the links'
    /// lengths and the longest hair (a turn of the base by `a` radians moves a point by at
    /// most `reach_m a`).
    pub(super) reach_m: f64,
    /// Friction is off for the rest of this step (see [`StepReport::friction_dropped`]).
    pub(super) friction_off: bool,
    /// Friction was dropped in the last step.
    pub(super) friction_locked: bool,
    /// One solve only: no fixed point on the normal forces where it fails.
    pub(super) quick_attempt: bool,
}

/// How many times a step that fails its check is halved before it is refused.
const CERTIFY_SPLITS: usize = 3;

/// Failed substeps in a row whose repairs found other modes converging only to answers
/// those modes refuse ([`super::ssn::Ssn::refused_repairs`]), after which a substep is not
/// halved again but followed downhill as a snap (see [`QuasiStatic::advance`]).
const FOLD_FAILURES: usize = 2;

/// The last plain (sub)step's change: the base's displacement and turn, and the change of
/// the joint angles `theta_1..theta_n` (the secant predictor, [`QuasiStatic::secant_prediction`]).
#[derive(Clone, Debug)]
pub(super) struct Secant {
    pub delta_m: Vector2<f64>,
    pub turn_rad: f64,
    pub dtheta_rad: Vec<f64>,
}

/// The committed state a (sub)step started from: the base pivot, the joint angles
/// (`theta_0` the base angle then) and the hair angles.
#[derive(Clone, Debug, Default)]
pub(super) struct StepStart {
    pub base_m: Vector2<f64>,
    pub theta: Vec<f64>,
    pub beta: Vec<f64>,
}

/// The state a step changes ([`QuasiStatic::step_to_pose`] takes a refused step again from
/// it).
struct SavedState {
    base_m: Vector2<f64>,
    theta: Vec<f64>,
    beta: Vec<f64>,
    pairs: Vec<Pair>,
    hand_force_n: Vector2<f64>,
    secant: Option<Secant>,
    step_start: StepStart,
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
        // A vertex within the penetration tolerance of the chord that replaces it is not a
        // corner: see `Polyline::without_flat_vertices`.
        let walls: Vec<Wall> = walls
            .iter()
            .map(|w| w.without_flat_vertices(settings.penetration_tolerance_m))
            .collect();
        let pieces = Pieces::new(&walls);
        let hair_reach_m = chain
            .hairs()
            .iter()
            .flatten()
            .map(|h| h.pivot_in_link_m().norm() + h.length_m)
            .fold(0.0_f64, f64::max);
        let reach_m = chain.total_length_m() + hair_reach_m;
        let step_start = StepStart {
            base_m,
            theta: theta.clone(),
            beta: beta.clone(),
        };
        let mut sim = QuasiStatic {
            chain,
            pieces,
            walls,
            tip_force_n: Vector2::zeros(),
            settings,
            base_m,
            theta,
            beta,
            pairs: Vec::new(),
            ssn: Ssn::default(),
            start: Posture::default(),
            probe: Posture::default(),
            hand_offset_m: None,
            hand_angle_rad: 0.0,
            hand_force_n: Vector2::zeros(),
            anchoring_blocked: false,
            secant: None,
            step_start,
            reach_m,
            friction_off: false,
            friction_locked: false,
            quick_attempt: false,
        };
        sim.check_start()?;
        Ok(sim)
    }

    /// A dead load at the tip (ground frame, newtons) from now on.
    pub fn set_tip_force_n(&mut self, tip_force_n: Vector2<f64>) {
        self.tip_force_n = tip_force_n;
    }

    /// The dead load at the tip, newtons.
    pub fn tip_force_n(&self) -> Vector2<f64> {
        self.tip_force_n
    }

    /// Holds the tip near `offset_m` from the base pivot (a hand moving and turning with the
    /// base, for placing the antenna: the offset is in the ground frame at the current base
    /// angle, and turns about the pivot as the base turns) by a stiff spring, or lets go
    /// (`None`). While held, [`Self::hand_force_n`] is the hand's force on the tip.
    pub fn hold_tip(&mut self, offset_m: Option<Vector2<f64>>) {
        self.hand_offset_m = offset_m;
        self.hand_angle_rad = self.theta[0];
        if offset_m.is_none() {
            self.hand_force_n = Vector2::zeros();
        }
    }

    /// The force of the hand on the tip after the last step, newtons.
    pub fn hand_force_n(&self) -> Vector2<f64> {
        self.hand_force_n
    }

    /// The chain; its base angle ([`Chain::base_angle_rad`]) is the current one,
    /// `theta_rad()[0]`.
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// The walls, without their flat vertices (see [`Self::new`]).
    pub fn walls(&self) -> &[Wall] {
        &self.walls
    }

    /// The base pivot, ground frame, metres.
    pub fn base_m(&self) -> Vector2<f64> {
        self.base_m
    }

    /// The base link's angle `theta_0` from the ground x-axis, radians (`theta_rad()[0]`).
    pub fn base_angle_rad(&self) -> f64 {
        self.theta[0]
    }

    /// The farthest a point of the chain can be from the base pivot, metres: the sum of the
    /// link lengths and the longest reach of a hair past its link. A turn of the base by
    /// `a` radians moves no point by more than `reach_m() * a`, and
    /// [`Self::step_to_pose`] measures a step by `max(|d base|, reach_m() |d angle|)`.
    pub fn reach_m(&self) -> f64 {
        self.reach_m
    }

    /// The joint angles `theta_0..theta_n`, radians.
    pub fn theta_rad(&self) -> &[f64] {
        &self.theta
    }

    /// The hair angles per link (`n + 1`; `0` on links without a hair), radians: the open
    /// angle ([`crate::Hair::rest_angle_rad`]) unless a contact folds the hair (or bends a
    /// compliant one past its stop).
    pub fn hair_angles_rad(&self) -> &[f64] {
        &self.beta
    }

    /// The settings.
    pub fn settings(&self) -> &ContactSettings {
        &self.settings
    }

    /// Replaces the settings for the steps to come.
    ///
    /// # Errors
    /// [`ContactError::BadSetting`] naming the first setting out of range (the settings are
    /// then unchanged).
    pub fn set_settings(&mut self, settings: ContactSettings) -> Result<(), ContactError> {
        settings.validate()?;
        self.settings = settings;
        Ok(())
    }

    /// The contacts after the last step, ordered by link then kind.
    pub fn contacts(&self) -> Vec<Contact> {
        let mut out = Vec::with_capacity(self.pairs.len());
        self.contacts_into(&mut out);
        out
    }

    /// [`Self::contacts`] into a caller's buffer (cleared first).
    pub fn contacts_into(&self, out: &mut Vec<Contact>) {
        out.clear();
        out.extend(self.pairs.iter().map(|c| Contact {
            feature: c.key.feature(),
            wall: self.pieces.piece_of[c.key.piece],
            s: c.geo.s,
            point_m: c.geo.point_m,
            normal: c.geo.normal,
            tangent: c.geo.tangent,
            normal_force_n: c.normal_force_n,
            shear_force_n: c.shear_force_n,
            law: c.law,
            slip: c.slip,
            slip_m: c.slip_m,
            relaxed_shear_bound_n: c.relaxed_bound_n,
        }));
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
            self.chain.clone(),
            self.walls.clone(),
            base_m,
            theta_rad,
            self.settings,
        )?;
        self.base_m = fresh.base_m;
        self.theta = fresh.theta;
        self.beta = fresh.beta;
        self.pairs.clear();
        Ok(())
    }

    /// Lets the current posture come to rest where it is (the base does not move): a step of
    /// length zero. A posture that is not an equilibrium follows its downhill path.
    ///
    /// # Errors
    /// As [`Self::step_to`].
    pub fn settle(&mut self) -> Result<StepReport, ContactError> {
        self.step_to(self.base_m)
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
        self.step_to_pose(base_m, self.theta[0])
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
        self.sync_chain_angle();
        result
    }

    /// The committed base pose.
    pub(super) fn pose(&self) -> Pose {
        Pose {
            base_m: self.base_m,
            angle_rad: self.theta[0],
        }
    }

    /// Keeps the chain's base angle ([`Chain::base_angle_rad`]) at the committed `theta_0`
    /// (the solver itself reads only `theta_0`): a turned step replaces the chain by its
    /// copy at the new angle, once per step.
    fn sync_chain_angle(&mut self) {
        if self.chain.base_angle_rad() != self.theta[0]
            && let Ok(turned) = self.chain.with_base_angle_rad(self.theta[0])
        {
            self.chain = turned;
        }
    }

    /// [`Self::step_to_pose`] with `splits` halvings left for a step that fails its check.
    fn step_certified(&mut self, goal: Pose, splits: usize) -> Result<StepReport, ContactError> {
        let from = self.pose();
        if splits == 0 || from.distance_m(&goal, self.reach_m) == 0.0 {
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
            base_m: self.base_m,
            theta: self.theta.clone(),
            beta: self.beta.clone(),
            pairs: self.pairs.clone(),
            hand_force_n: self.hand_force_n,
            secant: self.secant.clone(),
            step_start: self.step_start.clone(),
            friction_locked: self.friction_locked,
            anchoring_blocked: self.anchoring_blocked,
        }
    }

    fn restore_state(&mut self, saved: SavedState) {
        self.base_m = saved.base_m;
        self.theta = saved.theta;
        self.beta = saved.beta;
        self.pairs = saved.pairs;
        self.hand_force_n = saved.hand_force_n;
        self.secant = saved.secant;
        self.step_start = saved.step_start;
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
        let unloaded_at_rest =
            self.tip_force_n == Vector2::zeros() && self.hand_offset_m.is_none() && self.at_rest();
        if unloaded_at_rest && (self.walls.is_empty() || self.clear_of_walls(goal)) {
            self.base_m = base_m;
            self.theta[0] = goal.angle_rad;
            report.substeps = 1;
            self.certify(&mut report)?;
            return Ok(report);
        }
        if self.walls.is_empty() {
            self.base_m = base_m;
        }
        let dense_before = self.ssn.system.dense_solves;
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
                    report.note_residual(accepted.residual_m, &self.settings);
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
            self.advance(goal, self.step_budget(), &mut report)
        };
        if let Err(first) = result {
            // No frictional equilibrium nearby (friction locks the antenna: sliding would
            // need ever more normal force). Friction is dropped at every contact for the rest
            // of the step, which the step reports; without friction either, it failed.
            result = if self.has_friction() {
                self.friction_off = true;
                let retry = self.advance(goal, self.step_budget(), &mut report);
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
            result = self.advance(goal, self.step_budget(), &mut report);
        }
        report.dense_solves = self.ssn.system.dense_solves - dense_before;
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
        let full_m = self.pose().distance_m(&target, self.reach_m);
        let min_m = full_m / f64::powi(2.0, self.settings.max_substep_depth as i32);
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
            let refused_before = self.ssn.refused_repairs();
            let attempted = self.attempt(goal, None, report);
            refused_in_a_row = match attempted {
                Err(_) if self.ssn.refused_repairs() > refused_before => refused_in_a_row + 1,
                _ => 0,
            };
            match attempted {
                Ok(accepted) => {
                    report.note_residual(accepted.residual_m, &self.settings);
                    let delta_m = goal.base_m - self.base_m;
                    let turn_rad = goal.angle_rad - self.theta[0];
                    let dtheta_rad: Vec<f64> = accepted.x[..self.chain.n()]
                        .iter()
                        .zip(&self.theta[1..])
                        .map(|(a, b)| a - b)
                        .collect();
                    let moved = self.pose().distance_m(&goal, self.reach_m) > 0.0;
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
                    let d = self.pose().distance_m(&goal, self.reach_m);
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
                        goals.push(self.pose().midway(&goal));
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

    /// The Newton iterations a step may take ([`ContactSettings::step_iteration_budget`]:
    /// `max_step_iterations`, scaled with the chain's joints by default).
    fn step_budget(&self) -> usize {
        self.settings.step_iteration_budget(self.chain.n())
    }

    /// Whether any wall has friction (or anchoring) anywhere.
    fn has_friction(&self) -> bool {
        self.walls.iter().any(|w| w.surfaces.has_friction())
    }

    /// Runs the independent check on the state reached and refuses it if it fails.
    fn certify(&self, report: &mut StepReport) -> Result<(), ContactError> {
        let check = self.check();
        report.certificate = check;
        let tolerances = self.certify_tolerances();
        if check.holds_within(&tolerances) {
            Ok(())
        } else {
            Err(ContactError::Uncertified {
                base_x_m: self.base_m.x,
                base_y_m: self.base_m.y,
                failures: check.failures(&tolerances).join("; "),
                check: Box::new(check),
            })
        }
    }

    /// Whether, with no pair standing and every hair open, every link and hair tip with the
    /// base at `goal` is farther than the candidate margin from every wall by the broad phase's
    /// bound ([`crate::WallShape::segment_gap_lower_bound_m`]).
    fn clear_of_walls(&mut self, goal: Pose) -> bool {
        if !self.pairs.is_empty() {
            return false;
        }
        let hairs_open = self
            .chain
            .hairs()
            .iter()
            .zip(&self.beta)
            .all(|(h, &b)| h.is_none_or(|h| b == h.rest_angle_rad()));
        if !hairs_open {
            return false;
        }
        let margin_m = self.settings.margin_m;
        self.probe.update_at(&self.chain, goal, &self.theta);
        let probe = &self.probe;
        self.walls.iter().all(|wall| {
            (0..=self.chain.n()).all(|link| {
                wall.segment_gap_lower_bound_m(&probe.start_of(link), &probe.end_m[link]) > margin_m
            }) && self.chain.hairs().iter().enumerate().all(|(link, hair)| {
                hair.as_ref().is_none_or(|hair| {
                    wall.gap_lower_bound_m(&probe.hair_tip(hair, link, self.beta[link])) > margin_m
                })
            })
        })
    }

    /// Whether every joint sits at its rest angle within its limits (the free equilibrium
    /// without loads).
    fn at_rest(&self) -> bool {
        self.chain
            .rest_theta()
            .iter()
            .zip(&self.theta)
            .skip(1)
            .all(|(r, t)| r == t)
    }

    /// The joint angles `theta_1..theta_n` (the hair angles are not carried).
    pub(super) fn coordinates(&self) -> Vec<f64> {
        self.theta[1..].to_vec()
    }

    /// Makes an accepted (sub)step the state (the base at `goal`, pivot and angle); the
    /// state it started from is kept as [`Self::step_start`].
    pub(super) fn commit(&mut self, goal: Pose, accepted: Accepted) {
        let n = self.chain.n();
        self.step_start.base_m = self.base_m;
        self.step_start.theta.clone_from(&self.theta);
        self.step_start.beta.clone_from(&self.beta);
        self.base_m = goal.base_m;
        self.theta[0] = goal.angle_rad;
        self.hand_force_n = accepted.hand_force_n;
        self.theta[1..].copy_from_slice(&accepted.x[..n]);
        for (link, hair) in self.chain.hairs().iter().enumerate() {
            if let Some(hair) = hair {
                self.beta[link] = hair.rest_angle_rad();
            }
        }
        for (h, &link) in accepted.hair_links.iter().enumerate() {
            self.beta[link] = accepted.x[n + h];
        }
        self.pairs.clear();
        self.pairs.extend(
            accepted
                .pairs
                .into_iter()
                // Touching ones only: a contact that let go ends its solve with a normal
                // force of rounding size (1e-25 N), not zero, and would be carried (and
                // reported, with its touch bit) however far the chain moves from the wall.
                // One that still carries a force (a solve accepted where it stalled with a
                // contact touching at N = 0 and gap = 0: its mode undecided, its force up
                // to the acceptable residual times the contact scale) stays: the posture
                // balances that force, and the check then holds it to the contact's gap.
                .filter(|c| {
                    c.normal_active
                        || c.normal_force_n.abs() > FORCE_ZERO_N
                        || c.shear_force_n.abs() > FORCE_ZERO_N
                }),
        );
        self.pairs.sort_by_key(|a| a.key);
    }

    /// The base link must stay out of every wall.
    pub(super) fn check_base(
        &self,
        w: usize,
        wall: &Wall,
        posture: &Posture,
        base_m: Vector2<f64>,
    ) -> Result<(), ContactError> {
        let tol = self.settings.penetration_tolerance_m;
        if wall.segment_gap_lower_bound_m(&posture.base_m, &posture.end_m[0]) >= -tol {
            return Ok(());
        }
        let sc = wall.segment_contact(&posture.base_m, &posture.end_m[0]);
        if sc.wall.gap_m < -tol {
            return Err(ContactError::BaseInsideWall {
                wall: w,
                depth_m: -sc.wall.gap_m,
                base_x_m: base_m.x,
                base_y_m: base_m.y,
            });
        }
        Ok(())
    }

    /// The start posture must be outside every wall.
    fn check_start(&mut self) -> Result<(), ContactError> {
        let tol = self.settings.penetration_tolerance_m;
        self.probe.update(&self.chain, self.base_m, &self.theta);
        for (w, wall) in self.walls.iter().enumerate() {
            self.check_base(w, wall, &self.probe, self.base_m)?;
            for link in 1..=self.chain.n() {
                let sc = wall.segment_contact(&self.probe.start_of(link), &self.probe.end_m[link]);
                if sc.wall.gap_m < -tol {
                    return Err(ContactError::StartInsideWall {
                        wall: w,
                        link,
                        hair: "",
                        depth_m: -sc.wall.gap_m,
                        at_x_m: sc.point_m.x,
                        at_y_m: sc.point_m.y,
                    });
                }
                if let Some(Some(hair)) = self.chain.hairs().get(link) {
                    let tip = self.probe.hair_tip(hair, link, self.beta[link]);
                    let gap = wall.signed_distance(&tip).gap_m;
                    if gap < -tol {
                        return Err(ContactError::StartInsideWall {
                            wall: w,
                            link,
                            hair: " (its hair tip)",
                            depth_m: -gap,
                            at_x_m: tip.x,
                            at_y_m: tip.y,
                        });
                    }
                }
            }
        }
        Ok(())
    }

    /// The point the hand holding the tip pulls it to with the base at `at` (its offset
    /// turned by the base's turn since [`Self::hold_tip`]); `None` without a hand.
    pub(super) fn hand_target(&self, at: Pose) -> Option<Vector2<f64>> {
        self.hand_offset_m.map(|o| {
            let turn_rad = at.angle_rad - self.hand_angle_rad;
            if turn_rad == 0.0 {
                at.base_m + o
            } else {
                at.base_m + super::posture::rotate(turn_rad, o)
            }
        })
    }

    /// The friction law of a fresh contact on piece `piece` at `point_m`: the surface's
    /// Coulomb law (a hair tip anchors only once it touches, see [`super::anchoring`]).
    pub(super) fn coulomb_at(&self, piece: usize, point_m: &Vector2<f64>) -> FrictionLaw {
        FrictionLaw::Coulomb {
            mu: self.pieces.surface_at(&self.walls, piece, point_m).mu(),
        }
    }
}

/// `theta` with its flexible joints replaced by the first `n` coordinates of `x`.
pub(super) fn theta_of(theta: &[f64], x: &[f64]) -> Vec<f64> {
    let mut out = theta.to_vec();
    let n = out.len() - 1;
    out[1..].copy_from_slice(&x[..n]);
    out
}

pub(super) fn finite(argument: &'static str, values: &[f64]) -> Result<(), ContactError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(ContactError::NotFinite {
            argument,
            index,
            value: values[index],
        }),
        None => Ok(()),
    }
}
