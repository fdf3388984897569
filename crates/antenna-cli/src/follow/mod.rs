//! `antenna follow`: a follow scene's closed-loop run (sim-core's [`Follow`]) with the JSON
//! lines of antenna-scene's [`follow_lines`](antenna_scene::follow_lines), a summary and a plot
//! ([`plot`]). [`FollowRun::start`] turns a scene into a run; [`run_summary`] runs one to its
//! end for the studies and the optimizer.
//!
//! ```
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use antenna_cli::follow::FollowRun;
//! use antenna_scene::Scene;
//!
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/follow/straight_wall.toml");
//! let mut scene = Scene::from_path(std::path::Path::new(path))?;
//! scene.follow.as_mut().expect("a follow scene").config.settings.duration_s = 0.2;
//! let mut run = FollowRun::start(&scene)?;
//! let mut lines = 0;
//! while let Some(Ok(_line)) = run.next_line() {
//!     lines += 1;
//! }
//! assert_eq!(lines, 20);
//! assert!(run.failure().is_none());
//! assert_eq!(run.summary_line().status, "ok");
//! # Ok(())
//! # }
//! ```

pub mod plot;
pub mod v_max;

use std::time::Instant;

use antenna_scene::follow_lines::{
    FollowStart, FollowStepLine, FollowSummaryLine, step_line, summary_line,
};
use antenna_scene::{Scene, SceneError};
use sim_core::Wall;
use sim_core::follow::{
    BodyModel, Follow, FollowConfig, FollowError, FollowStatus, FollowStep, FollowSummary,
};

/// Why a follow run could not start or ended in the solver: bad input (exit 2) or the
/// solver's outcome (exit 1 for no convergence or a jam, 3 for a step that failed its
/// check).
#[derive(Debug, thiserror::Error)]
pub enum FollowFailure {
    /// The scene or the start is not usable: located where it can be.
    #[error("{0}")]
    BadInput(String),
    /// The antenna's solver ended the run (the lines so far and the summary are written).
    #[error("{message}")]
    Solver {
        /// The status's name.
        status: &'static str,
        /// In words, with the time.
        message: String,
    },
}

impl FollowFailure {
    /// The exit status: 2 bad input; 1 no convergence or a jam; 3 a step that failed its
    /// check.
    pub fn exit_status(&self) -> u8 {
        match self {
            FollowFailure::BadInput(_) => 2,
            FollowFailure::Solver { status, .. } if *status == "uncertified" => 3,
            FollowFailure::Solver { .. } => 1,
        }
    }
}

impl From<SceneError> for FollowFailure {
    fn from(e: SceneError) -> Self {
        FollowFailure::BadInput(e.to_string())
    }
}

/// A follow scene's run in progress.
pub struct FollowRun {
    label: String,
    scene_toml: String,
    walls: Vec<Wall>,
    link_lengths_m: Vec<f64>,
    follow: Follow,
    failure: Option<FollowFailure>,
    started: Instant,
}

impl FollowRun {
    /// The run of `scene` (a scene with `[robot]`, `[controller]`, `[follow]`): the antenna
    /// placed, the bend estimator calibrated if it is the one.
    ///
    /// # Errors
    /// [`FollowFailure::BadInput`] located in the scene file (a footprint in a wall at the
    /// start: at `[follow] pose_m`), or a placement that fails.
    pub fn start(scene: &Scene) -> Result<FollowRun, FollowFailure> {
        let started = Instant::now();
        let (sweep_scene, config, sensors) = scene.follow_parts()?;
        let follow =
            Follow::new(&sweep_scene, &sensors, &config).map_err(|e| match &scene.follow {
                Some(f) => FollowFailure::BadInput(f.locate(&e).to_string()),
                None => FollowFailure::BadInput(format!("{}: {e}", scene.locations.path)),
            })?;
        Ok(FollowRun {
            label: scene.locations.path.clone(),
            scene_toml: std::fs::read_to_string(&scene.locations.path).unwrap_or_default(),
            walls: scene.walls.clone(),
            link_lengths_m: scene.chain.link_lengths_m().to_vec(),
            follow,
            failure: None,
            started,
        })
    }

    /// The walls (the scene's frame).
    pub fn walls(&self) -> &[Wall] {
        &self.walls
    }

    /// The run's description.
    pub fn config(&self) -> &FollowConfig {
        self.follow.config()
    }

    /// The steps the run has at most.
    pub fn steps(&self) -> usize {
        self.follow.steps()
    }

