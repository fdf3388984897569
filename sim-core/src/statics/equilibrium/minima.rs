//! [`all_minima`]: every distinct stable equilibrium a multi-start search finds.
//!
//! Starts: straight, C, S, the mirrored straight, C and S, then `random_starts` random
//! postures (SplitMix64 from `seed`; each joint uniform in its limits intersected with
//! `[-a, a]`, `a = min(pi/2, 2 pi / n)` so the random chain turns about as much as the C
//! does). Each start is solved with [`solve_equilibrium`]; the converged, stable answers are
//! kept. Then every minimum found is mirrored (every flexible joint's sign flipped, clamped
//! into the limits) and solved from there, until no new minimum appears: a symmetric
//! problem's mirror pairs are completed even when only one of a pair was hit. Two answers are the same equilibrium when their joint angles differ by less than
//! `1e-6` rad everywhere (the lower-potential copy is kept). The list is sorted by
//! [`Equilibrium::total_potential_j`], lowest first: the first is the global minimum as far
//! as the search can tell. It is a search: a minimum whose basin no start falls into is
//! missed.

use std::collections::VecDeque;

use super::{
    Equilibrium, EquilibriumError, EquilibriumProblem, InitialGuess, MinimaSearch, SolveOptions,
    solve_equilibrium,
};

/// Two equilibria are the same when `max_j |delta theta_j| <` this (radians).
pub const SAME_EQUILIBRIUM_RAD: f64 = 1e-6;

/// SplitMix64: a tiny deterministic generator, enough for random starts.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Every distinct stable equilibrium found, lowest total potential first.
///
/// # Errors
/// As [`solve_equilibrium`] for errors of the problem itself (bad input, an unreachable pin);
/// a start whose solve fails for another reason is skipped.
pub fn all_minima(
    problem: &EquilibriumProblem<'_>,
    options: &SolveOptions,
    search: &MinimaSearch,
) -> Result<Vec<Equilibrium>, EquilibriumError> {
    let chain = problem.chain;
    let n = chain.n();
    let mut starts = vec![
        InitialGuess::Straight,
        InitialGuess::C,
        InitialGuess::S,
        InitialGuess::Straight.mirrored(),
        InitialGuess::C.mirrored(),
        InitialGuess::S.mirrored(),
    ];
    let amplitude = if n == 0 {
        0.0
    } else {
        (core::f64::consts::FRAC_PI_2).min(2.0 * core::f64::consts::PI / n as f64)
    };
    let mut rng = SplitMix64(search.seed);
    for _ in 0..search.random_starts {
        let angles = chain.joint_limits()[1..]
            .iter()
            .map(|lim| {
                let lo = lim.cw_rad.max(-amplitude).min(lim.ccw_rad);
                let hi = lim.ccw_rad.min(amplitude).max(lo);
                lo + (hi - lo) * rng.next_f64()
            })
            .collect();
        starts.push(InitialGuess::Angles(angles));
    }
    let mut found: Vec<Equilibrium> = Vec::new();
    let mut queue: VecDeque<InitialGuess> = starts.into();
    let mut completed = 0;
    loop {
        let Some(start) = queue.pop_front() else {
            // Mirror completion: every minimum found, mirrored, is one more start.
            if completed == found.len() {
                break;
            }
            for eq in &found[completed..] {
                queue.push_back(InitialGuess::Angles(eq.theta_rad[1..].to_vec()).mirrored());
            }
            completed = found.len();
            continue;
        };
        let start = &start;
        let eq = match solve_equilibrium(problem, start, options) {
            Ok(eq) => eq,
            Err(
                e @ (EquilibriumError::Unreachable { .. }
                | EquilibriumError::InvalidOption { .. }
                | EquilibriumError::NotFinite { .. }
                | EquilibriumError::WrongLength { .. }),
            ) => return Err(e),
            Err(_) => continue,
        };
        if !(eq.converged && eq.stable) {
            continue;
        }
        match found.iter_mut().find(|f| same(f, &eq)) {
            Some(existing) => {
                if eq.total_potential_j < existing.total_potential_j {
                    *existing = eq;
                }
            }
            None => found.push(eq),
        }
    }
    found.sort_by(|a, b| a.total_potential_j.total_cmp(&b.total_potential_j));
    Ok(found)
}

fn same(a: &Equilibrium, b: &Equilibrium) -> bool {
    a.theta_rad
        .iter()
        .zip(&b.theta_rad)
        .all(|(x, y)| (x - y).abs() < SAME_EQUILIBRIUM_RAD)
}
