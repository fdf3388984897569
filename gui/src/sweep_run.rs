//! [`SweepWorker`]: a scene file's simulated sweep, run on its own thread so that the monitor
//! shows its progress and animates the steps already solved while the rest are being solved.
//!
//! [`SweepWorker::start`] reads the scene with `antenna-scene` ([`Scene::from_path`], then
//! [`Scene::sweep_scene`]); a file that does not parse is an error at once, naming the key
//! and, where known, its line and column. The thread then places the antenna (sim-core's
//! [`Sweep::new`]) and steps it, appending every step to the shared [`SweepRunState`]: the
//! step itself (drawn as a frame by [`frame_from_step`] when the cursor reaches it) and one
//! sample of a [`History`] (joint angles, touch bits, the base's x as the stage), so the
//! time-series panels, the scrub slider, playback and the exports work as for a recording.
//!
//! Each step also joins the sweep's wall map ([`SweepRunState::mapping`], a [`SweepMapping`]):
//! the contact points the robot would estimate from its sensors' reading (the scene's
//! `[sensors]`, unless [`SweepWorker::start_with_sensors`] is given others) and the wall sections passed,
//! from which the chain panel draws the wall shaded by how well it was mapped.
//!
//! A placement or a step that fails stops the sweep with the time it failed at
//! ([`MonitorError::SweepStopped`]); the steps before it stay, to be played and scrubbed.
//! Dropping the worker stops the thread after the step it is solving.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError, TryLockError};
use std::thread::JoinHandle;

use antenna_scene::{Scene, SweepFailure};
use sim_core::sweep::{Sweep, SweepError, SweepScene, SweepStep};
use sim_core::{Chain, SensorSettings, Wall};

use crate::error::MonitorError;
use crate::frame::{ChainFrame, PointM};
use crate::history::{Health, History, Sample, SegmentReading};
use crate::mapping::SweepMapping;
use crate::sweep::{base_path_m, frame_from_step, track_m};

/// The most steps the monitor holds of one sweep (2000 s at 100 Hz); a longer scene is run
/// to this many and says so.
pub const MAX_SWEEP_STEPS: usize = 200_000;

/// Where a sweep is.
#[derive(Debug)]
pub enum SweepPhase {
    /// Placing the antenna (step 0): no frame yet.
    Placing,
    /// Solving the steps.
    Stepping,
    /// Every step solved (or the most the worker keeps: see [`SweepRunState::steps_run`]).
    Done,
    /// Stopped by an error; the steps before it are kept.
    Failed(MonitorError),
}

/// A sweep's steps so far, shared between its thread and the monitor.
#[derive(Debug)]
pub struct SweepRunState {
    /// The scene file.
    pub path: PathBuf,
    /// Its name (the file's stem).
    pub name: String,
    /// The antenna swept.
    pub chain: Chain,
    /// The walls.
    pub walls: Vec<Wall>,
    /// The stage track the base runs along, metres ([`track_m`]).
    pub track_m: Option<(f64, f64)>,
    /// The base's straight path from its start to its planned end, in any direction
    /// ([`base_path_m`]), drawn in the chain panel.
    pub path_m: Vec<PointM>,
    /// The steps solved, in time order: the placed posture (step 0) first.
    pub steps: Vec<SweepStep>,
    /// The same steps as polls: joint `k`'s angle and touch bits as segment `k`'s reading,
    /// the base's x as the stage position, the base angle beyond the chain's as the servo.
    pub history: History,
    /// The scene's number of steps after the placement.
    pub steps_total: usize,
    /// The steps that are run: `steps_total`, or fewer if the worker keeps fewer.
    pub steps_run: usize,
    /// The time step, seconds.
    pub step_s: f64,
    /// What the placement did (sim-core's note), once it is done.
    pub placement_note: Option<String>,
    /// Where the sweep is.
    pub phase: SweepPhase,
    /// Steps in which the solver relaxed something to get through (friction dropped,
    /// anchors torn out, a residual accepted above the tolerance): every step is certified
    /// by sim-core's independent check, and these are said on screen.
    pub relaxed_steps: usize,
    /// The wall map: the points estimated from the sensed steps and the sections passed,
    /// step by step (one entry per step in `steps`).
    pub mapping: SweepMapping,
}

