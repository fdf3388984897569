//! A trial's script as the motion thread runs it: on the simulated rig the scene's `[start]`
//! placement once the stage is homed, then the stage moves one after another, each followed
//! by its pause, waiting (not failing) while the stage is being homed or has briefly
//! vanished; and how a script's end is told to whoever waits for it ([`ScriptEnds`]).

use crate::config::TrialConfig;
use crate::hardware::device::DeviceError;
use crate::hardware::homing::HomingState;
use crate::service::motion::Notes;
use crate::service::rig::{DaemonRig, RigError};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

/// How long a script with moves left waits for a vanished stage before its trial ends.
pub const STAGE_LOST_AFTER: Duration = Duration::from_secs(2);

/// A trial's script on the motion thread.
pub(crate) struct Script {
    /// The trial's number (the hub's).
    pub(crate) id: u64,
    pub(crate) trial: Box<TrialConfig>,
    next_move: usize,
    step: Step,
    /// Whether the simulated antenna has been placed (or there is none to place).
    placed: bool,
}

enum Step {
    Idle,
    Moving(usize),
    Pausing(Duration),
    Done,
}

/// Moves started and refused, over every script.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct MoveCounts {
    pub(crate) started: usize,
    pub(crate) refused: usize,
}

impl Script {
    pub(crate) fn new(id: u64, trial: Box<TrialConfig>) -> Self {
        Self {
            id,
            trial,
            next_move: 0,
            step: Step::Idle,
            placed: false,
        }
    }

    /// Whether every move has been made (or refused).
    pub(crate) fn is_done(&self) -> bool {
        matches!(self.step, Step::Done)
    }

    /// One step at `now`: starts the next move when the last one and its pause are over.
    /// `Err(why)`: the script cannot go on (the stage could not be homed) and its trial ends.
    pub(crate) fn step(
        &mut self,
        rig: &mut DaemonRig,
        now: Duration,
        notes: &mut Notes<'_>,
        counts: &mut MoveCounts,
    ) -> Result<(), String> {
        self.step = match std::mem::replace(&mut self.step, Step::Idle) {
            Step::Moving(j) => match rig.stage_moving(now) {
                Ok(true) => Step::Moving(j),
                Ok(false) => {
                    let pause = self.trial.moves.get(j).map_or(0.0, |m| m.pause_s);
                    Step::Pausing(now + Duration::from_secs_f64(pause))
                }
                Err(RigError::Device(DeviceError::Unavailable { .. })) => Step::Moving(j),
                Err(e) => {
                    notes.send(now, format!("stage failed: {e}"));
                    Step::Moving(j)
                }
            },
            Step::Pausing(until) if now < until => Step::Pausing(until),
            Step::Done => Step::Done,
            Step::Idle if !self.placed => {
                match rig.homing_state() {
                    HomingState::Homed => {}
                    HomingState::Failed(why) => {
                        return Err(format!("the stage could not be homed: {why}"));
                    }
                    // Placed once the stage is homed.
                    HomingState::Unhomed | HomingState::Homing => {
                        self.step = Step::Idle;
                        return Ok(());
                    }
                }
                match rig.place_antenna(now) {
                    Ok(Some(note)) => notes.send(now, format!("antenna placed: {note}")),
                    Ok(None) => {}
                    Err(e) => return Err(format!("placing the simulated antenna failed: {e}")),
                }
                self.placed = true;
                Step::Idle
            }
            Step::Pausing(_) | Step::Idle => match self.trial.moves.get(self.next_move).copied() {
                Some(m) => {
                    let j = self.next_move;
                    match rig.start_move_mm(m.distance_mm, m.speed_mm_per_s, now) {
                        Ok(()) => {
                            self.next_move += 1;
                            counts.started += 1;
                            notes.send(
                                now,
                                format!(
                                    "move {}: {:+.1} mm at {} mm/s",
                                    j + 1,
                                    m.distance_mm,
                                    m.speed_mm_per_s
                                ),
                            );
                            Step::Moving(j)
                        }
                        // Wait for the stage to come back or be homed.
                        Err(RigError::Device(
                            DeviceError::Unavailable { .. } | DeviceError::NotHomed(_),
                        )) => Step::Idle,
                        Err(RigError::Device(DeviceError::HomingFailed(why))) => {
                            return Err(format!("the stage could not be homed: {why}"));
                        }
                        Err(e) => {
                            self.next_move += 1;
                            counts.refused += 1;
                            notes.send(now, format!("move {} refused: {e}", j + 1));
                            Step::Idle
                        }
                    }
                }
                None => Step::Done,
            },
        };
        Ok(())
    }
}

/// How scripts ended, for the thread that ends their trials: the last script done, and the
/// last one that could not go on, with why.
#[derive(Debug, Default)]
pub struct ScriptEnds {
    done: AtomicU64,
    failed: Mutex<Option<(u64, String)>>,
}

impl ScriptEnds {
    /// Script `id` made (or had refused) every move.
    /// Everything the motion thread sent before this call (its last stage sample) is in the
    /// event channel by the time [`ScriptEnds::is_done`] says so (release, acquire).
    pub fn set_done(&self, id: u64) {
        self.done.store(id, Ordering::Release);
    }

    /// Script `id` cannot go on, because `why`.
    pub fn set_failed(&self, id: u64, why: String) {
        if let Ok(mut failed) = self.failed.lock() {
            *failed = Some((id, why));
        }
    }

    /// Whether script `id` is done.
    pub fn is_done(&self, id: u64) -> bool {
        self.done.load(Ordering::Acquire) == id
    }

    /// Why script `id` could not go on, if it could not.
    pub fn failure(&self, id: u64) -> Option<String> {
        self.failed.lock().ok().and_then(|f| {
            f.as_ref()
                .filter(|(f_id, _)| *f_id == id)
                .map(|f| f.1.clone())
        })
    }
}
