//! A closed-loop wall-following run (sim-core's [`sim_core::follow`], `antenna follow`) as the
//! monitor plays it: a top view of the robot, its antenna and the walls, the distance error
//! against time, and the cursor scrubbing both.
//!
//! Whatever its source, a run is one model, [`FollowRunState`]: the `start` line of
//! `antenna follow --jsonl` ([`FollowStart`]: the scene's text, the footprint, the setpoint,
//! the link lengths), the walls (parsed from that text with `antenna-scene`), one
//! [`FollowStepLine`] per step and, at the end, the [`FollowSummaryLine`]. Two sources fill
//! it:
//! - a `--jsonl` file of `antenna follow` ([`read_follow_file`]): read at once; a line that
//!   is not a follow line, or out of order, is an error naming the file and the line;
//! - a follow scene (`[robot]`, `[controller]`, `[follow]`; [`FollowWorker::start_scene`]):
//!   run by sim-core's [`Follow`] on its own thread, each
//!   [`FollowStep`](sim_core::follow::FollowStep) turned into its line ([`step_line`],
//!   antenna-scene's) and handed to the UI when it is not drawing, as a sweep's steps are.
//!
//! Each step is also one sample of a [`History`] (joint `k` as segment `k`, the sensed touch
//! bits), so the joint angles, the touch raster, the scrub slider, **Play** and the exports
//! work as for a recording. [`FollowRunState::frame_at`] draws the step at the cursor as a
//! [`ChainFrame`]: the antenna from its base (`base_m`) and joint angles (`theta_0` the
//! ground-frame base angle), the body's footprint at its pose and heading, the estimator's
//! points, the path so far and the whole run's extent.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError, TryLockError};
use std::thread::JoinHandle;
use std::time::Instant;

use antenna_scene::Scene;
use antenna_scene::follow_lines::{
    FollowLine, FollowStart, FollowStepLine, FollowSummaryLine, step_line, summary_line,
};
use sim_core::follow::{BodyModel, Follow, FollowError};
use sim_core::sweep::SweepScene;
use sim_core::{SensorSettings, Wall};

use crate::error::MonitorError;
use crate::frame::{BodyDrawing, ChainFrame, PointM, SegmentState};
use crate::history::{Health, History, Sample, SegmentReading};
use crate::sweep::wall_polyline_m;

/// The most steps the monitor holds of one run (2000 s at 100 Hz); a longer scene is run to
/// this many.
pub const MAX_FOLLOW_STEPS: usize = 200_000;

/// The most points of the path drawn (a longer path is thinned evenly, its newest point
/// kept).
const MAX_PATH_POINTS: usize = 4000;

/// Where a run is.
#[derive(Debug)]
pub enum FollowPhase {
    /// Placing the antenna and stepping (a scene run).
    Running,
    /// Every step in (a file read, or a scene run to its end).
    Done,
    /// Stopped by an error; the steps before it are kept.
    Failed(MonitorError),
}

/// A closed-loop run (see the module documentation).
#[derive(Debug)]
pub struct FollowRunState {
    /// The scene or `--jsonl` file.
    pub path: PathBuf,
    /// Its name (the file's stem).
    pub name: String,
    /// Whether it was read from a `--jsonl` file (else: run from a scene).
    pub from_file: bool,
    /// The run's `start` line.
    pub start: FollowStart,
    /// The walls, scene frame.
    pub walls: Vec<Wall>,
    /// Why no wall is drawn, when the scene's text in the file did not give them.
    pub walls_note: Option<String>,
    /// The steps, in time order.
    pub steps: Vec<FollowStepLine>,
    /// The same steps as polls (joint `k`'s angle and touch bits as segment `k`'s reading).
    pub history: History,
    /// The `summary` line, once the run is over (a file cut short has none).
    pub summary: Option<FollowSummaryLine>,
    /// Where the run is.
    pub phase: FollowPhase,
    walls_m: Vec<Vec<PointM>>,
    extent_m: Option<(PointM, PointM)>,
}

