//! The `O(n)` fast paths of sim-core equal the thesis's matrix forms (thesis 2.2.1.6, 2.2.1.14,
//! 2.2.2.1-3, 2.2.3.3-7, 3.2.1.1-3) to 1e-12 relative, for random chains with n from 1 to
//! 2000, random link lengths (uniform or per link), random angles and any frame pair.
//!
//! Relative means: positions to the total length of the chain, velocities to the total length
//! times the sum of |theta_dot|, angles to the sum of |theta|.
#![allow(clippy::unwrap_used)]

use crate::common_kinematics;

use common_kinematics::{Case, assert_close, assert_close_f, case};
use nalgebra::{Matrix3xX, Vector2};
use proptest::prelude::*;
use sim_core::kinematics::hair::hair_velocities;
use sim_core::kinematics::jacobian::{
    all_jacobians, body_jacobian, hybrid_jacobian, spatial_jacobian, tip_jacobian,
};
use sim_core::kinematics::matrix_forms::{
    seed_all_jacobians, seed_body_jacobian, seed_frame_poses, seed_frame_velocities, seed_hair_tip,
    seed_hair_tip_velocity, seed_hybrid_jacobian, seed_pose, seed_spatial_jacobian, seed_transform,
    seed_velocity,
};
use sim_core::kinematics::positions::frame_pose;
use sim_core::kinematics::velocity::{frame_velocities, frame_velocity};
use sim_core::{Chain, Frame, Hair, frame_poses, hair_poses, tip_pose};

const TOL: f64 = 1e-12;

fn check_poses(c: &Case) -> Result<(), TestCaseError> {
    let fast = frame_poses(&c.chain, &c.theta, c.s).unwrap();
    let seed = seed_frame_poses(&c.chain, &c.theta, c.s).unwrap();
    assert_close(
        "P_s (2.2.3.3)",
        &fast.positions_m,
        &seed.positions_m,
        TOL,
        c.length_scale(),
    )?;
    assert_close(
        "Theta_s (2.2.3.4)",
        &fast.angles_rad,
        &seed.angles_rad,
        TOL,
        c.angle_scale(),
    )?;

    let one = frame_pose(&c.chain, &c.theta, c.s, c.b).unwrap();
    let seed_one = seed_pose(&c.chain, &c.theta, c.s, c.b).unwrap();
    assert_close(
        "p_sb (2.2.1.6)",
        &one.position_m,
        &seed_one.position_m,
        TOL,
        c.length_scale(),
    )?;
    assert_close_f(
        "theta_sb (2.2.1.6)",
        one.angle_rad,
        seed_one.angle_rad,
        TOL,
        c.angle_scale(),
    )?;
    // H_sb's rotation block is R(theta_sb).
    let h = seed_transform(&c.chain, &c.theta, c.s, c.b).unwrap();
    let r = one.rotation();
    assert_close("R_sb (2.2.1.6)", &h.fixed_view::<2, 2>(0, 0), &r, TOL, 1.0)?;

    let tip = tip_pose(&c.chain, &c.theta).unwrap();
    let seed_tip = seed_pose(&c.chain, &c.theta, Frame::GROUND, c.chain.tip()).unwrap();
    assert_close(
        "tip",
        &tip.position_m,
        &seed_tip.position_m,
        TOL,
        c.length_scale(),
    )?;
    Ok(())
}

