//! Stress: randomized scenes with a fixed seed. Chains of 1 to 4096 joints, stiffness
//! ratios between neighbours up to 1e6, loads up to alpha = |F| L^2 / EI = 100 (with the
//! chain's equivalent `EI = mean(k) l`), pin targets at 0.9999 of the reach, unreachable
//! targets, every joint on a limit (tiny limits, big loads). Every solve must end without
//! NaN or panic, either converged with a KKT residual within the tolerance or with a typed
//! error that says why, and the merit must never increase within a segment of accepted
//! steps.
//!
//! The default run takes a few seconds in the test profile. A longer soak with many more
//! scenes runs when the environment variable `ANTENNA_SOAK=1` is set:
//! `ANTENNA_SOAK=1 cargo test -p sim-core --test integration stress_equilibrium -- --nocapture`.
//! `STRESS_DEBUG=1` prints the merit trace (residual/step per accepted step, per segment) of
//! any solve that does not converge. The iteration budget is 10000: the hardest scenes
//! (a pinned chain of thousands of joints whose stiffness jumps by up to 1e6 between
//! neighbours, a nearly free rope) need a few thousand iterations.
#![allow(clippy::unwrap_used)]

use nalgebra::Vector2;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use sim_core::statics::equilibrium::{SolverSettings, solve_equilibrium_with};
use sim_core::{
    Chain, EquilibriumError, EquilibriumProblem, InitialGuess, JointLimit, SolveOptions,
};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    DeadLoad,
    PinInside,
    PinNearReach,
    PinUnreachable,
    AllOnLimits,
}

struct Outcome {
    converged: usize,
    not_converged: usize,
    errors: usize,
    infeasible: usize,
    max_iterations: usize,
    worst_residual: f64,
    iterations: usize,
}

fn random_chain(rng: &mut StdRng, n: usize, tiny_limits: bool) -> Chain {
    let l = rng.random_range(0.005..0.05);
    let k0 = rng.random_range(1e-3..1e-1);
    // Neighbour ratios up to 1e6: each joint's exponent in [0, 6] independently.
    let k: Vec<f64> = (0..n)
        .map(|_| k0 * 10f64.powf(rng.random_range(0.0..6.0)))
        .collect();
    let limits: Vec<JointLimit> = (0..n)
        .map(|_| {
            if tiny_limits {
                JointLimit::new(-rng.random_range(0.0..1e-3), rng.random_range(0.0..1e-3))
            } else if rng.random_bool(0.3) {
                JointLimit::new(-rng.random_range(0.05..1.5), rng.random_range(0.05..1.5))
            } else {
                JointLimit::new(-3.0, 3.0)
            }
        })
        .collect();
    let rest: Vec<f64> = (0..n)
        .map(|i| if rng.random_bool(0.2) { rng.random_range(-0.1..0.1) } else { 0.0 } * limits[i].half_range_rad().min(1.0))
        .collect();
    Chain::builder(n)
        .link_length_m(l)
        .base_angle_rad(rng.random_range(-3.0..3.0))
        .stiffnesses_nm_per_rad(k)
        .joint_limits(limits)
        .rest_angles_rad(rest)
        .build()
        .unwrap()
}