impl FollowRunState {
    fn new(
        path: &Path,
        from_file: bool,
        start: FollowStart,
        walls: Vec<Wall>,
        walls_note: Option<String>,
        centre_m: PointM,
        capacity: usize,
    ) -> Self {
        let links = start.link_lengths_m.len();
        let reach_m: f64 = start.link_lengths_m.iter().sum::<f64>()
            + start.footprint_m[0].hypot(start.footprint_m[1]);
        let travel_m = start.speed_m_per_s.abs() * start.steps as f64 * start.step_s;
        let half_length_m = if travel_m.is_finite() {
            travel_m + 2.0 * reach_m + 0.2
        } else {
            2.0 * reach_m + 0.2
        };
        let walls_m = walls
            .iter()
            .map(|w| wall_polyline_m(w, centre_m, half_length_m))
            .collect();
        Self {
            path: path.to_path_buf(),
            name: path
                .file_stem()
                .map_or_else(|| "follow".to_owned(), |s| s.to_string_lossy().into_owned()),
            from_file,
            history: History::new(
                links.saturating_sub(1),
                capacity.max(start.steps).max(1) + 1,
            ),
            start,
            walls,
            walls_note,
            steps: Vec::new(),
            summary: None,
            phase: FollowPhase::Running,
            walls_m,
            extent_m: None,
        }
    }

    /// Whether the run is over (every step in, or stopped by an error).
    pub fn is_finished(&self) -> bool {
        matches!(self.phase, FollowPhase::Done | FollowPhase::Failed(_))
    }

    /// Why the run stopped early, if it did.
    pub fn error(&self) -> Option<&MonitorError> {
        match &self.phase {
            FollowPhase::Failed(e) => Some(e),
            _ => None,
        }
    }

    /// The run's planned end, seconds after its start.
    pub fn planned_end_s(&self) -> f64 {
        self.start.steps.saturating_sub(1) as f64 * self.start.step_s
    }

    /// The index in `steps` of the step showing instant `t_s`: the last one at or before it
    /// (the first if all are later); `None` without steps.
    pub fn step_index_at(&self, t_s: f64) -> Option<usize> {
        let after = self.steps.partition_point(|s| s.t_s <= t_s);
        (!self.steps.is_empty()).then(|| after.saturating_sub(1))
    }

    /// The step showing instant `t_s` ([`Self::step_index_at`]).
    pub fn step_at(&self, t_s: f64) -> Option<&FollowStepLine> {
        self.step_index_at(t_s).and_then(|k| self.steps.get(k))
    }

    /// The whole run's extent so far `(min, max)`: every pose's footprint and antenna.
    pub fn extent_m(&self) -> Option<(PointM, PointM)> {
        self.extent_m
    }

    /// One line on the run's progress, e.g. `follow straight_wall: step 12 of 1000`.
    pub fn progress(&self) -> String {
        let name = &self.name;
        let (k, n) = (self.steps.len(), self.start.steps);
        let status = self
            .summary
            .as_ref()
            .map_or_else(String::new, |s| format!(", status {}", s.status));
        match &self.phase {
            FollowPhase::Running if k == 0 => format!("follow {name}: placing the antenna"),
            FollowPhase::Running => format!("follow {name}: step {k} of {n}"),
            FollowPhase::Done => format!(
                "follow {name}: {k} steps ({:.2} s){status}",
                self.steps.last().map_or(0.0, |s| s.t_s)
            ),
            FollowPhase::Failed(_) => format!("follow {name}: stopped at step {k} of {n}{status}"),
        }
    }

    /// The step at instant `t_s` ([`Self::step_at`]) as a frame for the chain panel; `None`
    /// without steps.
    pub fn frame_at(&self, t_s: f64) -> Option<ChainFrame> {
        self.step_index_at(t_s).and_then(|k| self.frame_at_index(k))
    }

    /// Step `k` as a frame: the antenna, the body, the estimator's points, the path up to it,
    /// the walls, the run's extent.
    pub fn frame_at_index(&self, k: usize) -> Option<ChainFrame> {
        let step = self.steps.get(k)?;
        let links = self.start.link_lengths_m.len();
        let joints_m = match step.base_m {
            Some(base) if step.theta_rad.len() == links => {
                antenna_joints_m(base, &step.theta_rad, &self.start.link_lengths_m)
            }
            _ => Vec::new(),
        };
        let segment_count = if joints_m.is_empty() {
            0
        } else {
            links.saturating_sub(1)
        };
        let segments = (1..=segment_count)
            .map(|link| SegmentState {
                touch_bits: step.touch.get(link).copied().unwrap_or(0),
                ..SegmentState::QUIET
            })
            .collect();
        let mut body = BodyDrawing::new(
            step.pose_m,
            step.heading_rad,
            self.start.footprint_m,
            step.collided,
        );
        body.estimated_wall_m = step
            .estimate_m
            .zip(step.estimate_preview_m)
            .map(|(d, preview)| {
                let (sin, cos) = step.heading_rad.sin_cos();
                // Toward the wall: the body's left for a left wall, its right otherwise.
                let side = if self.start.wall_side == "right" {
                    -1.0
                } else {
                    1.0
                };
                [
                    step.pose_m[0] + cos * preview - sin * side * d,
                    step.pose_m[1] + sin * preview + cos * side * d,
                ]
            });
        let stride = (k + 1).div_ceil(MAX_PATH_POINTS).max(1);
        let mut path_m: Vec<PointM> = self.steps[..=k]
            .iter()
            .step_by(stride)
            .map(|s| s.pose_m)
            .collect();
        if path_m.last() != Some(&step.pose_m) {
            path_m.push(step.pose_m);
        }
        let base_m = step.base_m.unwrap_or(step.pose_m);
        Some(ChainFrame {
            t_s: step.t_s,
            base_m,
            joints_m,
            segments,
            walls_m: self.walls_m.clone(),
            base_angle_rad: step.theta_rad.first().copied().unwrap_or(step.heading_rad),
            path_m,
            body: Some(body),
            estimated_points_m: step.estimated_points_m.clone(),
            run_extent_m: self.extent_m,
            ..ChainFrame::default()
        })
    }

