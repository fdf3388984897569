//! The evaluations of `antenna optimize`: each a sweep of every scene with one set of joint
//! stiffnesses (for a follow objective, a closed-loop run or a v_max search of every follow
//! scene, each counted as one "sweep" of the budget), the sweeps of a batch run in parallel,
//! never more sweeps than the budget, each set of stiffnesses swept once (a point the search
//! comes back to is looked up).

use std::collections::HashMap;
use std::panic::AssertUnwindSafe;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use indicatif::ProgressBar;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::log::LogWriter;
use super::{Objective, OptimizeSpec};
use crate::follow::run_summary;
use crate::follow::v_max::{VMaxOptions, v_max};
use crate::progress;
use crate::sweep::SweepRun;
use antenna_scene::{Scene, StiffnessSpec};

/// One scene's sweep of an evaluation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneResult {
    /// The scene's index in `scenes`.
    pub scene: usize,
    /// The objective of this sweep, metres (`null`: infeasible, see `why`).
    pub objective_value: Option<f64>,
    /// The sweep's outcome: `"finished"`, `"jammed"` or `"failed"`; for `follow-rms` the
    /// run's status (`"ok"`, `"collided"`, `"lost"`, the solver's outcome) and for
    /// `follow-v-max` `"ok"` when a speed was found, else the slowest speed's status
    /// (`"failed"`: the run could not start).
    pub outcome: String,
    /// Why the sweep has no objective: why it stopped, or what it lacked.
    pub why: Option<String>,
}

/// One evaluation: the stiffnesses, the objective averaged over the scenes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Evaluation {
    /// 0-based, in the order evaluated.
    pub index: usize,
    /// The named profile it is (`null` for a point of the search).
    pub profile: Option<String>,
    /// Joint stiffnesses, N m/rad, joint 1 first.
    pub values_n_m_per_rad: Vec<f64>,
    /// The mean objective over the scenes, metres (`null`: infeasible, some sweep failed,
    /// jammed or had no objective).
    pub objective_value: Option<f64>,
    /// Each scene's sweep.
    pub scenes: Vec<SceneResult>,
}

impl Evaluation {
    /// Whether some sweep made it infeasible.
    pub fn failed(&self) -> bool {
        self.objective_value.is_none()
    }
}

/// The search asked this many times in a row only for stiffness sets swept before (a swarm
/// whose particles all sit on the same wires, a simplex shrunk below a wire's step): it has
/// converged on what it can tell apart.
pub const STALL_CALLS: usize = 200;

/// Why the search stops before its solver does: argmin's run ends with this error.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum Stop {
    /// The budget of sweeps is spent.
    #[error("the budget of {budget} sweep(s) is spent")]
    Budget {
        /// The budget, sweeps.
        budget: usize,
    },
    /// [`STALL_CALLS`] calls in a row (or four times the simplex's vertices, if more) asked
    /// only for stiffness sets swept before.
    #[error("no new stiffness set in {STALL_CALLS} calls")]
    Stalled,
    /// Interrupted (Ctrl-C, SIGTERM): the sweeps under way finished, no new one started.
    #[error("interrupted")]
    Interrupted,
    /// The log could not be written (a full disk): the run stops rather than go on
    /// unrecorded.
    #[error("the log could not be written: {0}")]
    Log(String),
}

impl Stop {
    /// The report's `stopped_by`.
    pub fn reason(&self) -> String {
        match self {
            Stop::Budget { .. } => "budget".to_string(),
            Stop::Stalled => "stalled".to_string(),
            Stop::Interrupted => "interrupted".to_string(),
            Stop::Log(why) => format!("log failed: {why}"),
        }
    }
}

/// Runs and remembers the evaluations of one optimization.
#[derive(Debug)]
pub struct Evaluator<'a> {
    spec: &'a OptimizeSpec,
    /// `jobs` threads (`None`: the system gave none, the sweeps run on the caller's).
    pool: Option<rayon::ThreadPool>,
    interrupt: Option<Arc<AtomicBool>>,
    inner: Mutex<Inner>,
}

#[derive(Debug)]
struct Inner {
    records: Vec<Evaluation>,
    seen: HashMap<Vec<u64>, usize>,
    /// Evaluations of a resumed run's log, not yet asked for again.
    logged: HashMap<Vec<u64>, Evaluation>,
    log: Option<LogWriter>,
    sweeps: usize,
    replayed: usize,
    idle_calls: usize,
    best: Option<f64>,
    progress: ProgressBar,
}

