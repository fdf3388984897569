//! One quasi-static step as a nonlinear complementarity problem (the Alart-Curnier form of
//! Coulomb contact): its unknowns, its residual `Phi` and the modes of its pieces.
//!
//! # Unknowns and equations
//! `z = (x, N_1..N_c, T_1..T_c)`: the free coordinates `x` (flexible joint angles, then the
//! angles of the hairs taking part), and per contact pair ([`super::pair`]) its normal force
//! `N_k` and shear force `T_k` (on the chain, along the pair's normal and tangent). With the
//! generalized force `r(x, N, T) = grad U(x) - J_tip^T F - sum_k J_k^T (N_k n_k + T_k t_k)`
//! (plus a proximal term when following a snap), the step's equations are, with
//! `proj_[a,b]` the clamp and `c` a contact stiffness scale:
//! - coordinates (box `lo <= x_a <= hi`): `x_a - proj_[lo,hi](x_a - r_a / s_a) = 0`, i.e.
//!   `r_a = 0` inside the box, `r_a >= 0` at `lo`, `r_a <= 0` at `hi` (the KKT conditions of
//!   the joint limits, with the stop's multiplier of the right sign); `x` stays in the box,
//!   and a coordinate's row is `x_a - bound` only while it is on that bound (inside, `r_a`
//!   itself: see [`Equations::evaluate`]);
//! - normal: `N_k - proj_[N_min, inf)(N_k - c gap_k(x)) = 0`: `N >= N_min`, `gap >= 0`,
//!   complementary (`N_min = 0`, or minus the tension hold of an anchored hair tip);
//! - tangential: `T_k - proj_[-B_k, B_k](T_k - c u_k(x)) = 0` with `B_k = mu N_k` (Coulomb)
//!   or the shear hold of an anchored hair, and `u_k = t_k . (X_k(x) - X_k^0)` the slip of
//!   the pair's material point over the step: `u = 0` while `|T| < B` (stuck: no creep),
//!   else `T = -B sign(u)`.
//!
//! Each is piecewise smooth: the **modes** (a coordinate held on a bound or free, a normal
//! row active or not, a tangent row stuck or sliding) pick the piece, and Newton's method on
//! the active piece is the semismooth Newton method ([`super::newton_system`] builds its
//! linear system, [`super::ssn`] drives it).
//!
//! Every residual is scaled to metres for the merit: joint rows by the mean link length `L`
//! (`L r_a / s_a` or `L (x_a - bound)`), normal and shear rows are gaps and slips, or forces
//! divided by `c`.

// Joint `j` (1-based), its coordinate `j - 1` and the link ends `p_(j-1)` are indexed
// together throughout: index loops say what they do here.
#![allow(clippy::needless_range_loop)]

use nalgebra::Vector2;

use crate::contact::feature::{FrictionLaw, Slip};
use crate::contact::geometry::{evaluate as evaluate_geometry, hair_of};
use crate::contact::pair::Pair;
use crate::contact::posture::{Posture, cross};
use crate::{Chain, Wall};

/// A proximal term `gamma/2 sum_a s_a (x_a - x_prev_a)^2`: one implicit step of the
/// (friction-aware) gradient flow, used to follow a snap downhill.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Proximal<'a> {
    pub gamma: f64,
    pub x_prev: &'a [f64],
}

/// What one step is about.
pub(crate) struct StepProblem<'a> {
    pub chain: &'a Chain,
    /// The walls as the contacts see them ([`super::pieces`]).
    pub pieces: &'a [Wall],
    pub tip_force_n: Vector2<f64>,
    pub base_m: Vector2<f64>,
    /// The base link's angle `theta_0` at the goal, radians (the base turns with the step).
    pub base_angle_rad: f64,
    /// Links whose hair angle is a coordinate, in coordinate order after the joints.
    pub hair_links: &'a [usize],
    /// Hair angles of every link (`n + 1`; links without a hair, or whose hair is not a
    /// coordinate, keep theirs).
    pub hair_beta_rad: &'a [f64],
    pub proximal: Option<Proximal<'a>>,
    /// A hand holding the tip near this point (ground frame) with a stiff spring: the force
    /// `k_hand (target - p_n)` acts on the tip, `k_hand = HAND_STIFFNESS k_mean / R^2` (`R`
    /// the chain's length: a thousand times the chain's own stiffness at its tip).
    pub hand_m: Option<Vector2<f64>>,
    pub tolerance_m: f64,
    /// The residual accepted from a solve that stalls above `tolerance_m`.
    pub acceptable_m: f64,
    /// A solve whose joint angles wander farther than this from where it started gives up
    /// (its step would be refused as a jump anyway), radians.
    pub max_departure_rad: f64,
    pub max_iterations: usize,
    /// `Some(k)`: a solve whose best merit has not halved in `k` iterations has stopped
    /// making progress and gives up early, at its best point (see [`super::ssn`]);
    /// `None`: it spends its whole budget.
    pub stall_after: Option<usize>,
}

