//! The thesis's identities hold for the bookkeeping and the fast paths: 2.2.1.3-2.2.1.5 and
//! 2.2.1.7-2.2.1.8 (and the two used between 2.2.1.13 and 2.2.1.14), 2.2.3.2 and 2.2.3.4,
//! `J_b = blockdiag(R_sb^T, 1) J_sb`, `J_sigma = [I, -R90 p_sb; 0, 1] J_sb`,
//! `g(g^-1(theta)) = theta` inside the limits, and rigid-motion invariance: changing
//! `theta_0` rotates every frame about the base and changes nothing relative to `C_0`.
#![allow(clippy::unwrap_used)]

use crate::common_kinematics;

use common_kinematics::{assert_close, assert_close_f, case};
use nalgebra::{DMatrix, DVector, Matrix2, Matrix3};
use proptest::prelude::*;
use sim_core::kinematics::active_frames::{
    active_frames_matrix, active_frames_matrix_from_vector, active_frames_vector,
    all_frames_active_matrix, all_frames_matrix, all_frames_matrix_from_extremes,
};
use sim_core::kinematics::jacobian::{body_jacobian, hybrid_jacobian, spatial_jacobian};
use sim_core::kinematics::joint_limits::{q_from_theta, theta_from_q};
use sim_core::kinematics::positions::frame_pose;
use sim_core::{Chain, Frame, JointLimit, frame_poses};

/// `C(x) = [cos(x)^T; sin(x)^T]`, 2 x len.
fn c_of(x: &DVector<f64>) -> DMatrix<f64> {
    DMatrix::from_fn(
        2,
        x.len(),
        |r, i| if r == 0 { x[i].cos() } else { x[i].sin() },
    )
}

