//! (d, g) Pinned tip: the pin is met, the KKT residual is small, the reported pin force is
//! the least-squares `J^T F = tau` force computed here independently, the C and S starts
//! reach equilibria with 0 and 1 inflections, mirrored starts give mirrored answers, and the
//! multi-start search finds the C, the S and their mirror images, sorted by energy.
#![allow(clippy::unwrap_used)]

use crate::equilibrium_common;

use equilibrium_common::{
    first_joint, least_squares_pin_force, residual_torques, seed_exponential_chain, torque_scale,
};
use nalgebra::Vector2;
use sim_core::statics::equilibrium::{LinearSolver, SolverSettings, solve_equilibrium_with};
use sim_core::{
    Chain, EquilibriumError, EquilibriumProblem, InitialGuess, JointLimit, MinimaSearch,
    SolveOptions, all_minima, solve_equilibrium, tip_pose,
};

fn pin_at(chain: &Chain, fraction_of_reach: f64, angle_deg: f64) -> Vector2<f64> {
    let reach: f64 = chain.link_lengths_m()[1..].iter().sum();
    let a = chain.base_angle_rad() + angle_deg.to_radians();
    first_joint(chain) + Vector2::new(a.cos(), a.sin()) * reach * fraction_of_reach
}

/// The thesis's robot's chain with wide limits (+-3 rad) so that the folded shapes are allowed.
fn wide_chain() -> Chain {
    let seed = seed_exponential_chain(0.0);
    Chain::builder(8)
        .link_length_m(0.04)
        .joint_limit(JointLimit::new(-3.0, 3.0))
        .stiffnesses_nm_per_rad(seed.stiffness_nm_per_rad()[1..].to_vec())
        .build()
        .unwrap()
}

fn check_pinned(chain: &Chain, pin: Vector2<f64>, dead: Vector2<f64>, eq: &sim_core::Equilibrium) {
    assert!(eq.converged, "{eq:?}");
    let tip = tip_pose(chain, &eq.theta_rad).unwrap().position_m;
    assert!(
        (tip - pin).norm() <= 1e-10 * 0.32,
        "pin missed by {}",
        (tip - pin).norm()
    );
    let f = dead + eq.pin_force_n;
    let r = residual_torques(chain, &eq.theta_rad, f);
    for j in 1..=chain.n() {
        // Zero on free joints; the stop torque on joints resting on a limit.
        let stop = eq.limit_torques_nm[j];
        assert!(
            (r[j - 1] - stop).abs() <= 1e-9 * torque_scale(chain, f),
            "joint {j} unbalanced: {} vs stop {stop}",
            r[j - 1]
        );
    }
    if eq
        .limit_sides
        .iter()
        .any(|s| *s != sim_core::LimitSide::Free)
    {
        return;
    }
    let ls = least_squares_pin_force(chain, eq, dead);
    assert!(
        (ls - eq.pin_force_n).norm() <= 1e-8 * (1.0 + ls.norm()),
        "pin force {:?} vs least squares {:?}",
        eq.pin_force_n,
        ls
    );
}

/// (d) On the thesis's robot (fast-exponential 0.082 -> 0.004 N m/rad, limits +-90 deg), with
/// the pin 32 mm from the first joint at 100 deg to the base link: the C start reaches a
/// C (0 inflections), the S start an S (1 inflection); both stable, the C lower.
#[test]
fn seed_robot_c_and_s_starts() {
    let chain = seed_exponential_chain(30f64.to_radians());
    let pin = pin_at(&chain, 0.1, 100.0);
    let problem = EquilibriumProblem::new(&chain).with_tip_pin_m(pin);
    let c = solve_equilibrium(&problem, &InitialGuess::C, &SolveOptions::default()).unwrap();
    let s = solve_equilibrium(&problem, &InitialGuess::S, &SolveOptions::default()).unwrap();
    check_pinned(&chain, pin, Vector2::zeros(), &c);
    check_pinned(&chain, pin, Vector2::zeros(), &s);
    assert_eq!(
        (c.inflections, s.inflections),
        (0, 1),
        "C {:?}\nS {:?}",
        c.theta_rad,
        s.theta_rad
    );
    assert!(c.stable && s.stable);
    assert!(c.total_potential_j < s.total_potential_j);
}