impl SweepRunState {
    /// Frames held: the placed posture and every step solved.
    pub fn frame_count(&self) -> usize {
        self.steps.len()
    }

    /// Steps solved after the placement.
    pub fn steps_done(&self) -> usize {
        self.steps.len().saturating_sub(1)
    }

    /// The sweep's planned end, seconds after its start.
    pub fn planned_end_s(&self) -> f64 {
        self.steps_run as f64 * self.step_s
    }

    /// Whether the thread is done (all steps solved, or stopped by an error).
    pub fn is_finished(&self) -> bool {
        matches!(self.phase, SweepPhase::Done | SweepPhase::Failed(_))
    }

    /// Why the sweep stopped early, if it did.
    pub fn error(&self) -> Option<&MonitorError> {
        match &self.phase {
            SweepPhase::Failed(e) => Some(e),
            _ => None,
        }
    }

    /// The step showing instant `t_s`: the last one at or before it (the first if all are
    /// later).
    pub fn step_at(&self, t_s: f64) -> Option<&SweepStep> {
        let after = self.steps.partition_point(|s| s.t_s <= t_s);
        self.steps.get(after.saturating_sub(1))
    }

    /// The index in `steps` of the step showing instant `t_s` ([`Self::step_at`]).
    pub fn step_index_at(&self, t_s: f64) -> Option<usize> {
        let after = self.steps.partition_point(|s| s.t_s <= t_s);
        (!self.steps.is_empty()).then(|| after.saturating_sub(1))
    }

    /// What the solver relaxed in the step showing instant `t_s` (empty when nothing).
    pub fn relaxations_at(&self, t_s: f64) -> Vec<String> {
        self.step_at(t_s)
            .map(|s| s.report.relaxations())
            .unwrap_or_default()
    }

    /// The chain at instant `t_s` ([`Self::step_at`]) as a frame; `None` before the
    /// placement is done.
    pub fn frame_at(&self, t_s: f64) -> Option<Result<ChainFrame, MonitorError>> {
        self.step_at(t_s).map(|step| {
            let mut frame = frame_from_step(&self.chain, &self.walls, self.track_m, step)?;
            frame.path_m.clone_from(&self.path_m);
            Ok(frame)
        })
    }

    /// One line on the sweep's progress, e.g. `sweep line_wall: step 12 of 50`.
    pub fn progress(&self) -> String {
        let name = &self.name;
        let (k, n) = (self.steps_done(), self.steps_run);
        match &self.phase {
            SweepPhase::Placing => format!("sweep {name}: placing the antenna ({n} steps to run)"),
            SweepPhase::Stepping => format!("sweep {name}: step {k} of {n}"),
            SweepPhase::Done if self.steps_run < self.steps_total => format!(
                "sweep {name}: done, {k} steps ({:.2} s) of the scene's {}: the monitor keeps \
                 at most {MAX_SWEEP_STEPS}",
                self.planned_end_s(),
                self.steps_total
            ),
            SweepPhase::Done => {
                format!(
                    "sweep {name}: done, {k} steps ({:.2} s)",
                    self.planned_end_s()
                )
            }
            SweepPhase::Failed(_) => format!("sweep {name}: stopped at step {k} of {n}"),
        }
    }

    /// Appends a solved step.
    fn push(&mut self, step: SweepStep) -> Result<(), MonitorError> {
        let segments = (1..=self.chain.n())
            .map(|joint| SegmentReading {
                angle_rad: step.theta_rad.get(joint).copied(),
                touch_bits: Some(step.touch_bits.get(joint).copied().unwrap_or(0)),
                health: Health::Ok,
            })
            .collect();
        self.history.push(&Sample {
            seq: Some(step.step as u64),
            t_s: step.t_s,
            segments,
            stage_position_m: Some(step.base_m.x),
            servo_angle_rad: step
                .theta_rad
                .first()
                .map(|theta_0| theta_0 - self.chain.base_angle_rad()),
        })?;
        if step.report.relaxed() {
            self.relaxed_steps += 1;
        }
        self.mapping.push(&self.chain, &step);
        self.steps.push(step);
        Ok(())
    }
}

