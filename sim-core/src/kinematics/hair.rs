//! Anisotropic hairs (thesis 3.2.1, docs/model.md 7): a massless rigid rod on a torsion spring,
//! pivoting on a side boss of its link. This file holds the hair's parameters and its
//! kinematics: tip position, orientation, velocity and Jacobian.
//!
//! # Geometry (in the link's frame `C_b`: origin at the distal end, x along the link)
//! - pivot `p' = (-d, sigma w)`: `d` = `pivot_from_distal_end_m` (the thesis: `l/2`, the
//!   midpoint), `w` = `lateral_offset_m` (the segment's half-width; the thesis: 0), and
//!   `sigma = +1` for a hair on the left (`+y`, counter-clockwise) side, `-1` on the right.
//! - the hair angle `beta` is the angle between the rod and the link: `0` folded along the
//!   link, `open_angle_rad` (45 degrees on the robot) open against its stop. A rigid hair
//!   (the default) cannot open further: `0 <= beta <= open_angle_rad`. A hair with a
//!   compliant root ([`Hair::root_stiffness_nm_per_rad`]) bends past its stop under load, up
//!   to [`Hair::max_angle_rad`] (the rod folded back within [`HAIR_BEND_MARGIN_RAD`] of its
//!   link); see [`Hair::fold_limit`].
//! - rod direction `delta = sigma beta` (pointing distally) or `pi - sigma beta` (pointing
//!   proximally, the thesis's control experiment); tip `p' + l_h (cos delta, sin delta)`.
//!
//! The thesis's own parametrisation (3.2.1.1: `R' = -I`, `p' = (-l/2, 0)`, hair angle
//! `theta'` in a base frame turned by pi) is the left, distal, centred hair with
//! `beta = theta' + pi`; [`crate::kinematics::matrix_forms::seed_hair_tip`] computes it as printed.

use nalgebra::{Matrix3xX, Vector2};

use crate::kinematics::chain::finite;
use crate::kinematics::error::ChainField;
use crate::kinematics::jacobian::hybrid_into_unchecked;
use crate::kinematics::positions::frame_pose_unchecked;
use crate::kinematics::positions::{FramePoses, Pose2};
use crate::kinematics::velocity::frame_velocities;
use crate::{Chain, ChainError, Frame, JointLimit, KinematicsError};

/// How close to its own link a hair with a compliant root may bend past its stop: its angle
/// stays at most `pi - HAIR_BEND_MARGIN_RAD` (5 degrees short of the rod lying folded back
/// along the link, on the hair's own side), see [`Hair::max_angle_rad`].
pub const HAIR_BEND_MARGIN_RAD: f64 = core::f64::consts::PI / 36.0;

/// Which side of its link a hair is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum HairSide {
    /// The `+y` side of the link frame (counter-clockwise of the link axis).
    Left,
    /// The `-y` side of the link frame.
    Right,
}

/// Which way an open hair points along its link.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum HairDirection {
    /// Towards the tip of the antenna (the thesis's hairs).
    Distal,
    /// Towards the base (the thesis's control experiment, 3.3.1).
    Proximal,
}

/// The parameters of one hair (docs/model.md 7). All lengths in metres, angles in radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hair {
    /// Rod length `l_h` (> 0; 0.018 m on the robot).
    pub length_m: f64,
    /// The open angle between rod and link at rest against the stop (in `(0, pi)`; pi/4 on
    /// the robot).
    pub open_angle_rad: f64,
    /// Distance of the pivot from the link's distal end, along the link (in `[0, l_b]`; the
    /// thesis puts it at `l_b / 2`).
    pub pivot_from_distal_end_m: f64,
    /// Lateral offset of the pivot from the link axis, towards `side` (`>= 0`).
    pub lateral_offset_m: f64,
    /// The side of the link carrying the hair.
    pub side: HairSide,
    /// Which way the hair points.
    pub direction: HairDirection,
    /// Spring preload holding the hair against its open stop, N m (`>= 0`).
    pub preload_nm: f64,
    /// Stiffness of the hair's torsion spring, N m / rad (`>= 0`): folding the hair to angle
    /// `beta` takes the torque `preload_nm + stiffness_nm_per_rad (open_angle_rad - beta)`.
    pub stiffness_nm_per_rad: f64,
    /// Stiffness of the hair's root, N m / rad (`> 0` and finite), or `None` for a rigid
    /// hair (today's hair, the limit of an infinitely stiff root). With a root stiffness
    /// `k_r` the stop is compliant: past it (`beta > open_angle_rad`) the root bends, adding
    /// the energy `k_r / 2 (beta - open_angle_rad)^2` to the torsion spring's (whose terms go
    /// on as they are), up to [`Hair::max_angle_rad`]. A free hair then rests at
    /// [`Hair::rest_angle_rad`], `preload / (k_h + k_r)` past its stop.
    pub root_stiffness_nm_per_rad: Option<f64>,
}