/// (d) Mirror flips signs: with the base angle 0 and the pin on the base axis the problem is
/// symmetric, and the mirrored starts give the negated answers.
#[test]
fn mirror_flips_signs() {
    let chain = wide_chain();
    let pin = pin_at(&chain, 0.2, 180.0);
    let problem = EquilibriumProblem::new(&chain).with_tip_pin_m(pin);
    for start in [InitialGuess::C, InitialGuess::S] {
        let a = solve_equilibrium(&problem, &start, &SolveOptions::default()).unwrap();
        let b = solve_equilibrium(
            &problem,
            &start.clone().mirrored(),
            &SolveOptions::default(),
        )
        .unwrap();
        check_pinned(&chain, pin, Vector2::zeros(), &a);
        check_pinned(&chain, pin, Vector2::zeros(), &b);
        for (x, y) in a.theta_rad[1..].iter().zip(&b.theta_rad[1..]) {
            assert!(
                (x + y).abs() < 1e-7,
                "{:?} vs {:?}",
                a.theta_rad,
                b.theta_rad
            );
        }
        assert!(
            (a.pin_force_n.x - b.pin_force_n.x).abs() < 1e-7
                && (a.pin_force_n.y + b.pin_force_n.y).abs() < 1e-7
        );
    }
}

/// (g) The multi-start search on the symmetric wide-limit chain finds at least the C, the S
/// and their mirror images: distinct, stable, converged, sorted by potential.
#[test]
fn all_minima_finds_c_s_and_mirrors() {
    let chain = wide_chain();
    let pin = pin_at(&chain, 0.2, 180.0);
    let problem = EquilibriumProblem::new(&chain).with_tip_pin_m(pin);
    let all = all_minima(&problem, &SolveOptions::default(), &MinimaSearch::default()).unwrap();
    assert!(all.len() >= 4, "{} minima", all.len());
    for w in all.windows(2) {
        assert!(w[0].total_potential_j <= w[1].total_potential_j);
    }
    for (i, a) in all.iter().enumerate() {
        assert!(a.converged && a.stable);
        check_pinned(&chain, pin, Vector2::zeros(), a);
        for b in &all[i + 1..] {
            let d = a
                .theta_rad
                .iter()
                .zip(&b.theta_rad)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            assert!(d >= 1e-6);
        }
    }
    let zero = all.iter().filter(|e| e.inflections == 0).count();
    let one = all.iter().filter(|e| e.inflections == 1).count();
    assert!(
        zero >= 2 && one >= 2,
        "inflections {:?}",
        all.iter().map(|e| e.inflections).collect::<Vec<_>>()
    );
    // The search is deterministic.
    let again = all_minima(&problem, &SolveOptions::default(), &MinimaSearch::default()).unwrap();
    assert_eq!(all, again);
}

/// A dead load and a pin together; structured and dense paths agree from the same start
/// when neither modified the Newton matrix, and the merit never increases within a segment.
#[test]
fn pin_with_dead_load_and_dense_reference() {
    let chain = seed_exponential_chain(0.3);
    let pin = pin_at(&chain, 0.7, 25.0);
    let dead = Vector2::new(0.0, -0.05);
    let problem = EquilibriumProblem::new(&chain)
        .with_tip_pin_m(pin)
        .with_tip_force_n(dead);
    for start in [
        InitialGuess::Straight,
        InitialGuess::C,
        InitialGuess::S.mirrored(),
    ] {
        let mut answers = Vec::new();
        for linear in [LinearSolver::Structured, LinearSolver::Dense] {
            let (eq, trace) = solve_equilibrium_with(
                &problem,
                &start,
                &SolveOptions::default(),
                &SolverSettings {
                    linear_solver: linear,
                    record_trace: true,
                },
            )
            .unwrap();
            check_pinned(&chain, pin, dead, &eq);
            assert!(trace.is_monotone());
            answers.push((eq, trace.steps.iter().any(|s| s.modified)));
        }
        if !answers[0].1 && !answers[1].1 {
            let d = answers[0]
                .0
                .theta_rad
                .iter()
                .zip(&answers[1].0.theta_rad)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            assert!(d < 1e-7);
        }
        assert_eq!(answers[0].0.stable, answers[1].0.stable);
    }
}