/// A scene's sweep on its own thread (see the module documentation).
#[derive(Debug)]
pub struct SweepWorker {
    shared: Arc<Mutex<SweepRunState>>,
    cancel: Arc<AtomicBool>,
    thread: JoinHandle<()>,
}

impl SweepWorker {
    /// Reads the scene at `path` and starts its sweep, keeping at most `max_steps` steps
    /// after the placement.
    ///
    /// # Errors
    /// [`MonitorError::Scene`] if the file cannot be read, does not parse or cannot be swept
    /// (naming the key, line and column); [`MonitorError::Sweep`] if the thread cannot start.
    ///
    /// The wall map is estimated from what the scene's own `[sensors]` read (ideal without
    /// the table).
    pub fn start(path: &Path, max_steps: usize) -> Result<SweepWorker, MonitorError> {
        Self::launch(path, max_steps, None)
    }

    /// As [`Self::start`], with the wall map estimated from what sensors as `sensors`
    /// describe them read ([`SweepMapping::new`]) instead of the scene's `[sensors]`.
    ///
    /// # Errors
    /// As [`Self::start`]; [`MonitorError::Sweep`] if `sensors` do not fit the scene's chain.
    pub fn start_with_sensors(
        path: &Path,
        max_steps: usize,
        sensors: &SensorSettings,
    ) -> Result<SweepWorker, MonitorError> {
        Self::launch(path, max_steps, Some(sensors))
    }

    fn launch(
        path: &Path,
        max_steps: usize,
        sensors: Option<&SensorSettings>,
    ) -> Result<SweepWorker, MonitorError> {
        let scene = Scene::from_path(path)?;
        let sensors = sensors.unwrap_or(&scene.sensors);
        let sweep_scene = scene.sweep_scene()?;
        let steps_total = sweep_scene.motion.steps();
        let mapping = SweepMapping::new(
            sensors,
            &sweep_scene.chain,
            sweep_scene.walls.len(),
            sweep_scene.motion.direction_rad(),
        )?;
        let state = SweepRunState {
            path: path.to_path_buf(),
            name: path
                .file_stem()
                .map_or_else(|| "scene".to_owned(), |s| s.to_string_lossy().into_owned()),
            chain: sweep_scene.chain.clone(),
            walls: sweep_scene.walls.clone(),
            track_m: track_m(&sweep_scene),
            path_m: base_path_m(&sweep_scene),
            steps: Vec::new(),
            history: History::new(sweep_scene.chain.n(), steps_total.min(max_steps) + 1),
            steps_total,
            steps_run: steps_total.min(max_steps),
            step_s: sweep_scene.motion.step_s,
            placement_note: None,
            phase: SweepPhase::Placing,
            relaxed_steps: 0,
            mapping,
        };
        let shared = Arc::new(Mutex::new(state));
        let cancel = Arc::new(AtomicBool::new(false));
        let thread = {
            let (shared, cancel) = (Arc::clone(&shared), Arc::clone(&cancel));
            std::thread::Builder::new()
                .name("sweep".to_owned())
                .spawn(move || {
                    let outcome = run(&scene, sweep_scene, max_steps, &shared, &cancel);
                    lock(&shared).phase = match outcome {
                        Ok(()) => SweepPhase::Done,
                        Err(e) => SweepPhase::Failed(e),
                    };
                })
                .map_err(|e| MonitorError::Sweep(format!("cannot start its thread: {e}")))?
        };
        Ok(SweepWorker {
            shared,
            cancel,
            thread,
        })
    }

    /// The sweep so far. Held briefly: the thread waits for it to append a step. A thread
    /// that ended without saying how (it panicked) is reported as a failure here.
    pub fn lock(&self) -> MutexGuard<'_, SweepRunState> {
        let mut state = lock(&self.shared);
        if self.thread.is_finished() && !state.is_finished() {
            state.phase = SweepPhase::Failed(MonitorError::Sweep(
                "its thread ended unexpectedly".to_owned(),
            ));
        }
        state
    }
}

impl Drop for SweepWorker {
    /// Stops the thread after the step it is solving (it is not waited for).
    fn drop(&mut self) {
        self.cancel.store(true, Ordering::Relaxed);
    }
}

/// The state even if a panicking thread poisoned its lock (every update leaves it whole).
fn lock(shared: &Mutex<SweepRunState>) -> MutexGuard<'_, SweepRunState> {
    shared.lock().unwrap_or_else(PoisonError::into_inner)
}

