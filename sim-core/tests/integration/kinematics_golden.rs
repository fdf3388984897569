//! Golden cases worked by hand: the thesis's own examples in 2.2.1 and 2.2.3 (n = 8, s = 5,
//! b = 1 and s = 1, b = 5: alpha and A exactly as printed), and small chains whose positions,
//! Jacobians, limit map, energy and hair tips can be read off a sketch.
//!
//! One erratum, found here: the thesis declares the all-frames matrix A for n = 8, s = 5 as
//! 9 x 10 (2.2.3.1) but prints 9 columns. The printed matrix is A without its zero column
//! alpha_55 (b = s); the test checks exactly that.
#![allow(clippy::unwrap_used)]

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

use nalgebra::{DMatrix, DVector, Matrix3xX, Vector2};
use sim_core::kinematics::active_frames::{
    active_frames_matrix, active_frames_vector, all_frames_matrix, all_frames_matrix_from_extremes,
};
use sim_core::kinematics::jacobian::{hybrid_jacobian, tip_jacobian};
use sim_core::kinematics::joint_limits::{q_from_theta, theta_from_q};
use sim_core::statics::energy::Potential;
use sim_core::{
    Chain, Frame, Hair, HairDirection, HairSide, JointLimit, frame_poses, hair_poses,
    strain_energy_j,
};

fn dv(v: &[f64]) -> DVector<f64> {
    DVector::from_column_slice(v)
}

fn rows(r: &[&[f64]]) -> DMatrix<f64> {
    DMatrix::from_fn(r.len(), r[0].len(), |i, j| r[i][j])
}

#[test]
fn alpha_5_1_as_printed() {
    let a = active_frames_vector(8, Frame::new(5), Frame::new(1)).unwrap();
    assert_eq!(a, dv(&[0., 0., -1., -1., -1., -1., 0., 0., 0.]));
}

#[test]
fn alpha_1_5_as_printed() {
    let a = active_frames_vector(8, Frame::new(1), Frame::new(5)).unwrap();
    assert_eq!(a, dv(&[0., 0., 1., 1., 1., 1., 0., 0., 0.]));
}

#[test]
fn a_5_1_as_printed() {
    let z = [0.0; 9];
    let printed = rows(&[
        &z,
        &z,
        &[0., 0., 0., -1., -1., -1., 0., 0., 0.],
        &[0., 0., 0., 0., -1., -1., 0., 0., 0.],
        &[0., 0., 0., 0., 0., -1., 0., 0., 0.],
        &z,
        &z,
        &z,
        &z,
    ]);
    assert_eq!(
        active_frames_matrix(8, Frame::new(5), Frame::new(1)).unwrap(),
        printed
    );
}

#[test]
fn a_1_5_as_printed() {
    let z = [0.0; 9];
    let printed = rows(&[
        &z,
        &z,
        &[0., 0., 1., 0., 0., 0., 0., 0., 0.],
        &[0., 0., 1., 1., 0., 0., 0., 0., 0.],
        &[0., 0., 1., 1., 1., 0., 0., 0., 0.],
        &[0., 0., 1., 1., 1., 1., 0., 0., 0.],
        &z,
        &z,
        &z,
    ]);
    assert_eq!(
        active_frames_matrix(8, Frame::new(1), Frame::new(5)).unwrap(),
        printed
    );
}

#[test]
fn all_alpha_5_b_as_printed() {
    let printed: [(isize, [f64; 9]); 10] = [
        (-1, [-1., -1., -1., -1., -1., -1., 0., 0., 0.]),
        (0, [0., -1., -1., -1., -1., -1., 0., 0., 0.]),
        (1, [0., 0., -1., -1., -1., -1., 0., 0., 0.]),
        (2, [0., 0., 0., -1., -1., -1., 0., 0., 0.]),
        (3, [0., 0., 0., 0., -1., -1., 0., 0., 0.]),
        (4, [0., 0., 0., 0., 0., -1., 0., 0., 0.]),
        (5, [0.; 9]),
        (6, [0., 0., 0., 0., 0., 0., 1., 0., 0.]),
        (7, [0., 0., 0., 0., 0., 0., 1., 1., 0.]),
        (8, [0., 0., 0., 0., 0., 0., 1., 1., 1.]),
    ];
    for (b, alpha) in printed {
        assert_eq!(
            active_frames_vector(8, Frame::new(5), Frame::new(b)).unwrap(),
            dv(&alpha),
            "alpha_5,{b}"
        );
    }
}

