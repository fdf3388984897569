//! [`MonitorApp`]: the whole monitor, laid out from the panels, for eframe and for tests.
//!
//! A source feeds it: [`LiveClient`] (antennad's stream), a [`RecordedTrial`] (an MCAP
//! file), a [`SweepWorker`] (a scene file's simulated sweep, solved on its own thread) or a
//! [`FollowWorker`] (a closed-loop wall-following run: a follow scene run on its own thread,
//! or a `--jsonl` file of `antenna follow`). Files open from the command line, the source bar
//! or by dropping them on the window (`.mcap`, `.toml`, `.jsonl`).
//! Every frame it reads the source's [`History`] under the view's window, draws the chain at
//! the view's cursor (with the prediction for the same base pose, for the rig's sources), and
//! carries out the user's view, export and control actions. A sweep is shown whole as it is
//! solved (the chain at the newest step) until the user moves the view, then played, paused
//! and scrubbed like a recording; a follow run the same way, with its top view (the robot, its
//! antenna, the walls, the estimator's points) and its distance error against time. Live and
//! recorded, the daemon's wall estimate at the cursor is drawn over the chain
//! ([`attach_estimate`]) and its distance plotted against time ([`EstimatePanel`]).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use antenna_data::stream::SegmentStatus;
use egui::{Color32, RichText};
use sim_core::CoverageSettings;

use crate::client::{ClientOptions, Command, ConnectionState, LiveClient, ReplyRecord};
use crate::error::MonitorError;
use crate::estimate::EstimateHistory;
use crate::export::{FigureInput, export_csv, export_figure};
use crate::follow::{FollowRunState, FollowWorker, MAX_FOLLOW_STEPS};
use crate::frame::{ChainFrame, SegmentState};
use crate::history::{Health, History};
use crate::mapping::CoverageCache;
use crate::panels::chain::WallMap;
use crate::panels::{
    ChainPanel, ControlsPanel, EstimatePanel, FollowErrorPanel, FollowInfoPanel, HealthPanel,
    JointAnglesPanel, StageInfo, StagePanel, TimelineAction, TimelinePanel, TouchRasterPanel,
};
use crate::prediction::{BasePose, PredictionWorker, predictor_for};
use crate::recording::{RecordedTrial, open_trial};
use crate::rig::RigGeometry;
use crate::sweep_run::{MAX_SWEEP_STEPS, SweepPhase, SweepRunState, SweepWorker};
use crate::view::ViewState;

/// How the app starts.
#[derive(Debug, Clone)]
pub struct AppOptions {
    /// Connect to antennad at this `host:port`.
    pub connect: Option<String>,
    /// The control token (empty: watch only).
    pub token: String,
    /// Open this recorded trial instead.
    pub trial: Option<PathBuf>,
    /// Run this scene file instead (when no trial is given): its sweep, or its closed-loop
    /// run for a follow scene.
    pub scene: Option<PathBuf>,
    /// Play this `--jsonl` file of `antenna follow` instead (when no trial or scene is
    /// given).
    pub follow: Option<PathBuf>,
    /// The live history window, seconds.
    pub history_s: f64,
    /// Where exports are written.
    pub export_dir: PathBuf,
}

impl Default for AppOptions {
    /// Nothing open, no token, 60 s of history, exports to the working directory.
    fn default() -> Self {
        Self {
            connect: None,
            token: String::new(),
            trial: None,
            scene: None,
            follow: None,
            history_s: 60.0,
            export_dir: PathBuf::from("."),
        }
    }
}

/// One export written.
#[derive(Debug, Clone, PartialEq)]
pub struct ExportRecord {
    /// The file.
    pub path: PathBuf,
    /// CSV rows written (figures: `None`).
    pub rows: Option<usize>,
    /// The range exported, seconds.
    pub t0_s: f64,
    /// See `t0_s`.
    pub t1_s: f64,
}

enum Source {
    Idle,
    Live(LiveClient),
    Trial(Box<RecordedTrial>),
    Sweep(SweepWorker),
    Follow(FollowWorker),
}

struct PredictionSlot {
    key: String,
    worker: Result<PredictionWorker, String>,
}

/// The monitor (see the module documentation).
pub struct MonitorApp {
    source: Source,
    view: ViewState,
    history_s: f64,
    panels: Panels,
    prediction: Option<PredictionSlot>,
    address: String,
    trial_path: String,
    scene_path: String,
    /// A sweep's view as the app last set it: while the user has not moved it since, the
    /// app keeps the whole sweep in view (`None`: the user has).
    sweep_view: Option<ViewState>,
    /// Whether the end of the current sweep has been reported.
    sweep_reported: bool,
    /// Sweeps opened so far: tells the coverage of one sweep from another's.
    sweeps_opened: u64,
    /// The wall map's coverage at the step drawn.
    coverage: CoverageCache,
    export_dir: PathBuf,
    exports: Vec<ExportRecord>,
    message: Option<(String, bool)>,
    refusal: Option<String>,
    /// The token given at start (`--token`, `ANTENNA_TOKEN`): proved with `auth` on every
    /// connection while the token field still holds it. A token typed in proves itself with
    /// its first command (so that typing sends no guesses).
    startup_token: String,
    /// The connection (its number) last proved with `auth`.
    authenticated: Option<u32>,
    /// Playing a recording: when the cursor last moved.
    playing: Option<Instant>,
}

struct Panels {
    chain: ChainPanel,
    angles: JointAnglesPanel,
    raster: TouchRasterPanel,
    health: HealthPanel,
    stage: StagePanel,
    controls: ControlsPanel,
    timeline: TimelinePanel,
    follow_error: FollowErrorPanel,
    follow_info: FollowInfoPanel,
    estimate: EstimatePanel,
}

/// What one frame reads from the source.
struct DataRef<'a> {
    history: &'a History,
    rig: Option<&'a RigGeometry>,
    /// A simulated sweep: the chain is its step at the cursor (there is no rig).
    sweep: Option<&'a SweepRunState>,
    /// A closed-loop run: the chain is its step at the cursor, with the robot.
    follow: Option<&'a FollowRunState>,
    /// antennad's wall estimates (live, or a recording's).
    estimates: Option<&'a EstimateHistory>,
    stage_range_m: Option<(f64, f64)>,
    mount_angle_rad: f64,
    addresses: &'a [u8],
    counters: Option<&'a [SegmentStatus]>,
    trial: Option<String>,
    note: Option<String>,
    replies: &'a [ReplyRecord],
    connected: bool,
    live: bool,
}