/// The thread's work: places the antenna, then solves up to `max_steps` steps unless
/// cancelled. Each step is solved without the lock and handed over when the lock is free
/// (the monitor holds it while it draws a frame): the sweep never waits for the screen.
fn run(
    scene: &Scene,
    sweep_scene: SweepScene,
    max_steps: usize,
    shared: &Mutex<SweepRunState>,
    cancel: &AtomicBool,
) -> Result<(), MonitorError> {
    let step_s = sweep_scene.motion.step_s;
    let stopped = |e: SweepError, frames_kept: usize| {
        let t_s = match &e {
            SweepError::Step { t_s, .. } => *t_s,
            // The placement (frame 0), or the step after the frames kept.
            _ => frames_kept as f64 * step_s,
        };
        MonitorError::SweepStopped {
            t_s,
            frames_kept,
            source: SweepFailure::from_sweep_error(scene, e),
        }
    };
    let mut sweep = Sweep::new(sweep_scene).map_err(|e| stopped(e, 0))?;
    let placed = sweep
        .placed()
        .cloned()
        .ok_or_else(|| MonitorError::Sweep("the placement left no posture".to_owned()))?;
    {
        let mut state = lock(shared);
        state.placement_note = Some(sweep.placement_note().to_owned());
        state.push(placed)?;
        state.phase = SweepPhase::Stepping;
    }
    let mut frames = 1;
    let mut pending = Vec::new();
    let outcome = loop {
        if frames > max_steps || cancel.load(Ordering::Relaxed) {
            break Ok(());
        }
        match sweep.next_step() {
            Some(Ok(step)) => {
                pending.push(step);
                frames += 1;
                let state = match shared.try_lock() {
                    Ok(state) => Some(state),
                    Err(TryLockError::Poisoned(p)) => Some(p.into_inner()),
                    Err(TryLockError::WouldBlock) => None,
                };
                if let Some(mut state) = state {
                    hand_over(&mut state, &mut pending)?;
                }
            }
            Some(Err(e)) => break Err(stopped(e, frames)),
            None => break Ok(()),
        }
    };
    hand_over(&mut lock(shared), &mut pending)?;
    outcome
}

