//! (e) Joint limits: a load that drives joints into their limits gives a KKT point of the
//! bound-constrained problem. Checked with finite differences of the potential (computed
//! with sim-core's kinematics, not the solver): moving a joint on a limit inward raises the
//! potential at the rate of the reported stop torque, a free joint has zero slope, and the
//! stop torque has the sign of a valid multiplier.
#![allow(clippy::unwrap_used)]

use crate::equilibrium_common;

use equilibrium_common::{potential, residual_torques, torque_scale};
use nalgebra::Vector2;
use sim_core::{
    Chain, EquilibriumProblem, InitialGuess, JointLimit, LimitSide, SolveOptions, solve_equilibrium,
};

fn check_kkt(chain: &Chain, f: Vector2<f64>, start: InitialGuess) -> sim_core::Equilibrium {
    let problem = EquilibriumProblem::new(chain).with_tip_force_n(f);
    let eq = solve_equilibrium(&problem, &start, &SolveOptions::default()).unwrap();
    assert!(eq.converged, "{eq:?}");
    let scale = torque_scale(chain, f);
    let r = residual_torques(chain, &eq.theta_rad, f);
    let h = 1e-6;
    for j in 1..=chain.n() {
        let lim = chain.joint_limits()[j];
        let t = eq.theta_rad[j];
        match eq.limit_sides[j] {
            LimitSide::Free => {
                assert!(lim.cw_rad < t && t < lim.ccw_rad);
                assert_eq!(eq.limit_torques_nm[j], 0.0);
                assert!(
                    r[j - 1].abs() <= 1e-9 * scale,
                    "joint {j} free but unbalanced: {}",
                    r[j - 1]
                );
                let mut up = eq.theta_rad.clone();
                let mut down = eq.theta_rad.clone();
                up[j] += h;
                down[j] -= h;
                let slope = (potential(chain, &up, f) - potential(chain, &down, f)) / (2.0 * h);
                assert!(slope.abs() <= 1e-6 * scale, "joint {j}: slope {slope}");
            }
            side => {
                let (bound, inward) = if side == LimitSide::Clockwise {
                    (lim.cw_rad, 1.0)
                } else {
                    (lim.ccw_rad, -1.0)
                };
                assert_eq!(t, bound);
                // Stop torque = K (theta - rest) - J^T F at that joint, with the right sign.
                let torque = eq.limit_torques_nm[j];
                assert!(
                    (torque - r[j - 1]).abs() <= 1e-9 * scale,
                    "joint {j}: {torque} vs {}",
                    r[j - 1]
                );
                assert!(inward * torque >= 0.0, "joint {j}: stop pulls ({torque})");
                if lim.cw_rad < lim.ccw_rad {
                    // Moving inward (feasible) does not decrease the potential.
                    let mut moved = eq.theta_rad.clone();
                    moved[j] += inward * h;
                    let rate = (potential(chain, &moved, f) - eq.total_potential_j) / h;
                    assert!(
                        rate >= -1e-6 * scale,
                        "joint {j}: feasible descent, rate {rate}"
                    );
                    assert!(
                        (rate - inward * torque).abs() <= 1e-4 * scale,
                        "joint {j}: rate {rate} vs torque {torque}"
                    );
                }
            }
        }
    }
    eq
}

#[test]
fn heavy_load_drives_joints_into_limits() {
    let chain = Chain::builder(6)
        .joint_limit(JointLimit::new(-0.3, 0.3))
        .stiffnesses_nm_per_rad(vec![0.08, 0.05, 0.03, 0.02, 0.01, 0.005])
        .base_angle_rad(0.4)
        .build()
        .unwrap();
    for (f, start) in [
        (Vector2::new(0.0, -1.0), InitialGuess::Straight),
        (Vector2::new(0.3, 0.8), InitialGuess::S),
        (Vector2::new(-0.5, -0.1), InitialGuess::C.mirrored()),
    ] {
        let eq = check_kkt(&chain, f, start);
        assert!(
            eq.limit_sides.iter().any(|s| *s != LimitSide::Free),
            "{eq:?}"
        );
    }
}

#[test]
fn every_joint_on_a_limit() {
    let chain = Chain::builder(12)
        .joint_limit(JointLimit::new(-1e-3, 2e-3))
        .stiffness_nm_per_rad(0.01)
        .build()
        .unwrap();
    let eq = check_kkt(&chain, Vector2::new(0.0, -10.0), InitialGuess::Straight);
    assert!(
        eq.limit_sides[1..]
            .iter()
            .all(|s| *s == LimitSide::Clockwise),
        "{:?}",
        eq.limit_sides
    );
    assert!(eq.stable);
    let eq = check_kkt(&chain, Vector2::new(0.0, 10.0), InitialGuess::Straight);
    assert!(
        eq.limit_sides[1..]
            .iter()
            .all(|s| *s == LimitSide::CounterClockwise)
    );
}

#[test]
fn fixed_joints_report_their_reaction() {
    let mut limits = vec![JointLimit::new(-1.0, 1.0); 5];
    limits[2] = JointLimit::fixed(0.2);
    let chain = Chain::builder(5)
        .joint_limits(limits)
        .stiffness_nm_per_rad(0.02)
        .build()
        .unwrap();
    let eq = check_kkt(&chain, Vector2::new(0.05, -0.2), InitialGuess::Straight);
    assert_eq!(eq.theta_rad[3], 0.2);
    assert_ne!(eq.limit_sides[3], LimitSide::Free);
}

#[test]
fn start_outside_limits_is_an_error() {
    let chain = Chain::builder(3)
        .joint_limit(JointLimit::new(-0.5, 0.5))
        .stiffness_nm_per_rad(0.01)
        .build()
        .unwrap();
    let problem = EquilibriumProblem::new(&chain);
    let err = solve_equilibrium(
        &problem,
        &InitialGuess::Angles(vec![0.0, 0.7, 0.0]),
        &SolveOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            sim_core::EquilibriumError::StartOutsideLimits { index: 2, .. }
        ),
        "{err}"
    );
    let err = solve_equilibrium(
        &problem,
        &InitialGuess::Angles(vec![0.0, 0.1]),
        &SolveOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(
        err,
        sim_core::EquilibriumError::WrongLength { .. }
    ));
    let err = solve_equilibrium(
        &problem,
        &InitialGuess::Straight,
        &SolveOptions {
            tolerance: f64::NAN,
            max_iterations: 10,
        },
    )
    .unwrap_err();
    assert!(matches!(
        err,
        sim_core::EquilibriumError::InvalidOption { .. }
    ));
    let bad = EquilibriumProblem::new(&chain).with_tip_force_n(Vector2::new(f64::NAN, 0.0));
    assert!(solve_equilibrium(&bad, &InitialGuess::Straight, &SolveOptions::default()).is_err());
}