    /// Appends a step (its time after the last one's).
    ///
    /// # Errors
    /// [`MonitorError::TimeOrder`] for a step not after the last one.
    fn push(&mut self, step: FollowStepLine) -> Result<(), MonitorError> {
        let n = self.history.segment_count();
        let segments = (1..=n)
            .map(|joint| SegmentReading {
                angle_rad: step.theta_rad.get(joint).copied(),
                touch_bits: Some(step.touch.get(joint).copied().unwrap_or(0)),
                health: Health::Ok,
            })
            .collect();
        self.history.push(&Sample {
            seq: Some(self.steps.len() as u64),
            t_s: step.t_s,
            segments,
            stage_position_m: None,
            servo_angle_rad: None,
        })?;
        let mut points = vec![step.pose_m];
        points.extend(
            BodyDrawing::new(step.pose_m, step.heading_rad, self.start.footprint_m, false)
                .corners_m,
        );
        if let Some(base) = step.base_m {
            let reach: f64 = self.start.link_lengths_m.iter().sum();
            points.extend([
                [base[0] - reach, base[1] - reach],
                [base[0] + reach, base[1] + reach],
            ]);
        }
        for p in points
            .iter()
            .filter(|p| p[0].is_finite() && p[1].is_finite())
        {
            let (min, max) = self.extent_m.get_or_insert((*p, *p));
            *min = [min[0].min(p[0]), min[1].min(p[1])];
            *max = [max[0].max(p[0]), max[1].max(p[1])];
        }
        self.steps.push(step);
        Ok(())
    }
}

/// The antenna's joint points from its base pivot `base_m`, its joint angles (`theta_rad[0]`
/// the base link's angle in the ground frame, each next one relative to the link before)
/// and its link lengths (the base link first): the base, then the distal end of every link,
/// as [`ChainFrame::joints_m`] has them.
pub fn antenna_joints_m(base_m: PointM, theta_rad: &[f64], link_lengths_m: &[f64]) -> Vec<PointM> {
    let mut points = Vec::with_capacity(link_lengths_m.len() + 1);
    let mut at = base_m;
    let mut angle_rad = 0.0;
    points.push(at);
    for (length_m, theta) in link_lengths_m.iter().zip(theta_rad) {
        angle_rad += theta;
        at = [
            at[0] + length_m * angle_rad.cos(),
            at[1] + length_m * angle_rad.sin(),
        ];
        points.push(at);
    }
    points
}

/// The error a follow file's line `line` (1-based) gives.
fn at_line(path: &Path, line: usize, message: impl Into<String>) -> MonitorError {
    MonitorError::FollowFile {
        path: path.to_path_buf(),
        line,
        message: message.into(),
    }
}

/// Reads a `--jsonl` file of `antenna follow` into a finished run.
///
/// # Errors
/// [`MonitorError::FollowFile`] naming the file and the line: a file that cannot be read
/// (line 0), a line that is not a follow line, a first line that is not the `start` line, a
/// step out of time order or with the wrong number of joint angles, a line after the
/// summary.
pub fn read_follow_file(path: &Path) -> Result<FollowRunState, MonitorError> {
    let text = std::fs::read_to_string(path).map_err(|e| at_line(path, 0, e.to_string()))?;
    parse_follow_text(&text, path)
}