/// Appends the `pending` steps to `state`.
fn hand_over(state: &mut SweepRunState, pending: &mut Vec<SweepStep>) -> Result<(), MonitorError> {
    pending.drain(..).try_for_each(|step| state.push(step))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::{Duration, Instant};

    const SCENE: &str = "[antenna]\nlinks = 4\nlink_length_m = 0.04\nbase_angle_deg = 60.0\n\
        [antenna.stiffness]\nvalues_n_m_per_rad = [0.02, 0.01, 0.005]\n\
        [[walls]]\nshape = \"line\"\npoint_m = [0.0, 0.3]\nsolid = \"left\"\n\
        [sweep]\nvelocity_m_per_s = [0.02, 0.0]\nduration_s = 0.2\nstep_s = 0.01\n";

    fn scene_file(name: &str, text: &str) -> PathBuf {
        let path = std::env::temp_dir().join(format!(
            "monitor-sweep-run-{name}-{}.toml",
            std::process::id()
        ));
        std::fs::write(&path, text).unwrap();
        path
    }

    fn wait(worker: &SweepWorker) {
        let deadline = Instant::now() + Duration::from_secs(30);
        while !worker.lock().is_finished() {
            assert!(Instant::now() < deadline, "the sweep did not finish");
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    #[test]
    fn runs_a_scene_into_steps_history_and_frames() {
        let path = scene_file("ok", SCENE);
        let worker = SweepWorker::start(&path, MAX_SWEEP_STEPS).unwrap();
        wait(&worker);
        std::fs::remove_file(&path).ok();
        let state = worker.lock();
        assert!(state.error().is_none(), "{:?}", state.error());
        assert_eq!(state.frame_count(), 21);
        assert_eq!(state.history.len(), 21);
        assert_eq!(state.history.segment_count(), 3);
        assert_eq!(state.track_m, Some((0.0, 0.2 * 0.02)));
        let last = state.history.sample(20).unwrap();
        assert!((last.t_s - 0.2).abs() < 1e-9);
        assert!((last.stage_position_m.unwrap() - 0.004).abs() < 1e-9);
        let frame = state.frame_at(0.155).unwrap().unwrap();
        assert_eq!(frame.t_s, state.steps[15].t_s);
        assert_eq!(frame.joints_m.len(), 5);
        assert_eq!(
            state.history.angle_rad(15, 2),
            Some(f64::from(state.steps[15].theta_rad[3] as f32))
        );
        assert!(
            state.progress().contains("done, 20 steps"),
            "{}",
            state.progress()
        );
    }

    #[test]
    fn the_wall_map_senses_through_the_scenes_sensors() {
        let text = format!("{SCENE}\n[sensors]\nangle_noise_counts = 2.0\nseed = 3\n");
        let path = scene_file("sensors", &text);
        let worker = SweepWorker::start(&path, MAX_SWEEP_STEPS).unwrap();
        let overridden =
            SweepWorker::start_with_sensors(&path, MAX_SWEEP_STEPS, &SensorSettings::IDEAL)
                .unwrap();
        wait(&worker);
        wait(&overridden);
        std::fs::remove_file(&path).ok();
        let settings = worker.lock().mapping.sensor_settings().clone();
        assert_eq!(settings.angle_noise_counts, 2.0);
        assert_eq!(settings.seed, 3);
        assert!(overridden.lock().mapping.sensor_settings().is_ideal());
    }

    #[test]
    fn keeps_at_most_max_steps() {
        let path = scene_file("cut", SCENE);
        let worker = SweepWorker::start(&path, 5).unwrap();
        wait(&worker);
        std::fs::remove_file(&path).ok();
        let state = worker.lock();
        assert_eq!((state.frame_count(), state.steps_run), (6, 5));
        assert!(
            state.progress().contains("of the scene's 20"),
            "{}",
            state.progress()
        );
    }

    #[test]
    fn a_scene_that_does_not_parse_names_its_key_and_line() {
        let path = scene_file("bad", &SCENE.replace("duration_s", "duraton_s"));
        let err = SweepWorker::start(&path, MAX_SWEEP_STEPS)
            .unwrap_err()
            .to_string();
        std::fs::remove_file(&path).ok();
        assert!(err.contains("duraton_s") && err.contains(":13:"), "{err}");
    }

    #[test]
    fn a_failed_placement_stops_with_its_time_and_the_start_key() {
        // The tip placed on a wall 0.3 m away, out of the 0.16 m antenna's reach.
        let text = format!(
            "{SCENE}[start]\nplacement = \"tip-on-wall\"\nwall = 0\nahead_m = 0.0\nshape = \"C\"\n"
        );
        let path = scene_file("unplaceable", &text);
        let worker = SweepWorker::start(&path, MAX_SWEEP_STEPS).unwrap();
        wait(&worker);
        std::fs::remove_file(&path).ok();
        let state = worker.lock();
        let err = state.error().expect("the placement fails").to_string();
        assert!(
            err.contains("t = 0.000 s") && err.contains("placement"),
            "{err}"
        );
        assert_eq!(state.frame_count(), 0);
        assert!(state.progress().contains("stopped at step 0 of 20"));
    }

    #[test]
    fn relaxed_steps_are_counted_and_said_step_by_step() {
        let path = scene_file("relaxed", SCENE);
        let worker = SweepWorker::start(&path, MAX_SWEEP_STEPS).unwrap();
        wait(&worker);
        std::fs::remove_file(&path).ok();
        let mut state = worker.lock();
        assert_eq!(state.relaxed_steps, 0);
        assert!(state.relaxations_at(0.1).is_empty());
        // A step whose solve dropped friction (sim-core reports it in the step's report).
        let mut step = state.steps[20].clone();
        step.step = 21;
        step.t_s = 0.21;
        step.report.friction_dropped = true;
        step.report.jams = 2;
        state.push(step).unwrap();
        assert_eq!(state.relaxed_steps, 1);
        let said = state.relaxations_at(0.21).join("; ");
        assert!(
            said.contains("friction dropped at every contact") && said.contains("2 jammed"),
            "{said}"
        );
        assert!(state.relaxations_at(0.2).is_empty());
    }
}
