//! The search of `antenna optimize`: the seven named profiles of the seed's Table 4.1 first,
//! then argmin's Nelder-Mead or particle swarm from the best of them, until the budget of
//! sweeps is spent or the solver converges.

use std::borrow::Borrow;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use argmin::core::{CostFunction, Error as ArgminError, Executor, SendAlias, SyncAlias};
use argmin::core::{State, TerminationReason, TerminationStatus};
use argmin::solver::neldermead::NelderMead;
use argmin::solver::particleswarm::{Particle, ParticleSwarm};
use rand::rngs::StdRng;
use rand::{Rng as _, SeedableRng as _};
use sim_core::StiffnessProfile;

use super::evaluator::BudgetSpent;
use super::{Evaluator, Method, NamedResult, OptimizeReport, OptimizeSpec, Space};

/// The seven profiles of the seed's Table 4.1, in its order.
pub const TABLE_4_1: [StiffnessProfile; 7] = [
    StiffnessProfile::Constant,
    StiffnessProfile::Linear,
    StiffnessProfile::SlowExponential,
    StiffnessProfile::FastExponential,
    StiffnessProfile::Logarithmic,
    StiffnessProfile::SlowReciprocal,
    StiffnessProfile::FastReciprocal,
];

/// Nelder-Mead's first step along each coordinate: a quarter of the box.
const SIMPLEX_STEP: f64 = 0.25;
/// Nelder-Mead stops when its vertices' objectives agree to this (standard deviation), m.
const SIMPLEX_TOLERANCE_M: f64 = 1e-9;

/// How to run an optimization.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OptimizeOptions {
    /// Sweeps at once (at least 1).
    pub jobs: usize,
    /// Whether to draw a progress bar on stderr (when it is a terminal).
    pub progress: bool,
}

/// Why an optimization could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OptimizeError {
    /// A named profile cannot be computed for the first scene's links.
    #[error("the named profile {name} cannot be made for these links: {why}")]
    Profile {
        /// The profile.
        name: &'static str,
        /// Why.
        why: String,
    },
    /// argmin stopped with an error other than the spent budget.
    #[error("the {method} search stopped: {message}")]
    Solver {
        /// The method's name.
        method: &'static str,
        /// argmin's message.
        message: String,
    },
}

/// The search asked this many times in a row only for stiffness sets swept before (a swarm
/// whose particles all sit on the same wires, a simplex shrunk below a wire's step): it has
/// converged on what it can tell apart.
pub const STALL_CALLS: usize = 200;

/// argmin's run stops with this error when the search has stalled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("no new stiffness set in {STALL_CALLS} calls")]
struct Stalled;

/// What argmin minimizes: minus the objective, `+inf` where infeasible.
struct Search<'e, 'a> {
    evaluator: &'e Evaluator<'a>,
    space: &'e Space,
    /// Calls in a row that swept nothing new.
    idle_calls: AtomicUsize,
}

impl Search<'_, '_> {
    fn costs(&self, points: &[&Vec<f64>]) -> Result<Vec<f64>, ArgminError> {
        let batch: Vec<(Vec<f64>, Option<&str>)> = points
            .iter()
            .map(|u| (self.space.values(u), None))
            .collect();
        let before = self.evaluator.sweeps();
        let objectives = self.evaluator.evaluate(&batch)?;
        if self.evaluator.sweeps() > before {
            self.idle_calls.store(0, Ordering::Relaxed);
        } else if self.idle_calls.fetch_add(1, Ordering::Relaxed) + 1 >= STALL_CALLS {
            return Err(Stalled.into());
        }
        Ok(objectives
            .into_iter()
            .map(|o| o.map_or(f64::INFINITY, |v| -v))
            .collect())
    }
}

impl CostFunction for Search<'_, '_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, u: &Vec<f64>) -> Result<f64, ArgminError> {
        Ok(self.costs(&[u])?[0])
    }

    /// The batch's sweeps in parallel (the swarm's particles).
    fn bulk_cost<P>(&self, params: &[P]) -> Result<Vec<f64>, ArgminError>
    where
        P: Borrow<Vec<f64>> + SyncAlias,
        f64: SendAlias,
        Self: SyncAlias,
    {
        let points: Vec<&Vec<f64>> = params.iter().map(Borrow::borrow).collect();
        self.costs(&points)
    }
}