fn run_case(rng: &mut StdRng, n: usize, kind: Kind, out: &mut Outcome) {
    let chain = random_chain(rng, n, kind == Kind::AllOnLimits);
    let l_flex: f64 = chain.link_lengths_m()[1..].iter().sum();
    let mean_k = chain.stiffness_nm_per_rad()[1..].iter().sum::<f64>() / n as f64;
    let ei = mean_k * chain.link_lengths_m()[1];
    let alpha = if kind == Kind::AllOnLimits {
        100.0
    } else {
        rng.random_range(0.0..100.0)
    };
    let dir = rng.random_range(-3.2..3.2f64);
    let force = Vector2::new(dir.cos(), dir.sin()) * alpha * ei / (l_flex * l_flex);
    let (l0, t0) = (chain.link_lengths_m()[0], chain.base_angle_rad());
    let p0 = Vector2::new(l0 * t0.cos(), l0 * t0.sin());
    let aim = rng.random_range(-3.2..3.2f64);
    let aim = Vector2::new(aim.cos(), aim.sin());
    let mut problem = EquilibriumProblem::new(&chain);
    match kind {
        Kind::DeadLoad | Kind::AllOnLimits => problem = problem.with_tip_force_n(force),
        Kind::PinInside => {
            problem = problem.with_tip_pin_m(p0 + aim * l_flex * rng.random_range(0.3..0.95))
        }
        Kind::PinNearReach => problem = problem.with_tip_pin_m(p0 + aim * l_flex * 0.9999),
        Kind::PinUnreachable => {
            problem = problem.with_tip_pin_m(p0 + aim * l_flex * rng.random_range(1.0001..2.0))
        }
    }
    if matches!(kind, Kind::PinInside | Kind::PinNearReach) && rng.random_bool(0.5) {
        problem = problem.with_tip_force_n(force * 0.1);
    }
    let start = match rng.random_range(0..4) {
        0 => InitialGuess::Straight,
        1 => InitialGuess::C,
        2 => InitialGuess::S.mirrored(),
        _ => InitialGuess::S,
    };
    let options = SolveOptions {
        tolerance: 1e-9,
        max_iterations: 10000,
    };
    let settings = SolverSettings {
        record_trace: true,
        ..Default::default()
    };
    match solve_equilibrium_with(&problem, &start, &options, &settings) {
        Ok((eq, trace)) => {
            assert!(trace.is_monotone(), "merit increased: n {n} {kind:?}");
            assert!(eq.theta_rad.iter().all(|t| t.is_finite()) && eq.kkt_residual.is_finite());
            assert!(kind != Kind::PinUnreachable, "unreachable target accepted");
            out.iterations += eq.iterations;
            out.max_iterations = out.max_iterations.max(eq.iterations);
            if eq.converged {
                assert!(eq.kkt_residual <= options.tolerance);
                out.converged += 1;
                out.worst_residual = out.worst_residual.max(eq.kkt_residual);
            } else {
                eprintln!(
                    "not converged: n {n} {kind:?} start {start:?} residual {:e} iterations {}",
                    eq.kkt_residual, eq.iterations
                );
                out.not_converged += 1;
                if std::env::var("STRESS_DEBUG").is_ok() {
                    let mut seg = usize::MAX;
                    let mut line = String::new();
                    for st in &trace.steps {
                        if st.segment != seg {
                            eprintln!("{line}");
                            seg = st.segment;
                            line = format!("seg {seg}:");
                        }
                        line += &format!(
                            " {:.0e}/{:.0e}{}",
                            st.residual,
                            st.step_length,
                            if st.modified { "m" } else { "" }
                        );
                    }
                    eprintln!("{}", &line[..line.len().min(3000)]);
                }
            }
        }
        Err(e) => {
            match (kind, e) {
                (Kind::PinUnreachable, EquilibriumError::Unreachable { .. }) => {}
                // A short chain dominated by one long link cannot come near its first joint
                // (n = 1 reaches only a circle): the error must say so.
                (
                    Kind::PinInside | Kind::PinNearReach,
                    EquilibriumError::Unreachable {
                        distance_m,
                        min_reach_m,
                        ..
                    },
                ) if distance_m < min_reach_m => {}
                (Kind::PinInside | Kind::PinNearReach, EquilibriumError::PinInfeasible { .. }) => {
                    out.infeasible += 1
                }
                (_, e) => panic!("n {n} {kind:?} start {start:?}: unexpected error {e}"),
            }
            out.errors += 1;
        }
    }
}

#[test]
fn randomized_scenes() {
    let soak = std::env::var("ANTENNA_SOAK").is_ok_and(|v| v == "1");
    let mut rng = StdRng::seed_from_u64(0x5EED_0004);
    let mut out = Outcome {
        converged: 0,
        not_converged: 0,
        errors: 0,
        infeasible: 0,
        max_iterations: 0,
        worst_residual: 0.0,
        iterations: 0,
    };
    let kinds = [
        Kind::DeadLoad,
        Kind::PinInside,
        Kind::PinNearReach,
        Kind::PinUnreachable,
        Kind::AllOnLimits,
    ];
    let small = if soak { 5000 } else { 600 };
    let start = std::time::Instant::now();
    for i in 0..small {
        let n = rng.random_range(1..=64);
        run_case(&mut rng, n, kinds[i % kinds.len()], &mut out);
    }
    let large: &[usize] = if soak {
        &[512, 1024, 2048, 2048, 4096, 4096, 4096, 4096]
    } else {
        &[1024, 2048, 4096]
    };
    for &n in large {
        for kind in kinds {
            run_case(&mut rng, n, kind, &mut out);
        }
    }
    eprintln!(
        "stress: {} converged, {} not converged, {} typed errors ({} pins infeasible within \
         the limits), worst KKT residual {:e}, {} iterations (at most {} in one solve), {:?}",
        out.converged,
        out.not_converged,
        out.errors,
        out.infeasible,
        out.worst_residual,
        out.iterations,
        out.max_iterations,
        start.elapsed()
    );

    assert_eq!(out.not_converged, 0);
}