    /// The `start` line.
    pub fn start_line(&self) -> FollowStart {
        let c = self.follow.config();
        FollowStart {
            scene: self.label.clone(),
            scene_toml: self.scene_toml.clone(),
            note: self.follow.placement_note().to_string(),
            estimator: c.controller.estimator.name().to_string(),
            body: body_name(&c.robot.body).to_string(),
            wall_side: c.robot.wall_side.name().to_string(),
            speed_m_per_s: c.robot.speed_m_per_s,
            setpoint_m: c.controller.setpoint_m,
            steps: self.follow.steps(),
            step_s: c.settings.step_s,
            delay_steps: c.delay_steps(),
            footprint_m: c.robot.footprint_m,
            links: self.link_lengths_m.len(),
            link_lengths_m: self.link_lengths_m.clone(),
        }
    }

    /// The next step (sim-core's record); `None` at the end. A solver's refusal is
    /// returned once, then the run is over.
    pub fn next_step(&mut self) -> Option<Result<FollowStep, &FollowFailure>> {
        match self.follow.next_step()? {
            Ok(step) => Some(Ok(step)),
            Err(e) => {
                let status = self.follow.summary().status;
                self.failure = Some(match status {
                    FollowStatus::Solver { kind, .. } => FollowFailure::Solver {
                        status: kind,
                        message: format!("{}: {e}", self.label),
                    },
                    _ => FollowFailure::Solver {
                        status: "no-convergence",
                        message: format!("{}: {e}", self.label),
                    },
                });
                self.failure.as_ref().map(Err)
            }
        }
    }

    /// The next step as its JSON line.
    pub fn next_line(&mut self) -> Option<Result<FollowStepLine, &FollowFailure>> {
        let setpoint_m = self.follow.config().controller.setpoint_m;
        Some(match self.next_step()? {
            Ok(step) => Ok(step_line(&step, setpoint_m)),
            Err(e) => Err(e),
        })
    }

    /// The summary so far.
    pub fn summary(&self) -> FollowSummary {
        self.follow.summary()
    }

    /// The `summary` line.
    pub fn summary_line(&self) -> FollowSummaryLine {
        summary_line(&self.follow.summary(), self.started.elapsed().as_secs_f64())
    }

    /// The solver's refusal that ended the run, if one did.
    pub fn failure(&self) -> Option<&FollowFailure> {
        self.failure.as_ref()
    }
}

/// The body's name in the scene.
pub fn body_name(body: &BodyModel) -> &'static str {
    match body {
        BodyModel::Template { .. } => "template",
        BodyModel::Wheeled { .. } => "wheeled",
    }
}

/// The summary as a table for people.
pub fn human(summary: &FollowSummaryLine) -> String {
    let mm = |v: Option<f64>| v.map_or_else(|| "-".to_string(), |v| format!("{:.1} mm", v * 1e3));
    let m = |v: Option<f64>| v.map_or_else(|| "-".to_string(), |v| format!("{v:.3} m"));
    let mut out = String::new();
    let mut row = |k: &str, v: String| out.push_str(&format!("  {k:<22} {v}\n"));
    row("status", summary.status.clone());
    if let Some(d) = &summary.detail {
        row("detail", d.clone());
    }
    row(
        "steps",
        format!("{} ({:.2} s simulated)", summary.steps, summary.duration_s),
    );
    row("travel", format!("{:.3} m", summary.travel_m));
    row("rms error", mm(summary.rms_error_m));
    row("max error", mm(summary.max_error_m));
    row("settling distance", m(summary.settling_distance_m));
    row("collisions", summary.collisions.to_string());
    row(
        "first collision",
        summary
            .first_collision_s
            .map_or_else(|| "-".to_string(), |t| format!("{t:.3} s")),
    );
    row(
        "contact share",
        format!("{:.1} %", 100.0 * summary.contact_share),
    );
    row(
        "estimate share",
        format!("{:.1} %", 100.0 * summary.estimate_share),
    );
    row("estimate rms error", mm(summary.estimate_rms_error_m));
    row("wall time", format!("{:.2} s", summary.wall_time_s));
    out
}

/// Runs a follow scene's parts to the end and returns its summary (the studies' and the
/// optimizer's evaluation); a run the solver ended has that status.
///
/// # Errors
/// [`FollowError`] when the run cannot start.
pub fn run_summary(
    sweep_scene: &sim_core::sweep::SweepScene,
    sensors: &sim_core::SensorSettings,
    config: &FollowConfig,
) -> Result<FollowSummary, FollowError> {
    let mut follow = Follow::new(sweep_scene, sensors, config)?;
    while let Some(step) = follow.next_step() {
        if step.is_err() {
            break;
        }
    }
    Ok(follow.summary())
}
