//! Homing as a state machine the motion thread steps: a stage is never moved before it has
//! been homed against its limit switch (indexed to the switch, zeroed there), and loses its
//! home when the controller shows signs of a power cycle. Homing runs without blocking: the
//! motion thread keeps sampling, and a kill stops it like any move.
//!
//! `Unhomed` → [`HomingStage::step`] starts homing → `Homing` → the stage stops at step zero
//! → `Homed` (moves allowed) — or `Failed` (timed out, killed, stopped away from zero), which
//! stays until [`HomingStage::retry`]. [`HomingStage::lose_home`] goes back to `Unhomed`.

use crate::hardware::stage::{Homed, HomingDirection, LimitedStage, Online, Stage, StageError};
use std::time::{Duration, Instant};

/// How a stage homes (`[stage]`'s `homing_*` keys).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HomingSettings {
    /// The limit switch homed against.
    pub toward: HomingDirection,
    /// Homing speed, steps per second.
    pub speed_steps_per_s: u32,
    /// Longest homing before it counts as failed (the stage is then killed).
    pub timeout: Duration,
}

/// Where a [`HomingStage`] is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum HomingState {
    /// Not homed; homing starts at the next step.
    Unhomed,
    /// Running toward the limit switch.
    Homing,
    /// Homed: moves within the soft limits allowed.
    Homed,
    /// Homing failed (why); no moves until [`HomingStage::retry`].
    Failed(String),
}

/// What a step of the state machine did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum HomingEvent {
    /// Homing started.
    Started,
    /// The stage is homed.
    Homed,
    /// Homing failed, and why.
    Failed(String),
}

enum Mode<S: Stage> {
    Unhomed(LimitedStage<S, Online>),
    Homing {
        stage: LimitedStage<S, Online>,
        deadline: Instant,
    },
    Homed(LimitedStage<S, Homed>),
    Failed {
        stage: LimitedStage<S, Online>,
        why: String,
    },
}

/// A stage with its homing state (see the module documentation).
pub struct HomingStage<S: Stage> {
    mode: Option<Mode<S>>,
    settings: HomingSettings,
}

impl<S: Stage> std::fmt::Debug for HomingStage<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HomingStage")
            .field("state", &self.state())
            .field("settings", &self.settings)
            .finish_non_exhaustive()
    }
}

impl<S: Stage> HomingStage<S> {
    /// An on-line stage, not homed yet.
    pub fn new(stage: LimitedStage<S, Online>, settings: HomingSettings) -> Self {
        Self {
            mode: Some(Mode::Unhomed(stage)),
            settings,
        }
    }

    /// Where the state machine is.
    pub fn state(&self) -> HomingState {
        match &self.mode {
            Some(Mode::Unhomed(_)) | None => HomingState::Unhomed,
            Some(Mode::Homing { .. }) => HomingState::Homing,
            Some(Mode::Homed(_)) => HomingState::Homed,
            Some(Mode::Failed { why, .. }) => HomingState::Failed(why.clone()),
        }
    }

    /// The homed stage, or why there is none.
    pub fn homed(&mut self) -> Result<&mut LimitedStage<S, Homed>, HomingState> {
        let state = self.state();
        match &mut self.mode {
            Some(Mode::Homed(stage)) => Ok(stage),
            _ => Err(state),
        }
    }

    /// Steps the state machine at `now`: starts homing if unhomed, finishes or fails it if
    /// under way. A device error leaves the state as it was.
    pub fn step(&mut self, now: Instant) -> Result<Option<HomingEvent>, StageError<S::Error>> {
        let Some(mode) = self.mode.take() else {
            return Ok(None);
        };
        let (mode, result) = match mode {
            Mode::Unhomed(mut stage) => match self.start(&mut stage) {
                Ok(()) => (
                    Mode::Homing {
                        stage,
                        deadline: now + self.settings.timeout,
                    },
                    Ok(Some(HomingEvent::Started)),
                ),
                Err(e) => (Mode::Unhomed(stage), Err(e)),
            },
            Mode::Homing {
                mut stage,
                deadline,
            } => match stage.is_moving() {
                Ok(true) if now < deadline => (Mode::Homing { stage, deadline }, Ok(None)),
                Ok(true) => {
                    let _ = stage.kill();
                    let why = format!(
                        "no limit switch within stage.homing_timeout_s = {} s; the stage was \
                         stopped",
                        self.settings.timeout.as_secs_f64()
                    );
                    (
                        Mode::Failed {
                            stage,
                            why: why.clone(),
                        },
                        Ok(Some(HomingEvent::Failed(why))),
                    )
                }
                Ok(false) => match stage.finish_homing() {
                    Ok(homed) => (Mode::Homed(homed), Ok(Some(HomingEvent::Homed))),
                    Err(e) => match e.error {
                        StageError::Device(error) => (
                            Mode::Homing {
                                stage: e.stage,
                                deadline,
                            },
                            Err(StageError::Device(error)),
                        ),
                        other => {
                            let why = other.to_string();
                            (
                                Mode::Failed {
                                    stage: e.stage,
                                    why: why.clone(),
                                },
                                Ok(Some(HomingEvent::Failed(why))),
                            )
                        }
                    },
                },
                Err(e) => (Mode::Homing { stage, deadline }, Err(e)),
            },
            other => (other, Ok(None)),
        };
        self.mode = Some(mode);
        result
    }

    fn start(&self, stage: &mut LimitedStage<S, Online>) -> Result<(), StageError<S::Error>> {
        // After a power cycle the controller is off line: put it back first.
        stage.stage_mut().online().map_err(StageError::Device)?;
        stage
            .stage_mut()
            .set_speed_steps_per_s(self.settings.speed_steps_per_s)
            .map_err(StageError::Device)?;
        stage.start_homing(self.settings.toward)
    }

