//! Bad input to the tip-force functions gives a typed error naming the argument and the
//! index (never a panic or a NaN), and degenerate but valid input gives a documented answer.
#![allow(clippy::unwrap_used)]

use nalgebra::Vector2;
use sim_core::statics::castigliano::castigliano_deflection_rad;
use sim_core::statics::tip_force::{
    TipForceError, joints_on_limit, tip_force_free_body, tip_force_least_squares,
    tip_wrench_least_squares,
};
use sim_core::{Chain, KinematicsError};

fn chain(n: usize) -> Chain {
    Chain::builder(n)
        .stiffness_nm_per_rad(0.01)
        .rest_angles_rad(vec![0.2; n])
        .build()
        .unwrap()
}

#[test]
fn wrong_lengths_name_the_argument() {
    let c = chain(4);
    let short = [0.0; 3];
    let want = TipForceError::Kinematics(KinematicsError::WrongLength {
        argument: "theta",
        expected: 5,
        actual: 3,
    });
    assert_eq!(tip_force_least_squares(&c, &short).unwrap_err(), want);
    assert_eq!(tip_wrench_least_squares(&c, &short).unwrap_err(), want);
    assert_eq!(
        tip_force_free_body(&c, &short, &[false; 5]).unwrap_err(),
        want
    );
    assert_eq!(joints_on_limit(&c, &short, 0.0).unwrap_err(), want);
    assert_eq!(
        castigliano_deflection_rad(&c, &short, Vector2::zeros(), 0.0).unwrap_err(),
        want
    );
    assert_eq!(want.to_string(), "theta has length 3, expected 5");

    let err = tip_force_free_body(&c, &[0.0; 5], &[false; 4]).unwrap_err();
    assert_eq!(
        err,
        TipForceError::Kinematics(KinematicsError::WrongLength {
            argument: "on_limit",
            expected: 5,
            actual: 4,
        })
    );
}

#[test]
fn non_finite_input_names_the_entry() {
    let c = chain(4);
    let mut theta = [0.0; 5];
    theta[2] = f64::NAN;
    let err = tip_force_least_squares(&c, &theta).unwrap_err();
    assert!(matches!(
        err,
        TipForceError::NotFinite { argument: "theta", index: 2, value } if value.is_nan()
    ));
    assert_eq!(err.to_string(), "theta[2] is not finite (NaN)");
    theta[2] = f64::INFINITY;
    assert!(matches!(
        tip_force_free_body(&c, &theta, &[false; 5]).unwrap_err(),
        TipForceError::NotFinite {
            argument: "theta",
            index: 2,
            ..
        }
    ));

    let ok = [0.0; 5];
    assert!(matches!(
        castigliano_deflection_rad(&c, &ok, Vector2::new(0.0, f64::NAN), 0.0).unwrap_err(),
        TipForceError::NotFinite {
            argument: "tip_force_n",
            index: 1,
            ..
        }
    ));
    assert!(matches!(
        castigliano_deflection_rad(&c, &ok, Vector2::zeros(), f64::NEG_INFINITY).unwrap_err(),
        TipForceError::NotFinite {
            argument: "tip_moment_nm",
            index: 0,
            ..
        }
    ));
    assert!(matches!(
        joints_on_limit(&c, &ok, f64::NAN).unwrap_err(),
        TipForceError::NotFinite {
            argument: "tolerance_rad",
            ..
        }
    ));
}

#[test]
fn the_base_is_never_on_a_limit() {
    let c = chain(3);
    let err = tip_force_free_body(&c, &[0.0; 4], &[true, false, false, false]).unwrap_err();
    assert_eq!(err, TipForceError::BaseOnLimit);
    assert!(err.to_string().contains("on_limit[0]"));
}

#[test]
fn castigliano_needs_stiff_joints() {
    let c = Chain::builder(3)
        .stiffnesses_nm_per_rad(vec![0.01, 0.0, 0.02])
        .build()
        .unwrap();
    let err = castigliano_deflection_rad(&c, &[0.0; 4], Vector2::new(0.0, 1.0), 0.0).unwrap_err();
    assert_eq!(err, TipForceError::ZeroStiffness { joint: 2 });
    assert!(err.to_string().contains("stiffness_nm_per_rad[2]"));
}

/// Every flexible joint on a limit: no equation is left for `F` (rank 0, `F = 0`), every
/// spring torque is taken by its stop. One free joint: rank 1, the force along that joint's
/// lever arm is undetermined and left at zero.
#[test]
fn too_few_free_joints_give_a_rank_deficient_answer() {
    let c = chain(3);
    let theta = [0.0, 0.3, -0.1, 0.5];
    let fb = tip_force_free_body(&c, &theta, &[false, true, true, true]).unwrap();
    assert_eq!(fb.tip.rank, 0);
    assert_eq!(fb.tip.force_n, Vector2::zeros());
    for (j, &t) in theta.iter().enumerate().skip(1) {
        let spring = 0.01 * (t - 0.2);
        assert!((fb.stop_torques_nm[j] - spring).abs() < 1e-18);
        assert_eq!(fb.joint_torques_nm[j], 0.0);
    }
    assert_eq!(fb.servo_torque_nm, 0.0);

    let fb = tip_force_free_body(&c, &theta, &[false, true, false, true]).unwrap();
    assert_eq!(fb.tip.rank, 1);
    assert!(
        fb.tip.residual_norm_nm < 1e-18,
        "one equation, fitted exactly"
    );

    // A chain with no flexible joint at all.
    let c0 = Chain::builder(0).build().unwrap();
    let fit = tip_force_least_squares(&c0, &[0.0]).unwrap();
    assert_eq!((fit.rank, fit.force_n), (0, Vector2::zeros()));
}

/// NaN never comes out: a zero-stiffness chain at any posture fits `F = 0` exactly.
#[test]
fn zero_stiffness_chain_gives_zero_force() {
    let c = Chain::builder(5).build().unwrap();
    let theta = [0.1, 0.2, -0.3, 0.4, 0.5, -0.6];
    let fit = tip_force_least_squares(&c, &theta).unwrap();
    assert_eq!(fit.force_n, Vector2::zeros());
    assert_eq!(fit.rank, 2);
    assert!(fit.condition_number.is_finite());
}
