//! The linear stage: the [`Stage`] trait every stage driver implements (the Velmex VXM in
//! [`crate::hardware::vxm`], the in-memory [`crate::FakeStage`]), and [`LimitedStage`], the wrapper the
//! daemon drives it through, which converts millimetres to steps, enforces the soft limits
//! whatever it is told and, by typestate, refuses to move a stage that is not online and
//! homed.
//!
//! ```
//! use host_daemon::hardware::stage::HomingDirection;
//! use host_daemon::{FakeStage, LimitedStage, StageError, StageGeometry};
//! use std::time::Duration;
//!
//! let geometry = StageGeometry::new(100.0, 0.0, 300.0).expect("valid geometry");
//! let stage = LimitedStage::new(FakeStage::new(), geometry);
//! let mut stage = stage
//!     .online()
//!     .expect("on line")
//!     .home(HomingDirection::Negative, Duration::from_secs(10))
//!     .expect("homed");
//! stage.move_absolute_mm(150.0, Duration::from_secs(10)).expect("within limits");
//! assert!(matches!(
//!     stage.start_relative_mm(200.0),
//!     Err(StageError::BeyondSoftLimits { .. })
//! ));
//! ```
//!
//! A stage that is on line but not homed has no moves:
//!
//! ```compile_fail
//! use host_daemon::{FakeStage, LimitedStage, StageGeometry};
//!
//! let geometry = StageGeometry::new(100.0, 0.0, 300.0).expect("valid geometry");
//! let mut stage = LimitedStage::new(FakeStage::new(), geometry).online().expect("on line");
//! stage.start_relative_mm(1.0);
//! ```

use core::marker::PhantomData;
use std::time::Duration;

/// A stepper-driven linear stage, positions in motor steps.
///
/// Contract: the implementation owns its port or model. `start_*` methods return once the
/// move has been handed to the controller; [`Stage::wait_done`] blocks (or, for a simulated
/// stage, advances simulated time) until the move has finished or the timeout has passed.
/// A relative move of zero steps does nothing and completes at once. Nothing here checks
/// soft limits: that is [`LimitedStage`]'s job.
pub trait Stage {
    /// What can go wrong talking to the stage.
    type Error: core::error::Error + 'static;

    /// Puts the controller on line (ready to take commands from the host).
    fn online(&mut self) -> Result<(), Self::Error>;
    /// Starts homing: runs toward the limit switch at `toward` (at the set speed) until it
    /// trips, then makes that position step zero. Like a move, it ends when
    /// [`Stage::is_moving`] says `false` or [`Stage::wait_done`] returns; killed before
    /// the switch, the position is not zeroed.
    fn start_homing(&mut self, toward: HomingDirection) -> Result<(), Self::Error>;
    /// Whether a move (or homing) is under way; does not wait.
    fn is_moving(&mut self) -> Result<bool, Self::Error>;
    /// Sets the speed of the following moves, steps per second.
    fn set_speed_steps_per_s(&mut self, speed_steps_per_s: u32) -> Result<(), Self::Error>;
    /// Starts a move of `steps` from the current position.
    fn start_relative_steps(&mut self, steps: i32) -> Result<(), Self::Error>;
    /// Starts a move to step position `position_steps`.
    fn start_absolute_steps(&mut self, position_steps: i32) -> Result<(), Self::Error>;
    /// Waits until the current move (if any) has finished, at most `timeout`.
    fn wait_done(&mut self, timeout: Duration) -> Result<(), Self::Error>;
    /// The current position, steps.
    fn position_steps(&mut self) -> Result<i32, Self::Error>;
    /// Stops the motor at once and abandons the current move.
    fn kill(&mut self) -> Result<(), Self::Error>;
}

pub use crate::config::geometry::{GeometryError, HomingDirection, StageGeometry};

