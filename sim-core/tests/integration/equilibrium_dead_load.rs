//! Dead load at the tip: the solver's answer satisfies the equilibrium equations computed
//! independently (sim-core's dense tip Jacobian), matches the dense reference path, the
//! small-load linear theory, closed forms for one and two joints, and the rest posture
//! without load; the potential never increases along the iteration.
#![allow(clippy::unwrap_used)]

use crate::equilibrium_common;

use equilibrium_common::{potential, residual_torques, seed_exponential_chain, torque_scale};
use nalgebra::{DVector, Vector2};
use proptest::prelude::*;
use sim_core::kinematics::jacobian::tip_jacobian;
use sim_core::statics::equilibrium::{LinearSolver, SolverSettings, solve_equilibrium_with};
use sim_core::{
    Chain, EquilibriumProblem, InitialGuess, JointLimit, LimitSide, SolveOptions, solve_equilibrium,
};

fn settings(linear: LinearSolver) -> SolverSettings {
    SolverSettings {
        linear_solver: linear,
        record_trace: true,
    }
}

prop_compose! {
    fn random_chain()(n in 1usize..24, base in -3.0f64..3.0, seed_k in proptest::collection::vec(0.005f64..0.1, 24),
                      lengths in proptest::collection::vec(0.01f64..0.06, 25), rest in proptest::collection::vec(-0.2f64..0.2, 24)) -> Chain {
        Chain::builder(n)
            .link_lengths_m(lengths[..=n].to_vec())
            .base_angle_rad(base)
            .joint_limit(JointLimit::new(-3.0, 3.0))
            .stiffnesses_nm_per_rad(seed_k[..n].to_vec())
            .rest_angles_rad(rest[..n].to_vec())
            .build()
            .unwrap()
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// (a) `K (theta - rest) = J^T F` at the answer (dense Jacobian, independent of the
    /// solver), the answer is a stable minimum, and the dense reference path finds the same
    /// point; the potential decreases monotonically on both paths.
    #[test]
    fn equilibrium_equations_hold_and_dense_path_agrees(chain in random_chain(), fx in -0.5f64..0.5, fy in -0.5f64..0.5) {
        let f = Vector2::new(fx, fy);
        let problem = EquilibriumProblem::new(&chain).with_tip_force_n(f);
        let opts = SolveOptions::default();
        let (fast, trace) = solve_equilibrium_with(&problem, &InitialGuess::Straight, &opts, &settings(LinearSolver::Structured)).unwrap();
        prop_assert!(fast.converged, "{fast:?}");
        prop_assert!(trace.is_monotone());
        let r = residual_torques(&chain, &fast.theta_rad, f);
        let scale = torque_scale(&chain, f);
        for j in 1..=chain.n() {
            // Zero on free joints; on a joint resting on a limit, the stop torque.
            let stop = fast.limit_torques_nm[j];
            prop_assert!((r[j - 1] - stop).abs() <= 1e-9 * scale, "joint {} residual {} stop {} scale {}", j, r[j - 1], stop, scale);
        }
        let (dense, dtrace) = solve_equilibrium_with(&problem, &InitialGuess::Straight, &opts, &settings(LinearSolver::Dense)).unwrap();
        prop_assert!(dense.converged && dtrace.is_monotone());
        let differ = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
        // Where the Newton matrix never needed modification, both paths take the same
        // Newton steps and land on the same point; otherwise (an indefinite stretch, where
        // the two modifications differ) they may find different minima, so the dense path is
        // restarted from the structured answer and must stay there.
        if !trace.steps.iter().any(|s| s.modified) && !dtrace.steps.iter().any(|s| s.modified) {
            prop_assert!(differ(&fast.theta_rad, &dense.theta_rad) < 1e-7);
            prop_assert_eq!(fast.iterations, dense.iterations);
        }
        let warm = InitialGuess::Angles(fast.theta_rad[1..].to_vec());
        let (again, _) = solve_equilibrium_with(&problem, &warm, &opts, &settings(LinearSolver::Dense)).unwrap();
        prop_assert!(again.converged);
        if fast.stable {
            prop_assert!(differ(&fast.theta_rad, &again.theta_rad) < 1e-7);
        }
        let dense = again;
        prop_assert_eq!(fast.stable, dense.stable);
    }
}

/// (b) For a small load the deflection is `K^-1 J^T F` with `J` at the rest posture (first
/// order); the error is second order in the load.
#[test]
fn small_load_matches_linear_theory() {
    let chain = seed_exponential_chain(0.3);
    let theta0 = chain.rest_theta();
    let j = tip_jacobian(&chain, &theta0).unwrap();
    for scale in [1e-3, 1e-4] {
        let f = Vector2::new(0.3, -0.7) * scale;
        let problem = EquilibriumProblem::new(&chain).with_tip_force_n(f);
        let eq =
            solve_equilibrium(&problem, &InitialGuess::Straight, &SolveOptions::default()).unwrap();
        assert!(eq.converged);
        let jtf = j.fixed_rows::<2>(0).transpose() * f;
        let mut worst = 0.0_f64;
        let mut size = 0.0_f64;
        for i in 1..=chain.n() {
            let lin = jtf[i] / chain.stiffness_nm_per_rad()[i];
            worst = worst.max((eq.theta_rad[i] - lin).abs());
            size = size.max(lin.abs());
        }
        // Second order: the relative error scales with the load.
        assert!(
            worst <= 5.0 * size * size.max(1e-12),
            "scale {scale}: error {worst}, deflection {size}"
        );
    }
}

/// (c) One joint: `k theta = F l cos(theta)` for a load `F` perpendicular to the unbent link
/// (solved here by bisection).
#[test]
fn one_joint_closed_form() {
    let (k, l, force) = (0.05, 0.04, 2.0);
    let chain = Chain::builder(1)
        .link_length_m(l)
        .stiffness_nm_per_rad(k)
        .build()
        .unwrap();
    let problem = EquilibriumProblem::new(&chain).with_tip_force_n(Vector2::new(0.0, force));
    let eq =
        solve_equilibrium(&problem, &InitialGuess::Straight, &SolveOptions::default()).unwrap();
    let (mut lo, mut hi) = (0.0_f64, 1.5_f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if k * mid - force * l * mid.cos() < 0.0 {
            lo = mid
        } else {
            hi = mid
        }
    }
    assert!(eq.converged && eq.stable);
    assert!(
        (eq.theta_rad[1] - lo).abs() < 1e-12,
        "{} vs {}",
        eq.theta_rad[1],
        lo
    );
}

/// (c) Two joints: the answer is the global minimum found by an independent grid search
/// refined by a local grid, and no grid point has lower potential.
#[test]
fn two_joints_match_brute_force_minimum() {
    let chain = Chain::builder(2)
        .link_lengths_m(vec![0.02, 0.05, 0.03])
        .stiffnesses_nm_per_rad(vec![0.08, 0.02])
        .rest_angles_rad(vec![0.1, -0.2])
        .build()
        .unwrap();
    let f = Vector2::new(-0.4, -1.1);
    let problem = EquilibriumProblem::new(&chain).with_tip_force_n(f);
    let eq =
        solve_equilibrium(&problem, &InitialGuess::Straight, &SolveOptions::default()).unwrap();
    assert!(eq.converged && eq.stable);
    let pot = |a: f64, b: f64| potential(&chain, &[0.0, a, b], f);
    let (mut best, mut arg) = (f64::INFINITY, (0.0, 0.0));
    let steps = 400;
    let h = std::f64::consts::PI / steps as f64;
    for i in 0..=steps {
        for j in 0..=steps {
            let (a, b) = (
                -std::f64::consts::FRAC_PI_2 + i as f64 * h,
                -std::f64::consts::FRAC_PI_2 + j as f64 * h,
            );
            let p = pot(a, b);
            if p < best {
                best = p;
                arg = (a, b);
            }
        }
    }
    // Refine around the best grid point.
    let mut span = h;
    for _ in 0..40 {
        let (a0, b0) = arg;
        for i in -4..=4 {
            for j in -4..=4 {
                let (a, b) = (a0 + i as f64 * span / 4.0, b0 + j as f64 * span / 4.0);
                let p = pot(a, b);
                if p < best {
                    best = p;
                    arg = (a, b);
                }
            }
        }
        span *= 0.5;
    }
    assert!(
        (eq.theta_rad[1] - arg.0).abs() < 1e-6 && (eq.theta_rad[2] - arg.1).abs() < 1e-6,
        "{:?} vs {:?}",
        eq.theta_rad,
        arg
    );
    assert!(eq.total_potential_j <= best + 1e-15);
    assert!((eq.total_potential_j - potential(&chain, &eq.theta_rad, f)).abs() < 1e-15);
}

/// (f) Without a load the answer is the rest posture clamped into the limits; a joint whose
/// rest angle lies beyond a limit rests on it, pushed by the stop the right way.
#[test]
fn no_load_gives_rest_posture_clamped() {
    let chain = Chain::builder(4)
        .stiffnesses_nm_per_rad(vec![0.05, 0.02, 0.01, 0.03])
        .joint_limit(JointLimit::new(-0.5, 0.5))
        .rest_angles_rad(vec![0.2, 0.9, -0.3, -1.2])
        .build()
        .unwrap();
    let problem = EquilibriumProblem::new(&chain);
    for start in [
        InitialGuess::Straight,
        InitialGuess::C,
        InitialGuess::S.mirrored(),
    ] {
        let eq = solve_equilibrium(&problem, &start, &SolveOptions::default()).unwrap();
        assert!(eq.converged && eq.stable);
        let expected = chain.rest_theta();
        for (a, b) in eq.theta_rad.iter().zip(&expected) {
            assert!(
                (a - b).abs() < 1e-12,
                "{:?} vs {:?}",
                eq.theta_rad,
                expected
            );
        }
        assert_eq!(eq.limit_sides[2], LimitSide::CounterClockwise);
        assert!((eq.limit_torques_nm[2] - -0.02 * 0.4).abs() < 1e-12);
        assert_eq!(eq.limit_sides[4], LimitSide::Clockwise);
        assert!((eq.limit_torques_nm[4] - 0.03 * 0.7).abs() < 1e-12);
        assert_eq!(eq.limit_sides[1], LimitSide::Free);
        assert_eq!(eq.energy_j, 0.5 * (0.02 * 0.4 * 0.4 + 0.03 * 0.7 * 0.7));
    }
}

/// (i) The potential never increases across accepted steps, even for a large load from a
/// bad start, and the traced merit matches the potential recomputed directly at the end.
#[test]
fn potential_never_increases() {
    let chain = seed_exponential_chain(0.5);
    for (f, start) in [
        (Vector2::new(0.0, -5.0), InitialGuess::Straight),
        (Vector2::new(3.0, 4.0), InitialGuess::S),
        (Vector2::new(-8.0, 0.5), InitialGuess::C.mirrored()),
    ] {
        let problem = EquilibriumProblem::new(&chain).with_tip_force_n(f);
        let (eq, trace) = solve_equilibrium_with(
            &problem,
            &start,
            &SolveOptions::default(),
            &settings(LinearSolver::Structured),
        )
        .unwrap();
        assert!(eq.converged, "{eq:?}");
        assert!(trace.is_monotone());
        assert!(trace.steps.windows(2).all(|w| w[1].merit_j <= w[0].merit_j));
        let last = trace.steps.last().unwrap().merit_j;
        assert!(
            (last - eq.total_potential_j).abs() <= 1e-12 * eq.total_potential_j.abs().max(1e-3)
        );
    }
}

/// A straight column under an axial compressive load beyond buckling is an exact but
/// unstable equilibrium; the solver leaves it along the buckling mode and ends stable.
#[test]
fn axial_compression_buckles_from_straight() {
    let chain = Chain::builder(10)
        .link_length_m(0.02)
        .stiffness_nm_per_rad(0.01)
        .build()
        .unwrap();
    let problem = EquilibriumProblem::new(&chain).with_tip_force_n(Vector2::new(-5.0, 0.0));
    let (eq, trace) = solve_equilibrium_with(
        &problem,
        &InitialGuess::Straight,
        &SolveOptions::default(),
        &settings(LinearSolver::Structured),
    )
    .unwrap();
    assert!(eq.converged && eq.stable, "{eq:?}");
    assert!(trace.is_monotone());
    assert!(eq.theta_rad[1..].iter().any(|t| t.abs() > 0.01));
    assert!(eq.total_potential_j < potential(&chain, &chain.rest_theta(), Vector2::new(-5.0, 0.0)));
}

/// The residual reported is the one the test computes.
#[test]
fn reported_residual_is_honest() {
    let chain = seed_exponential_chain(0.0);
    let f = Vector2::new(0.1, 0.3);
    let problem = EquilibriumProblem::new(&chain).with_tip_force_n(f);
    let eq = solve_equilibrium(
        &problem,
        &InitialGuess::C,
        &SolveOptions {
            tolerance: 1e-4,
            max_iterations: 200,
        },
    )
    .unwrap();
    let r: DVector<f64> = residual_torques(&chain, &eq.theta_rad, f);
    let mine = r.amax() / torque_scale(&chain, f);
    assert!(
        (mine - eq.kkt_residual).abs() <= 1e-12 + 1e-6 * mine,
        "{mine} vs {}",
        eq.kkt_residual
    );
}