impl Hair {
    /// The thesis's hair on a link of length `link_length_m`: 18 mm, open at 45 degrees,
    /// pointing distally, pivot on the axis at the link's midpoint, on the left side. The
    /// thesis gives no spring constants (a 0.1 mm Nitinol wire swings the hair open, 3.3.1.1);
    /// this takes a light spring: preload `1e-4` N m (5.6 mN at the tip of an open hair) and
    /// stiffness `2e-4` N m / rad.
    pub fn seed(link_length_m: f64) -> Hair {
        Hair {
            length_m: 0.018,
            open_angle_rad: core::f64::consts::FRAC_PI_4,
            pivot_from_distal_end_m: 0.5 * link_length_m,
            lateral_offset_m: 0.0,
            side: HairSide::Left,
            direction: HairDirection::Distal,
            preload_nm: 1e-4,
            stiffness_nm_per_rad: 2e-4,
            root_stiffness_nm_per_rad: None,
        }
    }

    /// The largest hair angle, radians: `open_angle_rad` for a rigid hair; with a compliant
    /// root, `pi - HAIR_BEND_MARGIN_RAD` (the root bent until the rod is folded back within
    /// [`HAIR_BEND_MARGIN_RAD`] of its link; never below `open_angle_rad`).
    pub fn max_angle_rad(&self) -> f64 {
        match self.root_stiffness_nm_per_rad {
            None => self.open_angle_rad,
            Some(_) => (core::f64::consts::PI - HAIR_BEND_MARGIN_RAD).max(self.open_angle_rad),
        }
    }

    /// The angle of a free hair, radians: against its stop (`open_angle_rad`) if rigid; with
    /// a compliant root, where the preload balances the root's bending, `open_angle_rad +
    /// preload / (k_h + k_r)` (at most [`Self::max_angle_rad`]).
    pub fn rest_angle_rad(&self) -> f64 {
        match self.root_stiffness_nm_per_rad {
            None => self.open_angle_rad,
            Some(k_r) => (self.open_angle_rad
                + self.preload_nm / (self.stiffness_nm_per_rad + k_r))
                .min(self.max_angle_rad()),
        }
    }

    /// Whether the hair at `beta_rad` is open against its stop, or bent beyond it (a
    /// compliant root), within `tolerance_rad`.
    pub fn on_stop(&self, beta_rad: f64, tolerance_rad: f64) -> bool {
        beta_rad >= self.open_angle_rad - tolerance_rad
    }

    /// The range of the hair angle: `0 <= beta <= max_angle_rad` (`open_angle_rad` for a
    /// rigid hair), as a [`JointLimit`] so the limit map `g` applies to hairs too (thesis
    /// 3.2.1: `theta' = g'(q')`).
    pub fn fold_limit(&self) -> JointLimit {
        JointLimit::new(0.0, self.max_angle_rad())
    }

    fn sigma(&self) -> f64 {
        match self.side {
            HairSide::Left => 1.0,
            HairSide::Right => -1.0,
        }
    }

    /// `d delta / d beta`: `+-1` by side and direction.
    pub fn direction_rate(&self) -> f64 {
        match self.direction {
            HairDirection::Distal => self.sigma(),
            HairDirection::Proximal => -self.sigma(),
        }
    }

    /// The pivot in the link frame, `(-d, sigma w)`.
    pub fn pivot_in_link_m(&self) -> Vector2<f64> {
        Vector2::new(
            -self.pivot_from_distal_end_m,
            self.sigma() * self.lateral_offset_m,
        )
    }

    /// The rod direction angle `delta` in the link frame for hair angle `beta_rad`.
    pub fn direction_in_link_rad(&self, beta_rad: f64) -> f64 {
        match self.direction {
            HairDirection::Distal => self.sigma() * beta_rad,
            HairDirection::Proximal => core::f64::consts::PI - self.sigma() * beta_rad,
        }
    }

