//! An independent check of a quasi-static state (model.md 6: "every step is checked"):
//! recomputed from the posture and the reported contact forces with the crate's own
//! kinematics ([`crate::frame_poses`], [`crate::hair_poses`]), not from the solver's
//! equations.

use nalgebra::Vector2;

use super::feature::{Contact, Feature, FrictionLaw};
use super::quasistatic::QuasiStatic;
use crate::{Frame, hair_poses};

/// How far a state is from a frictional-contact equilibrium; every field is `0` for an
/// exact one.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EquilibriumCheck {
    /// The largest torque imbalance at a joint strictly inside its limits, or at a hair in
    /// contact strictly inside its range, N m.
    pub torque_residual_nm: f64,
    /// The largest stop torque of the wrong sign (a stop that would have to pull), N m.
    pub limit_sign_violation_nm: f64,
    /// The deepest penetration of a link or a hair tip into a wall, metres.
    pub penetration_m: f64,
    /// The largest violation of `N >= N_min` or `|T| <= bound` (the friction cone, or an
    /// anchored hair's holds), newtons.
    pub cone_violation_n: f64,
    /// The largest gap of a contact that carries a force (complementarity), metres.
    pub separation_m: f64,
}

/// A joint or hair this close to a limit is on it (the solver ends within its tolerance of
/// a limit, about `1e-12` rad).
const ON_LIMIT_RAD: f64 = 1e-9;

/// Forces below this are zero for the complementarity check (rounding of forces of order
/// 0.01-1 N).
const FORCE_ZERO_N: f64 = 1e-12;

impl EquilibriumCheck {
    /// Whether every residual is within its tolerance (torques in N m, lengths in m,
    /// forces in N).
    pub fn holds(&self, torque_nm: f64, length_m: f64, force_n: f64) -> bool {
        self.torque_residual_nm <= torque_nm
            && self.limit_sign_violation_nm <= torque_nm
            && self.penetration_m <= length_m
            && self.cone_violation_n <= force_n
            && self.separation_m <= length_m
    }
}

impl QuasiStatic {
    /// Re-derives the equilibrium conditions of the current state: the torque balance at
    /// every joint and hair from the contact forces reported by [`Self::contacts`] (and the
    /// tip load), the joint-limit multipliers' signs, non-penetration of every link and
    /// hair tip, the friction cone and the complementarity of forces and gaps.
    pub fn check(&self) -> EquilibriumCheck {
        let mut out = EquilibriumCheck::default();
        let chain = self.chain();
        let n = chain.n();
        let theta = self.theta_rad();
        let base = self.base_m();
        let Ok(poses) = crate::frame_poses(chain, theta, Frame::GROUND) else {
            out.torque_residual_nm = f64::INFINITY;
            return out;
        };
        let ends: Vec<Vector2<f64>> = (0..=n)
            .map(|i| base + poses.position_m(Frame::link(i)).unwrap_or_default())
            .collect();
        let start_of = |link: usize| if link == 0 { base } else { ends[link - 1] };
        let hairs =
            hair_poses(chain, theta, self.hair_angles_rad(), Frame::GROUND).unwrap_or_default();
        let hair_tip = |link: usize| {
            hairs
                .iter()
                .find(|h| h.link == link)
                .map(|h| (base + h.pivot_m, base + h.tip_m))
        };
        let contacts = self.contacts();
        // Where each contact's force acts, from the feature alone.
        let point_of = |c: &Contact| match c.feature {
            Feature::Vertex { link } => Some(ends[link]),
            Feature::Link { link } => Some(start_of(link) + (ends[link] - start_of(link)) * c.s),
            Feature::HairTip { link } => hair_tip(link).map(|(_, tip)| tip),
        };
        // Torques about each joint j (at p_(j-1)) of the forces on links >= j.
        let k = chain.stiffness_nm_per_rad();
        let rest = chain.rest_angles_rad();
        let limits = chain.joint_limits();
        let mut loads: Vec<(usize, Vector2<f64>, Vector2<f64>)> = Vec::new();
        for c in &contacts {
            match point_of(c) {
                Some(x) => loads.push((c.feature.link(), x, c.force_n())),
                None => out.torque_residual_nm = f64::INFINITY,
            }
        }
        let tip_force = self.tip_force_n() + self.hand_force_n();
        if tip_force != Vector2::zeros() {
            loads.push((n, ends[n], tip_force));
        }
        for j in 1..=n {
            let joint = ends[j - 1];
            let mut tau = k[j] * (theta[j] - rest[j]);
            for &(link, x, f) in &loads {
                if link >= j {
                    let arm = x - joint;
                    tau -= arm.x * f.y - arm.y * f.x;
                }
            }
            let lim = limits[j];
            let on_cw = theta[j] <= lim.cw_rad + ON_LIMIT_RAD;
            let on_ccw = theta[j] >= lim.ccw_rad - ON_LIMIT_RAD;
            if on_cw && on_ccw {
                continue;
            } else if on_cw {
                out.limit_sign_violation_nm = out.limit_sign_violation_nm.max(-tau);
            } else if on_ccw {
                out.limit_sign_violation_nm = out.limit_sign_violation_nm.max(tau);
            } else {
                out.torque_residual_nm = out.torque_residual_nm.max(tau.abs());
            }
        }
        // Hairs in contact: spring torque against the contact force's moment about the pivot.
        for c in &contacts {
            let Feature::HairTip { link } = c.feature else {
                continue;
            };
            let (Some((pivot, tip)), Some(Some(hair))) = (hair_tip(link), chain.hairs().get(link))
            else {
                continue;
            };
            let beta = self.hair_angles_rad()[link];
            // d tip / d beta = rate * R90 (tip - pivot).
            let arm = tip - pivot;
            let rate = Vector2::new(-arm.y, arm.x) * hair.direction_rate();
            let g = hair.spring_gradient_nm(beta) - rate.dot(&c.force_n());
            if beta >= hair.open_angle_rad - ON_LIMIT_RAD {
                out.limit_sign_violation_nm = out.limit_sign_violation_nm.max(g);
            } else if beta <= ON_LIMIT_RAD {
                out.limit_sign_violation_nm = out.limit_sign_violation_nm.max(-g);
            } else {
                out.torque_residual_nm = out.torque_residual_nm.max(g.abs());
            }
        }
        // Non-penetration of every link and hair tip.
        for wall in self.walls() {
            for (link, end) in ends.iter().enumerate() {
                let sc = wall.segment_contact(&start_of(link), end);
                out.penetration_m = out.penetration_m.max(-sc.wall.gap_m);
            }
            for h in &hairs {
                let gap = wall.signed_distance(&(base + h.tip_m)).gap_m;
                out.penetration_m = out.penetration_m.max(-gap);
            }
        }
        // Cone and complementarity.
        for c in &contacts {
            let (min_n, bound) = match c.law {
                FrictionLaw::Coulomb { mu } => (0.0, mu * c.normal_force_n.max(0.0)),
                FrictionLaw::Anchored {
                    hold_shear_n,
                    hold_tension_n,
                } => (-hold_tension_n, hold_shear_n),
            };
            out.cone_violation_n = out
                .cone_violation_n
                .max(min_n - c.normal_force_n)
                .max(c.shear_force_n.abs() - bound);
            if let Some(x) = point_of(c)
                && c.force_n().norm() > FORCE_ZERO_N
            {
                let gap = self.walls()[c.wall].signed_distance(&x).gap_m;
                out.separation_m = out.separation_m.max(gap.abs());
            }
        }
        out.penetration_m = out.penetration_m.max(0.0);
        out
    }
}
