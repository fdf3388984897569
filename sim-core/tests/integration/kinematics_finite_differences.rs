//! Every Jacobian and velocity of sim-core equals central finite differences of the
//! positions; the limit map's derivatives equal finite differences of the map (settling the
//! thesis's sign slip in 2.2.4.5-6, docs/model.md 3); the energy's gradient and Hessian equal finite
//! differences of the energy and gradient, in theta and in q.
//!
//! Tolerances are relative to the magnitude of what is differenced: position rows to the
//! chain's length, angle rows to the sum of |theta| (the size of the frame angles), each
//! times the joint rates for velocities. A central difference's rounding error is
//! `eps |f| / h` of the function's own magnitude, so one scale for both kinds of row was
//! wrong in units and failed on a 10 mm chain at theta_0 = -3.07 rad (the committed seed).
#![allow(clippy::unwrap_used)]

use std::f64::consts::FRAC_PI_4;

use crate::common_kinematics;

use common_kinematics::{Case, assert_close, assert_close_planar, case, central_jacobian};
use nalgebra::{DMatrix, DVector, Matrix3xX, Vector2};
use proptest::prelude::*;
use sim_core::kinematics::hair::{hair_tip_jacobian, hair_velocities};
use sim_core::kinematics::jacobian::{
    all_jacobians, body_jacobian, hybrid_jacobian, spatial_jacobian, tip_jacobian,
};
use sim_core::kinematics::joint_limits::{d2theta_dq2, dtheta_dq, theta_from_q};
use sim_core::kinematics::positions::frame_pose;
use sim_core::kinematics::velocity::{frame_velocities, frame_velocity};
use sim_core::statics::energy::Potential;
use sim_core::{
    Chain, Frame, Hair, HairDirection, HairSide, JointLimit, frame_poses, hair_poses, tip_pose,
};

const H: f64 = 1e-6;
const TOL: f64 = 1e-8;

/// `(p_sb, theta_sb)` as a 3-vector.
fn pose3(chain: &Chain, theta: &[f64], s: Frame, b: Frame) -> Vec<f64> {
    let p = frame_pose(chain, theta, s, b).unwrap();
    vec![p.position_m.x, p.position_m.y, p.angle_rad]
}

fn to_dmatrix(j: &Matrix3xX<f64>) -> DMatrix<f64> {
    DMatrix::from_column_slice(3, j.ncols(), j.as_slice())
}

fn check_pair_jacobians(c: &Case) -> Result<(), TestCaseError> {
    let (chain, s, b) = (&c.chain, c.s, c.b);
    let fd = central_jacobian(&c.theta, H, |t| pose3(chain, t, s, b));
    let (l, a) = (c.length_scale(), c.angle_scale());
    let hybrid = hybrid_jacobian(chain, &c.theta, s, b).unwrap();
    assert_close_planar("hybrid J_sb vs FD", &to_dmatrix(&hybrid), &fd, TOL, l, a)?;

    // Body: the same derivative written in C_b.
    let pose = frame_pose(chain, &c.theta, s, b).unwrap();
    let rt = pose.rotation().transpose();
    let mut fd_body = fd.clone();
    for mut col in fd_body.column_iter_mut() {
        let v = rt * Vector2::new(col[0], col[1]);
        col[0] = v.x;
        col[1] = v.y;
    }
    let body = body_jacobian(chain, &c.theta, s, b).unwrap();
    assert_close_planar("body J_b vs FD", &to_dmatrix(&body), &fd_body, TOL, l, a)?;

    // Spatial: d p_sb - d theta_sb R90 p_sb.
    let p = pose.position_m;
    let mut fd_spatial = fd.clone();
    for mut col in fd_spatial.column_iter_mut() {
        let w = col[2];
        col[0] += w * p.y;
        col[1] -= w * p.x;
    }
    let spatial = spatial_jacobian(chain, &c.theta, s, b).unwrap();
    assert_close_planar(
        "spatial J_sigma vs FD",
        &to_dmatrix(&spatial),
        &fd_spatial,
        TOL,
        l,
        a,
    )?;

    // Single-frame velocity: the finite-difference Jacobian of the pose times theta_dot.
    let fd_v = &fd * DVector::from_column_slice(&c.theta_dot);
    let v = frame_velocity(chain, &c.theta, &c.theta_dot, s, b).unwrap();
    let v3 = DVector::from_vec(vec![
        v.linear_m_per_s.x,
        v.linear_m_per_s.y,
        v.angular_rad_per_s,
    ]);
    assert_close_planar(
        "frame velocity vs FD",
        &v3,
        &fd_v,
        TOL,
        c.velocity_scale(),
        c.angle_scale() * c.angular_velocity_scale(),
    )?;
    Ok(())
}