fn check_velocities(c: &Case) -> Result<(), TestCaseError> {
    let fast = frame_velocities(&c.chain, &c.theta, &c.theta_dot, c.s).unwrap();
    let seed = seed_frame_velocities(&c.chain, &c.theta, &c.theta_dot, c.s).unwrap();
    let vs = c.velocity_scale();
    assert_close(
        "P_dot_s (2.2.3.6)",
        &fast.linear_m_per_s,
        &seed.linear_m_per_s,
        TOL,
        vs,
    )?;
    assert_close(
        "Theta_dot_s (2.2.3.7)",
        &fast.angular_rad_per_s,
        &seed.angular_rad_per_s,
        TOL,
        vs,
    )?;

    let one = frame_velocity(&c.chain, &c.theta, &c.theta_dot, c.s, c.b).unwrap();
    let seed_one = seed_velocity(&c.chain, &c.theta, &c.theta_dot, c.s, c.b).unwrap();
    assert_close(
        "p_dot_sb (2.2.1.14)",
        &one.linear_m_per_s,
        &seed_one.linear_m_per_s,
        TOL,
        vs,
    )?;
    assert_close_f(
        "omega_sb (2.2.1.9)",
        one.angular_rad_per_s,
        seed_one.angular_rad_per_s,
        TOL,
        vs,
    )?;
    Ok(())
}

fn check_jacobians(c: &Case) -> Result<(), TestCaseError> {
    let l = c.length_scale();
    let pairs: [(&str, Matrix3xX<f64>, Matrix3xX<f64>); 3] = [
        (
            "J_sb (2.2.2.1)",
            hybrid_jacobian(&c.chain, &c.theta, c.s, c.b).unwrap(),
            seed_hybrid_jacobian(&c.chain, &c.theta, c.s, c.b).unwrap(),
        ),
        (
            "J_b (2.2.2.2)",
            body_jacobian(&c.chain, &c.theta, c.s, c.b).unwrap(),
            seed_body_jacobian(&c.chain, &c.theta, c.s, c.b).unwrap(),
        ),
        (
            "J_sigma (2.2.2.3)",
            spatial_jacobian(&c.chain, &c.theta, c.s, c.b).unwrap(),
            seed_spatial_jacobian(&c.chain, &c.theta, c.s, c.b).unwrap(),
        ),
    ];
    for (what, fast, seed) in &pairs {
        assert_close(what, fast, seed, TOL, l)?;
    }
    let tip = tip_jacobian(&c.chain, &c.theta).unwrap();
    let seed_tip = seed_hybrid_jacobian(&c.chain, &c.theta, Frame::GROUND, c.chain.tip()).unwrap();
    assert_close("J_Gn", &tip, &seed_tip, TOL, l)?;
    Ok(())
}

fn check_all_jacobians(c: &Case) -> Result<(), TestCaseError> {
    let fast = all_jacobians(&c.chain, &c.theta, c.s).unwrap();
    let seed = seed_all_jacobians(&c.chain, &c.theta, c.s).unwrap();
    assert_close(
        "all Jacobians (2.2.3.6-7)",
        &fast,
        &seed,
        TOL,
        c.length_scale(),
    )
}

/// All Jacobians against the thesis's per-frame Jacobians (2.2.3.5) for a few frames: the
/// O(n^3) stacked product is too slow at n = 2000 for the test budget.
fn check_all_jacobians_sampled(c: &Case) -> Result<(), TestCaseError> {
    let fast = all_jacobians(&c.chain, &c.theta, c.s).unwrap();
    let n = c.chain.n() as isize;
    for b in [-1, 0, c.s.index(), c.b.index(), n / 2, n] {
        let seed = seed_hybrid_jacobian(&c.chain, &c.theta, c.s, Frame::new(b)).unwrap();
        let slot = (b + 1) as usize;
        assert_close(
            "all Jacobians, one frame",
            &fast.rows(3 * slot, 3),
            &seed,
            TOL,
            c.length_scale(),
        )?;
    }
    Ok(())
}

/// A chain like `c`'s with the thesis's hair (left, distal, centred) on every link 0..=n, the
/// hair angles and rates, and the thesis's hair angles `theta' = beta - pi`.
fn with_seed_hairs(c: &Case, hair_length_m: f64, betas: &[f64]) -> (Chain, Vec<f64>) {
    let n = c.chain.n();
    let mut builder = Chain::builder(n)
        .link_lengths_m(c.chain.link_lengths_m().to_vec())
        .base_angle_rad(c.chain.base_angle_rad());
    for (link, &l) in c.chain.link_lengths_m().iter().enumerate() {
        builder = builder.hair(
            link,
            Hair {
                length_m: hair_length_m,
                ..Hair::seed(l)
            },
        );
    }
    let chain = builder.build().unwrap();
    let seed_angles = betas.iter().map(|b| b - std::f64::consts::PI).collect();
    (chain, seed_angles)
}