fn rot(a: f64) -> Matrix2<f64> {
    let (s, c) = a.sin_cos();
    Matrix2::new(c, -s, s, c)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1024, ..ProptestConfig::default() })]

    /// 2.2.1.3-2.2.1.5: reversing a frame pair.
    #[test]
    fn reversal_identities(c in case(1..=40)) {
        let n = c.chain.n();
        let a_sb = active_frames_vector(n, c.s, c.b).unwrap();
        let a_bs = active_frames_vector(n, c.b, c.s).unwrap();
        let m_sb = active_frames_matrix(n, c.s, c.b).unwrap();
        let m_bs = active_frames_matrix(n, c.b, c.s).unwrap();
        prop_assert_eq!(&a_sb, &(-&a_bs), "2.2.1.3");
        prop_assert_eq!(&m_sb, &(&m_bs - a_bs.abs() * a_bs.transpose()), "2.2.1.4");
        prop_assert_eq!(m_sb.abs(), &a_bs * a_bs.transpose() - m_bs.abs(), "2.2.1.5 (first line)");
        prop_assert_eq!(m_sb.abs() - &a_sb * a_sb.transpose(), -m_bs.abs(), "2.2.1.5 (second line)");
    }

    /// 2.2.1.7-2.2.1.8: `R_sb^T C(A_sb theta) X = C(A_bs theta) X` for `X = alpha_sb`,
    /// `diag(l) alpha_sb` and `A_sb`; and the relations used to reach 2.2.1.14:
    /// `diag(A x) alpha = |A| x`, `A^T diag(sin(A x)) alpha = |A|^T sin(A x)`.
    #[test]
    fn rotation_identities(c in case(1..=40)) {
        let n = c.chain.n();
        let th = DVector::from_column_slice(&c.theta);
        let a_sb = active_frames_vector(n, c.s, c.b).unwrap();
        let m_sb = active_frames_matrix(n, c.s, c.b).unwrap();
        let m_bs = active_frames_matrix(n, c.b, c.s).unwrap();
        let rt = rot(a_sb.dot(&th)).transpose();
        let rt = DMatrix::from_column_slice(2, 2, rt.as_slice());
        let c_sb = c_of(&(&m_sb * &th));
        let c_bs = c_of(&(&m_bs * &th));
        let l = DMatrix::from_diagonal(&DVector::from_column_slice(c.chain.link_lengths_m()));
        let scale = c.theta.len() as f64;
        assert_close("2.2.1.7", &(&rt * &c_sb * &a_sb), &(&c_bs * &a_sb), 1e-12, scale)?;
        assert_close("2.2.1.7 with lengths", &(&rt * &c_sb * &l * &a_sb), &(&c_bs * &l * &a_sb), 1e-12, scale)?;
        assert_close("2.2.1.8", &(&rt * &c_sb * &m_sb), &(&c_bs * &m_sb), 1e-12, scale)?;

        let x = th;
        let ax = &m_sb * &x;
        assert_close("diag(Ax) alpha = |A| x", &(DMatrix::from_diagonal(&ax) * &a_sb), &(m_sb.abs() * &x), 1e-12, c.angle_scale())?;
        let sin_ax = ax.map(f64::sin);
        assert_close(
            "A^T diag(sin Ax) alpha = |A|^T sin Ax",
            &(m_sb.transpose() * DMatrix::from_diagonal(&sin_ax) * &a_sb),
            &(m_sb.abs().transpose() * &sin_ax),
            1e-12,
            scale,
        )?;
    }

    /// 2.2.3.1-2.2.3.4: A from all alpha vectors equals A from the two extremes;
    /// `A_(sG+sn) = A_sG + A_sn`; `Theta_s = A^T theta`.
    #[test]
    fn all_frames_identities(c in case(1..=40)) {
        let n = c.chain.n();
        let a = all_frames_matrix(n, c.s).unwrap();
        prop_assert_eq!(&a, &all_frames_matrix_from_extremes(n, c.s).unwrap(), "2.2.3.2");
        let sum = active_frames_vector(n, c.s, Frame::GROUND).unwrap() + active_frames_vector(n, c.s, c.chain.tip()).unwrap();
        prop_assert_eq!(
            active_frames_matrix_from_vector(&sum),
            active_frames_matrix(n, c.s, Frame::GROUND).unwrap() + active_frames_matrix(n, c.s, c.chain.tip()).unwrap()
        );
        prop_assert_eq!(all_frames_active_matrix(n, c.s).unwrap(), active_frames_matrix_from_vector(&sum));
        let poses = frame_poses(&c.chain, &c.theta, c.s).unwrap();
        let theta_s = a.transpose() * DVector::from_column_slice(&c.theta);
        assert_close("2.2.3.4", &poses.angles_rad, &theta_s, 1e-12, c.angle_scale())?;
    }

    /// `J_b = blockdiag(R_sb^T, 1) J_sb` and `J_sigma = [I, -R90 p_sb; 0, 1] J_sb` on the fast
    /// paths.
    #[test]
    fn jacobian_frame_changes(c in case(1..=200)) {
        let j = hybrid_jacobian(&c.chain, &c.theta, c.s, c.b).unwrap();
        let pose = frame_pose(&c.chain, &c.theta, c.s, c.b).unwrap();
        let rt = pose.rotation().transpose();
        let mut block = Matrix3::identity();
        block.fixed_view_mut::<2, 2>(0, 0).copy_from(&rt);
        let jb = body_jacobian(&c.chain, &c.theta, c.s, c.b).unwrap();
        assert_close("J_b = blockdiag(R^T, 1) J_sb", &jb, &(block * &j), 1e-13, c.length_scale())?;
        let p = pose.position_m;
        let spatial = Matrix3::new(1.0, 0.0, p.y, 0.0, 1.0, -p.x, 0.0, 0.0, 1.0);
        let js = spatial_jacobian(&c.chain, &c.theta, c.s, c.b).unwrap();
        assert_close("J_sigma = [I, -R90 p; 0, 1] J_sb", &js, &(spatial * &j), 1e-13, c.length_scale())?;
    }

    /// Poses compose: `p_sb = R_Gs^T (p_Gb - p_Gs)`, `theta_sb = theta_Gb - theta_Gs`.
    #[test]
    fn poses_compose_through_ground(c in case(1..=200)) {
        let gs = frame_pose(&c.chain, &c.theta, Frame::GROUND, c.s).unwrap();
        let gb = frame_pose(&c.chain, &c.theta, Frame::GROUND, c.b).unwrap();
        let sb = frame_pose(&c.chain, &c.theta, c.s, c.b).unwrap();
        let expect = gs.rotation().transpose() * (gb.position_m - gs.position_m);
        assert_close("p_sb", &sb.position_m, &expect, 1e-12, c.length_scale())?;
        assert_close_f("theta_sb", sb.angle_rad, gb.angle_rad - gs.angle_rad, 1e-12, c.angle_scale())?;
    }

    /// Rigid-motion invariance: adding `d` to `theta_0` turns every ground-frame pose by `d`
    /// about the base (the ground origin), and leaves every pose relative to a frame `s >= 0`
    /// unchanged; the ground-frame Jacobians turn with it.
    #[test]
    fn base_angle_rotates_everything_about_the_base(c in case(1..=200), d in -3.0..3.0f64) {
        let mut turned = c.theta.clone();
        turned[0] += d;
        let chain2 = c.chain.with_base_angle_rad(turned[0]).unwrap();
        let before = frame_poses(&c.chain, &c.theta, Frame::GROUND).unwrap();
        let after = frame_poses(&chain2, &turned, Frame::GROUND).unwrap();
        let r = rot(d);
        assert_close("positions turn", &after.positions_m, &(r * &before.positions_m), 1e-12, c.length_scale())?;
        let shifted = before.angles_rad.map(|a| a + d);
        // the ground frame itself does not turn
        let mut expect = shifted;
        expect[0] = 0.0;
        assert_close("angles turn", &after.angles_rad, &expect, 1e-12, c.angle_scale() + d.abs())?;
        if c.s.index() >= 0 {
            let rel_before = frame_poses(&c.chain, &c.theta, c.s).unwrap();
            let rel_after = frame_poses(&chain2, &turned, c.s).unwrap();
            // every frame but the ground frame (column 0) is unchanged relative to s
            let m = rel_before.positions_m.ncols() - 1;
            assert_close(
                "relative positions unchanged",
                &rel_after.positions_m.columns(1, m),
                &rel_before.positions_m.columns(1, m),
                1e-12,
                c.length_scale(),
            )?;
        }
        let j1 = hybrid_jacobian(&c.chain, &c.theta, Frame::GROUND, c.b).unwrap();
        let j2 = hybrid_jacobian(&chain2, &turned, Frame::GROUND, c.b).unwrap();
        let mut block = Matrix3::identity();
        block.fixed_view_mut::<2, 2>(0, 0).copy_from(&r);
        assert_close("Jacobian turns", &j2, &(block * j1), 1e-12, c.length_scale())?;
    }

    /// `g(g^-1(theta)) = theta` for theta inside the limits (limits of any width, fixed joints
    /// included), `g^-1` lands in `[-pi/2, pi/2]`, and `g^-1(g(q)) = q` there.
    #[test]
    fn limit_map_round_trip(
        limits in prop::collection::vec((-3.0..3.0f64, 0.0..3.0f64, 0.0..=1.0f64, -1.5..1.5f64), 1..30),
        base in -3.0..3.0f64,
    ) {
        let chain = Chain::builder(limits.len())
            .base_angle_rad(base)
            .joint_limits(limits.iter().map(|&(cw, w, _, _)| JointLimit::new(cw, cw + w)).collect::<Vec<_>>())
            .build()
            .unwrap();
        let mut theta = vec![base];
        theta.extend(limits.iter().map(|&(cw, w, f, _)| (cw + f * w).min(cw + w)));
        let q = q_from_theta(&chain, &theta).unwrap();
        for &qj in q.iter() {
            prop_assert!((-std::f64::consts::FRAC_PI_2..=std::f64::consts::FRAC_PI_2).contains(&qj));
        }
        let back = theta_from_q(&chain, q.as_slice()).unwrap();
        assert_close("g(g^-1(theta))", &back, &DVector::from_vec(theta.clone()), 1e-12, 4.0)?;

        let mut q2 = vec![0.0];
        q2.extend(limits.iter().map(|&(_, _, _, q)| q));
        let t2 = theta_from_q(&chain, &q2).unwrap();
        let q_back = q_from_theta(&chain, t2.as_slice()).unwrap();
        for (j, &(_, w, _, _)) in limits.iter().enumerate() {
            // well-conditioned joints only: asin is ill-conditioned near +-pi/2 and w -> 0
            if w > 1e-3 && q2[j + 1].abs() < 1.4 {
                assert_close_f("g^-1(g(q))", q_back[j + 1], q2[j + 1], 1e-9, 1.0)?;
            }
        }
    }
}

#[test]
fn base_is_fixed_in_the_limit_map() {
    let chain = Chain::builder(2).base_angle_rad(0.7).build().unwrap();
    let theta = theta_from_q(&chain, &[123.0, 0.0, 0.0]).unwrap();
    assert_eq!(theta[0], 0.7);
    let q = q_from_theta(&chain, &[0.7, 0.0, 0.0]).unwrap();
    assert_eq!(q[0], 0.0, "pseudo-inverse convention for equal limits");
    assert_eq!(
        sim_core::kinematics::joint_limits::dtheta_dq(&chain, &[1.0, 0.0, 0.0]).unwrap()[0],
        0.0
    );
}