    /// The tip in the link frame for hair angle `beta_rad`.
    pub fn tip_in_link_m(&self, beta_rad: f64) -> Vector2<f64> {
        let (sn, cs) = self.direction_in_link_rad(beta_rad).sin_cos();
        self.pivot_in_link_m() + self.length_m * Vector2::new(cs, sn)
    }

    /// `d tip / d beta` in the link frame: `l_h (d delta / d beta) (-sin delta, cos delta)`.
    pub fn tip_rate_in_link_m(&self, beta_rad: f64) -> Vector2<f64> {
        let (sn, cs) = self.direction_in_link_rad(beta_rad).sin_cos();
        self.length_m * self.direction_rate() * Vector2::new(-sn, cs)
    }

    /// The spring's torque on the hair at angle `beta_rad`, as a gradient: `dU_h / d beta =
    /// -preload - k_h (open - beta)` (negative: it pushes the hair open), with
    /// `U_h = preload (open - beta) + k_h / 2 (open - beta)^2`; with a compliant root, past
    /// the stop, plus the root's `k_r (beta - open)`.
    pub fn spring_gradient_nm(&self, beta_rad: f64) -> f64 {
        let spring =
            -self.preload_nm - self.stiffness_nm_per_rad * (self.open_angle_rad - beta_rad);
        match self.root_stiffness_nm_per_rad {
            Some(k_r) if beta_rad > self.open_angle_rad => {
                spring + k_r * (beta_rad - self.open_angle_rad)
            }
            _ => spring,
        }
    }

    /// The spring energy `U_h(beta)`, joules (zero when open against the stop); with a
    /// compliant root, past the stop, plus the root's `k_r / 2 (beta - open)^2`.
    pub fn spring_energy_j(&self, beta_rad: f64) -> f64 {
        let folded = self.open_angle_rad - beta_rad;
        let spring = self.preload_nm * folded + 0.5 * self.stiffness_nm_per_rad * folded * folded;
        match self.root_stiffness_nm_per_rad {
            Some(k_r) if folded < 0.0 => spring + 0.5 * k_r * folded * folded,
            _ => spring,
        }
    }

    /// The spring's stiffness at `beta_rad`, `d^2 U_h / d beta^2`, N m / rad: `k_h`, plus the
    /// root's `k_r` at and past the stop (at the stop itself, the side the preload pushes the
    /// hair to).
    pub fn spring_hessian_nm_per_rad(&self, beta_rad: f64) -> f64 {
        match self.root_stiffness_nm_per_rad {
            Some(k_r) if beta_rad >= self.open_angle_rad => self.stiffness_nm_per_rad + k_r,
            _ => self.stiffness_nm_per_rad,
        }
    }

    pub(crate) fn validate(&self, link: usize, link_length_m: f64) -> Result<(), ChainError> {
        let fields = [
            (ChainField::HairLength, self.length_m),
            (ChainField::HairOpenAngle, self.open_angle_rad),
            (ChainField::HairPivot, self.pivot_from_distal_end_m),
            (ChainField::HairLateralOffset, self.lateral_offset_m),
            (ChainField::HairPreload, self.preload_nm),
            (ChainField::HairStiffness, self.stiffness_nm_per_rad),
        ];
        for (field, value) in fields {
            finite(field, link, value)?;
        }
        let bad = |field, value| {
            Err(ChainError::HairOutOfRange {
                field,
                index: link,
                value,
            })
        };
        if self.length_m <= 0.0 {
            return bad(ChainField::HairLength, self.length_m);
        }
        if !(self.open_angle_rad > 0.0 && self.open_angle_rad < core::f64::consts::PI) {
            return bad(ChainField::HairOpenAngle, self.open_angle_rad);
        }
        if !(0.0..=link_length_m).contains(&self.pivot_from_distal_end_m) {
            return bad(ChainField::HairPivot, self.pivot_from_distal_end_m);
        }
        if self.lateral_offset_m < 0.0 {
            return bad(ChainField::HairLateralOffset, self.lateral_offset_m);
        }
        if self.preload_nm < 0.0 {
            return bad(ChainField::HairPreload, self.preload_nm);
        }
        if self.stiffness_nm_per_rad < 0.0 {
            return bad(ChainField::HairStiffness, self.stiffness_nm_per_rad);
        }
        if let Some(k_r) = self.root_stiffness_nm_per_rad
            && !(k_r > 0.0 && k_r.is_finite())
        {
            return bad(ChainField::HairRootStiffness, k_r);
        }
        Ok(())
    }
}