/// The hand spring's stiffness in units of the chain's stiffness at its tip, `k_mean / R^2`.
pub(super) const HAND_STIFFNESS: f64 = 1e3;

/// The hysteresis of the contact modes, as a length (times `c` it is a force).
const HYSTERESIS_M: f64 = 1e-11;

/// How deep in its wall a pair the last step let go (unloaded) may start a solve and keep
/// its mode for the solve's first Newton step, metres ([`Equations::keep_last_modes`]): the
/// last posture carried with the base may push a free contact into its wall as it lifts a
/// pressed one off (the thesis's 14.2 cycles/m sinusoid under 4 links: a joint 1.5 nm off the
/// wall's flank carried 14 nm into it, pressed, took the load of the crest beside it, and the
/// modes cycled, step after step, until the sweep failed at 6.19 s; kept free, it finishes,
/// Newton p99 40). A pair deeper than this is a contact the step brings on, and presses at
/// once: with no limit, the same sinusoid under 150 links took a p99 of 510 against 309.
const KEEP_FREE_DEPTH_M: f64 = 1e-6;

/// A mode a repair of a stalled solve forces on one part of the step's equations
/// ([`super::ssn`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Forced {
    /// A coordinate that is never held on its bounds (its row stays the balance).
    Free(usize),
    /// A pair whose normal row is never active (its forces go to zero).
    LetGo(usize),
    /// A touching pair that sticks (its slip held at zero, its shear force free).
    Stuck(usize),
}

/// The step's equations at the current unknowns, and their scratch space (reused from step
/// to step).
#[derive(Debug, Default)]
pub(super) struct Equations {
    pub(super) posture: Posture,
    pub(super) theta: Vec<f64>,
    pub(super) beta: Vec<f64>,
    /// The generalized force `r` (`m` entries).
    pub(super) r: Vec<f64>,
    /// The coordinates' scales (stiffnesses), bounds.
    pub(super) scale: Vec<f64>,
    pub(super) lo: Vec<f64>,
    pub(super) hi: Vec<f64>,
    /// `Some(bound)` for a coordinate held on a bound by its mode.
    pub(super) held: Vec<Option<f64>>,
    /// The scaled residual `Phi` (`m + 2c`).
    pub(super) phi: Vec<f64>,
    /// The unknowns `z`.
    pub(super) z: Vec<f64>,
    /// The mean link length `L`, metres.
    pub(super) length_m: f64,
    /// The contact scale `c`, N/m.
    pub(super) c_n_per_m: f64,
    /// The hand spring's stiffness, N/m.
    pub(super) hand_stiffness_n_per_m: f64,
    /// The hand's force on the tip at the current posture.
    pub(super) hand_force_n: Vector2<f64>,
    /// Per link `0..=n`: the sum of the forces on points of the link (contacts, and the tip
    /// load on link `n`), of their moments `cross(X, F)` and of `F . X`.
    pub(super) link_force_n: Vec<Vector2<f64>>,
    pub(super) link_moment_nm: Vec<f64>,
    pub(super) link_work_nm: Vec<f64>,
    /// The mode forced by a repair of a stalled solve ([`super::ssn`]); `None`: no mode
    /// is forced.
    pub(super) forced: Option<Forced>,
    /// Keep the modes (coordinates held, pairs' normal and tangent modes) as they are
    /// instead of updating them (tests of the Jacobian on a given piece).
    #[cfg(test)]
    pub(super) frozen_modes: bool,
    /// Keep the pressed pairs pressed, and the stuck ones among them stuck, in the next
    /// evaluation (a solve's first: the modes the last step ended in, see [`super::ssn`]);
    /// and the unloaded pairs let go, unless deeper in their wall than
    /// [`KEEP_FREE_DEPTH_M`].
    pub(super) keep_last_modes: bool,
}