fn check_tip(c: &Case) -> Result<(), TestCaseError> {
    let chain = &c.chain;
    let fd = central_jacobian(&c.theta, H, |t| {
        let p = tip_pose(chain, t).unwrap();
        vec![p.position_m.x, p.position_m.y, p.angle_rad]
    });
    let j = tip_jacobian(chain, &c.theta).unwrap();
    assert_close_planar(
        "tip Jacobian vs FD",
        &to_dmatrix(&j),
        &fd,
        TOL,
        c.length_scale(),
        c.angle_scale(),
    )
}

/// All frames: velocities along theta_dot and the stacked Jacobians.
fn check_all_frames(c: &Case) -> Result<(), TestCaseError> {
    let chain = &c.chain;
    let s = c.s;
    let stacked = |t: &[f64]| -> Vec<f64> {
        let p = frame_poses(chain, t, s).unwrap();
        let mut out = Vec::with_capacity(3 * p.angles_rad.len());
        for (k, a) in p.angles_rad.iter().enumerate() {
            out.extend([p.positions_m[(0, k)], p.positions_m[(1, k)], *a]);
        }
        out
    };
    let fd = central_jacobian(&c.theta, H, stacked);
    let all = all_jacobians(chain, &c.theta, s).unwrap();
    assert_close_planar(
        "all Jacobians vs FD",
        &all,
        &fd,
        TOL,
        c.length_scale(),
        c.angle_scale(),
    )?;

    let v = frame_velocities(chain, &c.theta, &c.theta_dot, s).unwrap();
    let fd_v = &fd * DVector::from_column_slice(&c.theta_dot);
    let mut v3 = DVector::zeros(fd_v.len());
    for k in 0..v.angular_rad_per_s.len() {
        v3[3 * k] = v.linear_m_per_s[(0, k)];
        v3[3 * k + 1] = v.linear_m_per_s[(1, k)];
        v3[3 * k + 2] = v.angular_rad_per_s[k];
    }
    assert_close_planar(
        "all frame velocities vs FD",
        &v3,
        &fd_v,
        TOL,
        c.velocity_scale(),
        c.angle_scale() * c.angular_velocity_scale(),
    )
}

fn hair_strategy() -> impl Strategy<Value = Hair> {
    (
        0.005..0.03f64,
        0.2..1.2f64,
        0.0..1.0f64,
        0.0..0.004f64,
        prop::bool::ANY,
        prop::bool::ANY,
    )
        .prop_map(|(length_m, open, pivot_frac, offset, left, distal)| Hair {
            length_m,
            open_angle_rad: open,
            // scaled to the link below
            pivot_from_distal_end_m: pivot_frac,
            lateral_offset_m: offset,
            side: if left {
                HairSide::Left
            } else {
                HairSide::Right
            },
            direction: if distal {
                HairDirection::Distal
            } else {
                HairDirection::Proximal
            },
            preload_nm: 0.0,
            stiffness_nm_per_rad: 0.0,
            root_stiffness_nm_per_rad: None,
        })
}

/// Hairs on a random subset of links, with angles and rates.
fn hair_case() -> impl Strategy<Value = (Case, Chain, Vec<f64>, Vec<f64>)> {
    case(1..=24).prop_flat_map(|c| {
        let m = c.chain.dof();
        (
            Just(c),
            prop::collection::vec(prop::option::weighted(0.7, hair_strategy()), m),
            prop::collection::vec(0.0..1.2f64, m),
            prop::collection::vec(-2.0..2.0f64, m),
        )
            .prop_map(|(c, hairs, betas, rates)| {
                let mut builder = Chain::builder(c.chain.n())
                    .link_lengths_m(c.chain.link_lengths_m().to_vec())
                    .base_angle_rad(c.chain.base_angle_rad());
                for (link, hair) in hairs.into_iter().enumerate() {
                    if let Some(mut h) = hair {
                        h.pivot_from_distal_end_m *= c.chain.link_lengths_m()[link];
                        builder = builder.hair(link, h);
                    }
                }
                let chain = builder.build().unwrap();
                (c, chain, betas, rates)
            })
    })
}