/// Why [`LimitedStage`] refused or failed a command.
#[derive(Debug, thiserror::Error)]
pub enum StageError<E> {
    /// The move would end beyond the soft limits; nothing was sent to the stage.
    #[error("target {target_steps} steps is beyond the soft limits {min_steps}..={max_steps}")]
    BeyondSoftLimits {
        /// Where the move would have ended, steps.
        target_steps: i64,
        /// Lower soft limit, steps.
        min_steps: i32,
        /// Upper soft limit, steps.
        max_steps: i32,
    },
    /// A distance or speed in millimetres was not finite, or too large to express in steps;
    /// nothing was sent.
    #[error("{what} of {value} is not a usable number")]
    InvalidNumber {
        /// Which quantity ("distance mm", "speed mm/s").
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// Homing ended away from step zero: it was stopped before its limit switch.
    #[error("homing ended at step {position_steps}, not at the limit switch (stopped early?)")]
    NotAtHome {
        /// Where the stage reads after homing, steps.
        position_steps: i32,
    },
    /// The stage itself failed.
    #[error("stage: {0}")]
    Device(#[source] E),
}

/// A failed mode change; the stage is handed back in the mode it was in.
#[derive(Debug, thiserror::Error)]
#[error("stage mode change failed: {error}")]
pub struct ModeChangeError<E, D> {
    /// What went wrong.
    #[source]
    pub error: E,
    /// The stage, unchanged in mode.
    pub stage: D,
}

/// Typestate: the controller has not been put on line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Offline;
/// Typestate: on line, not homed; position can be read, the stage cannot be moved.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Online;
/// Typestate: on line and homed; moves within the soft limits are allowed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Homed;

/// The modes in which the controller is on line ([`Online`] and [`Homed`]).
pub trait OnLineMode: private::Sealed {}
impl OnLineMode for Online {}
impl OnLineMode for Homed {}

mod private {
    pub trait Sealed {}
    impl Sealed for super::Online {}
    impl Sealed for super::Homed {}
}

/// A [`Stage`] as the daemon drives it: millimetres and steps, soft limits checked before
/// anything is sent, and modes as types (`Offline` → [`LimitedStage::online`] → `Online` →
/// [`LimitedStage::home`] → `Homed`, the only mode with moves).
#[derive(Debug)]
pub struct LimitedStage<S, M> {
    stage: S,
    geometry: StageGeometry,
    mode: PhantomData<M>,
}

impl<S: Stage> LimitedStage<S, Offline> {
    /// Wraps `stage` (taken by value; [`LimitedStage::destroy`] gives it back).
    pub fn new(stage: S, geometry: StageGeometry) -> Self {
        Self {
            stage,
            geometry,
            mode: PhantomData,
        }
    }

    /// Puts the controller on line.
    #[allow(clippy::type_complexity)]
    pub fn online(
        mut self,
    ) -> Result<LimitedStage<S, Online>, ModeChangeError<StageError<S::Error>, Self>> {
        match self.stage.online() {
            Ok(()) => Ok(self.into_mode()),
            Err(error) => Err(ModeChangeError {
                error: StageError::Device(error),
                stage: self,
            }),
        }
    }
}

impl<S: Stage> LimitedStage<S, Online> {
    /// Homes the stage against its limit switch at `toward` (see [`Stage::start_homing`]),
    /// waiting at most `timeout`: the switch becomes step zero, the origin of the soft limits.
    /// A homing that does not finish in time is killed and the stage handed back unhomed.
    #[allow(clippy::type_complexity)]
    pub fn home(
        mut self,
        toward: HomingDirection,
        timeout: Duration,
    ) -> Result<LimitedStage<S, Homed>, ModeChangeError<StageError<S::Error>, Self>> {
        let homed = self
            .start_homing(toward)
            .and_then(|()| self.wait_done(timeout).inspect_err(|_| _ = self.kill()));
        match homed {
            Ok(()) => self.finish_homing(),
            Err(error) => Err(ModeChangeError { error, stage: self }),
        }
    }

    /// Starts homing against the limit switch at `toward` and returns at once; when
    /// [`LimitedStage::is_moving`] says it is over, [`LimitedStage::finish_homing`].
    pub fn start_homing(&mut self, toward: HomingDirection) -> Result<(), StageError<S::Error>> {
        self.stage.start_homing(toward).map_err(StageError::Device)
    }

    /// After a homing has ended: checks that the stage reads step zero (a homing killed before
    /// its switch does not) and makes it [`Homed`].
    #[allow(clippy::type_complexity)]
    pub fn finish_homing(
        mut self,
    ) -> Result<LimitedStage<S, Homed>, ModeChangeError<StageError<S::Error>, Self>> {
        match self.position_steps() {
            Ok(0) => Ok(self.into_mode()),
            Ok(position_steps) => Err(ModeChangeError {
                error: StageError::NotAtHome { position_steps },
                stage: self,
            }),
            Err(error) => Err(ModeChangeError { error, stage: self }),
        }
    }
}

impl<S: Stage, M: OnLineMode> LimitedStage<S, M> {
    /// The current position, steps.
    pub fn position_steps(&mut self) -> Result<i32, StageError<S::Error>> {
        self.stage.position_steps().map_err(StageError::Device)
    }

    /// The current position, millimetres from home.
    pub fn position_mm(&mut self) -> Result<f64, StageError<S::Error>> {
        let steps = self.position_steps()?;
        Ok(self.geometry.mm_for_steps(steps))
    }

    /// Stops the motor at once.
    pub fn kill(&mut self) -> Result<(), StageError<S::Error>> {
        self.stage.kill().map_err(StageError::Device)
    }

    /// Whether a move (or homing) is under way.
    pub fn is_moving(&mut self) -> Result<bool, StageError<S::Error>> {
        self.stage.is_moving().map_err(StageError::Device)
    }

    /// Waits for the current move to finish, at most `timeout`.
    pub fn wait_done(&mut self, timeout: Duration) -> Result<(), StageError<S::Error>> {
        self.stage.wait_done(timeout).map_err(StageError::Device)
    }
}

impl<S: Stage> LimitedStage<S, Homed> {
    /// Forgets the home (the controller lost its position, e.g. it was power-cycled): no
    /// moves until it is homed again.
    pub fn lose_home(self) -> LimitedStage<S, Online> {
        self.into_mode()
    }

    /// Sets the speed of the following moves, steps per second.
    pub fn set_speed_steps_per_s(&mut self, speed: u32) -> Result<(), StageError<S::Error>> {
        self.stage
            .set_speed_steps_per_s(speed)
            .map_err(StageError::Device)
    }

    /// Sets the speed of the following moves, millimetres per second (to the nearest step/s).
    pub fn set_speed_mm_per_s(&mut self, speed_mm_per_s: f64) -> Result<(), StageError<S::Error>> {
        let steps = (speed_mm_per_s * self.geometry.steps_per_mm()).round();
        if !(steps.is_finite() && steps >= 1.0 && steps <= f64::from(u32::MAX)) {
            return Err(StageError::InvalidNumber {
                what: "speed mm/s",
                value: speed_mm_per_s,
            });
        }
        self.set_speed_steps_per_s(steps as u32)
    }

    /// Starts a move of `steps` from the current position (read from the stage first), if it
    /// ends within the soft limits; otherwise nothing is sent but that position query.
    pub fn start_relative_steps(&mut self, steps: i32) -> Result<(), StageError<S::Error>> {
        let here = self.position_steps()?;
        self.check(i64::from(here) + i64::from(steps))?;
        self.stage
            .start_relative_steps(steps)
            .map_err(StageError::Device)
    }

    /// Starts a move to `position_steps` if it is within the soft limits; otherwise nothing is
    /// sent.
    pub fn start_absolute_steps(
        &mut self,
        position_steps: i32,
    ) -> Result<(), StageError<S::Error>> {
        self.check(i64::from(position_steps))?;
        self.stage
            .start_absolute_steps(position_steps)
            .map_err(StageError::Device)
    }

    /// [`LimitedStage::start_relative_steps`] in millimetres (to the nearest step).
    pub fn start_relative_mm(&mut self, distance_mm: f64) -> Result<(), StageError<S::Error>> {
        let steps = self.steps(distance_mm)?;
        self.start_relative_steps(steps)
    }

    /// [`LimitedStage::start_absolute_steps`] in millimetres from home (to the nearest step).
    pub fn start_absolute_mm(&mut self, position_mm: f64) -> Result<(), StageError<S::Error>> {
        let steps = self.steps(position_mm)?;
        self.start_absolute_steps(steps)
    }

    /// A relative move in millimetres, waiting at most `timeout` for it to finish.
    pub fn move_relative_mm(
        &mut self,
        distance_mm: f64,
        timeout: Duration,
    ) -> Result<(), StageError<S::Error>> {
        self.start_relative_mm(distance_mm)?;
        self.wait_done(timeout)
    }

    /// An absolute move in millimetres from home, waiting at most `timeout` for it to finish.
    pub fn move_absolute_mm(
        &mut self,
        position_mm: f64,
        timeout: Duration,
    ) -> Result<(), StageError<S::Error>> {
        self.start_absolute_mm(position_mm)?;
        self.wait_done(timeout)
    }

    fn steps(&self, mm: f64) -> Result<i32, StageError<S::Error>> {
        self.geometry
            .steps_for_mm(mm)
            .and_then(|steps| i32::try_from(steps).ok())
            .ok_or(StageError::InvalidNumber {
                what: "distance mm",
                value: mm,
            })
    }

    fn check(&self, target_steps: i64) -> Result<(), StageError<S::Error>> {
        let (min_steps, max_steps) = self.geometry.limits_steps();
        if (i64::from(min_steps)..=i64::from(max_steps)).contains(&target_steps) {
            Ok(())
        } else {
            Err(StageError::BeyondSoftLimits {
                target_steps,
                min_steps,
                max_steps,
            })
        }
    }
}

impl<S, M> LimitedStage<S, M> {
    /// The stage's scale and soft limits.
    pub fn geometry(&self) -> &StageGeometry {
        &self.geometry
    }

    /// The stage driver, e.g. to reconnect a vanished serial device. Moves made through it
    /// bypass the soft limits.
    pub fn stage_mut(&mut self) -> &mut S {
        &mut self.stage
    }

    /// Gives the stage driver back.
    pub fn destroy(self) -> S {
        self.stage
    }

    fn into_mode<N>(self) -> LimitedStage<S, N> {
        LimitedStage {
            stage: self.stage,
            geometry: self.geometry,
            mode: PhantomData,
        }
    }
}