#[test]
fn all_frames_matrix_n8_s5_as_printed() {
    let printed = rows(&[
        &[-1., 0., 0., 0., 0., 0., 0., 0., 0.],
        &[-1., -1., 0., 0., 0., 0., 0., 0., 0.],
        &[-1., -1., -1., 0., 0., 0., 0., 0., 0.],
        &[-1., -1., -1., -1., 0., 0., 0., 0., 0.],
        &[-1., -1., -1., -1., -1., 0., 0., 0., 0.],
        &[-1., -1., -1., -1., -1., -1., 0., 0., 0.],
        &[0., 0., 0., 0., 0., 0., 1., 1., 1.],
        &[0., 0., 0., 0., 0., 0., 0., 1., 1.],
        &[0., 0., 0., 0., 0., 0., 0., 0., 1.],
    ]);
    let a = all_frames_matrix(8, Frame::new(5)).unwrap();
    assert_eq!(a.shape(), (9, 10), "A is (n+1) x (n+2) (2.2.3.1)");
    // column b + 1 = 6 is alpha_55 = 0; the print leaves it out
    assert!(a.column(6).iter().all(|&x| x == 0.0));
    let without_s = a.clone().remove_column(6);
    assert_eq!(without_s, printed);
    assert_eq!(
        all_frames_matrix_from_extremes(8, Frame::new(5)).unwrap(),
        a,
        "2.2.3.2"
    );
}

/// A straight chain along x, then turned by the base angle.
#[test]
fn straight_chain_positions() {
    let chain = Chain::builder(3)
        .link_lengths_m(vec![1.0, 2.0, 3.0, 4.0])
        .build()
        .unwrap();
    let p = frame_poses(&chain, &[0.0; 4], Frame::GROUND).unwrap();
    let xs: Vec<f64> = p.positions_m.row(0).iter().copied().collect();
    assert_eq!(xs, vec![0.0, 1.0, 3.0, 6.0, 10.0]);
    assert!(p.positions_m.row(1).iter().all(|&y| y == 0.0));
    // relative to the tip, everything lies behind it
    let p = frame_poses(&chain, &[0.0; 4], chain.tip()).unwrap();
    let xs: Vec<f64> = p.positions_m.row(0).iter().copied().collect();
    assert_eq!(xs, vec![-10.0, -9.0, -7.0, -4.0, 0.0]);
}

/// theta = (0, pi/2, pi/2), unit links: p_0 = (1, 0), p_1 = (1, 1), p_2 = (0, 1).
#[test]
fn hook_chain_by_hand() {
    let chain = Chain::builder(2).link_length_m(1.0).build().unwrap();
    let theta = [0.0, FRAC_PI_2, FRAC_PI_2];
    let p = frame_poses(&chain, &theta, Frame::GROUND).unwrap();
    let expect = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
    for (k, (x, y)) in expect.iter().enumerate() {
        assert!(
            (p.positions_m[(0, k)] - x).abs() < 1e-15 && (p.positions_m[(1, k)] - y).abs() < 1e-15
        );
    }
    assert!((p.angles_rad[3] - PI).abs() < 1e-15);

    // Tip Jacobian: column j = R90 (p_2 - p_(j-1)), angular 1.
    let j = tip_jacobian(&chain, &theta).unwrap();
    let expect = Matrix3xX::from_column_slice(&[-1.0, 0.0, 1.0, -1.0, -1.0, 1.0, 0.0, -1.0, 1.0]);
    assert!((j - expect).amax() < 1e-15);

    // J_(2,0): frame 2 held, frame 0 moves. In C_2 (turned by pi), p_20 = (-1, 1), joint 2 at
    // p_21 = (-1, 0). Joint 1 sits at frame 0 itself: only turns it (-1). Joint 2 swings it
    // about (-1, 0) by -theta_2_dot: velocity (1, 0).
    let j = hybrid_jacobian(&chain, &theta, Frame::new(2), Frame::new(0)).unwrap();
    let expect = Matrix3xX::from_column_slice(&[0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 1.0, 0.0, -1.0]);
    assert!((&j - expect).amax() < 1e-15, "{j}");
}