/// What a frame asks of the source after it is drawn.
#[derive(Default)]
struct Deferred {
    commands: Vec<Command>,
    history_s: Option<f64>,
}

impl MonitorApp {
    /// The app of `options`: connects or opens at once (a trial that does not open leaves
    /// the app idle with the error shown).
    pub fn new(options: AppOptions) -> Self {
        let mut app = Self {
            source: Source::Idle,
            view: ViewState::new(10.0_f64.min(options.history_s)),
            history_s: options.history_s,
            panels: Panels {
                chain: ChainPanel::default(),
                angles: JointAnglesPanel::default(),
                raster: TouchRasterPanel,
                health: HealthPanel,
                stage: StagePanel,
                controls: ControlsPanel::new(options.token.clone()),
                timeline: TimelinePanel::new(options.history_s),
                follow_error: FollowErrorPanel,
                follow_info: FollowInfoPanel,
                estimate: EstimatePanel,
            },
            prediction: None,
            address: options
                .connect
                .clone()
                .unwrap_or_else(|| "127.0.0.1:7878".to_owned()),
            trial_path: options
                .trial
                .as_ref()
                .or(options.follow.as_ref())
                .map_or_else(String::new, |p| p.display().to_string()),
            scene_path: options
                .scene
                .as_ref()
                .map_or_else(String::new, |p| p.display().to_string()),
            sweep_view: None,
            sweep_reported: false,
            sweeps_opened: 0,
            coverage: CoverageCache::default(),
            export_dir: options.export_dir,
            exports: Vec::new(),
            message: None,
            refusal: None,
            startup_token: options.token.clone(),
            authenticated: None,
            playing: None,
        };
        if let Some(path) = &options.trial {
            app.open(path);
        } else if let Some(path) = &options.scene {
            app.open_scene(path);
        } else if let Some(path) = &options.follow {
            app.open_follow_file(path);
        } else if let Some(address) = &options.connect {
            app.connect(address.clone());
        }
        app
    }

    /// Connects to antennad at `address` (replacing the current source).
    pub fn connect(&mut self, address: String) {
        let mut options = ClientOptions::new(address.clone());
        options.history_s = self.history_s;
        match LiveClient::connect(options) {
            Ok(client) => {
                self.source = Source::Live(client);
                self.view = ViewState::new(self.view.window_s());
                // The bar shows the connection's state from now on.
                self.message = None;
            }
            Err(e) => self.message = Some((e.to_string(), true)),
        }
    }

    /// Opens the file at `path` by its extension: a scene file (`.toml`, [`Self::open_scene`]),
    /// a follow file (`.jsonl`, [`Self::open_follow_file`]) or a recorded trial (anything else,
    /// [`Self::open`]). Dropping a file on the window does this.
    pub fn open_path(&mut self, path: &Path) {
        match extension(path).as_str() {
            "toml" => self.open_scene(path),
            _ => self.open(path),
        }
    }

    /// Opens the recorded trial at `path` (replacing the current source); a `.jsonl` file is a
    /// follow file ([`Self::open_follow_file`]).
    pub fn open(&mut self, path: &Path) {
        if extension(path) == "jsonl" {
            self.open_follow_file(path);
            return;
        }
        match open_trial(path) {
            Ok(trial) => {
                let span = trial
                    .history
                    .first_t_s()
                    .zip(trial.history.latest_t_s())
                    .map_or(1.0, |(a, b)| (b - a).max(0.01));
                // The whole trial in view, the chain at its start.
                self.view = ViewState::new(span);
                if let Some(first) = trial.history.first_t_s() {
                    self.view.show_range(first, first + span, first);
                }
                let mut note = format!(
                    "opened {} ({} polls, {:.2} s)",
                    path.display(),
                    trial.history.len(),
                    span
                );
                if let Some(why) = &trial.geometry_note {
                    note.push_str(&format!("; geometry assumed: {why}"));
                }
                if let Some(cut) = &trial.truncated {
                    note.push_str(&format!("; the file was cut short: {cut}"));
                }
                self.message = Some((note, false));
                self.playing = None;
                self.source = Source::Trial(Box::new(trial));
            }
            Err(e) => self.message = Some((e.to_string(), true)),
        }
    }

    /// Opens a `--jsonl` file of `antenna follow` and shows the whole run (replacing the
    /// current source). A file that cannot be played leaves the source as it was, with the
    /// error (naming the file and the line) in the status line.
    pub fn open_follow_file(&mut self, path: &Path) {
        match FollowWorker::open_file(path) {
            Ok(worker) => {
                let note = {
                    let state = worker.lock();
                    let span = state.history.first_t_s().zip(state.history.latest_t_s());
                    let length_s = span.map_or(1.0, |(a, b)| (b - a).max(0.01));
                    self.view = ViewState::new(length_s);
                    if let Some((first, _)) = span {
                        self.view.show_range(first, first + length_s, first);
                    }
                    let mut note = format!(
                        "opened {} ({} steps, {:.2} s, status {})",
                        path.display(),
                        state.steps.len(),
                        length_s,
                        state
                            .summary
                            .as_ref()
                            .map_or("unknown: no summary line", |s| s.status.as_str())
                    );
                    if let Some(why) = &state.walls_note {
                        note.push_str(&format!("; no walls drawn: {why}"));
                    }
                    note
                };
                self.message = Some((note, false));
                self.sweep_view = None;
                self.sweep_reported = true;
                self.playing = None;
                self.source = Source::Follow(worker);
            }
            Err(e) => self.message = Some((e.to_string(), true)),
        }
    }