impl Equations {
    /// Sets up the coordinate scales and bounds for `problem` (`m = n + hairs`).
    pub fn prepare(&mut self, p: &StepProblem<'_>) {
        let chain = p.chain;
        let n = chain.n();
        let m = n + p.hair_links.len();
        let k = chain.stiffness_nm_per_rad();
        let k_max = k[1..].iter().copied().fold(0.0_f64, f64::max);
        let k_mean = if n > 0 {
            k[1..].iter().sum::<f64>() / n as f64
        } else {
            0.0
        };
        let lengths = chain.link_lengths_m();
        self.length_m = lengths.iter().sum::<f64>() / lengths.len() as f64;
        let k_ref = if k_mean > 0.0 { k_mean } else { 1e-3 };
        self.c_n_per_m = k_ref / (self.length_m * self.length_m);
        let reach_m: f64 = lengths.iter().sum();
        self.hand_stiffness_n_per_m = HAND_STIFFNESS * k_ref / (reach_m * reach_m);
        self.scale.clear();
        self.lo.clear();
        self.hi.clear();
        for j in 1..=n {
            self.scale.push(k[j].max(1e-3 * k_max).max(1e-12));
            let lim = chain.joint_limits()[j];
            self.lo.push(lim.cw_rad);
            self.hi.push(lim.ccw_rad);
        }
        for &link in p.hair_links {
            let hair = hair_of(chain, link);
            let s = hair
                .stiffness_nm_per_rad
                .max(hair.preload_nm / hair.open_angle_rad)
                .max(1e-9);
            self.scale.push(s);
            self.lo.push(0.0);
            self.hi.push(hair.max_angle_rad());
        }
        self.r.clear();
        self.r.resize(m, 0.0);
        self.held.clear();
        self.held.resize(m, None);
        self.theta.clear();
        self.theta.resize(n + 1, 0.0);
        self.theta[0] = p.base_angle_rad;
        self.beta.clear();
        self.beta.extend_from_slice(p.hair_beta_rad);
        self.link_force_n.clear();
        self.link_force_n.resize(n + 1, Vector2::zeros());
        self.link_moment_nm.clear();
        self.link_moment_nm.resize(n + 1, 0.0);
        self.link_work_nm.clear();
        self.link_work_nm.resize(n + 1, 0.0);
    }

    /// The number of coordinates `m`.
    pub fn m(&self) -> usize {
        self.scale.len()
    }

    /// Loads `x` (clamped to the box) and the pairs' forces into `z`.
    pub fn load(&mut self, x: &[f64], pairs: &[Pair]) {
        let m = x.len();
        let c = pairs.len();
        self.z.clear();
        self.z.resize(m + 2 * c, 0.0);
        for (a, &v) in x.iter().enumerate() {
            self.z[a] = v.clamp(self.lo[a], self.hi[a]);
        }
        for (k, pair) in pairs.iter().enumerate() {
            self.z[m + k] = pair.normal_force_n;
            self.z[m + c + k] = pair.shear_force_n;
        }
    }

    /// The hand spring's force on the tip (zero without a hand); valid after the posture
    /// is updated.
    fn hand_force(&self, p: &StepProblem<'_>) -> Vector2<f64> {
        match (p.hand_m, self.posture.end_m.last()) {
            (Some(target), Some(tip)) => (target - tip) * self.hand_stiffness_n_per_m,
            _ => Vector2::zeros(),
        }
    }