fn check_hairs(c: &Case, hair_length_m: f64, betas: &[f64]) -> Result<(), TestCaseError> {
    let (chain, seed_angles) = with_seed_hairs(c, hair_length_m, betas);
    let poses = hair_poses(&chain, &c.theta, betas, c.s).unwrap();
    let zero = vec![0.0; betas.len()];
    let vels = hair_velocities(&chain, &c.theta, &c.theta_dot, betas, &zero, c.s).unwrap();
    prop_assert_eq!(poses.len(), chain.dof());
    let scale = c.length_scale() + hair_length_m;
    let vscale =
        c.velocity_scale() + hair_length_m * c.theta_dot.iter().map(|v| v.abs()).sum::<f64>();
    // Every hair when n is small, a sample when it is large.
    let step = (chain.dof() / 16).max(1);
    for link in (0..chain.dof()).step_by(step) {
        let seed_tip: Vector2<f64> = seed_hair_tip(
            &chain,
            &c.theta,
            c.s,
            link,
            hair_length_m,
            seed_angles[link],
        )
        .unwrap();
        assert_close(
            "hair tip (3.2.1.1)",
            &poses[link].tip_m,
            &seed_tip,
            TOL,
            scale,
        )?;
        let seed_v = seed_hair_tip_velocity(
            &chain,
            &c.theta,
            &c.theta_dot,
            c.s,
            link,
            hair_length_m,
            seed_angles[link],
        )
        .unwrap();
        assert_close(
            "hair tip velocity (3.2.1.3)",
            &vels[link].tip_m_per_s,
            &seed_v.linear_m_per_s,
            TOL,
            vscale,
        )?;
        assert_close_f(
            "hair angular velocity",
            vels[link].angular_rad_per_s,
            seed_v.angular_rad_per_s,
            TOL,
            vscale,
        )?;
    }
    Ok(())
}

fn hair_case(n: std::ops::RangeInclusive<usize>) -> impl Strategy<Value = (Case, f64, Vec<f64>)> {
    case(n).prop_flat_map(|c| {
        let m = c.chain.dof();
        (
            Just(c),
            0.005..0.03f64,
            prop::collection::vec(0.0..std::f64::consts::FRAC_PI_4, m),
        )
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn small_chains_match_seed(c in case(1..=12)) {
        check_poses(&c)?;
        check_velocities(&c)?;
        check_jacobians(&c)?;
        check_all_jacobians(&c)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn medium_chains_match_seed(c in case(13..=160)) {
        check_poses(&c)?;
        check_velocities(&c)?;
        check_jacobians(&c)?;
        check_all_jacobians(&c)?;
    }

    #[test]
    fn hair_tips_match_seed((c, hair_len, betas) in hair_case(1..=40)) {
        check_hairs(&c, hair_len, &betas)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    #[test]
    fn long_chains_match_seed(c in case(161..=1000)) {
        check_poses(&c)?;
        check_velocities(&c)?;
        check_jacobians(&c)?;
        check_all_jacobians_sampled(&c)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4, ..ProptestConfig::default() })]

    #[test]
    fn chains_of_2000_match_seed(c in case(2000..=2000)) {
        check_poses(&c)?;
        check_velocities(&c)?;
        check_jacobians(&c)?;
        check_all_jacobians_sampled(&c)?;
    }

    #[test]
    fn hairs_of_2000_match_seed((c, hair_len, betas) in hair_case(2000..=2000)) {
        check_hairs(&c, hair_len, &betas)?;
    }
}