    /// Reads the scene file at `path` and starts its sweep on a worker thread, or for a follow
    /// scene (`[robot]`, `[controller]`, `[follow]`) its closed-loop run (replacing the
    /// current source). A file that does not parse leaves the source as it was, with the
    /// error (naming the key, line and column) in the status line.
    pub fn open_scene(&mut self, path: &Path) {
        match antenna_scene::Scene::from_path(path) {
            Ok(scene) if scene.follow.is_some() => {
                match FollowWorker::start_scene(path, &scene, MAX_FOLLOW_STEPS) {
                    Ok(worker) => {
                        let planned_end_s = worker.lock().planned_end_s();
                        self.view = ViewState::new(planned_end_s.max(0.01));
                        self.sweep_view = Some(self.view.clone());
                        self.sweep_reported = false;
                        self.message = Some((
                            format!("running the follow run of {}", path.display()),
                            false,
                        ));
                        self.playing = None;
                        self.source = Source::Follow(worker);
                    }
                    Err(e) => self.message = Some((e.to_string(), true)),
                }
                return;
            }
            Ok(_) => {}
            Err(e) => {
                self.message = Some((MonitorError::Scene(e).to_string(), true));
                return;
            }
        }
        match SweepWorker::start(path, MAX_SWEEP_STEPS) {
            Ok(worker) => {
                let planned_end_s = worker.lock().planned_end_s();
                self.view = ViewState::new(planned_end_s.max(0.01));
                self.sweep_view = Some(self.view.clone());
                self.sweep_reported = false;
                self.sweeps_opened += 1;
                self.coverage.clear();
                self.message = Some((format!("running the sweep of {}", path.display()), false));
                self.playing = None;
                self.source = Source::Sweep(worker);
            }
            Err(e) => self.message = Some((e.to_string(), true)),
        }
    }

    /// The simulated sweep, if one is the source.
    pub fn sweep(&self) -> Option<&SweepWorker> {
        match &self.source {
            Source::Sweep(w) => Some(w),
            _ => None,
        }
    }

    /// The sweep and step whose wall map is held: `(n, step)` for the `n`th sweep opened
    /// (from 1) and the index of the step among its steps (the placement is 0); `None` before
    /// a map is computed. The map is computed only while it is shown.
    pub fn coverage_key(&self) -> Option<(u64, usize)> {
        self.coverage.key()
    }

    /// The closed-loop run, if one is the source (a follow scene's or a file's).
    pub fn follow(&self) -> Option<&FollowWorker> {
        match &self.source {
            Source::Follow(w) => Some(w),
            _ => None,
        }
    }

    /// Moves the cursor to `t_s` (as the scrub slider does), stopping playback; the view
    /// stays where this puts it.
    pub fn scrub_to(&mut self, t_s: f64) {
        let latest = match &self.source {
            Source::Live(c) => c.lock().history.latest_t_s(),
            Source::Trial(t) => t.history.latest_t_s(),
            Source::Sweep(w) => w.lock().history.latest_t_s(),
            Source::Follow(w) => w.lock().history.latest_t_s(),
            Source::Idle => None,
        };
        self.playing = None;
        self.view.scrub(t_s, latest);
    }

    /// The view (window, cursor, following).
    pub fn view(&self) -> &ViewState {
        &self.view
    }

    /// The live client, if the source is antennad.
    pub fn live(&self) -> Option<&LiveClient> {
        match &self.source {
            Source::Live(c) => Some(c),
            _ => None,
        }
    }

    /// The recorded trial, if one is open.
    pub fn trial(&self) -> Option<&RecordedTrial> {
        match &self.source {
            Source::Trial(t) => Some(t),
            _ => None,
        }
    }

    /// The exports written so far, oldest first.
    pub fn exports(&self) -> &[ExportRecord] {
        &self.exports
    }

    /// The status line: the last thing that happened and whether it was an error.
    pub fn message(&self) -> Option<(&str, bool)> {
        self.message.as_ref().map(|(m, e)| (m.as_str(), *e))
    }