/// [`read_follow_file`] of `text`, errors naming `path`.
///
/// # Errors
/// As [`read_follow_file`].
pub fn parse_follow_text(text: &str, path: &Path) -> Result<FollowRunState, MonitorError> {
    // Every step kept, however many steps the start line announced.
    let lines_total = text.lines().count();
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l))
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(number, l)| {
            serde_json::from_str::<FollowLine>(l)
                .map(|line| (number, line))
                .map_err(|e| at_line(path, number, format!("not a follow line: {e}")))
        });
    let (number, first) = lines.next().ok_or_else(|| {
        at_line(
            path,
            1,
            "empty: not a follow file of antenna follow --jsonl",
        )
    })??;
    let FollowLine::Start(start) = first else {
        return Err(at_line(
            path,
            number,
            "the first line is not the start line (\"type\": \"start\") of antenna follow --jsonl",
        ));
    };
    if start.link_lengths_m.iter().any(|l| !l.is_finite())
        || start.footprint_m.iter().any(|l| !l.is_finite())
    {
        return Err(at_line(
            path,
            number,
            "the link lengths and the footprint must be finite",
        ));
    }
    let (walls, walls_note) = walls_of(&start, path);
    let mut state: Option<FollowRunState> = None;
    let mut pending_start = Some((start, walls, walls_note));
    let mut summary_at: Option<usize> = None;
    for line in lines {
        let (number, line) = line?;
        if let Some(at) = summary_at {
            return Err(at_line(
                path,
                number,
                format!("a line after the summary (line {at})"),
            ));
        }
        match line {
            FollowLine::Start(_) => {
                return Err(at_line(path, number, "a second start line"));
            }
            FollowLine::Step(step) => {
                if let Some((start, walls, note)) = pending_start.take() {
                    state = Some(FollowRunState::new(
                        path,
                        true,
                        start,
                        walls,
                        note,
                        step.pose_m,
                        lines_total,
                    ));
                }
                let Some(state) = state.as_mut() else {
                    continue;
                };
                let links = state.start.link_lengths_m.len();
                if step.base_m.is_some() && step.theta_rad.len() != links {
                    return Err(at_line(
                        path,
                        number,
                        format!(
                            "{} joint angles for an antenna of {links} links (the start line's \
                             link_lengths_m)",
                            step.theta_rad.len()
                        ),
                    ));
                }
                if !(step.pose_m.iter().all(|v| v.is_finite()) && step.heading_rad.is_finite()) {
                    return Err(at_line(path, number, "the pose or heading is not finite"));
                }
                if let Some(last) = state.steps.last()
                    && step.t_s.partial_cmp(&last.t_s) != Some(std::cmp::Ordering::Greater)
                {
                    return Err(at_line(
                        path,
                        number,
                        format!(
                            "a step at t = {} s after one at t = {} s",
                            step.t_s, last.t_s
                        ),
                    ));
                }
                state
                    .push(step)
                    .map_err(|e| at_line(path, number, e.to_string()))?;
            }
            FollowLine::Summary(summary) => {
                if let Some((start, walls, note)) = pending_start.take() {
                    state = Some(FollowRunState::new(
                        path,
                        true,
                        start,
                        walls,
                        note,
                        [0.0, 0.0],
                        lines_total,
                    ));
                }
                if let Some(state) = state.as_mut() {
                    state.summary = Some(summary);
                }
                summary_at = Some(number);
            }
        }
    }
    let mut state = match (state, pending_start) {
        (Some(state), _) => state,
        (None, Some((start, walls, note))) => {
            FollowRunState::new(path, true, start, walls, note, [0.0, 0.0], lines_total)
        }
        (None, None) => return Err(at_line(path, 1, "no start line")),
    };
    state.phase = FollowPhase::Done;
    Ok(state)
}

/// The walls of a `start` line's scene text, or why there are none. A wall's points file is
/// looked for relative to the scene as the start line names it (from the working folder, as
/// `antenna follow` was run), then relative to the folder of the follow file `path`.
fn walls_of(start: &FollowStart, path: &Path) -> (Vec<Wall>, Option<String>) {
    if start.scene_toml.trim().is_empty() {
        return (
            Vec::new(),
            Some("the start line holds no scene text".to_owned()),
        );
    }
    let first = Scene::parse(&start.scene_toml, &start.scene);
    let scene_folder = Path::new(&start.scene)
        .parent()
        .unwrap_or_else(|| Path::new(""));
    let beside_file = path
        .parent()
        .map(|folder| folder.join(scene_folder))
        .filter(|_| scene_folder.is_relative());
    let parsed = match (first, beside_file) {
        (Err(_), Some(folder)) => Scene::parse_in(&start.scene_toml, &start.scene, &folder),
        (first, _) => first,
    };
    match parsed {
        Ok(scene) => (scene.walls, None),
        Err(e) => (
            Vec::new(),
            Some(format!("the scene in the start line: {e}")),
        ),
    }
}