    /// Evaluates the pairs' geometry, `r`, the modes and `Phi` at `z` (the pairs receive
    /// their forces, geometry and modes); returns the merit `|Phi|^2 / 2` (`+inf` if any part
    /// is not finite).
    pub fn evaluate(&mut self, p: &StepProblem<'_>, pairs: &mut [Pair]) -> f64 {
        let chain = p.chain;
        let n = chain.n();
        let m = self.m();
        let c = pairs.len();
        for j in 1..=n {
            self.theta[j] = self.z[j - 1];
        }
        for (h, &link) in p.hair_links.iter().enumerate() {
            self.beta[link] = self.z[n + h];
        }
        self.posture.update(chain, p.base_m, &self.theta);
        self.hand_force_n = self.hand_force(p);

        // The potential's gradient: springs, proximal term.
        let k = chain.stiffness_nm_per_rad();
        let rest = chain.rest_angles_rad();
        for j in 1..=n {
            self.r[j - 1] = k[j] * (self.theta[j] - rest[j]);
        }
        for (h, &link) in p.hair_links.iter().enumerate() {
            self.r[n + h] = hair_of(chain, link).spring_gradient_nm(self.beta[link]);
        }
        if let Some(prox) = p.proximal {
            for a in 0..m {
                self.r[a] += prox.gamma * self.scale[a] * (self.z[a] - prox.x_prev[a]);
            }
        }

        // Forces on the links: the tip load and every pair's, summed per link.
        self.link_force_n.fill(Vector2::zeros());
        self.link_moment_nm.fill(0.0);
        self.link_work_nm.fill(0.0);
        let tip = self.posture.end_m[n];
        let load = p.tip_force_n + self.hand_force_n;
        self.add_link_force(n, tip, load);
        for (idx, pair) in pairs.iter_mut().enumerate() {
            pair.normal_force_n = self.z[m + idx];
            pair.shear_force_n = self.z[m + c + idx];
            evaluate_geometry(
                chain,
                &p.pieces[pair.key.piece],
                &self.posture,
                &self.beta,
                &pair.key,
                &mut pair.geo,
            );
            pair.material_m = match pair.geo.hair_rate {
                Some(_) => pair.geo.point_m,
                None => self.posture.link_point(pair.material_link, pair.material_s),
            };
            pair.slip_m = pair.geo.tangent.dot(&(pair.material_m - pair.start_m));
            let force = pair.force_n();
            self.add_link_force(pair.geo.link, pair.geo.point_m, force);
            if let (Some(rate), Some(link)) = (pair.geo.hair_rate, pair.key.hair_link()) {
                let v = n + hair_index(p.hair_links, link);
                self.r[v] -= rate.dot(&force);
            }
        }
        // r_j -= sum over forces on links >= j of cross(X - p_(j-1), F), by suffix sums.
        let mut force = Vector2::zeros();
        let mut moment = 0.0;
        for j in (1..=n).rev() {
            force += self.link_force_n[j];
            moment += self.link_moment_nm[j];
            self.r[j - 1] -= moment - cross(self.posture.end_m[j - 1], force);
        }

        // Phi and the modes.
        let cn = self.c_n_per_m;
        let len = self.length_m;
        self.phi.clear();
        self.phi.resize(m + 2 * c, 0.0);
        for a in 0..m {
            let y = self.z[a] - self.r[a] / self.scale[a];
            #[cfg(test)]
            if self.frozen_modes {
                self.phi[a] = match self.held[a] {
                    Some(b) => len * (self.z[a] - b),
                    None => len * self.r[a] / self.scale[a],
                };
                continue;
            }
            // Held only on the bound itself (the line search clamps onto it): the natural
            // map would hold a coordinate anywhere its `r` is large enough, and then its
            // row, `L (x - bound)`, no longer grows with the forces in `r`; Newton's method
            // could lower the merit by driving a contact force towards infinity (every
            // joint "held" far from its stop, 1e8 N on a link) and stall there. A
            // coordinate inside its range is balanced (`L r / s`) until a step reaches
            // the stop.
            self.held[a] = if self.forced == Some(Forced::Free(a)) {
                None
            } else if y <= self.lo[a] && self.z[a] <= self.lo[a] {
                Some(self.lo[a])
            } else if y >= self.hi[a] && self.z[a] >= self.hi[a] {
                Some(self.hi[a])
            } else {
                None
            };
            self.phi[a] = match self.held[a] {
                Some(b) => len * (self.z[a] - b),
                None => len * self.r[a] / self.scale[a],
            };
        }
        for (idx, pair) in pairs.iter_mut().enumerate() {
            let (row_n, row_t) = (m + idx, m + c + idx);
            let n_min = pair.law.min_normal_n();
            let normal = pair.normal_force_n;
            // Hysteresis: a mode changes only when its condition is violated by more than
            // `hyst` (a force of `c` times 1e-11 m): at a degenerate point (a contact
            // touching with N = 0, or sliding at exactly |T| = B) the plain rule flips the
            // mode back and forth between iterations and Newton's method stalls.
            let hyst = HYSTERESIS_M * cn;
            let y_normal = normal - cn * pair.geo.gap_m - n_min;
            #[cfg(test)]
            let frozen = self.frozen_modes;
            #[cfg(not(test))]
            let frozen = false;
            // The first evaluation of a solve keeps a pressed pair pressed, and an unloaded
            // one let go unless it starts deeper in its wall than KEEP_FREE_DEPTH_M.
            let deep = pair.geo.gap_m < -KEEP_FREE_DEPTH_M;
            let keep_normal = self.keep_last_modes
                && (pair.normal_active || (pair.normal_force_n == 0.0 && !deep));
            if self.forced == Some(Forced::LetGo(idx)) {
                pair.normal_active = false;
            } else if !frozen && !keep_normal {
                pair.normal_active = if pair.normal_active {
                    y_normal > -hyst
                } else {
                    y_normal > hyst
                };
            }
            self.phi[row_n] = if pair.normal_active {
                pair.geo.gap_m
            } else {
                (normal - n_min) / cn
            };
            let bound = bound_of(pair).0;
            let shear = pair.shear_force_n;
            let y = shear - cn * pair.slip_m;
            let margin = if pair.normal_active { hyst } else { 0.0 };
            let slip = match pair.slip {
                // Letting go: the shear force follows the normal force to zero (a contact that
                // does not touch has nothing to stick to).
                _ if !pair.normal_active => free_mode(y, bound),
                Slip::Stuck if y > bound + margin => Slip::Backward,
                Slip::Stuck if y < -bound - margin => Slip::Forward,
                Slip::Stuck => Slip::Stuck,
                Slip::Backward if y >= bound - margin => Slip::Backward,
                Slip::Forward if y <= -bound + margin => Slip::Forward,
                // A slip that reverses passes through sticking: flipped straight from one
                // friction limit to the other, Newton's method cycles between the two
                // (150 links on a digitized trapezoid, replay `soak:4221:426`: +-B on one contact for dozens of iterations a step). Without
                // friction both limits are zero and the flip is harmless.
                Slip::Backward | Slip::Forward if bound > 0.0 => Slip::Stuck,
                Slip::Backward | Slip::Forward => free_mode(y, bound),
            };
            let keep_slip = self.keep_last_modes && pair.normal_active && pair.slip == Slip::Stuck;
            let slip = if frozen || keep_slip {
                pair.slip
            } else if pair.normal_active && self.forced == Some(Forced::Stuck(idx)) {
                Slip::Stuck
            } else {
                slip
            };
            pair.slip = slip;
            let sliding_bound = sliding_bound_of(pair).0;
            self.phi[row_t] = match slip {
                Slip::Stuck => pair.slip_m,
                Slip::Backward => (shear - sliding_bound) / cn,
                Slip::Forward => (shear + sliding_bound) / cn,
            };
        }
        let merit = 0.5 * self.phi.iter().map(|v| v * v).sum::<f64>();
        if merit.is_finite() {
            merit
        } else {
            f64::INFINITY
        }
    }

