//! The search of `antenna optimize`: the seven named profiles of the thesis's Table 4.1 first,
//! then argmin's Nelder-Mead or particle swarm from the best of them, until the budget of
//! sweeps is spent or the solver converges.

use std::borrow::Borrow;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use argmin::core::{CostFunction, Error as ArgminError, Executor, SendAlias, SyncAlias};
use argmin::core::{State, TerminationReason, TerminationStatus};
use argmin::solver::neldermead::NelderMead;
use argmin::solver::particleswarm::{Particle, ParticleSwarm};
use rand::rngs::StdRng;
use rand::{Rng as _, SeedableRng as _};
use sim_core::StiffnessProfile;

use super::evaluator::Stop;
use super::log::{LogError, open_log};
use super::{Evaluator, Method, NamedResult, OptimizeReport, OptimizeSpec, Space};

/// The seven profiles of the thesis's Table 4.1, in its order.
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
#[derive(Debug, Clone, Default)]
pub struct OptimizeOptions {
    /// Sweeps at once (at least 1).
    pub jobs: usize,
    /// Whether to draw a progress bar on stderr (when it is a terminal).
    pub progress: bool,
    /// Write every evaluation to this log as it completes ([`super::log`]).
    pub log: Option<PathBuf>,
    /// Continue the run the log records.
    pub resume: bool,
    /// Start no new sweep once this is set (Ctrl-C); the report covers what was swept.
    pub interrupt: Option<Arc<AtomicBool>>,
}

/// Why an optimization could not run.
#[derive(Debug, thiserror::Error)]
pub enum OptimizeError {
    /// The log cannot be used.
    #[error(transparent)]
    Log(#[from] LogError),
    /// A named profile cannot be computed for the first scene's links.
    #[error("the named profile {name} cannot be made for these links: {why}")]
    Profile {
        /// The profile.
        name: &'static str,
        /// Why.
        why: String,
    },
    /// argmin stopped with an error other than a [`Stop`].
    #[error("the {method} search stopped: {message}")]
    Solver {
        /// The method's name.
        method: &'static str,
        /// argmin's message.
        message: String,
    },
}

/// What argmin minimizes: minus the objective, `+inf` where infeasible.
struct Search<'e, 'a> {
    evaluator: &'e Evaluator<'a>,
    space: &'e Space,
}

impl Search<'_, '_> {
    fn costs(&self, points: &[&Vec<f64>]) -> Result<Vec<f64>, Stop> {
        let batch: Vec<(Vec<f64>, Option<&str>)> = points
            .iter()
            .map(|u| (self.space.values(u), None))
            .collect();
        let objectives = self.evaluator.evaluate(&batch, true)?;
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
        Ok(self.costs(&points)?)
    }
}

/// Runs the optimization `spec` describes.
///
/// # Errors
/// [`OptimizeError`] when the log cannot be used, a named profile cannot be made for the
/// links, or argmin fails other than by a [`Stop`]. A sweep that fails is not an error: its
/// evaluation is infeasible and reported.
pub fn run_optimization(
    spec: &OptimizeSpec,
    options: &OptimizeOptions,
) -> Result<OptimizeReport, OptimizeError> {
    let started = Instant::now();
    let mut evaluator = Evaluator::new(spec, options.jobs, options.progress);
    if let Some(path) = &options.log {
        let (writer, logged) = open_log(path, spec, options.resume)?;
        evaluator = evaluator.with_log(writer, logged);
    }
    if let Some(flag) = &options.interrupt {
        evaluator = evaluator.with_interrupt(flag.clone());
    }
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
    let stopped_by = match evaluator.evaluate(&named, false) {
        Ok(objectives) => search_from_the_best(spec, &evaluator, &named, &objectives)?,
        // Interrupted, or a log that cannot be written: the report covers what was swept.
        Err(stop) => stop.reason(),
    };
    evaluator.finish();
    let records = evaluator.records();
    let named: Vec<NamedResult> = TABLE_4_1
        .iter()
        .zip(named)
        .map(|(profile, (values, _))| NamedResult {
            name: profile.name().to_string(),
            objective_value: records
                .iter()
                .find(|r| r.values_n_m_per_rad == values)
                .and_then(|r| r.objective_value),
            values_n_m_per_rad: values,
        })
        .collect();
    let mut report = OptimizeReport::new(
        spec,
        named,
        &records,
        evaluator.sweeps(),
        stopped_by,
        started.elapsed().as_secs_f64(),
    );
    report.replayed_evaluations = evaluator.replayed();
    Ok(report)
}

/// The search proper, from the best of the named profiles (the middle of the box if none
/// is feasible); why it stopped.
fn search_from_the_best(
    spec: &OptimizeSpec,
    evaluator: &Evaluator<'_>,
    named: &[(Vec<f64>, Option<&str>)],
    named_objectives: &[Option<f64>],
) -> Result<String, OptimizeError> {
    let space = &spec.space;
    let best_named = named_objectives
        .iter()
        .enumerate()
        .filter_map(|(i, o)| o.map(|v| (i, v)))
        .fold(None, |best: Option<(usize, f64)>, (i, v)| match best {
            Some((_, b)) if b >= v => best,
            _ => Some((i, v)),
        });
    let start = match best_named {
        Some((i, _)) => {
            let start = space.coordinates(&named[i].0);
            evaluator.alias(&space.values(&start), &named[i].0);
            start
        }
        None => vec![0.5; space.dim()],
    };
    let search = Search { evaluator, space };
    let max_iters = (spec.budget as u64).saturating_mul(50).saturating_add(1000);
    let result = match spec.method {
        Method::NelderMead => run_nelder_mead(search, start, max_iters),
        Method::ParticleSwarm => run_particle_swarm(search, start, spec.seed, max_iters),
    };
    match result {
        Ok(reason) => Ok(reason),
        Err(e) => match e.downcast_ref::<Stop>() {
            Some(stop) => Ok(stop.reason()),
            None => Err(solver_error(spec.method, &e)),
        },
    }
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