/// Runs the optimization `spec` describes.
///
/// # Errors
/// [`OptimizeError`] when a named profile cannot be made for the links, or argmin fails
/// other than by spending the budget. A sweep that fails is not an error: its evaluation is
/// infeasible and reported.
pub fn run_optimization(
    spec: &OptimizeSpec,
    options: &OptimizeOptions,
) -> Result<OptimizeReport, OptimizeError> {
    let started = Instant::now();
    let evaluator = Evaluator::new(spec, options.jobs, options.progress);
    let space = &spec.space;
    let (lo, hi) = space.bounds_n_m_per_rad;
    let lengths = spec.scenes[0].1.chain.link_lengths_m();
    let mut named = Vec::with_capacity(TABLE_4_1.len());
    for profile in &TABLE_4_1 {
        let values = profile
            .stiffness_n_m_per_rad(lengths, lo, hi)
            .map_err(|e| OptimizeError::Profile {
                name: profile.name(),
                why: e.to_string(),
            })?;
        named.push((space.made(&values), Some(profile.name())));
    }
    let named_objectives = evaluator
        .evaluate(&named)
        .map_err(|e| solver_error(spec.method, &e))?;
    let best_named = named_objectives
        .iter()
        .enumerate()
        .filter_map(|(i, o)| o.map(|v| (i, v)))
        .fold(None, |best: Option<(usize, f64)>, (i, v)| match best {
            Some((_, b)) if b >= v => best,
            _ => Some((i, v)),
        });
    let start = match best_named {
        Some((i, _)) => space.coordinates(&named[i].0),
        None => vec![0.5; space.dim()],
    };
    let search = Search {
        evaluator: &evaluator,
        space,
        idle_calls: AtomicUsize::new(0),
    };
    let max_iters = (spec.budget as u64).saturating_mul(50).saturating_add(1000);
    let result = match spec.method {
        Method::NelderMead => run_nelder_mead(search, start, max_iters),
        Method::ParticleSwarm => run_particle_swarm(search, start, spec.seed, max_iters),
    };
    evaluator.finish();
    let stopped_by = match result {
        Ok(reason) => reason,
        Err(e) if e.downcast_ref::<BudgetSpent>().is_some() => "budget".to_string(),
        Err(e) if e.downcast_ref::<Stalled>().is_some() => "stalled".to_string(),
        Err(e) => return Err(solver_error(spec.method, &e)),
    };
    let named: Vec<NamedResult> = TABLE_4_1
        .iter()
        .zip(named)
        .zip(named_objectives)
        .map(|((profile, (values, _)), objective_value)| NamedResult {
            name: profile.name().to_string(),
            objective_value,
            values_n_m_per_rad: values,
        })
        .collect();
    Ok(OptimizeReport::new(
        spec,
        named,
        &evaluator.records(),
        evaluator.sweeps(),
        stopped_by,
        started.elapsed().as_secs_f64(),
    ))
}

fn solver_error(method: Method, e: &dyn std::fmt::Display) -> OptimizeError {
    OptimizeError::Solver {
        method: method.name(),
        message: e.to_string(),
    }
}

/// Why argmin stopped, in words.
fn reason(status: &TerminationStatus) -> String {
    match status {
        TerminationStatus::Terminated(TerminationReason::SolverConverged) => "converged",
        TerminationStatus::Terminated(TerminationReason::MaxItersReached) => "max iterations",
        TerminationStatus::Terminated(other) => return other.text().to_string(),
        TerminationStatus::NotTerminated => "not terminated",
    }
    .to_string()
}

/// Nelder-Mead from `start` with a first step of [`SIMPLEX_STEP`] along each coordinate
/// (inward where the box ends); the simplex's vertices are swept in parallel first.
fn run_nelder_mead(
    search: Search<'_, '_>,
    start: Vec<f64>,
    max_iters: u64,
) -> Result<String, ArgminError> {
    let mut vertices = vec![start.clone()];
    for i in 0..start.len() {
        let mut v = start.clone();
        v[i] += if v[i] + SIMPLEX_STEP <= 1.0 {
            SIMPLEX_STEP
        } else {
            -SIMPLEX_STEP
        };
        vertices.push(v);
    }
    // Sweep the vertices in parallel; argmin's own start looks them up (it evaluates them
    // one at a time).
    search.bulk_cost(&vertices)?;
    let solver = NelderMead::new(vertices).with_sd_tolerance(SIMPLEX_TOLERANCE_M)?;
    let result = Executor::new(search, solver)
        .configure(|state| state.max_iters(max_iters))
        .run()?;
    Ok(reason(result.state.get_termination_status()))
}

/// A particle swarm in the unit box: `start` one particle, the others uniform (seeded), each
/// with a velocity uniform in `[-1, 1]` per coordinate (argmin's own rule for the box).
fn run_particle_swarm(
    search: Search<'_, '_>,
    start: Vec<f64>,
    seed: u64,
    max_iters: u64,
) -> Result<String, ArgminError> {
    let dim = start.len();
    let mut rng = StdRng::seed_from_u64(seed);
    let mut positions = vec![start];
    for _ in 1..Method::particles(dim) {
        positions.push((0..dim).map(|_| rng.random_range(0.0..=1.0)).collect());
    }
    let costs = search.bulk_cost(&positions)?;
    let population: Vec<Particle<Vec<f64>, f64>> = positions
        .into_iter()
        .zip(costs)
        .map(|(position, cost)| {
            let velocity = (0..dim).map(|_| rng.random_range(-1.0..=1.0)).collect();
            Particle::new(position, cost, velocity)
        })
        .collect();
    let solver = ParticleSwarm::new((vec![0.0; dim], vec![1.0; dim]), population.len())
        .with_rng_generator(StdRng::seed_from_u64(seed.wrapping_add(1)));
    let result = Executor::new(search, solver)
        .configure(|state| state.population(population).max_iters(max_iters))
        .run()?;
    Ok(reason(result.state.get_termination_status()))
}