/// Where a hair is, relative to a spatial frame `C_s`, written in `C_s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HairPose {
    /// The link carrying the hair.
    pub link: usize,
    /// The pivot, metres.
    pub pivot_m: Vector2<f64>,
    /// The tip, metres.
    pub tip_m: Vector2<f64>,
    /// The rod's direction (pivot to tip) from `C_s`'s x-axis, radians.
    pub angle_rad: f64,
}

/// How fast a hair moves relative to `C_s`, written in `C_s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HairVelocity {
    /// The link carrying the hair.
    pub link: usize,
    /// The tip velocity, m/s.
    pub tip_m_per_s: Vector2<f64>,
    /// The rod's angular velocity, rad/s.
    pub angular_rad_per_s: f64,
}

fn hair_of(chain: &Chain, link: usize) -> Result<&Hair, KinematicsError> {
    match chain.hairs().get(link) {
        None => Err(KinematicsError::LinkOutOfRange {
            argument: "link",
            index: link,
            n: chain.n(),
        }),
        Some(None) => Err(KinematicsError::NoHair { link }),
        Some(Some(h)) => Ok(h),
    }
}

fn pose_from_link(hair: &Hair, link: usize, link_pose: &Pose2, beta: f64) -> HairPose {
    HairPose {
        link,
        pivot_m: link_pose.transform_point(&hair.pivot_in_link_m()),
        tip_m: link_pose.transform_point(&hair.tip_in_link_m(beta)),
        angle_rad: link_pose.angle_rad + hair.direction_in_link_rad(beta),
    }
}

/// The pose of the hair on link `link` relative to `s` in `O(|link - s|)`, no allocation.
/// `hair_angles_rad` has one entry per link `0..=n` (entries of links without a hair are
/// ignored), like the thesis's `theta'`.
///
/// # Errors
/// [`KinematicsError::WrongLength`] for `theta` or `hair_angles_rad` not of length `n + 1`,
/// [`KinematicsError::FrameOutOfRange`] for `s`, [`KinematicsError::LinkOutOfRange`] or
/// [`KinematicsError::NoHair`] for `link`.
pub fn hair_pose(
    chain: &Chain,
    theta: &[f64],
    hair_angles_rad: &[f64],
    s: Frame,
    link: usize,
) -> Result<HairPose, KinematicsError> {
    chain.check_len("theta", theta.len())?;
    chain.check_len("hair_angles_rad", hair_angles_rad.len())?;
    s.check(chain.n(), "s")?;
    let hair = hair_of(chain, link)?;
    let link_pose = frame_pose_unchecked(chain.link_lengths_m(), theta, s, Frame::link(link));
    Ok(pose_from_link(
        hair,
        link,
        &link_pose,
        hair_angles_rad[link],
    ))
}

/// The poses of every hair relative to `s`, ordered by link, in `O(n)`.
///
/// # Errors
/// As [`hair_pose`] (without the `link` errors).
pub fn hair_poses(
    chain: &Chain,
    theta: &[f64],
    hair_angles_rad: &[f64],
    s: Frame,
) -> Result<Vec<HairPose>, KinematicsError> {
    chain.check_len("hair_angles_rad", hair_angles_rad.len())?;
    let poses = crate::frame_poses(chain, theta, s)?;
    Ok(hairs_from_poses(chain, &poses, hair_angles_rad))
}

fn hairs_from_poses(chain: &Chain, poses: &FramePoses, hair_angles_rad: &[f64]) -> Vec<HairPose> {
    chain
        .hairs()
        .iter()
        .enumerate()
        .filter_map(|(link, hair)| {
            let hair = hair.as_ref()?;
            let slot = link + 1;
            let link_pose = Pose2 {
                position_m: poses.positions_m.column(slot).into_owned(),
                angle_rad: poses.angles_rad[slot],
            };
            Some(pose_from_link(
                hair,
                link,
                &link_pose,
                hair_angles_rad[link],
            ))
        })
        .collect()
}

