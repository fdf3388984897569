//! The committed state: the equilibrium the last accepted (sub)step reached (base pose,
//! joint and hair angles, the contacts with their forces and friction state, the hand's
//! force) and the state that (sub)step started from, which its contacts' slips are measured
//! from. The driver makes a solve's answer the state ([`Committed::commit`]); the broad
//! phase, the step solver's problem and the certifier read it.

use nalgebra::Vector2;

use super::certifier::FORCE_ZERO_N;
use super::driver::Accepted;
use super::feature::{Contact, FrictionLaw};
use super::pair::Pair;
use super::posture::Pose;
use crate::Chain;

/// The committed state (see the module docs).
#[derive(Clone, Debug)]
pub(super) struct Committed {
    base_m: Vector2<f64>,
    /// `theta_0..theta_n`, `theta_0` the base angle.
    theta: Vec<f64>,
    /// The hair angles per link (`0` where a link has no hair).
    beta: Vec<f64>,
    /// The contacts of the last step (touching pairs only), ordered by key.
    pairs: Vec<Pair>,
    hand_force_n: Vector2<f64>,
    /// The state the last committed (sub)step started from.
    step_start: StepStart,
}

/// The committed state a (sub)step started from: the base pivot, the joint angles
/// (`theta_0` the base angle then) and the hair angles.
#[derive(Clone, Debug, Default)]
pub(super) struct StepStart {
    base_m: Vector2<f64>,
    theta: Vec<f64>,
    beta: Vec<f64>,
}

impl StepStart {
    pub fn base_m(&self) -> Vector2<f64> {
        self.base_m
    }

    pub fn theta(&self) -> &[f64] {
        &self.theta
    }

    pub fn beta(&self) -> &[f64] {
        &self.beta
    }
}

impl Committed {
    /// The posture `theta` (`theta_0` the base angle) and hair angles `beta` with the pivot
    /// at `base_m`, no contact; it is its own start.
    pub fn new(base_m: Vector2<f64>, theta: Vec<f64>, beta: Vec<f64>) -> Committed {
        let step_start = StepStart {
            base_m,
            theta: theta.clone(),
            beta: beta.clone(),
        };
        Committed {
            base_m,
            theta,
            beta,
            pairs: Vec::new(),
            hand_force_n: Vector2::zeros(),
            step_start,
        }
    }

    pub fn base_m(&self) -> Vector2<f64> {
        self.base_m
    }

    pub fn theta(&self) -> &[f64] {
        &self.theta
    }

    pub fn beta(&self) -> &[f64] {
        &self.beta
    }

    pub fn pairs(&self) -> &[Pair] {
        &self.pairs
    }

    pub fn hand_force_n(&self) -> Vector2<f64> {
        self.hand_force_n
    }

    pub fn step_start(&self) -> &StepStart {
        &self.step_start
    }

    /// The base pose, pivot and angle.
    pub fn pose(&self) -> Pose {
        Pose {
            base_m: self.base_m,
            angle_rad: self.theta[0],
        }
    }

    /// The joint angles `theta_1..theta_n` (the hair angles are not carried).
    pub fn coordinates(&self) -> Vec<f64> {
        self.theta[1..].to_vec()
    }

    /// The contacts, reported against the walls `piece_of` maps the pieces to, into `out`
    /// (cleared first).
    pub fn contacts_into(&self, piece_of: &[usize], out: &mut Vec<Contact>) {
        out.clear();
        out.extend(self.pairs.iter().map(|c| Contact {
            feature: c.key.feature(),
            wall: piece_of[c.key.piece],
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

    /// Makes an accepted (sub)step of `chain` the state (the base at `goal`, pivot and
    /// angle); the state it started from becomes [`Self::step_start`].
    pub fn commit(&mut self, chain: &Chain, goal: Pose, accepted: Accepted) {
        let n = chain.n();
        self.step_start.base_m = self.base_m;
        self.step_start.theta.clone_from(&self.theta);
        self.step_start.beta.clone_from(&self.beta);
        self.base_m = goal.base_m;
        self.theta[0] = goal.angle_rad;
        self.hand_force_n = accepted.hand_force_n;
        self.theta[1..].copy_from_slice(&accepted.x[..n]);
        for (link, hair) in chain.hairs().iter().enumerate() {
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

    /// Moves the base to `goal` (pivot and angle) with nothing else changed: a step where
    /// nothing touches or can touch.
    pub fn move_base_to(&mut self, goal: Pose) {
        self.base_m = goal.base_m;
        self.theta[0] = goal.angle_rad;
    }

    /// Moves the base pivot to `base_m`, the angles kept (no wall: the free posture does
    /// not depend on where the pivot is).
    pub fn move_pivot_to(&mut self, base_m: Vector2<f64>) {
        self.base_m = base_m;
    }

    /// Replaces the posture by `placed`'s, dropping every contact (the start the last step
    /// took and the hand's force kept).
    pub fn place(&mut self, placed: Committed) {
        self.base_m = placed.base_m;
        self.theta = placed.theta;
        self.beta = placed.beta;
        self.pairs.clear();
    }

    /// The hand let go: no force on the tip.
    pub fn let_go_of_tip(&mut self) {
        self.hand_force_n = Vector2::zeros();
    }

    /// Gives every anchored contact the law `law_of` says (a Coulomb law: the anchors torn
    /// out); how many there were.
    pub fn tear_out_anchors(&mut self, law_of: impl Fn(&Pair) -> FrictionLaw) -> usize {
        let mut released = 0;
        for pair in &mut self.pairs {
            if pair.law.is_anchored() {
                pair.law = law_of(pair);
                released += 1;
            }
        }
        released
    }

    /// The contacts, to tamper with in a test of what reads them.
    #[cfg(test)]
    pub fn pairs_mut(&mut self) -> &mut Vec<Pair> {
        &mut self.pairs
    }

    /// The start's joint angles, to tamper with in a test of what reads them.
    #[cfg(test)]
    pub fn step_start_theta_mut(&mut self) -> &mut Vec<f64> {
        &mut self.step_start.theta
    }
}