fn check_hairs(c: &Case, chain: &Chain, betas: &[f64], rates: &[f64]) -> Result<(), TestCaseError> {
    let m = chain.dof();
    let s = c.s;
    // Hair tips and rod angles as a function of (theta, beta).
    let f = |x: &[f64]| -> Vec<f64> {
        let poses = hair_poses(chain, &x[..m], &x[m..], s).unwrap();
        poses
            .iter()
            .flat_map(|h| [h.tip_m.x, h.tip_m.y, h.angle_rad])
            .collect()
    };
    let mut x = c.theta.clone();
    x.extend_from_slice(betas);
    let fd = central_jacobian(&x, H, f);
    let mut xdot = c.theta_dot.clone();
    xdot.extend_from_slice(rates);
    let fd_v = &fd * DVector::from_vec(xdot);
    let vels = hair_velocities(chain, &c.theta, &c.theta_dot, betas, rates, s).unwrap();
    let hair_rates: f64 = rates.iter().map(|r| r.abs()).sum();
    let scale = c.velocity_scale() + 0.03 * hair_rates;
    let angular_scale = (c.angle_scale() + FRAC_PI_4) * (c.angular_velocity_scale() + hair_rates);
    let mut v = DVector::zeros(fd_v.len());
    for (k, h) in vels.iter().enumerate() {
        v[3 * k] = h.tip_m_per_s.x;
        v[3 * k + 1] = h.tip_m_per_s.y;
        v[3 * k + 2] = h.angular_rad_per_s;
    }
    assert_close_planar(
        "hair velocities vs FD",
        &v,
        &fd_v,
        TOL,
        scale,
        angular_scale,
    )?;

    // Hair tip Jacobians: columns 0..=n are theta, column n+1 is that hair's beta.
    let poses = hair_poses(chain, &c.theta, betas, s).unwrap();
    for (k, h) in poses.iter().enumerate() {
        let j = hair_tip_jacobian(chain, &c.theta, betas, s, h.link).unwrap();
        let mut expect = DMatrix::zeros(3, m + 1);
        expect
            .columns_mut(0, m)
            .copy_from(&fd.view((3 * k, 0), (3, m)));
        expect
            .column_mut(m)
            .copy_from(&fd.view((3 * k, m + h.link), (3, 1)));
        assert_close_planar(
            "hair tip Jacobian vs FD",
            &to_dmatrix(&j),
            &expect,
            TOL,
            c.length_scale() + 0.03,
            c.angle_scale() + FRAC_PI_4,
        )?;
    }
    Ok(())
}

fn limit_strategy() -> impl Strategy<Value = JointLimit> {
    (-3.0..3.0f64, 0.0..3.0f64).prop_map(|(cw, range)| JointLimit::new(cw, cw + range))
}