/// The velocities of every hair relative to `s`, ordered by link, in `O(n)`: tip velocity
/// `p_dot_sb + omega_sb R90 R_sb p'_b + R_sb (dp'_b/dbeta) beta_dot` and rod angular velocity
/// `omega_sb + d delta/d beta beta_dot`. With `hair_rates = 0` this is the thesis's 3.2.1.3.
///
/// # Errors
/// [`KinematicsError::WrongLength`] for any vector not of length `n + 1`,
/// [`KinematicsError::FrameOutOfRange`] for `s`.
pub fn hair_velocities(
    chain: &Chain,
    theta: &[f64],
    theta_dot: &[f64],
    hair_angles_rad: &[f64],
    hair_rates_rad_per_s: &[f64],
    s: Frame,
) -> Result<Vec<HairVelocity>, KinematicsError> {
    chain.check_len("hair_angles_rad", hair_angles_rad.len())?;
    chain.check_len("hair_rates_rad_per_s", hair_rates_rad_per_s.len())?;
    let poses = crate::frame_poses(chain, theta, s)?;
    let vels = frame_velocities(chain, theta, theta_dot, s)?;
    Ok(chain
        .hairs()
        .iter()
        .enumerate()
        .filter_map(|(link, hair)| {
            let hair = hair.as_ref()?;
            let slot = link + 1;
            let (sn, cs) = poses.angles_rad[slot].sin_cos();
            let rot = |v: Vector2<f64>| Vector2::new(cs * v.x - sn * v.y, sn * v.x + cs * v.y);
            let r90 = |v: Vector2<f64>| Vector2::new(-v.y, v.x);
            let beta = hair_angles_rad[link];
            let beta_dot = hair_rates_rad_per_s[link];
            let omega = vels.angular_rad_per_s[slot];
            let tip_rel = rot(hair.tip_in_link_m(beta));
            let (dsn, dcs) = hair.direction_in_link_rad(beta).sin_cos();
            let rate = hair.direction_rate();
            let dtip_dbeta = rot(hair.length_m * rate * Vector2::new(-dsn, dcs));
            Some(HairVelocity {
                link,
                tip_m_per_s: vels.linear_m_per_s.column(slot).into_owned()
                    + omega * r90(tip_rel)
                    + beta_dot * dtip_dbeta,
                angular_rad_per_s: omega + rate * beta_dot,
            })
        })
        .collect())
}

/// The hybrid Jacobian of the tip of the hair on link `link` relative to `s`, `3 x (n+2)`:
/// columns `0..=n` are `d(tip, rod angle)/d theta_j`, column `n + 1` is `d/d beta_link`.
/// `O(n)`.
///
/// # Errors
/// As [`hair_pose`].
pub fn hair_tip_jacobian(
    chain: &Chain,
    theta: &[f64],
    hair_angles_rad: &[f64],
    s: Frame,
    link: usize,
) -> Result<Matrix3xX<f64>, KinematicsError> {
    chain.check_len("theta", theta.len())?;
    chain.check_len("hair_angles_rad", hair_angles_rad.len())?;
    let n = chain.n();
    s.check(n, "s")?;
    let hair = hair_of(chain, link)?;
    let mut out = Matrix3xX::zeros(n + 2);
    let b = Frame::link(link);
    let (_, psi_b) = hybrid_into_unchecked(
        chain.link_lengths_m(),
        theta,
        s,
        b,
        &mut out.as_mut_slice()[..3 * (n + 1)],
    );
    let (sn, cs) = psi_b.sin_cos();
    let rot = |v: Vector2<f64>| Vector2::new(cs * v.x - sn * v.y, sn * v.x + cs * v.y);
    let beta = hair_angles_rad[link];
    let tip_rel = rot(hair.tip_in_link_m(beta));
    for mut col in out.columns_mut(0, n + 1).column_iter_mut() {
        // + alpha_j R90 (R_sb p'_b); alpha_j = col[2]
        let a = col[2];
        col[0] -= a * tip_rel.y;
        col[1] += a * tip_rel.x;
    }
    let (dsn, dcs) = hair.direction_in_link_rad(beta).sin_cos();
    let rate = hair.direction_rate();
    let d = rot(hair.length_m * rate * Vector2::new(-dsn, dcs));
    out[(0, n + 1)] = d.x;
    out[(1, n + 1)] = d.y;
    out[(2, n + 1)] = rate;
    Ok(out)
}

#[cfg(test)]
mod tests {
    //! The hair spring's energy, gradient and Hessian against central differences, rigid
    //! and with a compliant root (before, past and at the stop), and the root's validation.
    #![allow(clippy::unwrap_used)]

    use super::*;
    use proptest::prelude::*;