    /// Waits (at most `timeout`) until the live history spans `history_s` seconds and the
    /// prediction for the newest pose is in (a sweep: until it has run `history_s` seconds,
    /// or ended): for a screenshot that shows the chain from the first frame. Returns whether
    /// that happened.
    pub fn wait_for_data(&mut self, history_s: f64, timeout: Duration) -> bool {
        let deadline = Instant::now() + timeout;
        while Instant::now() < deadline {
            let measured = match &self.source {
                Source::Live(client) => {
                    let state = client.lock();
                    let span = state
                        .history
                        .first_t_s()
                        .zip(state.history.latest_t_s())
                        .map(|(a, b)| b - a);
                    match (&state.rig, span) {
                        (Some(rig), Some(span)) if span >= history_s => state
                            .history
                            .len()
                            .checked_sub(1)
                            .and_then(|i| rig.frame_at(&state.history, i).ok())
                            .map(|f| (f, rig.clone())),
                        _ => None,
                    }
                }
                Source::Trial(_) => return true,
                Source::Sweep(worker) => {
                    let state = worker.lock();
                    let span = state
                        .history
                        .first_t_s()
                        .zip(state.history.latest_t_s())
                        .map(|(a, b)| b - a);
                    if state.is_finished() || span.is_some_and(|s| s >= history_s) {
                        return true;
                    }
                    None
                }
                Source::Follow(worker) => {
                    let state = worker.lock();
                    let span = state
                        .history
                        .first_t_s()
                        .zip(state.history.latest_t_s())
                        .map(|(a, b)| b - a);
                    if state.is_finished() || span.is_some_and(|s| s >= history_s) {
                        return true;
                    }
                    None
                }
                Source::Idle => return false,
            };
            if let Some((frame, rig)) = measured {
                let (_, note) = self.predicted(&rig, &frame);
                let current = self
                    .prediction
                    .as_mut()
                    .and_then(|p| p.worker.as_mut().ok())
                    .is_some_and(PredictionWorker::is_current);
                if current || note.is_some_and(|n| !n.contains("solving")) {
                    return true;
                }
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        false
    }

    /// The prediction for `measured`'s base pose against `rig`'s wall, as a frame, or why
    /// there is none.
    fn predicted(
        &mut self,
        rig: &RigGeometry,
        measured: &ChainFrame,
    ) -> (Option<ChainFrame>, Option<String>) {
        let key = format!("{}#{}", rig.source, rig.segment_count());
        if self.prediction.as_ref().is_none_or(|p| p.key != key) {
            let worker = predictor_for(rig)
                .and_then(PredictionWorker::start)
                .map_err(|e| e.to_string());
            self.prediction = Some(PredictionSlot { key, worker });
        }
        let Some(slot) = self.prediction.as_mut() else {
            return (None, None);
        };
        let worker = match &mut slot.worker {
            Ok(w) => w,
            Err(e) => return (None, Some(e.clone())),
        };
        let Some(stage_position_m) = measured.stage_position_m else {
            return (None, Some("the stage position is unknown".to_owned()));
        };
        worker.request(BasePose {
            stage_position_m,
            servo_angle_rad: measured.base_angle_rad - rig.base_mount_angle_rad,
        });
        match worker.latest() {
            Some(Ok(p)) => {
                let states = p
                    .touch_bits
                    .iter()
                    .map(|&touch_bits| SegmentState {
                        touch_bits,
                        ..SegmentState::QUIET
                    })
                    .collect();
                let frame = rig.frame(
                    measured.t_s,
                    &p.joint_angles_rad,
                    states,
                    Some(p.pose.stage_position_m),
                    Some(p.pose.servo_angle_rad),
                );
                match frame {
                    Ok(f) => (Some(f), None),
                    Err(e) => (None, Some(e.to_string())),
                }
            }
            Some(Err(e)) => (None, Some(e.clone())),
            None => (None, Some("solving...".to_owned())),
        }
    }

    /// Draws the whole app into `ui` (eframe's root `Ui`, or a test harness's).
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        let dropped: Option<PathBuf> = ui.ctx().input(|i| {
            i.raw
                .dropped_files
                .iter()
                .rev()
                .map(|f| f.path().to_path_buf())
                .find(|p| !p.as_os_str().is_empty())
        });
        if let Some(path) = dropped {
            if extension(&path) == "toml" {
                self.scene_path = path.display().to_string();
            } else {
                self.trial_path = path.display().to_string();
            }
            self.open_path(&path);
        }
        self.follow_sweep();
        self.follow_follow_run();
        self.source_bar(ui);
        let mut source = std::mem::replace(&mut self.source, Source::Idle);
        let deferred = match &mut source {
            Source::Live(client) => {
                let state = client.lock();
                let data = DataRef {
                    history: &state.history,
                    rig: state.rig.as_ref(),
                    sweep: None,
                    follow: None,
                    estimates: Some(&state.estimates),
                    stage_range_m: state.rig.as_ref().and_then(|r| r.stage_range_m),
                    mount_angle_rad: state.rig.as_ref().map_or(0.0, |r| r.base_mount_angle_rad),
                    addresses: &state.segment_addresses,
                    counters: state.status.as_ref().map(|s| s.segments.as_slice()),
                    trial: state.status.as_ref().and_then(|s| s.trial.clone()),
                    note: state.status.as_ref().and_then(|s| s.note.clone()),
                    replies: &state.replies,
                    connected: matches!(state.connection, ConnectionState::Connected { .. }),
                    live: true,
                };
                self.draw(ui, &data)
            }
            Source::Trial(trial) => {
                let note = trial
                    .log
                    .iter()
                    .rev()
                    .find(|l| {
                        self.view
                            .cursor_s(trial.history.latest_t_s())
                            .is_some_and(|c| l.t_s <= c)
                    })
                    .map(|l| format!("{:.2} s: {}", l.t_s, l.text));
                let data = DataRef {
                    history: &trial.history,
                    rig: Some(&trial.rig),
                    sweep: None,
                    follow: None,
                    // A recording from before the estimates has no panel for them.
                    estimates: (!trial.estimates.is_empty()).then_some(&trial.estimates),
                    stage_range_m: trial.rig.stage_range_m,
                    mount_angle_rad: trial.rig.base_mount_angle_rad,
                    addresses: &trial.segment_addresses,
                    counters: None,
                    trial: Some(trial.name.clone()),
                    note,
                    replies: &[],
                    connected: false,
                    live: false,
                };
                self.draw(ui, &data)
            }
            Source::Sweep(worker) => {
                let state = worker.lock();
                if !state.is_finished() {
                    // Steps arrive between locks: the chain drawn is the newest of this lock.
                    keep_run_in_view(
                        &mut self.view,
                        &mut self.sweep_view,
                        &state.history,
                        state.planned_end_s(),
                    );
                }
                let data = DataRef {
                    history: &state.history,
                    rig: None,
                    sweep: Some(&state),
                    follow: None,
                    estimates: None,
                    stage_range_m: state.track_m,
                    mount_angle_rad: state.chain.base_angle_rad(),
                    addresses: &[],
                    counters: None,
                    trial: Some(format!("sweep-{}", state.name)),
                    note: state
                        .placement_note
                        .as_ref()
                        .map(|n| format!("placement: {n}")),
                    replies: &[],
                    connected: false,
                    live: false,
                };
                let deferred = self.draw(ui, &data);
                if !state.is_finished() {
                    // The progress and the newest step, as they come.
                    ui.ctx().request_repaint_after(Duration::from_millis(30));
                } else if !self.sweep_reported {
                    // It ended during this frame: the next one says how.
                    ui.ctx().request_repaint();
                }
                deferred
            }
            Source::Follow(worker) => {
                let state = worker.lock();
                if !state.is_finished() {
                    keep_run_in_view(
                        &mut self.view,
                        &mut self.sweep_view,
                        &state.history,
                        state.planned_end_s(),
                    );
                }
                let data = DataRef {
                    history: &state.history,
                    rig: None,
                    sweep: None,
                    follow: Some(&state),
                    estimates: None,
                    stage_range_m: None,
                    mount_angle_rad: 0.0,
                    addresses: &[],
                    counters: None,
                    trial: Some(format!("follow-{}", state.name)),
                    note: None,
                    replies: &[],
                    connected: false,
                    live: false,
                };
                let deferred = self.draw(ui, &data);
                if !state.is_finished() {
                    ui.ctx().request_repaint_after(Duration::from_millis(30));
                } else if !self.sweep_reported {
                    ui.ctx().request_repaint();
                }
                deferred
            }
            Source::Idle => {
                egui::CentralPanel::default().show(ui, |ui| {
                    ui.label(
                        "Connect to antennad, open a recorded trial (.mcap) or a follow run \
                         (.jsonl of antenna follow), or run a scene file (.toml: a sweep or a \
                         follow scene) above, or drop one of these files here.",
                    );
                });
                Deferred::default()
            }
        };
        if let Source::Live(client) = &mut source {
            if let Some(s) = deferred.history_s {
                self.history_s = s;
                client.set_history_s(s);
            }
            // With the token given at start, each new connection proves it at once, so that
            // antennad keeps it (an operator's) when readers fill its slots.
            let token = &self.panels.controls.token;
            let connection = {
                let state = client.lock();
                matches!(state.connection, ConnectionState::Connected { .. })
                    .then_some(state.connections)
            };
            if let Some(connection) = connection
                && !token.is_empty()
                && *token == self.startup_token
                && self.authenticated != Some(connection)
                && client.send(&Command::Auth, token).is_ok()
            {
                self.authenticated = Some(connection);
            }
            for command in &deferred.commands {
                match client.send(command, &self.panels.controls.token) {
                    Ok(_) => self.refusal = None,
                    Err(e) => self.refusal = Some(e.to_string()),
                }
            }
            if self.view.is_following() {
                ui.ctx().request_repaint_after(Duration::from_millis(16));
            } else {
                ui.ctx().request_repaint_after(Duration::from_millis(100));
            }
        }
        self.source = source;
    }

    fn source_bar(&mut self, ui: &mut egui::Ui) {
        egui::Panel::top("source_bar")
            .frame(unfilled(egui::Frame::side_top_panel(ui.style())))
            .show(ui, |ui| {
                // Wrapped: the source's state (a sweep's progress, a connection's) is never cut
                // off in a narrow window.
                ui.horizontal_wrapped(|ui| {
                    let label = ui.label("antennad");
                    ui.add(egui::TextEdit::singleline(&mut self.address).desired_width(140.0))
                        .labelled_by(label.id);
                    if ui.button("Connect").clicked() {
                        let address = self.address.clone();
                        self.connect(address);
                    }
                    ui.separator();
                    let label = ui.label("trial .mcap");
                    ui.add(egui::TextEdit::singleline(&mut self.trial_path).desired_width(180.0))
                        .labelled_by(label.id);
                    if ui
                        .button("Open")
                        .on_hover_text("a recorded trial (.mcap) or a follow run (.jsonl)")
                        .clicked()
                    {
                        let path = PathBuf::from(self.trial_path.trim());
                        self.open(&path);
                    }
                    ui.separator();
                    let label = ui.label("scene .toml");
                    ui.add(egui::TextEdit::singleline(&mut self.scene_path).desired_width(180.0))
                        .labelled_by(label.id);
                    if ui
                        .button("Run sweep")
                        .on_hover_text("a sweep scene, or a follow scene's closed-loop run")
                        .clicked()
                    {
                        let path = PathBuf::from(self.scene_path.trim());
                        self.open_scene(&path);
                    }
                    ui.separator();
                    match &self.source {
                        Source::Live(client) => {
                            let state = client.lock();
                            let (text, colour) = match &state.connection {
                                ConnectionState::Connected { daemon } => (
                                    format!("connected to {daemon} at {}", client.address()),
                                    Color32::from_rgb(0, 150, 0),
                                ),
                                ConnectionState::Connecting { attempt } => (
                                    format!(
                                        "connecting to {} (attempt {attempt})",
                                        client.address()
                                    ),
                                    Color32::from_rgb(200, 140, 0),
                                ),
                                ConnectionState::Disconnected { error, retry_at } => (
                                    format!(
                                        "DISCONNECTED: {error}; reconnecting in {:.1} s",
                                        retry_at
                                            .saturating_duration_since(Instant::now())
                                            .as_secs_f64()
                                    ),
                                    Color32::RED,
                                ),
                            };
                            ui.label(RichText::new(text).color(colour).strong());
                            if state.lagged_dropped > 0 {
                                ui.label(format!(
                                    "{} messages dropped (lagged), {} of them polls",
                                    state.lagged_dropped, state.lagged_samples_dropped
                                ));
                            }
                            if let (n @ 1.., Some(kind)) = &state.unknown_lines {
                                ui.label(
                                    RichText::new(format!(
                                        "skipped {n} line(s) of message types not known \
                                         here (last: {kind}; from a newer daemon)"
                                    ))
                                    .weak(),
                                );
                            }
                            ui.label(format!(
                                "{} samples held, {} received",
                                state.history.len(),
                                state.history.total_pushed()
                            ));
                        }
                        Source::Trial(t) => {
                            ui.label(format!("trial {} ({})", t.name, t.path.display()));
                        }
                        Source::Sweep(worker) => {
                            let state = worker.lock();
                            let colour = match state.phase {
                                SweepPhase::Placing | SweepPhase::Stepping => {
                                    Color32::from_rgb(200, 140, 0)
                                }
                                SweepPhase::Done => Color32::from_rgb(0, 150, 0),
                                SweepPhase::Failed(_) => Color32::RED,
                            };
                            // Whole: on the next row rather than broken.
                            ui.add(
                                egui::Label::new(
                                    RichText::new(state.progress()).color(colour).strong(),
                                )
                                .wrap_mode(egui::TextWrapMode::Extend),
                            );
                            if state.relaxed_steps > 0 {
                                let here = self
                                    .view
                                    .cursor_s(state.history.latest_t_s())
                                    .map(|t| state.relaxations_at(t))
                                    .unwrap_or_default();
                                let mut text =
                                    format!("solver relaxed {} step(s)", state.relaxed_steps);
                                if !here.is_empty() {
                                    text.push_str(&format!("; this one: {}", here.join(", ")));
                                }
                                ui.label(RichText::new(text).color(Color32::from_rgb(220, 120, 0)));
                            }
                        }
                        Source::Follow(worker) => {
                            let state = worker.lock();
                            let colour = match &state.phase {
                                crate::follow::FollowPhase::Running => {
                                    Color32::from_rgb(200, 140, 0)
                                }
                                crate::follow::FollowPhase::Failed(_) => Color32::RED,
                                crate::follow::FollowPhase::Done
                                    if state.summary.as_ref().is_some_and(|s| s.status != "ok") =>
                                {
                                    Color32::from_rgb(220, 120, 0)
                                }
                                crate::follow::FollowPhase::Done => Color32::from_rgb(0, 150, 0),
                            };
                            ui.add(
                                egui::Label::new(
                                    RichText::new(state.progress()).color(colour).strong(),
                                )
                                .wrap_mode(egui::TextWrapMode::Extend),
                            );
                        }
                        Source::Idle => {
                            ui.label("no source");
                        }
                    }
                });
                if let Some((message, error)) = &self.message {
                    let colour = if *error {
                        Color32::RED
                    } else {
                        ui.visuals().weak_text_color()
                    };
                    ui.label(RichText::new(message).color(colour).small());
                }
            });
    }

    fn draw(&mut self, ui: &mut egui::Ui, data: &DataRef<'_>) -> Deferred {
        let mut deferred = Deferred::default();
        let history = data.history;
        let latest = history.latest_t_s();
        let span = history.first_t_s().zip(latest);
        let ended_playing = self.advance_playback(ui.ctx(), latest);
        let cursor_index = self.view.cursor_s(latest).and_then(|c| history.index_at(c));
        let measured = match (data.sweep, data.rig, cursor_index) {
            _ if data.follow.is_some() => self
                .view
                .cursor_s(latest)
                .zip(data.follow)
                .and_then(|(c, follow)| follow.frame_at(c)),
            (Some(sweep), _, _) => self
                .view
                .cursor_s(latest)
                .and_then(|c| sweep.frame_at(c))
                .and_then(Result::ok),
            (None, Some(rig), Some(i)) => rig.frame_at(history, i).ok(),
            _ => None,
        };
        let measured = match (measured, data.estimates, data.rig) {
            (Some(mut frame), Some(estimates), Some(rig)) => {
                attach_estimate(&mut frame, estimates, rig, history);
                Some(frame)
            }
            (measured, ..) => measured,
        };
        let (predicted, prediction_note) = match (data.rig, &measured) {
            (Some(rig), Some(m)) => self.predicted(rig, m),
            _ => (None, None),
        };
        let model = self
            .prediction
            .as_ref()
            .and_then(|p| p.worker.as_ref().ok())
            .map_or("", PredictionWorker::name);
        // A sweep's wall map up to the step drawn, recomputed only when that step changes.
        let map_step = data
            .sweep
            .filter(|_| self.panels.chain.show_map)
            .zip(self.view.cursor_s(latest))
            .and_then(|(sweep, c)| sweep.step_index_at(c).map(|k| (sweep, k)));
        if let Some((sweep, k)) = map_step {
            let settings = CoverageSettings::default();
            let pending = self
                .coverage
                .refresh(self.sweeps_opened, k, Instant::now(), || {
                    sweep.mapping.coverage(&sweep.walls, k, &settings)
                });
            if pending {
                ui.ctx().request_repaint_after(CoverageCache::MIN_INTERVAL);
            }
        }

        let playing = self.playing.is_some();
        let actions = egui::Panel::top("timeline_bar")
            .frame(unfilled(egui::Frame::side_top_panel(ui.style())))
            .show(ui, |ui| {
                self.panels
                    .timeline
                    .ui(ui, &self.view, span, data.live, playing)
            })
            .inner;
        let max_window_s = if data.live {
            self.history_s
        } else {
            span.map_or(1.0, |(a, b)| (b - a).max(0.01))
        };
        for action in actions {
            match action {
                TimelineAction::Pause => self.view.pause(latest),
                TimelineAction::Follow => self.view.follow_latest(),
                TimelineAction::Zoom(f) => self.view.zoom(f, max_window_s),
                TimelineAction::SetHistory(s) => deferred.history_s = Some(s),
                TimelineAction::Scrub(t) => self.view.scrub(t, latest),
                // Playback reached the end in this very frame, so the button under the
                // click was drawn as "Stop playing" in the frame the user saw: the click
                // means stop (it stays stopped at the end), not play again from the start.
                TimelineAction::Play if ended_playing => {}
                TimelineAction::Play => {
                    // From the start again if the cursor is at the end.
                    if let (Some((first, last)), Some(c)) = (span, self.view.cursor_s(latest))
                        && c >= last
                    {
                        self.view.scrub(first, latest);
                    }
                    self.playing = Some(Instant::now());
                }
                TimelineAction::StopPlaying => self.playing = None,
                TimelineAction::ExportCsv
                | TimelineAction::ExportPng
                | TimelineAction::ExportSvg => {
                    let result = self.export(action, data, measured.as_ref(), predicted.as_ref());
                    self.message = Some(match result {
                        Ok(r) => (
                            format!(
                                "exported {:.3} s to {:.3} s to {}{}",
                                r.t0_s,
                                r.t1_s,
                                r.path.display(),
                                r.rows.map_or_else(String::new, |n| format!(" ({n} rows)"))
                            ),
                            false,
                        ),
                        Err(e) => (e.to_string(), true),
                    });
                }
            }
        }

        egui::Panel::left("side_panel")
            .frame(unfilled(egui::Frame::side_top_panel(ui.style())))
            .resizable(true)
            .default_size(340.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    if data.live {
                        ui.heading("Controls");
                        deferred.commands = self.panels.controls.ui(
                            ui,
                            data.connected,
                            data.replies,
                            self.refusal.as_deref(),
                        );
                        ui.separator();
                    }
                    let sample = cursor_index.and_then(|i| history.sample(i));
                    if let Some(follow) = data.follow {
                        ui.heading("Follow run");
                        self.panels
                            .follow_info
                            .ui(ui, follow, self.view.cursor_s(latest));
                        ui.separator();
                    } else {
                        ui.heading("Stage and servo");
                        let info = StageInfo {
                            stage_position_m: sample.as_ref().and_then(|s| s.stage_position_m),
                            stage_range_m: data.stage_range_m,
                            servo_angle_deg: sample
                                .as_ref()
                                .and_then(|s| s.servo_angle_rad)
                                .map(f64::to_degrees),
                            mount_angle_deg: data.mount_angle_rad.to_degrees(),
                            trial: data.trial.clone(),
                            note: data.note.clone(),
                        };
                        self.panels.stage.ui(ui, &info);
                        ui.separator();
                    }
                    ui.heading("Segment health");
                    let now: Vec<Health> = sample
                        .as_ref()
                        .map(|s| s.segments.iter().map(|r| r.health).collect())
                        .unwrap_or_default();
                    self.panels
                        .health
                        .ui(ui, data.addresses, &now, data.counters);
                    if let Some(rig) = data.rig {
                        ui.separator();
                        ui.label(RichText::new(format!("geometry: {}", rig.source)).small());
                    }
                    if let Some(sweep) = data.sweep {
                        ui.separator();
                        ui.label(
                            RichText::new(format!(
                                "geometry: the scene {} (simulated: no prediction)",
                                sweep.path.display()
                            ))
                            .small(),
                        );
                    }
                });
            });

        let map = data.sweep.map(|sweep| {
            let shown = self
                .coverage
                .key()
                .filter(|(opened, _)| *opened == self.sweeps_opened && map_step.is_some());
            WallMap {
                coverage: shown.and_then(|_| {
                    self.coverage
                        .coverage()
                        .map(|c| c.as_ref().map_err(String::as_str))
                }),
                points_m: shown.map_or(&[], |(_, k)| sweep.mapping.points_m(k)),
                settings: CoverageSettings::default(),
                walls: &sweep.walls,
            }
        });
        egui::CentralPanel::default()
            .frame(unfilled(egui::Frame::central_panel(ui.style())))
            .show(ui, |ui| {
                let width = ui.available_width();
                let height = ui.available_height();
                let (chain_share, angles_share) = if data.follow.is_some() {
                    (0.45, 0.18)
                } else if data.estimates.is_some() {
                    (0.45, 0.2)
                } else {
                    (0.5, 0.3)
                };
                ui.allocate_ui(egui::vec2(width, height * chain_share), |ui| {
                    self.panels.chain.ui(
                        ui,
                        measured.as_ref(),
                        predicted.as_ref(),
                        model,
                        prediction_note.as_deref(),
                        map.as_ref(),
                    );
                });
                if let Some(follow) = data.follow {
                    ui.allocate_ui(egui::vec2(width, height * 0.22), |ui| {
                        self.panels.follow_error.ui(ui, follow, &mut self.view);
                    });
                }
                if let Some(estimates) = data.estimates {
                    ui.allocate_ui(egui::vec2(width, height * 0.17), |ui| {
                        self.panels
                            .estimate
                            .ui(ui, estimates, &mut self.view, latest);
                    });
                }
                ui.allocate_ui(egui::vec2(width, height * angles_share), |ui| {
                    self.panels
                        .angles
                        .ui(ui, history, &mut self.view, max_window_s);
                });
                let window = self.view.window(latest);
                let cursor = self.view.cursor_s(latest);
                self.panels.raster.ui(ui, history, window, cursor);
            });
        deferred
    }

    /// Keeps a sweep that is being solved in view as a whole, with the chain at its newest
    /// step, while the user has not moved the view; at its end, reports how it ended and
    /// (the view still untouched) shows it from its start, or at its last step if it stopped
    /// early.
    fn follow_sweep(&mut self) {
        let Source::Sweep(worker) = &self.source else {
            return;
        };
        let state = worker.lock();
        if !state.is_finished() {
            keep_run_in_view(
                &mut self.view,
                &mut self.sweep_view,
                &state.history,
                state.planned_end_s(),
            );
            return;
        }
        if self.sweep_reported {
            return;
        }
        self.sweep_reported = true;
        self.message = Some(match state.error() {
            Some(e) => (e.to_string(), true),
            None => {
                let mut text = format!(
                    "ran {}: {} frames",
                    state.path.display(),
                    state.frame_count()
                );
                if let Some(note) = &state.placement_note {
                    text.push_str(&format!("; placement: {note}"));
                }
                (text, false)
            }
        });
        show_finished_run(
            &mut self.view,
            &mut self.sweep_view,
            &state.history,
            state.error().is_some(),
        );
    }

    /// As [`Self::follow_sweep`] for a follow scene's closed-loop run: kept in view as a
    /// whole while it runs and the user has not moved the view; at its end, reports how it
    /// ended (its status and RMS error, or the error that stopped it) and shows it from its
    /// start.
    fn follow_follow_run(&mut self) {
        let Source::Follow(worker) = &self.source else {
            return;
        };
        let state = worker.lock();
        if !state.is_finished() {
            keep_run_in_view(
                &mut self.view,
                &mut self.sweep_view,
                &state.history,
                state.planned_end_s(),
            );
            return;
        }
        if self.sweep_reported {
            return;
        }
        self.sweep_reported = true;
        self.message = Some(match (state.error(), &state.summary) {
            (Some(e), _) => (e.to_string(), true),
            (None, summary) => {
                let mut text = format!("ran {}: {} steps", state.path.display(), state.steps.len());
                if let Some(s) = summary {
                    text.push_str(&format!(", status {}", s.status));
                    if let Some(rms) = s.rms_error_m {
                        text.push_str(&format!(", rms error {:.1} mm", rms * 1e3));
                    }
                }
                if !state.start.note.is_empty() {
                    text.push_str(&format!("; placement: {}", state.start.note));
                }
                (text, false)
            }
        });
        show_finished_run(
            &mut self.view,
            &mut self.sweep_view,
            &state.history,
            state.error().is_some(),
        );
    }

    /// Moves the cursor of a playing recording on by the time since the last frame times
    /// the speed; stops at the end. Returns whether it stopped at the end in this call.
    fn advance_playback(&mut self, ctx: &egui::Context, latest: Option<f64>) -> bool {
        let (Some(since), Some(last)) = (self.playing, latest) else {
            return false;
        };
        let now = Instant::now();
        let t = self.view.cursor_s(latest).unwrap_or(last)
            + (now - since).as_secs_f64() * self.panels.timeline.speed;
        self.view.scrub(t.min(last), latest);
        self.playing = (t < last).then_some(now);
        ctx.request_repaint_after(Duration::from_millis(16));
        self.playing.is_none()
    }

    fn export(
        &mut self,
        action: TimelineAction,
        data: &DataRef<'_>,
        measured: Option<&ChainFrame>,
        predicted: Option<&ChainFrame>,
    ) -> Result<ExportRecord, MonitorError> {
        let (t0_s, t1_s) =
            self.view
                .window(data.history.latest_t_s())
                .ok_or(MonitorError::NothingToExport {
                    t0_s: 0.0,
                    t1_s: 0.0,
                })?;
        let kind = if data.live {
            "live".to_owned()
        } else {
            data.trial.clone().unwrap_or_else(|| "trial".to_owned())
        };
        let stem = format!("antenna-{kind}-{t0_s:.3}-{t1_s:.3}");
        let (path, rows) = match action {
            TimelineAction::ExportCsv => {
                let path = self.export_dir.join(format!("{stem}.csv"));
                let rows = export_csv(data.history, t0_s, t1_s, &path)?;
                (path, Some(rows))
            }
            _ => {
                let extension = if action == TimelineAction::ExportSvg {
                    "svg"
                } else {
                    "png"
                };
                let path = self.export_dir.join(format!("{stem}.{extension}"));
                let joints = self.panels.angles.joints(data.history.segment_count());
                // The estimated wall only while the chain panel shows it.
                let without_estimate =
                    measured
                        .filter(|_| !self.panels.chain.show_estimate)
                        .map(|m| ChainFrame {
                            estimated_wall: None,
                            ..m.clone()
                        });
                let input = FigureInput {
                    history: data.history,
                    t0_s,
                    t1_s,
                    joints: &joints,
                    measured: without_estimate.as_ref().or(measured),
                    predicted: predicted.filter(|_| self.panels.chain.show_prediction),
                };
                export_figure(&input, &path)?;
                (path, None)
            }
        };
        let record = ExportRecord {
            path,
            rows,
            t0_s,
            t1_s,
        };
        self.exports.push(record.clone());
        Ok(record)
    }
}