/// 2.2.4: g(0) is the middle, g(+-pi/2) the limits; Figure 2.13's limits {pi, -pi}.
#[test]
fn limit_map_by_hand() {
    let lim = JointLimit::new(-FRAC_PI_2, FRAC_PI_2);
    assert_eq!(lim.theta_from_q(0.0), 0.0);
    assert_eq!(lim.theta_from_q(FRAC_PI_2), FRAC_PI_2);
    assert_eq!(lim.theta_from_q(-FRAC_PI_2), -FRAC_PI_2);
    assert!((lim.theta_from_q(FRAC_PI_2 + 2.0 * PI) - FRAC_PI_2).abs() < 1e-15);
    let wide = JointLimit::new(-PI, PI);
    assert_eq!(wide.q_from_theta(PI), Some(FRAC_PI_2));
    assert_eq!(wide.q_from_theta(-PI), Some(-FRAC_PI_2));
    assert_eq!(wide.q_from_theta(0.0), Some(0.0));
    assert_eq!(wide.q_from_theta(3.2), None);

    let chain = Chain::builder(2)
        .base_angle_rad(0.5)
        .joint_limits(vec![JointLimit::new(0.0, 1.0), JointLimit::new(-1.0, 0.0)])
        .build()
        .unwrap();
    let theta = theta_from_q(&chain, &[9.0, FRAC_PI_2, 0.0]).unwrap();
    assert_eq!(theta.as_slice(), &[0.5, 1.0, -0.5]);
    let q = q_from_theta(&chain, &[0.5, 0.5, -1.0]).unwrap();
    assert_eq!(q.as_slice(), &[0.0, 0.0, -FRAC_PI_2]);
}

/// U = 1/2 sum k_j (theta_j - rest_j)^2, base excluded; a tip load adds -F . p_n.
#[test]
fn energy_by_hand() {
    let chain = Chain::builder(2)
        .link_length_m(1.0)
        .base_angle_rad(1.0)
        .stiffnesses_nm_per_rad(vec![2.0, 4.0])
        .rest_angles_rad(vec![0.5, 0.0])
        .build()
        .unwrap();
    let theta = [1.0, 1.5, -1.0];
    // 1/2 (2 * 1^2 + 4 * 1^2) = 3
    assert_eq!(strain_energy_j(&chain, &theta).unwrap(), 3.0);
    let pot = Potential::new(&chain);
    assert_eq!(
        pot.gradient_theta(&theta).unwrap().as_slice(),
        &[0.0, 2.0, -4.0]
    );
    assert_eq!(
        pot.hessian_theta(&theta).unwrap(),
        DMatrix::from_diagonal(&dv(&[0.0, 2.0, 4.0]))
    );
    // Straight chain along x, unit links, pulled along -y at the tip by 1 N: the tip is at
    // (3, 0); the load potential is -F . p = 0, its gradient -F . R90 (p_n - p_(j-1)) =
    // -(0,-1).(0, 3 - j) = 3 - j.
    let straight = Chain::builder(2).link_length_m(1.0).build().unwrap();
    let pot = Potential::new(&straight).with_tip_force_n(Vector2::new(0.0, -1.0));
    assert_eq!(pot.value_theta(&[0.0; 3]).unwrap(), 0.0);
    assert_eq!(
        pot.gradient_theta(&[0.0; 3]).unwrap().as_slice(),
        &[3.0, 2.0, 1.0]
    );
}

/// The thesis's hair (3.2.1): 18 mm at 45 degrees, pivot at the middle of a 40 mm link.
#[test]
fn hair_tip_by_hand() {
    let hair = Hair::seed(0.04);
    let chain = Chain::builder(1)
        .link_length_m(0.04)
        .hair(1, hair)
        .build()
        .unwrap();
    let theta = [0.0, 0.0];
    let betas = [0.0, FRAC_PI_4];
    let h = hair_poses(&chain, &theta, &betas, Frame::GROUND).unwrap();
    assert_eq!(h.len(), 1);
    let c = 0.018 * FRAC_PI_4.cos();
    // link 1 ends at x = 0.08; pivot at 0.06; tip distal and on the left (+y)
    assert!((h[0].pivot_m - Vector2::new(0.06, 0.0)).norm() < 1e-15);
    assert!((h[0].tip_m - Vector2::new(0.06 + c, c)).norm() < 1e-15);
    assert!((h[0].angle_rad - FRAC_PI_4).abs() < 1e-15);

    // Proximal, right side, offset 2 mm: tip behind the pivot, below the axis.
    let other = Hair {
        side: HairSide::Right,
        direction: HairDirection::Proximal,
        lateral_offset_m: 0.002,
        ..hair
    };
    let chain = Chain::builder(1)
        .link_length_m(0.04)
        .hair(1, other)
        .build()
        .unwrap();
    let h = hair_poses(&chain, &theta, &betas, Frame::GROUND).unwrap();
    assert!((h[0].tip_m - Vector2::new(0.06 - c, -0.002 - c)).norm() < 1e-15);
}