/// A closed-loop run shared with the UI: a file read at once, or a scene run on its own
/// thread (see the module documentation). Dropping it stops the thread after the step it is
/// solving.
#[derive(Debug)]
pub struct FollowWorker {
    shared: Arc<Mutex<FollowRunState>>,
    cancel: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl FollowWorker {
    /// Reads a `--jsonl` file of `antenna follow` ([`read_follow_file`]).
    ///
    /// # Errors
    /// As [`read_follow_file`].
    pub fn open_file(path: &Path) -> Result<FollowWorker, MonitorError> {
        let state = read_follow_file(path)?;
        Ok(FollowWorker {
            shared: Arc::new(Mutex::new(state)),
            cancel: Arc::new(AtomicBool::new(false)),
            thread: None,
        })
    }

    /// Runs the follow scene at `path` (read already as `scene`) with sim-core's loop,
    /// keeping at most `max_steps` steps.
    ///
    /// # Errors
    /// [`MonitorError::Scene`] for a scene that is not a follow scene or whose run is not
    /// valid (located at its key); [`MonitorError::Follow`] if the thread cannot start. A
    /// placement that fails, or a footprint in a wall at the start, stops the run on its
    /// thread with the error located ([`FollowRunState::error`]).
    pub fn start_scene(
        path: &Path,
        scene: &Scene,
        max_steps: usize,
    ) -> Result<FollowWorker, MonitorError> {
        let (sweep_scene, mut config, sensors) = scene.follow_parts()?;
        if let Err(e) = config.validate() {
            return Err(locate(scene, &e));
        }
        let steps_total = config.steps();
        if steps_total > max_steps {
            config.settings.duration_s = max_steps as f64 * config.settings.step_s;
        }
        let link_lengths_m = scene.chain.link_lengths_m().to_vec();
        let start = FollowStart {
            scene: path.display().to_string(),
            scene_toml: std::fs::read_to_string(path).unwrap_or_default(),
            note: String::new(),
            estimator: config.controller.estimator.name().to_owned(),
            body: match config.robot.body {
                BodyModel::Template { .. } => "template",
                BodyModel::Wheeled { .. } => "wheeled",
            }
            .to_owned(),
            wall_side: config.robot.wall_side.name().to_owned(),
            speed_m_per_s: config.robot.speed_m_per_s,
            setpoint_m: config.controller.setpoint_m,
            steps: config.steps().min(max_steps),
            step_s: config.settings.step_s,
            delay_steps: config.delay_steps(),
            footprint_m: config.robot.footprint_m,
            links: link_lengths_m.len(),
            link_lengths_m,
        };
        let pose = config.settings.pose_m;
        let state = FollowRunState::new(
            path,
            false,
            start,
            scene.walls.clone(),
            None,
            [pose.x, pose.y],
            0,
        );
        let shared = Arc::new(Mutex::new(state));
        let cancel = Arc::new(AtomicBool::new(false));
        let thread = {
            let (shared, cancel) = (Arc::clone(&shared), Arc::clone(&cancel));
            let scene = scene.clone();
            std::thread::Builder::new()
                .name("follow".to_owned())
                .spawn(move || {
                    let outcome = run(&scene, &sweep_scene, &sensors, &config, &shared, &cancel);
                    lock(&shared).phase = match outcome {
                        Ok(()) => FollowPhase::Done,
                        Err(e) => FollowPhase::Failed(e),
                    };
                })
                .map_err(|e| MonitorError::Follow(format!("cannot start its thread: {e}")))?
        };
        Ok(FollowWorker {
            shared,
            cancel,
            thread: Some(thread),
        })
    }

    /// The run so far. Held briefly: the thread waits for it to append steps. A thread that
    /// ended without saying how (it panicked) is reported as a failure here.
    pub fn lock(&self) -> MutexGuard<'_, FollowRunState> {
        let mut state = lock(&self.shared);
        if self.thread.as_ref().is_some_and(JoinHandle::is_finished) && !state.is_finished() {
            state.phase = FollowPhase::Failed(MonitorError::Follow(
                "its thread ended unexpectedly".to_owned(),
            ));
        }
        state
    }
}

impl Drop for FollowWorker {
    /// Stops the thread after the step it is solving (it is not waited for).
    fn drop(&mut self) {
        self.cancel.store(true, Ordering::Relaxed);
    }
}

/// The state even if a panicking thread poisoned its lock (every update leaves it whole).
fn lock(shared: &Mutex<FollowRunState>) -> MutexGuard<'_, FollowRunState> {
    shared.lock().unwrap_or_else(PoisonError::into_inner)
}