impl<'a> Evaluator<'a> {
    /// An evaluator of `spec`'s scenes on a rayon pool of `jobs` threads, drawing a progress
    /// bar on stderr when `progress` (and stderr is a terminal).
    pub fn new(spec: &'a OptimizeSpec, jobs: usize, progress: bool) -> Evaluator<'a> {
        Evaluator {
            spec,
            pool: rayon::ThreadPoolBuilder::new()
                .num_threads(jobs.max(1))
                .build()
                .ok(),
            interrupt: None,
            inner: Mutex::new(Inner {
                records: Vec::new(),
                seen: HashMap::new(),
                logged: HashMap::new(),
                log: None,
                sweeps: 0,
                replayed: 0,
                idle_calls: 0,
                best: None,
                progress: progress::bar(spec.budget, "sweeps", progress),
            }),
        }
    }

    /// Writes every new evaluation to `log`; `logged` (a resumed run's) are looked up
    /// instead of swept when the search asks for them.
    #[must_use]
    pub fn with_log(self, log: LogWriter, logged: Vec<Evaluation>) -> Self {
        {
            let mut inner = self.lock();
            inner.log = Some(log);
            for e in logged {
                inner.logged.insert(key_of(&e.values_n_m_per_rad), e);
            }
        }
        self
    }

    /// Starts no new sweep once `flag` is set.
    #[must_use]
    pub fn with_interrupt(mut self, flag: Arc<AtomicBool>) -> Self {
        self.interrupt = Some(flag);
        self
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Inner> {
        // A worker that panicked leaves the records as they were: keep them.
        self.inner
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// The objective of each set of stiffnesses in `batch` (with the named profile it is, if
    /// any), `None` where infeasible. New sets are swept (every scene, in parallel), or taken
    /// from a resumed run's log; sets seen before are looked up.
    ///
    /// # Errors
    /// [`Stop::Budget`] when not every new set fits in what is left of the budget (those
    /// that fit, in order, are evaluated and recorded first); [`Stop::Interrupted`] once the
    /// interrupt flag is set; [`Stop::Log`] when the log cannot be written; with `stall`,
    /// [`Stop::Stalled`] after [`STALL_CALLS`] calls in a row with nothing new.
    pub fn evaluate(
        &self,
        batch: &[(Vec<f64>, Option<&str>)],
        stall: bool,
    ) -> Result<Vec<Option<f64>>, Stop> {
        let scenes = self.spec.scenes.len();
        let mut todo: Vec<Pending<'_>> = Vec::new();
        let mut stop = None;
        {
            let mut inner = self.lock();
            for (values, profile) in batch {
                let key = key_of(values);
                if inner.seen.contains_key(&key) || todo.iter().any(|p| p.key == key) {
                    continue;
                }
                if inner.sweeps + (todo.len() + 1) * scenes > self.spec.budget {
                    stop = Some(Stop::Budget {
                        budget: self.spec.budget,
                    });
                    break;
                }
                let logged = inner.logged.remove(&key);
                if logged.is_none() && self.interrupted() {
                    stop = Some(Stop::Interrupted);
                    break;
                }
                todo.push(Pending {
                    key,
                    values,
                    profile: *profile,
                    logged,
                });
            }
            if todo.is_empty() && stop.is_none() && stall {
                inner.idle_calls += 1;
                // Nelder-Mead's start looks its dim + 1 vertices up one by one (and must
                // not fail there): never call that a stall.
                if inner.idle_calls >= STALL_CALLS.max(4 * (self.spec.space.dim() + 1)) {
                    return Err(Stop::Stalled);
                }
            } else {
                inner.idle_calls = 0;
            }
        }
        let fresh: Vec<&[f64]> = todo
            .iter()
            .filter(|p| p.logged.is_none())
            .map(|p| p.values)
            .collect();
        let mut swept = self.sweep_all(&fresh).into_iter();
        let mut inner = self.lock();
        for Pending {
            key,
            values,
            profile,
            logged,
        } in todo
        {
            let index = inner.records.len();
            let replayed = logged.is_some();
            let scene_results = match logged {
                Some(e) => e.scenes,
                None => swept.next().unwrap_or_default(),
            };
            let objective_value = mean_objective(&scene_results);
            let evaluation = Evaluation {
                index,
                profile: profile.map(str::to_string),
                values_n_m_per_rad: values.to_vec(),
                objective_value,
                scenes: scene_results,
            };
            if !replayed
                && let Some(log) = inner.log.as_mut()
                && let Err(why) = log.write(&evaluation)
            {
                stop.get_or_insert(Stop::Log(why));
            }
            inner.records.push(evaluation);
            inner.seen.insert(key, index);
            inner.sweeps += scenes;
            inner.replayed += usize::from(replayed);
            if let Some(v) = objective_value
                && inner.best.is_none_or(|b| v > b)
            {
                inner.best = Some(v);
            }
        }
        if let Some(stop) = stop {
            return Err(stop);
        }
        Ok(batch
            .iter()
            .map(|(values, _)| {
                inner
                    .seen
                    .get(&key_of(values))
                    .and_then(|&i| inner.records.get(i))
                    .and_then(|r| r.objective_value)
            })
            .collect())
    }

    /// Makes `values` look up the evaluation of `of` (swept before) when they agree to a
    /// rounding (1e-12 relative): the search's start, whose stiffnesses come back from its
    /// coordinates within a rounding of the named profile's, is not swept again. Values that
    /// differ more (a taper through a named profile's ends) are left alone.
    pub fn alias(&self, values: &[f64], of: &[f64]) {
        let close = values.len() == of.len()
            && values
                .iter()
                .zip(of)
                .all(|(a, b)| (a - b).abs() <= 1e-12 * b.abs());
        if !close {
            return;
        }
        let mut inner = self.lock();
        if let Some(&index) = inner.seen.get(&key_of(of)) {
            inner.seen.entry(key_of(values)).or_insert(index);
        }
    }

    fn interrupted(&self) -> bool {
        self.interrupt
            .as_ref()
            .is_some_and(|f| f.load(Ordering::Relaxed))
    }

    /// Sweeps every scene with each set of `todo` on the pool of threads; the results by
    /// set, then by scene.
    fn sweep_all(&self, todo: &[&[f64]]) -> Vec<Vec<SceneResult>> {
        let scenes = self.spec.scenes.len();
        let work = todo.len() * scenes;
        let finished = AtomicUsize::new(0);
        let sweep = |w: usize| {
            let (set, scene) = (w / scenes, w % scenes);
            let result = std::panic::catch_unwind(AssertUnwindSafe(|| {
                if self.spec.objective.is_follow() {
                    follow_one(
                        &self.spec.scenes[scene].1,
                        scene,
                        todo[set],
                        self.spec.objective,
                        &self.spec.v_max,
                    )
                } else {
                    sweep_one(
                        &self.spec.scenes[scene].1,
                        scene,
                        todo[set],
                        self.spec.objective,
                    )
                }
            }))
            .unwrap_or_else(|panic| SceneResult {
                scene,
                objective_value: None,
                outcome: "failed".to_string(),
                why: Some(format!("the sweep panicked: {}", panic_message(&*panic))),
            });
            let inner = self.lock();
            let done = inner.sweeps + finished.fetch_add(1, Ordering::Relaxed) + 1;
            let note = match inner.best {
                Some(b) => format!(", best {}", self.spec.objective.show(b)),
                None => String::new(),
            };
            inner.progress.set_message(note);
            inner
                .progress
                .set_position(done.min(self.spec.budget) as u64);
            result
        };
        let mut results: std::vec::IntoIter<SceneResult> = match &self.pool {
            Some(pool) => pool.install(|| (0..work).into_par_iter().map(sweep).collect()),
            None => (0..work).map(sweep).collect::<Vec<_>>(),
        }
        .into_iter();
        (0..todo.len())
            .map(|_| results.by_ref().take(scenes).collect())
            .collect()
    }

    /// Every evaluation so far, in order.
    pub fn records(&self) -> Vec<Evaluation> {
        self.lock().records.clone()
    }

    /// Sweeps run so far (a resumed run's logged ones included).
    pub fn sweeps(&self) -> usize {
        self.lock().sweeps
    }

    /// Evaluations taken from a resumed run's log.
    pub fn replayed(&self) -> usize {
        self.lock().replayed
    }

    /// Clears the progress bar.
    pub fn finish(&self) {
        self.lock().progress.finish_and_clear();
    }
}

/// A stiffness set of a batch not looked up: swept, or taken from a resumed run's log.
struct Pending<'b> {
    key: Vec<u64>,
    values: &'b [f64],
    profile: Option<&'b str>,
    logged: Option<Evaluation>,
}

/// A panic's message, when it has one.
fn panic_message(panic: &(dyn std::any::Any + Send)) -> String {
    panic
        .downcast_ref::<&str>()
        .map(|s| (*s).to_string())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "no message".to_string())
}

/// The exact bits of a set of stiffnesses: the same set sweeps the same.
fn key_of(values: &[f64]) -> Vec<u64> {
    values.iter().map(|v| v.to_bits()).collect()
}

/// The mean over the scenes, `None` if any is infeasible.
fn mean_objective(results: &[SceneResult]) -> Option<f64> {
    let values: Option<Vec<f64>> = results.iter().map(|r| r.objective_value).collect();
    let values = values?;
    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
}

/// `scene` with these joint stiffnesses (as if given by `values_n_m_per_rad`).
///
/// # Errors
/// The chain builder's message for a stiffness it refuses.
pub fn with_stiffness(scene: &Scene, values_n_m_per_rad: &[f64]) -> Result<Scene, String> {
    let mut scene = scene.clone();
    scene.chain = scene
        .chain
        .to_builder()
        .stiffnesses_nm_per_rad(values_n_m_per_rad.to_vec())
        .build()
        .map_err(|e| e.to_string())?;
    scene.stiffness = StiffnessSpec::Values;
    Ok(scene)
}

/// One closed-loop run (`follow-rms`) or v_max search (`follow-v-max`) of the follow scene
/// `scene` with these stiffnesses and the scene's robot and gains.
fn follow_one(
    scene: &Scene,
    index: usize,
    values: &[f64],
    objective: Objective,
    options: &VMaxOptions,
) -> SceneResult {
    let failed = |why: String| SceneResult {
        scene: index,
        objective_value: None,
        outcome: "failed".to_string(),
        why: Some(why),
    };
    let scene_with = match with_stiffness(scene, values) {
        Ok(s) => s,
        Err(why) => return failed(why),
    };
    let (sweep_scene, config, sensors) = match scene_with.follow_parts() {
        Ok(parts) => parts,
        Err(e) => return failed(e.to_string()),
    };
    let located = |e: &sim_core::follow::FollowError| match &scene_with.follow {
        Some(f) => f.locate(e).to_string(),
        None => e.to_string(),
    };
    let (outcome, scored) = if objective == Objective::FollowVMax {
        match v_max(&sweep_scene, &sensors, &config, options) {
            Ok(result) => (
                match (&result.v_max_m_per_s, &result.failure) {
                    (None, Some(status)) => status.clone(),
                    _ => "ok".to_string(),
                },
                Objective::of_v_max(&result),
            ),
            Err(e) => return failed(located(&e)),
        }
    } else {
        match run_summary(&sweep_scene, &sensors, &config) {
            Ok(summary) => (
                summary.status.name().to_string(),
                Objective::of_follow(&summary),
            ),
            Err(e) => return failed(located(&e)),
        }
    };
    let (objective_value, why) = match scored {
        Ok(v) => (Some(v), None),
        Err(why) => (None, Some(why)),
    };
    SceneResult {
        scene: index,
        objective_value,
        outcome,
        why,
    }
}

/// One certified sweep of `scene` with these stiffnesses, scored by the spec's objective.
fn sweep_one(scene: &Scene, index: usize, values: &[f64], objective: Objective) -> SceneResult {
    let failed = |why: String| SceneResult {
        scene: index,
        objective_value: None,
        outcome: "failed".to_string(),
        why: Some(why),
    };
    let scene_with = match with_stiffness(scene, values) {
        Ok(s) => s,
        Err(why) => return failed(why),
    };
    let mut run = match SweepRun::start(&scene_with) {
        Ok(run) => run,
        Err(e) => return failed(e.to_string()),
    };
    while let Some(state) = run.next_state() {
        if state.is_err() {
            break;
        }
    }
    let summary = run.summary();
    let (objective_value, why) = if summary.outcome == "finished" {
        match objective.of_summary(&summary) {
            Ok(v) => (Some(v), None),
            Err(why) => (None, Some(why)),
        }
    } else {
        (None, summary.stopped_by.clone())
    };
    SceneResult {
        scene: index,
        objective_value,
        outcome: summary.outcome,
        why,
    }
}