    /// `max |Phi|`.
    pub fn residual_m(&self) -> f64 {
        self.phi.iter().fold(
            0.0_f64,
            |a, v| if v.is_nan() { f64::NAN } else { a.max(v.abs()) },
        )
    }

    fn add_link_force(&mut self, link: usize, x: Vector2<f64>, force: Vector2<f64>) {
        self.link_force_n[link] += force;
        self.link_moment_nm[link] += cross(x, force);
        self.link_work_nm[link] += force.dot(&x);
    }
}

/// The shear bound `B` of a pair and `dB/dN` (Tresca: the bound of the held normal force).
pub(super) fn bound_of(pair: &Pair) -> (f64, f64) {
    if pair.frictionless {
        return (0.0, 0.0);
    }
    match pair.tresca_n {
        Some(held) => (pair.law.shear_bound(held).0, 0.0),
        None => pair.law.shear_bound(pair.normal_force_n),
    }
}

/// The shear bound a sliding pair's equation holds its shear force to, and its `dB/dN`:
/// [`bound_of`], except that a pressed Coulomb contact's bound is `mu N` for either sign of
/// `N`. An answer is the same (its normal row asks `N >= 0` of a pressed contact), but
/// Newton's model of a pressed contact with `N < 0` now sees the friction that may be what
/// presses it: on the 4.2.1 wall a 150-link antenna's contact rolls onto the next joint,
/// which only its own friction holds on the wall; with the bound `mu max(N, 0)`, flat there,
/// each Newton step let it go (frictionless, it needs a pull) and the next pressed it again,
/// until the solve stalled and the fixed point settled it (the sweep's Newton p99 per step
/// 43, now 4; the stress soak's relaxed steps 6,643 -> 4,970). The modes still read the
/// cone's bound, [`bound_of`].
pub(super) fn sliding_bound_of(pair: &Pair) -> (f64, f64) {
    if pair.normal_active
        && pair.tresca_n.is_none()
        && !pair.frictionless
        && let crate::contact::feature::FrictionLaw::Coulomb { mu } = pair.law
    {
        return (mu * pair.normal_force_n, mu);
    }
    bound_of(pair)
}