/// Puts on `frame` (live or recorded, drawn with `rig` from `history`) the newest of `estimates` made
/// at or before its instant, if it is still current ([`EstimateHistory::current_at`]): the
/// estimated wall in the track frame, from the base pivot where the stage was at the
/// estimate's poll, along the stage's travel, toward the wall's side
/// ([`RigGeometry::wall_side`]), spanning the chain; or why there is none.
pub fn attach_estimate(
    frame: &mut ChainFrame,
    estimates: &EstimateHistory,
    rig: &RigGeometry,
    history: &History,
) {
    let estimate = match estimates.current_at(frame.t_s) {
        Ok(Some(estimate)) => estimate,
        Ok(None) if estimates.received() == 0 => {
            frame.estimate_note = Some("the daemon sends none".to_owned());
            return;
        }
        Ok(None) => {
            frame.estimate_note = Some("none yet at this instant".to_owned());
            return;
        }
        Err(age_s) => {
            frame.estimate_note = Some(format!("the newest was made {age_s:.1} s before"));
            return;
        }
    };
    let stage_position_m = history
        .index_at(estimate.t_s)
        .and_then(|i| history.sample(i))
        .filter(|s| s.seq == Some(estimate.seq))
        .map_or(frame.stage_position_m, |s| s.stage_position_m);
    let base_m = rig.base_m(stage_position_m);
    let direction = rig.travel_direction();
    // The chain's extent along the travel, from the base pivot, with a margin.
    let (lo, hi) = frame
        .joints_m
        .iter()
        .map(|p| (p[0] - base_m[0]) * direction[0] + (p[1] - base_m[1]) * direction[1])
        .fold((0.0_f64, 0.0_f64), |(lo, hi), x| (lo.min(x), hi.max(x)));
    let margin_m = 0.25 * (hi - lo).max(0.04);
    frame.estimated_wall = estimate.wall_in_track_m(
        base_m,
        direction,
        rig.wall_side(),
        (lo - margin_m, hi + margin_m),
    );
    if frame.estimated_wall.is_none() {
        frame.estimate_note = Some(format!(
            "{} ({})",
            estimate.reason.as_deref().unwrap_or("no reason given"),
            estimate.estimator
        ));
    }
}