    /// The home is lost (the controller was power-cycled): no moves until homed again.
    pub fn lose_home(&mut self) {
        self.mode = self.mode.take().map(|mode| Mode::Unhomed(online(mode)));
    }

    /// A failed homing is tried again at the next step (other states are left alone).
    pub fn retry(&mut self) {
        if let Some(Mode::Failed { .. }) = &self.mode {
            self.lose_home();
        }
    }

    /// Stops the motor at once; a homing under way fails ("stopped").
    pub fn kill(&mut self) -> Result<(), StageError<S::Error>> {
        let result = match &mut self.mode {
            Some(Mode::Homed(stage)) => stage.kill(),
            Some(
                Mode::Unhomed(stage) | Mode::Homing { stage, .. } | Mode::Failed { stage, .. },
            ) => stage.kill(),
            None => Ok(()),
        };
        if let Some(Mode::Homing { .. }) = &self.mode {
            self.mode = self.mode.take().map(|mode| Mode::Failed {
                stage: online(mode),
                why: "homing was stopped before its limit switch (stop_all); it is tried again \
                      when a trial starts"
                    .to_owned(),
            });
        }
        result
    }

    /// Whether the motor is moving (a move or homing).
    pub fn is_moving(&mut self) -> Result<bool, StageError<S::Error>> {
        match &mut self.mode {
            Some(Mode::Homed(stage)) => stage.is_moving(),
            Some(
                Mode::Unhomed(stage) | Mode::Homing { stage, .. } | Mode::Failed { stage, .. },
            ) => stage.is_moving(),
            None => Ok(false),
        }
    }

    /// The stage driver (e.g. to reconnect its port); moves made through it bypass the soft
    /// limits and the homing.
    pub fn driver_mut(&mut self) -> Option<&mut S> {
        match &mut self.mode {
            Some(Mode::Homed(stage)) => Some(stage.stage_mut()),
            Some(
                Mode::Unhomed(stage) | Mode::Homing { stage, .. } | Mode::Failed { stage, .. },
            ) => Some(stage.stage_mut()),
            None => None,
        }
    }

    /// Steps per millimetre of the stage.
    pub fn steps_per_mm(&self) -> f64 {
        match &self.mode {
            Some(Mode::Homed(stage)) => stage.geometry().steps_per_mm(),
            Some(
                Mode::Unhomed(stage) | Mode::Homing { stage, .. } | Mode::Failed { stage, .. },
            ) => stage.geometry().steps_per_mm(),
            None => 1.0,
        }
    }
}

fn online<S: Stage>(mode: Mode<S>) -> LimitedStage<S, Online> {
    match mode {
        Mode::Homed(stage) => stage.lose_home(),
        Mode::Unhomed(stage) | Mode::Homing { stage, .. } | Mode::Failed { stage, .. } => stage,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hardware::stage::StageGeometry;
    use crate::{FakeStage, Stage};

    fn stage(away_steps: u32) -> HomingStage<FakeStage> {
        let geometry = StageGeometry::new(100.0, 0.0, 300.0).unwrap();
        let stage = LimitedStage::new(FakeStage::away_from_limit(away_steps), geometry)
            .online()
            .unwrap();
        HomingStage::new(
            stage,
            HomingSettings {
                toward: HomingDirection::Negative,
                speed_steps_per_s: 1000,
                timeout: Duration::from_secs(3),
            },
        )
    }

    #[test]
    fn no_move_before_homing_and_homing_ends_on_the_switch() {
        let mut stage = stage(2_000);
        assert_eq!(stage.homed().err(), Some(HomingState::Unhomed));
        let t0 = Instant::now();
        assert_eq!(stage.step(t0).unwrap(), Some(HomingEvent::Started));
        assert_eq!(stage.homed().err(), Some(HomingState::Homing));
        stage.driver_mut().unwrap().advance(Duration::from_secs(1));
        assert_eq!(stage.step(t0).unwrap(), None);
        stage.driver_mut().unwrap().advance(Duration::from_secs(1));
        assert_eq!(stage.step(t0).unwrap(), Some(HomingEvent::Homed));
        let homed = stage.homed().unwrap();
        assert_eq!(homed.position_steps().unwrap(), 0);
        homed.start_absolute_mm(5.0).unwrap();
        // A power cycle: the home is gone, no more moves.
        stage.driver_mut().unwrap().power_cycle();
        stage.lose_home();
        assert_eq!(stage.homed().err(), Some(HomingState::Unhomed));
    }

    #[test]
    fn a_homing_past_its_timeout_or_killed_fails_until_retried() {
        let mut stage = stage(10_000);
        let t0 = Instant::now();
        stage.step(t0).unwrap();
        stage.driver_mut().unwrap().advance(Duration::from_secs(1));
        match stage.step(t0 + Duration::from_secs(4)).unwrap() {
            Some(HomingEvent::Failed(why)) => assert!(why.contains("homing_timeout_s"), "{why}"),
            other => panic!("{other:?}"),
        }
        assert!(!stage.is_moving().unwrap());
        assert_eq!(stage.step(t0).unwrap(), None, "a failure stays");
        stage.retry();
        assert_eq!(stage.step(t0).unwrap(), Some(HomingEvent::Started));
        stage.kill().unwrap();
        assert!(matches!(stage.state(), HomingState::Failed(why) if why.contains("stop_all")));
        assert!(Stage::position_steps(stage.driver_mut().unwrap()).unwrap() != 0);
    }
}
