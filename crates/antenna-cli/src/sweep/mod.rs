//! `antenna sweep`: a scene's sweep run step by step ([`SweepRun`]), each step with the
//! CLI's own metrics ([`StepMetrics`]), summarized ([`SweepSummary`]), printed as JSON lines
//! ([`record`]) and drawn ([`plot`]). Failures carry their exit status ([`SweepFailure`], worded
//! by antenna-scene with the scene's file and keys).
//!
//! ```
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use antenna_scene::Scene;
//! use antenna_cli::sweep::SweepRun;
//!
//! let scene = Scene::parse(
//!     "[antenna]\nlinks = 3\nlink_length_m = 0.04\nbase_angle_deg = 60.0\n\
//!      [antenna.stiffness]\nvalues_n_m_per_rad = [0.02, 0.01]\n\
//!      [[walls]]\nshape = \"line\"\npoint_m = [0.0, 0.2]\nsolid = \"left\"\n\
//!      [sweep]\nduration_s = 0.05\n",
//!     "scene.toml",
//! )?;
//! let mut run = SweepRun::start(&scene)?;
//! let mut states = 0;
//! while let Some(state) = run.next_state() {
//!     state?;
//!     states += 1;
//! }
//! assert_eq!(states, 6); // the placement (step 0) and five steps
//! assert_eq!(run.summary().steps, 5);
//! # Ok(())
//! # }
//! ```

pub mod plot;
pub mod record;
mod step_metrics;
mod summary;

use std::time::Instant;

use sim_core::Wall;
use sim_core::sweep::{Sweep, SweepStep};
use sim_core::{Chain, Sensors};

pub use step_metrics::{SensorSample, StepMetrics};
pub use summary::{
    COMPLETE_WITHIN_MM, SensorsSummary, SweepStats, SweepSummary, coverage_settings,
};

use antenna_scene::{Scene, SweepFailure};

/// One recorded state of a sweep: sim-core's step and the CLI's metrics of it.
#[derive(Debug, Clone)]
pub struct SweepState {
    /// The step.
    pub step: SweepStep,
    /// What the CLI derives from it.
    pub metrics: StepMetrics,
}

/// A scene's sweep in progress: the placement (step 0) first, then every step.
#[derive(Debug)]
pub struct SweepRun {
    scene: Scene,
    chain: Chain,
    walls: Vec<Wall>,
    sweep: Sweep,
    /// The scene's `[sensors]` in use: one sample clock, noise stream and set of debouncers
    /// for the whole sweep.
    sensors: Sensors,
    placed_pending: bool,
    stats: SweepStats,
    started: Instant,
}

impl SweepRun {
    /// Places the antenna as the scene's `[start]` says and gets ready to sweep.
    ///
    /// # Errors
    /// [`SweepFailure`] when the scene cannot be swept (a pinned tip) or the placement
    /// fails, with the file, the key and why.
    pub fn start(scene: &Scene) -> Result<SweepRun, SweepFailure> {
        let started = Instant::now();
        let sweep_scene = scene.sweep_scene()?;
        let chain = sweep_scene.chain.clone();
        let walls = sweep_scene.walls.clone();
        let sensors = Sensors::new(&scene.sensors, chain.n()).map_err(|e| {
            SweepFailure::BadInput(format!("{}: [sensors]: {e}", scene.locations.path))
        })?;
        let sweep = sim_core::sweep::Sweep::new(sweep_scene)
            .map_err(|e| SweepFailure::from_sweep_error(scene, e))?;
        let stats = SweepStats::with_coverage(walls.clone(), sweep.motion().direction_rad());
        Ok(SweepRun {
            scene: scene.clone(),
            chain,
            walls,
            sweep,
            sensors,
            placed_pending: true,
            stats,
            started,
        })
    }

    /// What the placement did, in words.
    pub fn placement_note(&self) -> &str {
        self.sweep.placement_note()
    }

    /// The number of steps after the placement.
    pub fn steps(&self) -> usize {
        self.sweep.steps()
    }

    /// The simulation (for its state after the last step).
    pub fn sweep(&self) -> &Sweep {
        &self.sweep
    }

    /// The chain swept.
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// The walls.
    pub fn walls(&self) -> &[Wall] {
        &self.walls
    }

    /// The next state: the placement (step 0) first, then the steps; `None` when done.
    pub fn next_state(&mut self) -> Option<Result<SweepState, SweepFailure>> {
        let step = if self.placed_pending {
            self.placed_pending = false;
            Ok(self.sweep.placed()?.clone())
        } else {
            match self.sweep.next_step()? {
                Ok(step) => Ok(step),
                Err(e) => {
                    let failure = SweepFailure::from_sweep_error(&self.scene, e);
                    let outcome = match failure {
                        SweepFailure::Jammed(_) => "jammed",
                        _ => "failed",
                    };
                    self.stats.stop(outcome, failure.to_string());
                    Err(failure)
                }
            }
        };
        Some(step.map(|step| {
            let metrics = StepMetrics::sensed(&self.chain, &self.walls, &step, &mut self.sensors);
            self.stats.push(&step, &metrics);
            SweepState { step, metrics }
        }))
    }

    /// The sensors in use (their settings, the calibration drawn, the samples taken).
    pub fn sensors(&self) -> &Sensors {
        &self.sensors
    }

    /// The summary of the states so far, with the wall-clock time since [`Self::start`] and,
    /// when the scene's sensors are not ideal, their settings and samples.
    pub fn summary(&self) -> SweepSummary {
        let mut summary = self
            .stats
            .summary(self.started.elapsed().as_secs_f64() * 1e3);
        summary.sensors = SensorsSummary::of(&self.sensors);
        summary
    }
}
