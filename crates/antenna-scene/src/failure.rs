//! Why a sweep (or the solve of a scene with walls, which is a sweep's placement) stopped,
//! sorted by the exit status the `antenna` command gives it, with the file, the key and the
//! step in the message.

use sim_core::EquilibriumError;
use sim_core::contact::ContactError;
use sim_core::sweep::SweepError;

use crate::Scene;
use crate::error::SceneError;

/// A sweep that could not start or go on. Each variant's message names the scene file and,
/// where it can, the key (`placement` in `[start]`) or the step and its time.
#[derive(Debug, thiserror::Error)]
pub enum SweepFailure {
    /// Bad input (exit status 2): the scene cannot be swept as written, e.g. a start posture
    /// inside a wall, a placement on a wall the tip cannot reach, a pinned tip.
    #[error("{0}")]
    BadInput(String),
    /// A step found no equilibrium (exit status 1): the message names the step and its time.
    #[error("{0}")]
    NoConvergence(String),
    /// The antenna jammed against a wall (exit status 1: an answer that is not a success):
    /// a physical outcome, not a failure of the solver. The message names the step, the
    /// contacts that pin the antenna and the joints on their stops.
    #[error("{0}")]
    Jammed(String),
    /// The solver broke down numerically (exit status 3).
    #[error("{0}")]
    Breakdown(String),
}

impl From<SceneError> for SweepFailure {
    fn from(e: SceneError) -> Self {
        SweepFailure::BadInput(e.to_string())
    }
}

impl SweepFailure {
    /// Sorts a sim-core sweep error for `scene` and words it with the scene's file and keys.
    pub fn from_sweep_error(scene: &Scene, e: SweepError) -> SweepFailure {
        let path = &scene.locations.path;
        let at_start = match scene.locations.start_placement {
            Some(l) => format!("{path}:{l}: `placement` in [start]"),
            None => format!("{path}: the start (no [start] table: placement \"rest\")"),
        };
        match e {
            SweepError::BadMotion { .. } => SweepFailure::BadInput(format!("{path}: [sweep]: {e}")),
            SweepError::Placement(why) => {
                SweepFailure::BadInput(format!("{at_start}: placement: {why}"))
            }
            SweepError::PlacementSolve(inner @ EquilibriumError::NumericalBreakdown { .. }) => {
                SweepFailure::Breakdown(format!(
                    "{at_start}: the pinned equilibrium of the placement broke down: {inner}"
                ))
            }
            SweepError::PlacementSolve(inner) => SweepFailure::BadInput(format!(
                "{at_start}: the pinned equilibrium of the placement failed: {inner}"
            )),
            SweepError::Step {
                step: 0, source, ..
            } => placement_step(&at_start, source),
            SweepError::Step {
                step,
                t_s,
                source: ContactError::Jammed(jam),
            } => SweepFailure::Jammed(format!("{path}: step {step} (t = {t_s:.4} s): {jam}")),
            SweepError::Step {
                step,
                t_s,
                source: source @ ContactError::Uncertified { .. },
            } => SweepFailure::Breakdown(format!(
                "{path}: step {step} (t = {t_s:.4} s) is refused: {source}"
            )),
            SweepError::Step { step, t_s, source } => SweepFailure::NoConvergence(format!(
                "{path}: step {step} (t = {t_s:.4} s) failed: {source}"
            )),
            SweepError::Contact(source @ ContactError::BaseInsideWall { wall, .. }) => {
                let at_wall = match scene.locations.walls.get(wall).copied().flatten() {
                    Some(l) => format!("{path}:{l}: [[walls]] (wall {wall})"),
                    None => format!("{path}: [[walls]] (wall {wall})"),
                };
                SweepFailure::BadInput(format!("{at_wall}: {source}"))
            }
            SweepError::Contact(source) => placement_step(&at_start, source),
            SweepError::Mapping(inner) => SweepFailure::Breakdown(format!(
                "{path}: the touch bits of a step could not be derived: {inner}"
            )),
        }
    }

    /// The exit status the `antenna` command gives this failure.
    pub fn exit_status(&self) -> u8 {
        match self {
            SweepFailure::BadInput(_) => 2,
            SweepFailure::NoConvergence(_) | SweepFailure::Jammed(_) => 1,
            SweepFailure::Breakdown(_) => 3,
        }
    }
}

/// A failure while placing and settling the antenna (step 0).
fn placement_step(at_start: &str, source: ContactError) -> SweepFailure {
    match source {
        ContactError::NoConvergence { .. } => SweepFailure::NoConvergence(format!(
            "{at_start}: the placement (step 0, t = 0 s) found no equilibrium: {source}"
        )),
        ContactError::Jammed(jam) => SweepFailure::Jammed(format!(
            "{at_start}: the placement (step 0, t = 0 s): {jam}"
        )),
        source @ ContactError::Uncertified { .. } => SweepFailure::Breakdown(format!(
            "{at_start}: the placement (step 0, t = 0 s) is refused: {source}"
        )),
        other => SweepFailure::BadInput(format!("{at_start}: {other}")),
    }
}
