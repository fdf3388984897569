//! Tip forces (thesis 3.2.2, docs/model.md 4) on exact equilibria built without a solver
//! (`tip_force_common`): least squares `J^T F = -tau` recovers the force when no joint is on
//! a limit; the free-body system agrees with it then, and with joints on a limit recovers
//! the force and the stop torques where least squares is provably wrong; the free-body
//! answer solves the thesis's per-link system 3.2.2.9 (assembled densely here); the base
//! reaction balances the chain and the servo torque is the virtual work of turning the base.
#![allow(clippy::unwrap_used)]

use crate::tip_force_common;

use nalgebra::{DMatrix, DVector, Vector2};
use proptest::prelude::*;
use sim_core::kinematics::jacobian::tip_jacobian;
use sim_core::statics::energy::Potential;
use sim_core::statics::tip_force::{
    joints_on_limit, tip_force_free_body, tip_force_least_squares, tip_wrench_least_squares,
};
use sim_core::{Chain, Frame, frame_poses, tip_pose};
use tip_force_common::{
    Equilibrium, close, close2, free_equilibrium, geometry, jt, limited_equilibrium,
    singular_values_2,
};

/// 2D cross product `a x b`.
fn cross(a: Vector2<f64>, b: Vector2<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

/// The thesis's free-body system 3.2.2.9, with a stop torque unknown at each joint on a limit,
/// assembled densely and solved by SVD: per link `i`, two force equations and the moment
/// about its proximal joint. Unknowns: `f_0..f_n` (the force link `i - 1`, or the ground, exerts on
/// link `i`), `F`, `tau_servo`, then the stop torques in joint order. Returns the solution
/// and the rank of the system.
fn seed_free_body(chain: &Chain, theta: &[f64], on_limit: &[bool]) -> (DVector<f64>, usize) {
    let n = chain.n();
    let limited: Vec<usize> = (1..=n).filter(|&j| on_limit[j]).collect();
    let (i_f, i_servo) = (2 * (n + 1), 2 * (n + 1) + 2);
    let cols = i_servo + 1 + limited.len();
    let rows = 3 * (n + 1);
    let mut a = DMatrix::zeros(rows, cols);
    let mut rhs = DVector::zeros(rows);
    let poses = frame_poses(chain, theta, Frame::GROUND).unwrap();
    let p = |i: isize| -> Vector2<f64> { poses.positions_m.column((i + 1) as usize).into() };
    let k = chain.stiffness_nm_per_rad();
    let r = chain.rest_angles_rad();
    let spring = |j: usize| k[j] * (theta[j] - r[j]);
    for i in 0..=n {
        let (fx, fy, m) = (3 * i, 3 * i + 1, 3 * i + 2);
        // f_i + (distal force) = 0; the distal force is -f_(i+1), or F on the tip link.
        a[(fx, 2 * i)] = 1.0;
        a[(fy, 2 * i + 1)] = 1.0;
        let (dx, dy, sign) = if i < n {
            (2 * (i + 1), 2 * (i + 1) + 1, -1.0)
        } else {
            (i_f, i_f + 1, 1.0)
        };
        a[(fx, dx)] = sign;
        a[(fy, dy)] = sign;
        // T_i - T_(i+1) + (p_i - p_(i-1)) x distal = 0, T_j = -k_j (theta_j - rest_j) + s_j,
        // T_0 = tau_servo - k_0 (theta_0 - rest_0).
        let arm = p(i as isize) - p(i as isize - 1);
        a[(m, dx)] = sign * -arm.y;
        a[(m, dy)] = sign * arm.x;
        if i == 0 {
            a[(m, i_servo)] = 1.0;
        } else if let Some(c) = limited.iter().position(|&j| j == i) {
            a[(m, i_servo + 1 + c)] = 1.0;
        }
        rhs[m] += spring(i);
        if i < n {
            if let Some(c) = limited.iter().position(|&j| j == i + 1) {
                a[(m, i_servo + 1 + c)] = -1.0;
            }
            rhs[m] -= spring(i + 1);
        }
    }
    // Householder QR (nalgebra's SVD is avoided: see tip_force.rs); the rank is judged from
    // R's diagonal.
    let qr = a.qr();
    let mut qtb = rhs;
    qr.q_tr_mul(&mut qtb);
    let r = qr.r();
    let d = r.diagonal().map(f64::abs);
    let rank = d.iter().filter(|&&x| x > 1e-12 * d.max()).count();
    let x = r
        .solve_upper_triangular(&qtb.rows(0, cols).into_owned())
        .unwrap();
    (x, rank)
}

/// `F` within `1e-9` relative, or the construction's rounding over `sigma_min` when that
/// is larger (an ill-conditioned posture).
fn check_equilibrium_force(e: &Equilibrium, got: Vector2<f64>) -> Result<(), TestCaseError> {
    close2("F", got, e.force_n, 1.0, e.force_tol_n())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    /// With no joint on a limit, least squares returns the force that was put in, with zero
    /// residual and full rank.
    #[test]
    fn least_squares_recovers_an_exact_equilibrium(e in free_equilibrium(2..=40)) {
        let fit = tip_force_least_squares(&e.chain, &e.theta).unwrap();
        check_equilibrium_force(&e, fit.force_n)?;
        if e.condition_number() < 1e8 {
            prop_assert_eq!(fit.rank, 2);
        }
        prop_assert_eq!(fit.moment_nm, 0.0);
        prop_assert_eq!(fit.residual_nm[0], 0.0);
        close("residual", fit.residual_norm_nm, 0.0, 1.0, e.residual_tol_nm())?;
        prop_assert_eq!(fit.force_on_environment_n(), -fit.force_n);
    }

    /// With no joint on a limit the free-body system is the least-squares fit, exactly, even
    /// for torques no tip force explains (random rest angles); stop torques are zero and the
    /// joint torques are the springs'.
    #[test]
    fn free_body_equals_least_squares_without_limits(
        (l, b, j, k) in geometry(1..=30),
        rest in prop::collection::vec(-1.0..1.0f64, 30),
    ) {
        let n = j.len();
        let chain = Chain::builder(n)
            .link_lengths_m(l)
            .base_angle_rad(b)
            .stiffnesses_nm_per_rad(k)
            .rest_angles_rad(rest[..n].to_vec())
            .build()
            .unwrap();
        let mut theta = vec![b];
        theta.extend(&j);
        let ls = tip_force_least_squares(&chain, &theta).unwrap();
        let fb = tip_force_free_body(&chain, &theta, &vec![false; n + 1]).unwrap();
        prop_assert_eq!(&fb.tip, &ls);
        prop_assert!(fb.stop_torques_nm.iter().all(|&s| s == 0.0));
        let tau = sim_core::statics::energy::joint_torques_nm(&chain, &theta).unwrap();
        for jj in 1..=n {
            prop_assert_eq!(fb.joint_torques_nm[jj], tau[jj]);
        }
        prop_assert_eq!(fb.base_reaction_force_n, -ls.force_n);
    }

    /// With joints on a limit (stop torques on top of `J^T F`), the free-body system recovers
    /// `F` and every stop torque, with the sign of its stop; `joints_on_limit` finds exactly
    /// those joints. Least squares is wrong by exactly `(A^T A)^-1 A^T S s` (`A = J^T`
    /// over the flexible joints, `S s` the stop torques) and cannot fit the torques:
    /// `||s||^2 = ||A dF||^2 + ||residual||^2`, so it errs in `F` or in its residual.
    #[test]
    fn free_body_recovers_stop_torques_where_least_squares_fails(e in limited_equilibrium(3..=30)) {
        let n = e.chain.n();
        let flags = joints_on_limit(&e.chain, &e.theta, 0.0).unwrap();
        prop_assert_eq!(&flags, &e.on_limit);

        let fb = tip_force_free_body(&e.chain, &e.theta, &e.on_limit).unwrap();
        check_equilibrium_force(&e, fb.tip.force_n)?;
        let scale = e.force_n.norm() * e.chain.total_length_m();
        for j in 0..=n {
            let tol = 1e-9 * scale + e.chain.total_length_m() * e.force_tol_n() + e.rounding_nm();
            close("stop torque", fb.stop_torques_nm[j], e.stop_nm[j], 1.0, tol)?;
            if e.on_limit[j] {
                let lim = e.chain.joint_limits()[j];
                if e.theta[j] == lim.cw_rad {
                    prop_assert!(fb.stop_torques_nm[j] > 0.0, "a clockwise stop pushes ccw");
                } else {
                    prop_assert!(fb.stop_torques_nm[j] < 0.0, "a ccw stop pushes clockwise");
                }
            }
        }
        close("residual", fb.tip.residual_norm_nm, 0.0, 1.0, e.residual_tol_nm())?;

        // Least squares: the independent formula for its error, and the proof it is wrong.
        let ls = tip_force_least_squares(&e.chain, &e.theta).unwrap();
        let a = jt(&e.chain, &e.theta).rows(1, n).into_owned();
        let s = DVector::from_column_slice(&e.stop_nm[1..]);
        let df = (a.transpose() * &a).try_inverse().unwrap() * a.transpose() * &s;
        let (sigma_max, sigma_min_all) = singular_values_2(&a);
        let tol = 1e-9 * (e.force_n.norm() + df.norm()) + 4.0 * e.rounding_nm() / sigma_min_all;
        close2("LS error", ls.force_n - e.force_n, Vector2::new(df[0], df[1]), 1.0, tol)?;
        let (df_norm, res) = ((ls.force_n - e.force_n).norm(), ls.residual_norm_nm);
        let lhs = ((sigma_max * df_norm).powi(2) + res * res).sqrt();
        prop_assert!(lhs >= s.norm() * (1.0 - 1e-6), "LS wrong: {lhs:e} vs ||s|| {:e}", s.norm());
    }

    /// The free-body answer solves the thesis's per-link system 3.2.2.9 (with stop torques):
    /// the same `F`, servo torque, stop torques, and base reaction `f_0 = -F`; every
    /// intersegmental force is `-F`.
    #[test]
    fn free_body_solves_the_seeds_per_link_system(e in prop_oneof![free_equilibrium(2..=10), limited_equilibrium(3..=10)]) {
        let n = e.chain.n();
        let fb = tip_force_free_body(&e.chain, &e.theta, &e.on_limit).unwrap();
        prop_assume!(fb.tip.condition_number < 1e4);
        let (x, rank) = seed_free_body(&e.chain, &e.theta, &e.on_limit);
        prop_assert_eq!(rank, x.len(), "3.2.2.9 has a unique solution");
        let i_f = 2 * (n + 1);
        let fscale = e.force_n.norm();
        let mscale = fscale * e.chain.total_length_m();
        close2("F", Vector2::new(x[i_f], x[i_f + 1]), fb.tip.force_n, 1e-8, fscale)?;
        for i in 0..=n {
            close2("f_i = -F", Vector2::new(x[2 * i], x[2 * i + 1]), -fb.tip.force_n, 1e-8, fscale)?;
        }
        close2("base reaction", Vector2::new(x[0], x[1]), fb.base_reaction_force_n, 1e-8, fscale)?;
        close("servo", x[i_f + 2], fb.servo_torque_nm, 1e-8, mscale)?;
        let limited: Vec<usize> = (1..=n).filter(|&j| e.on_limit[j]).collect();
        for (c, &j) in limited.iter().enumerate() {
            close("stop", x[i_f + 3 + c], fb.stop_torques_nm[j], 1e-8, mscale)?;
        }
    }

    /// Base reaction and servo torque, for the fitted `F` (any posture: these are
    /// definitions, not fit accuracy). Sum of forces: `R + F = 0`; sum of moments about the
    /// base: `M + p_n x F = 0` (tip position from `tip_pose`). Virtual work: the servo
    /// torque is `dP/dtheta_0` of `P = U - F . p_n` (central differences; turning the base
    /// turns the whole chain rigidly), and each stop torque is `dP/dtheta_j` at its joint
    /// (what the stop must hold). Joint torques: `-(J^T F)_j - residual_j`.
    #[test]
    fn base_reaction_and_servo_torque_balance_the_chain(e in prop_oneof![free_equilibrium(1..=20), limited_equilibrium(3..=20)]) {
        let fb = tip_force_free_body(&e.chain, &e.theta, &e.on_limit).unwrap();
        let f = fb.tip.force_n;
        let scale = f.norm() * e.chain.total_length_m();
        prop_assert_eq!(fb.base_reaction_force_n, -f);
        let tip = tip_pose(&e.chain, &e.theta).unwrap().position_m;
        close("M + p_n x F = 0", fb.base_reaction_moment_nm + cross(tip, f), 0.0, 1e-13, scale)?;
        prop_assert_eq!(fb.joint_torques_nm[0], fb.base_reaction_moment_nm);
        prop_assert_eq!(fb.servo_torque_nm, fb.base_reaction_moment_nm); // k_0 = 0

        let p = Potential::new(&e.chain).with_tip_force_n(f);
        let h = 1e-6;
        let dp = |j: usize| {
            let mut t = e.theta.clone();
            t[j] += h;
            let up = p.value_theta(&t).unwrap();
            t[j] -= 2.0 * h;
            (up - p.value_theta(&t).unwrap()) / (2.0 * h)
        };
        // Central differences: U is quadratic (exact), the load's truncation is
        // O(h^2 |F| L); rounding ~ eps |P| / h.
        let fd_tol = 1e-8 * scale + 1e-14 * p.value_theta(&e.theta).unwrap().abs() / h;
        close("servo = dP/dtheta_0", fb.servo_torque_nm, dp(0), 1.0, fd_tol)?;
        for j in 1..=e.chain.n() {
            if e.on_limit[j] {
                close("stop = dP/dtheta_j", fb.stop_torques_nm[j], dp(j), 1.0, fd_tol)?;
            }
        }
        let jt_f = jt(&e.chain, &e.theta) * f;
        for j in 1..=e.chain.n() {
            let sum = fb.joint_torques_nm[j] + jt_f[j] + fb.tip.residual_nm[j];
            close("joint torque = -(J^T F)_j - residual_j", sum, 0.0, 1e-12, scale + e.torque_scale())?;
        }
    }

    /// The wrench fit (thesis 3.2.2.11 with the angular row) recovers a tip force and moment
    /// put in together, with three or more joints.
    #[test]
    fn wrench_fit_recovers_force_and_moment(
        (l, b, j, k) in geometry(3..=30),
        f in tip_force_common::force(),
        m_factor in -1.0..1.0f64,
    ) {
        let n = j.len();
        let mut theta = vec![b];
        theta.extend(&j);
        let probe = Chain::builder(n).link_lengths_m(l.clone()).base_angle_rad(b).build().unwrap();
        let m = m_factor * f.norm() * probe.total_length_m();
        let jac = tip_jacobian(&probe, &theta).unwrap();
        let load = jac.transpose() * nalgebra::Vector3::new(f.x, f.y, m);
        let rest: Vec<f64> = (1..=n).map(|i| theta[i] - load[i] / k[i - 1]).collect();
        let chain = Chain::builder(n)
            .link_lengths_m(l)
            .base_angle_rad(b)
            .stiffnesses_nm_per_rad(k)
            .rest_angles_rad(rest)
            .build()
            .unwrap();
        let fit = tip_wrench_least_squares(&chain, &theta).unwrap();
        prop_assume!(fit.condition_number < 1e5);
        prop_assert_eq!(fit.rank, 3);
        close2("F", fit.force_n, f, 1e-9, f.norm())?;
        close("M", fit.moment_nm, m, 1e-9, f.norm() * chain.total_length_m())?;
    }
}

/// A straight chain cannot tell an axial force: rank 1, the perpendicular component is
/// recovered and the axial one is left at zero (minimum norm).
#[test]
fn straight_chain_has_rank_one() {
    let (n, k, l) = (6, 0.05, 0.03);
    let base = 0.4_f64;
    let axis = Vector2::new(base.cos(), base.sin());
    let perp = Vector2::new(-axis.y, axis.x);
    let f = 0.3 * perp + 0.7 * axis;
    // (J^T F)_j = d_j x F with d_j = (n + 1 - j) l axis: only the perpendicular part counts.
    let rest: Vec<f64> = (1..=n)
        .map(|j| -((n + 1 - j) as f64 * l * 0.3) / k)
        .collect();
    let chain = Chain::builder(n)
        .link_length_m(l)
        .base_angle_rad(base)
        .stiffness_nm_per_rad(k)
        .rest_angles_rad(rest)
        .build()
        .unwrap();
    let mut theta = vec![0.0; n + 1];
    theta[0] = base;
    let fit = tip_force_least_squares(&chain, &theta).unwrap();
    assert_eq!(fit.rank, 1);
    assert!(fit.condition_number.is_infinite());
    assert!(
        (fit.force_n - f.dot(&perp) * perp).norm() < 1e-12,
        "{:?}",
        fit.force_n
    );
    assert!(fit.residual_norm_nm < 1e-15);
}

/// A worked example of least squares going wrong at a limit: a 6-joint chain whose joint 3
/// rests on its clockwise stop, the stop pushing as hard as the tip force's moment.
#[test]
fn least_squares_is_wrong_at_a_limit_worked_example() {
    let e = tip_force_common::build(
        vec![0.04; 7],
        0.5,
        vec![0.3, -0.2, 0.4, 0.5, -0.1, 0.6],
        vec![0.02; 6],
        Vector2::new(0.0, -0.2),
        &[0.0, 0.0, 0.5, 0.0, 0.0, 0.0],
    );
    let fb = tip_force_free_body(&e.chain, &e.theta, &e.on_limit).unwrap();
    let ls = tip_force_least_squares(&e.chain, &e.theta).unwrap();
    assert!((fb.tip.force_n - e.force_n).norm() < 1e-12);
    assert!((fb.stop_torques_nm[3] - e.stop_nm[3]).abs() < 1e-15);
    let err = (ls.force_n - e.force_n).norm() / e.force_n.norm();
    assert!(err > 0.1, "least squares off by {err}");
}

/// `n = 4096`: the fit stays `O(n)` and exact on an exact equilibrium.
#[test]
fn long_chain() {
    let n = 4096;
    let joints: Vec<f64> = (0..n)
        .map(|j| 0.2 * (j as f64 * 0.01).sin() + 0.001)
        .collect();
    let e = tip_force_common::build(
        vec![1e-3; n + 1],
        0.3,
        joints,
        vec![0.01; n],
        Vector2::new(0.3, -0.4),
        &[],
    );
    // Its cost, O(n), is measured by the kinematics benchmark (`tip_force`, BENCHMARKS.md's
    // "Kinematics", time(4096) / time(512) <= 10), not bounded here: a loaded machine would
    // fail a bound on the time.
    let fit = tip_force_least_squares(&e.chain, &e.theta).unwrap();
    assert!(
        (fit.force_n - e.force_n).norm() < 1e-9 * e.force_n.norm(),
        "{:?}",
        fit.force_n
    );
}