/// The tangent mode without hysteresis.
fn free_mode(y: f64, bound: f64) -> Slip {
    if y >= bound {
        Slip::Backward
    } else if y <= -bound {
        Slip::Forward
    } else {
        Slip::Stuck
    }
}

/// The position of `link` in `hair_links`.
pub(super) fn hair_index(hair_links: &[usize], link: usize) -> usize {
    hair_links
        .iter()
        .position(|&l| l == link)
        .unwrap_or_else(|| panic!("internal error: no hair coordinate for link {link}"))
}

/// Whether `law` makes the normal row bilateral (an anchored hair tip).
#[allow(dead_code)]
pub(super) fn is_bilateral(law: &FrictionLaw) -> bool {
    law.min_normal_n() == f64::NEG_INFINITY
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector2;

    use super::{bound_of, sliding_bound_of};
    use crate::contact::feature::FrictionLaw;
    use crate::contact::pair::{ChainPoint, Pair, PairKey};

    fn pair(normal_force_n: f64, normal_active: bool) -> Pair {
        let mut p = Pair::new(
            PairKey::point(ChainPoint::Vertex(1), 0),
            FrictionLaw::Coulomb { mu: 0.3 },
            1,
            1.0,
            Vector2::zeros(),
        );
        p.normal_force_n = normal_force_n;
        p.normal_active = normal_active;
        p
    }

    /// A pressed contact's sliding equation sees its friction for either sign of `N` (the
    /// joint that the 150-link 4.2.1 sweep's contact rolls onto is pressed only by it); the
    /// cone (`bound_of`), a contact let go and a Tresca bound are unchanged.
    #[test]
    fn a_pressed_contact_slides_at_mu_n_for_either_sign_of_n() {
        assert_eq!(sliding_bound_of(&pair(-2.0, true)), (-0.6, 0.3));
        assert_eq!(sliding_bound_of(&pair(2.0, true)), (0.6, 0.3));
        assert_eq!(bound_of(&pair(-2.0, true)), (0.0, 0.0));
        assert_eq!(sliding_bound_of(&pair(-2.0, false)), (0.0, 0.0));
        let mut held = pair(-2.0, true);
        held.tresca_n = Some(1.0);
        assert_eq!(sliding_bound_of(&held), (0.3, 0.0));
        let mut frictionless = pair(2.0, true);
        frictionless.frictionless = true;
        assert_eq!(sliding_bound_of(&frictionless), (0.0, 0.0));
    }
}