/// Targets at 0.9999 of the reach (a nearly straight chain, a nearly singular Jacobian)
/// still converge.
#[test]
fn near_full_reach_converges() {
    let chain = seed_exponential_chain(0.2);
    for angle in [0.0, 15.0, -40.0, 60.0] {
        let pin = pin_at(&chain, 0.9999, angle);
        let problem = EquilibriumProblem::new(&chain).with_tip_pin_m(pin);
        for start in [InitialGuess::Straight, InitialGuess::C] {
            let eq = solve_equilibrium(&problem, &start, &SolveOptions::default()).unwrap();
            check_pinned(&chain, pin, Vector2::zeros(), &eq);
            assert!(eq.stable);
        }
    }
}

/// Unreachable targets are typed errors naming distance and reach.
#[test]
fn unreachable_targets_are_errors() {
    let chain = seed_exponential_chain(0.0);
    let far = pin_at(&chain, 1.001, 10.0);
    let err = solve_equilibrium(
        &EquilibriumProblem::new(&chain).with_tip_pin_m(far),
        &InitialGuess::C,
        &SolveOptions::default(),
    )
    .unwrap_err();
    match err {
        EquilibriumError::Unreachable {
            distance_m,
            reach_m,
            ..
        } => {
            assert!((reach_m - 0.32).abs() < 1e-12 && distance_m > reach_m);
        }
        other => panic!("{other}"),
    }
    let err = all_minima(
        &EquilibriumProblem::new(&chain).with_tip_pin_m(far),
        &SolveOptions::default(),
        &MinimaSearch::default(),
    )
    .unwrap_err();
    assert!(matches!(err, EquilibriumError::Unreachable { .. }));
    // One long link cannot fold back onto the first joint.
    let lopsided = Chain::builder(2)
        .link_lengths_m(vec![0.04, 0.1, 0.02])
        .stiffness_nm_per_rad(0.01)
        .build()
        .unwrap();
    let near = first_joint(&lopsided) + Vector2::new(0.01, 0.0);
    let err = solve_equilibrium(
        &EquilibriumProblem::new(&lopsided).with_tip_pin_m(near),
        &InitialGuess::Straight,
        &SolveOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(err, EquilibriumError::Unreachable { min_reach_m, .. } if (min_reach_m - 0.08).abs() < 1e-12)
    );
}

/// A pin inside the smallest circle that three 90 mm links can fold to within +-90 deg
/// limits (two right angles bring the tip back to one link length, 90 mm, from the first
/// flexible joint; the target is 82 mm away) is refused as out of reach within the limits,
/// not returned as an unconverged answer: the search stalls against the limits with the
/// penalty at its cap (the stress suite's CI sample 16).
#[test]
fn a_pin_the_folded_chain_cannot_reach_within_its_limits_is_refused() {
    let chain = Chain::builder(3)
        .link_length_m(0.09)
        .base_angle_rad(0.694_367_151_226_960_5)
        .joint_limit(JointLimit::new(
            -std::f64::consts::FRAC_PI_2,
            std::f64::consts::FRAC_PI_2,
        ))
        .stiffnesses_nm_per_rad(vec![0.004; 3])
        .build()
        .unwrap();
    let pin = Vector2::new(0.088_803_806_188_297, 0.136_970_991_155_216_63);
    let distance = (pin - first_joint(&chain)).norm();
    assert!(distance < 0.09 && distance > 0.0, "{distance}");
    let problem = EquilibriumProblem::new(&chain).with_tip_pin_m(pin);
    for start in [InitialGuess::S, InitialGuess::C, InitialGuess::Straight] {
        match solve_equilibrium(&problem, &start, &SolveOptions::default()) {
            Err(EquilibriumError::PinInfeasible { gap_m, .. }) => {
                assert!(gap_m > 0.0 && gap_m.is_finite(), "{gap_m}");
            }
            Ok(eq) => {
                // Whatever it returns must not claim the pin.
                let tip = tip_pose(&chain, &eq.theta_rad).unwrap().position_m;
                assert!(!eq.converged, "{start:?}: claims {tip:?} meets {pin:?}");
                panic!("{start:?}: an unconverged answer instead of PinInfeasible: {eq:?}");
            }
            Err(e) => panic!("{start:?}: {e}"),
        }
    }
}
