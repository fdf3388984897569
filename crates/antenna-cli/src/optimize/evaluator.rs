//! The evaluations of `antenna optimize`: each a sweep of every scene with one set of joint
//! stiffnesses, the sweeps of a batch run in parallel, never more sweeps than the budget,
//! each set of stiffnesses swept once (a point the search comes back to is looked up).

use std::collections::HashMap;
use std::panic::AssertUnwindSafe;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use serde::Serialize;

use super::{Objective, OptimizeSpec};
use crate::progress::Progress;
use crate::scene::{Scene, StiffnessSpec};
use crate::sweep::SweepRun;

/// One scene's sweep of an evaluation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SceneResult {
    /// The scene's index in `scenes`.
    pub scene: usize,
    /// The objective of this sweep, metres (`null`: infeasible, see `why`).
    pub objective_value: Option<f64>,
    /// The sweep's outcome: `"finished"`, `"jammed"` or `"failed"`.
    pub outcome: String,
    /// Why the sweep has no objective: why it stopped, or what it lacked.
    pub why: Option<String>,
}

/// One evaluation: the stiffnesses, the objective averaged over the scenes.
#[derive(Debug, Clone, PartialEq, Serialize)]
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

/// The budget of sweeps is spent: argmin's run stops with this error.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("the budget of {budget} sweep(s) is spent")]
pub struct BudgetSpent {
    /// The budget, sweeps.
    pub budget: usize,
}

/// Runs and remembers the evaluations of one optimization.
#[derive(Debug)]
pub struct Evaluator<'a> {
    spec: &'a OptimizeSpec,
    jobs: usize,
    inner: Mutex<Inner>,
}

#[derive(Debug)]
struct Inner {
    records: Vec<Evaluation>,
    seen: HashMap<Vec<u64>, usize>,
    sweeps: usize,
    best: Option<f64>,
    progress: Progress,
}

impl<'a> Evaluator<'a> {
    /// An evaluator of `spec`'s scenes on `jobs` threads, drawing a progress bar on stderr
    /// when `progress` (and stderr is a terminal).
    pub fn new(spec: &'a OptimizeSpec, jobs: usize, progress: bool) -> Evaluator<'a> {
        let mut bar = Progress::new(spec.budget, "sweeps");
        if !progress {
            bar.finish();
        }
        Evaluator {
            spec,
            jobs: jobs.max(1),
            inner: Mutex::new(Inner {
                records: Vec::new(),
                seen: HashMap::new(),
                sweeps: 0,
                best: None,
                progress: bar,
            }),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Inner> {
        // A worker that panicked leaves the records as they were: keep them.
        self.inner
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// The objective of each set of stiffnesses in `batch` (with the named profile it is, if
    /// any), `None` where infeasible. New sets are swept (every scene, in parallel); sets
    /// seen before are looked up.
    ///
    /// # Errors
    /// [`BudgetSpent`] when not every new set fits in what is left of the budget: those
    /// that fit, in order, are swept and recorded first.
    pub fn evaluate(
        &self,
        batch: &[(Vec<f64>, Option<&str>)],
    ) -> Result<Vec<Option<f64>>, BudgetSpent> {
        let scenes = self.spec.scenes.len();
        let mut todo: Vec<(Vec<u64>, &[f64], Option<&str>)> = Vec::new();
        let mut spent = false;
        {
            let inner = self.lock();
            for (values, profile) in batch {
                let key = key_of(values);
                if inner.seen.contains_key(&key) || todo.iter().any(|(k, ..)| *k == key) {
                    continue;
                }
                if inner.sweeps + (todo.len() + 1) * scenes > self.spec.budget {
                    spent = true;
                    break;
                }
                todo.push((key, values, *profile));
            }
        }
        let results = self.sweep_all(&todo);
        let mut inner = self.lock();
        for ((key, values, profile), scene_results) in todo.into_iter().zip(results) {
            let objective_value = mean_objective(&scene_results);
            let index = inner.records.len();
            inner.records.push(Evaluation {
                index,
                profile: profile.map(str::to_string),
                values_n_m_per_rad: values.to_vec(),
                objective_value,
                scenes: scene_results,
            });
            inner.seen.insert(key, index);
            inner.sweeps += scenes;
            if let Some(v) = objective_value
                && inner.best.is_none_or(|b| v > b)
            {
                inner.best = Some(v);
            }
        }
        if spent {
            return Err(BudgetSpent {
                budget: self.spec.budget,
            });
        }
        Ok(batch
            .iter()
            .map(|(values, _)| {
                let index = inner.seen[&key_of(values)];
                inner.records[index].objective_value
            })
            .collect())
    }

    /// Sweeps every scene with each set of `todo` on the pool of threads; the results by
    /// set, then by scene.
    fn sweep_all(&self, todo: &[(Vec<u64>, &[f64], Option<&str>)]) -> Vec<Vec<SceneResult>> {
        let scenes = self.spec.scenes.len();
        let work = todo.len() * scenes;
        let slots: Vec<Mutex<Option<SceneResult>>> = (0..work).map(|_| Mutex::new(None)).collect();
        let next = AtomicUsize::new(0);
        std::thread::scope(|scope| {
            for _ in 0..self.jobs.min(work) {
                scope.spawn(|| {
                    loop {
                        let w = next.fetch_add(1, Ordering::Relaxed);
                        if w >= work {
                            break;
                        }
                        let (set, scene) = (w / scenes, w % scenes);
                        let result = std::panic::catch_unwind(AssertUnwindSafe(|| {
                            sweep_one(
                                &self.spec.scenes[scene].1,
                                scene,
                                todo[set].1,
                                self.spec.objective,
                            )
                        }))
                        .unwrap_or_else(|panic| SceneResult {
                            scene,
                            objective_value: None,
                            outcome: "failed".to_string(),
                            why: Some(format!("the sweep panicked: {}", panic_message(&*panic))),
                        });
                        if let Ok(mut slot) = slots[w].lock() {
                            *slot = Some(result);
                        }
                        let mut inner = self.lock();
                        let done = inner.sweeps + w + 1;
                        let note = match inner.best {
                            Some(b) => format!(", best {:.4} mm", b * 1000.0),
                            None => String::new(),
                        };
                        inner.progress.set_noted(done.min(self.spec.budget), &note);
                    }
                });
            }
        });
        let mut results = Vec::with_capacity(todo.len());
        let mut slots = slots.into_iter();
        for _ in 0..todo.len() {
            let row: Vec<SceneResult> = (0..scenes)
                .map(|scene| {
                    slots
                        .next()
                        .and_then(|m| m.into_inner().ok().flatten())
                        .unwrap_or_else(|| SceneResult {
                            scene,
                            objective_value: None,
                            outcome: "failed".to_string(),
                            why: Some("the sweep left no result".to_string()),
                        })
                })
                .collect();
            results.push(row);
        }
        results
    }

    /// Every evaluation so far, in order.
    pub fn records(&self) -> Vec<Evaluation> {
        self.lock().records.clone()
    }

    /// Sweeps run so far.
    pub fn sweeps(&self) -> usize {
        self.lock().sweeps
    }

    /// Clears the progress bar.
    pub fn finish(&self) {
        self.lock().progress.finish();
    }
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