/// A simulated run (a sweep or a follow run) has ended: while the user has not moved `view`
/// since the app last set it (`sweep_view`), the whole run in view, the cursor at its start,
/// or at its last step if it `stopped` early; the app lets go of the view.
fn show_finished_run(
    view: &mut ViewState,
    sweep_view: &mut Option<ViewState>,
    history: &History,
    stopped: bool,
) {
    let untouched = sweep_view.as_ref() == Some(&*view);
    if let (true, Some((first, latest))) =
        (untouched, history.first_t_s().zip(history.latest_t_s()))
    {
        view.show_range(first, latest, if stopped { latest } else { first });
    }
    *sweep_view = None;
}

/// While the user has not moved `view` since the app last set it (`sweep_view`): the whole
/// simulated run (a sweep or a follow run) planned in view (`planned_end_s` after its start),
/// the chain at the newest step of its `history`.
fn keep_run_in_view(
    view: &mut ViewState,
    sweep_view: &mut Option<ViewState>,
    history: &History,
    planned_end_s: f64,
) {
    let span = history.first_t_s().zip(history.latest_t_s());
    if let (true, Some((first, latest))) = (sweep_view.as_ref() == Some(view), span) {
        let end = (first + planned_end_s).max(latest);
        view.show_range(first, end, latest);
        *sweep_view = Some(view.clone());
    }
}