/// `e` located in `scene`'s file where it can be (an invalid key, a footprint in a wall at
/// the start), else named with the file.
fn locate(scene: &Scene, e: &FollowError) -> MonitorError {
    match (&scene.follow, e) {
        (Some(f), FollowError::Invalid { .. } | FollowError::StartsInWall { .. }) => {
            MonitorError::Scene(f.locate(e))
        }
        _ => MonitorError::Follow(format!("{}: {e}", scene.locations.path)),
    }
}

/// The thread's work: starts the loop (placing the antenna), then runs it to its end unless
/// cancelled, handing the steps over when the lock is free (the run never waits for the
/// screen); the summary at the end, also when the solver ends the run.
fn run(
    scene: &Scene,
    sweep_scene: &SweepScene,
    sensors: &SensorSettings,
    config: &sim_core::follow::FollowConfig,
    shared: &Mutex<FollowRunState>,
    cancel: &AtomicBool,
) -> Result<(), MonitorError> {
    let started = Instant::now();
    let mut follow = Follow::new(sweep_scene, sensors, config).map_err(|e| locate(scene, &e))?;
    lock(shared).start.note = follow.placement_note().to_owned();
    let setpoint_m = config.controller.setpoint_m;
    let mut pending = Vec::new();
    let outcome = loop {
        if cancel.load(Ordering::Relaxed) {
            break Ok(());
        }
        match follow.next_step() {
            Some(Ok(step)) => {
                pending.push(step_line(&step, setpoint_m));
                let state = match shared.try_lock() {
                    Ok(state) => Some(state),
                    Err(TryLockError::Poisoned(p)) => Some(p.into_inner()),
                    Err(TryLockError::WouldBlock) => None,
                };
                if let Some(mut state) = state {
                    hand_over(&mut state, &mut pending)?;
                }
            }
            Some(Err(e)) => {
                break Err(MonitorError::Follow(format!(
                    "{}: the run stopped at t = {:.3} s: {e}",
                    scene.locations.path,
                    follow.summary().duration_s
                )));
            }
            None => break Ok(()),
        }
    };
    let mut state = lock(shared);
    hand_over(&mut state, &mut pending)?;
    state.summary = Some(summary_line(
        &follow.summary(),
        started.elapsed().as_secs_f64(),
    ));
    outcome
}