/// A chain with random limits, stiffness, rest angles; a q; and a tip force.
fn energy_case() -> impl Strategy<Value = (Chain, Vec<f64>, Vector2<f64>)> {
    (1usize..=30).prop_flat_map(|n| {
        (
            prop::collection::vec(0.01..0.06f64, n + 1),
            -3.0..3.0f64,
            prop::collection::vec(limit_strategy(), n),
            prop::collection::vec(0.0..0.1f64, n),
            prop::collection::vec(-1.0..1.0f64, n),
            prop::collection::vec(-4.0..4.0f64, n + 1),
            (-1.0..1.0f64, -1.0..1.0f64),
        )
            .prop_map(|(lengths, base, limits, k, rest, q, (fx, fy))| {
                let chain = Chain::builder(lengths.len() - 1)
                    .link_lengths_m(lengths)
                    .base_angle_rad(base)
                    .joint_limits(limits)
                    .stiffnesses_nm_per_rad(k)
                    .rest_angles_rad(rest)
                    .build()
                    .unwrap();
                (chain, q, Vector2::new(fx, fy))
            })
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn pair_jacobians_and_velocities_match_fd(c in case(1..=40)) {
        check_pair_jacobians(&c)?;
        check_tip(&c)?;
    }

    #[test]
    fn all_frames_match_fd(c in case(1..=30)) {
        check_all_frames(&c)?;
    }

    #[test]
    fn hairs_match_fd((c, chain, betas, rates) in hair_case()) {
        check_hairs(&c, &chain, &betas, &rates)?;
    }

    #[test]
    fn limit_map_derivatives_match_fd((chain, q, _f) in energy_case()) {
        let fd1 = central_jacobian(&q, H, |x| theta_from_q(&chain, x).unwrap().as_slice().to_vec());
        let d1 = dtheta_dq(&chain, &q).unwrap();
        assert_close("J_g vs FD", &DMatrix::from_diagonal(&d1), &fd1, TOL, 3.0)?;
        let fd2 = central_jacobian(&q, H, |x| dtheta_dq(&chain, x).unwrap().as_slice().to_vec());
        let d2 = d2theta_dq2(&chain, &q).unwrap();
        assert_close("d2g/dq2 vs FD", &DMatrix::from_diagonal(&d2), &fd2, TOL, 3.0)?;
    }

    #[test]
    fn energy_derivatives_match_fd_in_theta((chain, q, f) in energy_case()) {
        let theta = theta_from_q(&chain, &q).unwrap();
        let pot = Potential::new(&chain).with_tip_force_n(f);
        let scale = chain.stiffness_nm_per_rad().iter().sum::<f64>() * 10.0 + f.norm() * chain.total_length_m() + 1e-3;
        let fd_g = central_jacobian(theta.as_slice(), H, |t| vec![pot.value_theta(t).unwrap()]);
        let g = pot.gradient_theta(theta.as_slice()).unwrap();
        assert_close("grad_theta vs FD", &g.transpose(), &fd_g, TOL, scale)?;
        let fd_h = central_jacobian(theta.as_slice(), H, |t| pot.gradient_theta(t).unwrap().as_slice().to_vec());
        let h = pot.hessian_theta(theta.as_slice()).unwrap();
        assert_close("hess_theta vs FD", &h, &fd_h, TOL, scale)?;
        prop_assert!((&h - h.transpose()).amax() == 0.0, "Hessian not symmetric");
    }

    #[test]
    fn energy_derivatives_match_fd_in_q((chain, q, f) in energy_case()) {
        let pot = Potential::new(&chain).with_tip_force_n(f);
        let scale = chain.stiffness_nm_per_rad().iter().sum::<f64>() * 10.0 + f.norm() * chain.total_length_m() + 1e-3;
        let fd_g = central_jacobian(&q, H, |x| vec![pot.value_q(x).unwrap()]);
        let g = pot.gradient_q(&q).unwrap();
        assert_close("grad_q vs FD", &g.transpose(), &fd_g, TOL, scale)?;
        let fd_h = central_jacobian(&q, H, |x| pot.gradient_q(x).unwrap().as_slice().to_vec());
        let h = pot.hessian_q(&q).unwrap();
        assert_close("hess_q vs FD", &h, &fd_h, TOL, scale)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    /// Longer chains, fewer cases (each finite-difference Jacobian is O(n^2)).
    #[test]
    fn long_chain_jacobians_match_fd(c in case(100..=600)) {
        check_pair_jacobians(&c)?;
        check_tip(&c)?;
    }
}

/// The thesis prints `J_g = -1/2 diag(cos q) diag(ccw - cw)` (2.2.4.5) and
/// `dJ_g/dq = 1/2 [diag(ccw - cw) (.) diag(cos q)]` (2.2.4.6). Finite differences say the
/// signs and the trig function are as in docs/model.md 3: `+h cos q` and `-h sin q`.
#[test]
fn seed_limit_map_derivatives_have_a_sign_slip() {
    let lim = JointLimit::new(-0.5, 1.5); // h = 1
    let q = 0.3_f64;
    let fd1 = (lim.theta_from_q(q + H) - lim.theta_from_q(q - H)) / (2.0 * H);
    let seed1 = -0.5 * q.cos() * (lim.ccw_rad - lim.cw_rad);
    assert!((lim.dtheta_dq(q) - fd1).abs() < 1e-9);
    assert!(
        (seed1 - fd1).abs() > 0.5,
        "the thesis's printed J_g would agree"
    );
    let fd2 = (lim.dtheta_dq(q + H) - lim.dtheta_dq(q - H)) / (2.0 * H);
    let seed2 = 0.5 * (lim.ccw_rad - lim.cw_rad) * q.cos();
    assert!((lim.d2theta_dq2(q) - fd2).abs() < 1e-9);
    assert!(
        (seed2 - fd2).abs() > 0.5,
        "the thesis's printed second derivative would agree"
    );
}