/// `path`'s extension, lower case (empty without one).
fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// Whether eframe's OpenGL context is a software rasterizer (Mesa's llvmpipe or softpipe,
/// or another that says so in its renderer string).
pub fn is_software_gl(gl: &eframe::glow::Context) -> bool {
    use eframe::glow::HasContext as _;
    // SAFETY: glGetString(GL_RENDERER) on the context eframe made current on this thread for
    // the app's creation; it reads a static string and changes no state.
    let renderer = unsafe { gl.get_parameter_string(eframe::glow::RENDERER) }.to_ascii_lowercase();
    ["llvmpipe", "softpipe", "swrast", "software"]
        .iter()
        .any(|name| renderer.contains(name))
}

/// Settings for a software rasterizer: no anti-aliasing feathering. Feathering surrounds every
/// shape with a thin band of blended triangles; under llvmpipe it more than doubles the frame
/// time (BENCHMARKS.md, "Monitor"), so edges are drawn hard instead.
pub fn tune_for_software_gl(ctx: &egui::Context) {
    ctx.tessellation_options_mut(|o| o.feathering = false);
}

/// A panel frame without its fill: the window is cleared to the panel colour
/// ([`eframe::App::clear_color`]), so painting every panel's background again would only
/// cost time (under software rendering, each full-window layer costs milliseconds).
fn unfilled(frame: egui::Frame) -> egui::Frame {
    frame.fill(Color32::TRANSPARENT)
}

impl eframe::App for MonitorApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        MonitorApp::ui(self, ui);
    }

    fn clear_color(&self, visuals: &egui::Visuals) -> [f32; 4] {
        visuals.panel_fill.to_normalized_gamma_f32()
    }
}