    fn compliant(k_r: f64) -> Hair {
        Hair {
            root_stiffness_nm_per_rad: Some(k_r),
            ..Hair::seed(0.04)
        }
    }

    proptest! {
        #[test]
        fn gradient_and_hessian_match_central_differences(
            log_k_r in -4.0..2.0f64,
            preload in 0.0..1e-3f64,
            k_h in 0.0..1e-2f64,
            offset in -0.7..1.5f64,
            rigid in prop::bool::ANY,
        ) {
            let hair = Hair {
                preload_nm: preload,
                stiffness_nm_per_rad: k_h,
                root_stiffness_nm_per_rad: (!rigid).then(|| 10f64.powf(log_k_r)),
                ..Hair::seed(0.04)
            };
            let beta = hair.open_angle_rad + offset;
            // Central differences of a piecewise quadratic are exact away from the stop.
            prop_assume!((beta - hair.open_angle_rad).abs() > 1e-4);
            let h = 1e-6;
            let fd_grad = (hair.spring_energy_j(beta + h) - hair.spring_energy_j(beta - h)) / (2.0 * h);
            let grad = hair.spring_gradient_nm(beta);
            prop_assert!((fd_grad - grad).abs() <= 1e-7 * (1.0 + grad.abs()), "{fd_grad} vs {grad}");
            let fd_hess =
                (hair.spring_gradient_nm(beta + h) - hair.spring_gradient_nm(beta - h)) / (2.0 * h);
            let hess = hair.spring_hessian_nm_per_rad(beta);
            prop_assert!((fd_hess - hess).abs() <= 1e-6 * (1.0 + hess.abs()), "{fd_hess} vs {hess}");
            if offset > 0.0 && !rigid {
                prop_assert_eq!(hess, k_h + 10f64.powf(log_k_r));
            } else {
                prop_assert_eq!(hess, k_h);
            }
        }
    }

    #[test]
    fn at_the_stop_the_root_adds_nothing_but_its_stiffness() {
        let rigid = Hair::seed(0.04);
        let hair = compliant(0.05);
        let open = hair.open_angle_rad;
        assert_eq!(hair.spring_energy_j(open), 0.0);
        assert_eq!(
            hair.spring_gradient_nm(open),
            rigid.spring_gradient_nm(open)
        );
        assert_eq!(hair.spring_hessian_nm_per_rad(open), 0.05 + 2e-4);
        // The gradient is continuous through the stop.
        let below = hair.spring_gradient_nm(open - 1e-9);
        let above = hair.spring_gradient_nm(open + 1e-9);
        assert!((above - below).abs() < 1e-10);
        // A free hair rests where the gradient vanishes, past its stop.
        let rest = hair.rest_angle_rad();
        assert!(rest > open);
        assert!(hair.spring_gradient_nm(rest).abs() < 1e-18);
        assert!(hair.on_stop(rest, 0.0) && !hair.on_stop(open - 1e-6, 0.0));
    }

    #[test]
    fn a_rigid_hair_keeps_its_stop_as_its_limit_and_rest() {
        let hair = Hair::seed(0.04);
        assert_eq!(hair.max_angle_rad(), hair.open_angle_rad);
        assert_eq!(hair.rest_angle_rad(), hair.open_angle_rad);
        assert_eq!(hair.fold_limit(), JointLimit::new(0.0, hair.open_angle_rad));
        let bent = compliant(1.0);
        assert_eq!(
            bent.max_angle_rad(),
            core::f64::consts::PI - HAIR_BEND_MARGIN_RAD
        );
        assert_eq!(bent.fold_limit().ccw_rad, bent.max_angle_rad());
    }

    #[test]
    fn a_root_stiffness_must_be_positive_and_finite() {
        for k_r in [0.0, -1e-3, f64::NAN, f64::INFINITY] {
            let e = compliant(k_r).validate(3, 0.04).unwrap_err();
            assert!(
                matches!(
                    e,
                    ChainError::HairOutOfRange {
                        field: ChainField::HairRootStiffness,
                        index: 3,
                        ..
                    }
                ),
                "{k_r}: {e:?}"
            );
            assert!(
                e.to_string().contains("hair.root_stiffness_nm_per_rad[3]"),
                "{e}"
            );
        }
        compliant(1e-6).validate(3, 0.04).unwrap();
        assert!(Chain::builder(2).hair(1, compliant(0.0)).build().is_err());
    }
}