/// Appends the `pending` steps to `state`.
fn hand_over(
    state: &mut FollowRunState,
    pending: &mut Vec<FollowStepLine>,
) -> Result<(), MonitorError> {
    pending.drain(..).try_for_each(|step| state.push(step))
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim_core::{Chain, Frame, frame_poses};
    use std::time::Duration;

    /// `examples/follow/straight_wall.toml` cut to `duration_s`, written to a temporary file.
    fn short_scene(name: &str, duration_s: f64) -> PathBuf {
        let text = include_str!("../../examples/follow/straight_wall.toml")
            .replace("duration_s = 10.0", &format!("duration_s = {duration_s}"));
        assert!(text.contains(&format!("duration_s = {duration_s}")));
        let path =
            std::env::temp_dir().join(format!("monitor-follow-{name}-{}.toml", std::process::id()));
        std::fs::write(&path, text).unwrap();
        path
    }

    fn run_scene(path: &Path) -> FollowWorker {
        let scene = Scene::from_path(path).unwrap();
        let worker = FollowWorker::start_scene(path, &scene, MAX_FOLLOW_STEPS).unwrap();
        let deadline = Instant::now() + Duration::from_secs(120);
        while !worker.lock().is_finished() {
            assert!(Instant::now() < deadline, "the run did not finish");
            std::thread::sleep(Duration::from_millis(5));
        }
        worker
    }

    /// The lines `antenna follow --jsonl` writes for `state`.
    fn jsonl(state: &FollowRunState) -> String {
        let mut lines =
            vec![serde_json::to_string(&FollowLine::Start(state.start.clone())).unwrap()];
        lines.extend(
            state
                .steps
                .iter()
                .map(|s| serde_json::to_string(&FollowLine::Step(s.clone())).unwrap()),
        );
        if let Some(summary) = &state.summary {
            lines.push(serde_json::to_string(&FollowLine::Summary(summary.clone())).unwrap());
        }
        lines.join("\n") + "\n"
    }

    /// A follow scene runs into the model, and the same run read back from its JSON lines
    /// fills the same model: steps, history, frames; the cursor's time selects its step.
    #[test]
    fn a_scene_run_and_its_jsonl_fill_the_same_model_and_the_cursor_selects_the_step() {
        let path = short_scene("run", 0.3);
        let worker = run_scene(&path);
        std::fs::remove_file(&path).ok();
        let run = worker.lock();
        assert!(run.error().is_none(), "{:?}", run.error());
        assert!(!run.from_file);
        assert_eq!(run.steps.len(), 30);
        assert_eq!(run.history.len(), 30);
        assert_eq!(run.history.segment_count(), 8);
        assert_eq!(run.start.link_lengths_m.len(), 9);
        assert!(!run.start.note.is_empty());
        assert_eq!(run.summary.as_ref().unwrap().status, "ok");
        assert_eq!(run.walls.len(), 1);
        assert!(run.progress().contains("30 steps"), "{}", run.progress());

        let text = jsonl(&run);
        let read = parse_follow_text(&text, Path::new("run.jsonl")).unwrap();
        assert!(read.from_file && read.is_finished() && read.error().is_none());
        assert_eq!(read.steps, run.steps);
        assert_eq!(read.summary, run.summary);
        assert_eq!(read.walls, run.walls, "{:?}", read.walls_note);
        assert_eq!(read.history.len(), run.history.len());
        assert_eq!(read.extent_m(), run.extent_m());

        // The cursor's time selects the last step at or before it.
        assert_eq!(read.step_index_at(0.105), Some(10));
        assert_eq!(read.step_at(0.1).unwrap().t_s, read.steps[10].t_s);
        assert_eq!(read.step_index_at(-1.0), Some(0));
        assert_eq!(read.step_index_at(99.0), Some(29));
        assert_eq!(read.history.index_at(0.105), Some(10));
        let frame = read.frame_at(0.105).unwrap();
        assert_eq!(frame, run.frame_at(0.105).unwrap());
        let step = &read.steps[10];
        assert_eq!(frame.t_s, step.t_s);
        // The antenna from its base: 9 links, 10 points, the base at the step's base_m.
        assert_eq!(frame.joints_m.len(), 10);
        assert_eq!(frame.joints_m[0], step.base_m.unwrap());
        assert_eq!(frame.segments.len(), 8);
        let body = frame.body.unwrap();
        assert_eq!(
            (body.por_m, body.heading_rad),
            (step.pose_m, step.heading_rad)
        );
        // The path so far ends at the pose; the walls are drawn; the extent holds the body.
        assert_eq!(frame.path_m.len(), 11);
        assert_eq!(frame.path_m.last(), Some(&step.pose_m));
        assert_eq!(frame.walls_m.len(), 1);
        let (min, max) = frame.run_extent_m.unwrap();
        for c in body.corners_m {
            assert!(min[0] <= c[0] && c[0] <= max[0] && min[1] <= c[1] && c[1] <= max[1]);
        }
        // The wall is along y = 0.2 m: the estimated wall point, where there is one, near it.
        if let Some(p) = body.estimated_wall_m {
            assert!((p[1] - 0.2).abs() < 0.02, "{p:?}");
        }
        // The antenna touches the wall (at y = 0.2 m) and its tip stays short of it.
        let tip = frame.tip_m().unwrap();
        assert!(tip[1] < 0.2 + 1e-3, "{tip:?}");
    }

    /// A bad line, a file that does not start with the start line, steps out of order and a
    /// step with the wrong number of joint angles are errors naming the file and the line.
    #[test]
    fn a_bad_follow_file_names_its_line() {
        let start = FollowStart {
            scene: "nowhere.toml".into(),
            scene_toml: String::new(),
            note: String::new(),
            estimator: "ideal-preview".into(),
            body: "template".into(),
            wall_side: "left".into(),
            speed_m_per_s: 0.3,
            setpoint_m: 0.1,
            steps: 3,
            step_s: 0.01,
            delay_steps: 0,
            footprint_m: [0.12, 0.06],
            links: 2,
            link_lengths_m: vec![0.04, 0.04],
        };
        let step = |t_s: f64, theta: Vec<f64>| FollowStepLine {
            t_s,
            pose_m: [0.3 * t_s, 0.12],
            heading_rad: 0.0,
            omega_rad_per_s: 0.0,
            u_n_m: Some(0.0),
            turn_command_rad_per_s: None,
            antenna_moment_n_m: 0.0,
            wall_distance_m: Some(0.08),
            error_m: Some(-0.02),
            estimate_m: None,
            estimate_angle_rad: None,
            estimate_preview_m: None,
            no_estimate: Some("no contact in the window".into()),
            true_distance_at_preview_m: None,
            contacts: 0,
            touch: vec![0, 0],
            collided: false,
            base_m: Some([0.04, 0.14]),
            theta_rad: theta,
            estimated_points_m: vec![],
        };
        let line = |l: FollowLine| serde_json::to_string(&l).unwrap();
        let good = [
            line(FollowLine::Start(start.clone())),
            line(FollowLine::Step(step(0.0, vec![0.5, 0.0]))),
            line(FollowLine::Step(step(0.01, vec![0.5, 0.1]))),
        ];
        let path = Path::new("data/run.jsonl");
        let ok = parse_follow_text(&good.join("\n"), path).unwrap();
        assert_eq!(ok.steps.len(), 2);
        assert!(ok.summary.is_none());
        assert!(ok.walls.is_empty() && ok.walls_note.is_some());
        assert_eq!(ok.frame_at(0.01).unwrap().joints_m.len(), 3);
        // More steps than the start line announced: every one kept, in the history too.
        let announced_one = [
            line(FollowLine::Start(FollowStart {
                steps: 1,
                ..start.clone()
            })),
            good[1].clone(),
            good[2].clone(),
        ];
        let more = parse_follow_text(&announced_one.join("\n"), path).unwrap();
        assert_eq!((more.steps.len(), more.history.len()), (2, 2));

        let error = |text: String| parse_follow_text(&text, path).unwrap_err().to_string();
        let e = error(format!(
            "{}\n\n{}\n{{\"type\": \"step\", \"t_s\": }}\n",
            good[0], good[1]
        ));
        assert!(e.starts_with("data/run.jsonl:4: not a follow line"), "{e}");
        let e = error(format!("{}\n{}\n", good[1], good[0]));
        assert!(
            e.starts_with("data/run.jsonl:1: the first line is not the start line"),
            "{e}"
        );
        let e = error(format!("{}\n{}\n{}\n", good[0], good[2], good[1]));
        assert!(
            e.starts_with("data/run.jsonl:3: a step at t = 0 s after one at t = 0.01 s"),
            "{e}"
        );
        let e = error(format!(
            "{}\n{}\n{}\n",
            good[0],
            good[1],
            line(FollowLine::Step(step(0.02, vec![0.5, 0.1, 0.2])))
        ));
        assert!(
            e.starts_with("data/run.jsonl:3: 3 joint angles for an antenna of 2 links"),
            "{e}"
        );
        let e = error(String::new());
        assert!(e.starts_with("data/run.jsonl:1: empty"), "{e}");
        let e = error(format!("{}\n{}\n", good[0], good[0]));
        assert!(
            e.starts_with("data/run.jsonl:2: a second start line"),
            "{e}"
        );
        let e = read_follow_file(Path::new("/nonexistent/run.jsonl"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("/nonexistent/run.jsonl:0: "), "{e}");
    }

    /// A follow scene whose footprint starts in the wall is refused on the run's thread with
    /// the error located at `[follow] pose_m`; the steps kept are none.
    #[test]
    fn a_footprint_in_the_wall_at_the_start_is_located() {
        let path = short_scene("in-wall", 0.1);
        let text = std::fs::read_to_string(&path)
            .unwrap()
            .replace("pose_m = [0.0, 0.12]", "pose_m = [0.0, 0.19]");
        std::fs::write(&path, text).unwrap();
        let scene = Scene::from_path(&path).unwrap();
        let outcome = FollowWorker::start_scene(&path, &scene, MAX_FOLLOW_STEPS);
        let e = match outcome {
            Err(e) => e.to_string(),
            Ok(worker) => {
                let deadline = Instant::now() + Duration::from_secs(60);
                while !worker.lock().is_finished() {
                    assert!(Instant::now() < deadline, "the run did not finish");
                    std::thread::sleep(Duration::from_millis(5));
                }
                let state = worker.lock();
                assert!(state.steps.is_empty());
                state.error().expect("refused").to_string()
            }
        };
        std::fs::remove_file(&path).ok();
        assert!(e.contains("pose_m") && e.contains(":66:"), "{e}");
    }

    #[test]
    fn the_antennas_joints_are_sim_cores_kinematics_from_its_base() {
        let chain = Chain::builder(3)
            .link_lengths_m(vec![0.03, 0.04, 0.05, 0.02])
            .base_angle_rad(0.4)
            .stiffness_nm_per_rad(0.01)
            .build()
            .unwrap();
        let theta = [0.9, -0.2, 0.3, 0.5];
        let poses = frame_poses(&chain, &theta, Frame::GROUND).unwrap();
        let base = [1.0, -2.0];
        let joints = antenna_joints_m(base, &theta, chain.link_lengths_m());
        assert_eq!(joints.len(), 5);
        for (i, p) in (-1..=3).zip(&joints) {
            let q = poses.position_m(Frame::new(i)).unwrap();
            assert!(
                (p[0] - base[0] - q.x).abs() < 1e-12 && (p[1] - base[1] - q.y).abs() < 1e-12,
                "frame {i}: {p:?} against {q:?}"
            );
        }
    }
}
