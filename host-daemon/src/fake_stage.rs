//! An in-memory stage that moves at its set speed in simulated time: the stage of the
//! simulated rig and of tests that need no serial port.

use crate::stage::Stage;
use std::time::Duration;

/// What the fake stage refuses, mirroring the real one's failures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum FakeStageError {
    /// A command other than going on line was given before the stage was on line.
    #[error("the stage is not on line")]
    Offline,
    /// The move did not finish within the timeout (simulated time).
    #[error("the move did not finish within {0:?}")]
    Timeout(Duration),
    /// The speed is zero.
    #[error("a speed of zero steps/s never arrives")]
    ZeroSpeed,
    /// The stage has been made to vanish with [`FakeStage::set_vanished`].
    #[error("the stage is gone")]
    Disconnected,
}

/// A move under way.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Motion {
    from_steps: f64,
    to_steps: f64,
    elapsed_s: f64,
}

/// A stage in memory. Its clock only moves when told ([`FakeStage::advance`]) or while
/// [`Stage::wait_done`] waits, so runs are deterministic.
#[derive(Debug, Clone, PartialEq)]
pub struct FakeStage {
    online: bool,
    vanished: bool,
    position_steps: f64,
    speed_steps_per_s: u32,
    motion: Option<Motion>,
    now_s: f64,
}

impl Default for FakeStage {
    fn default() -> Self {
        Self::new()
    }
}

impl FakeStage {
    /// Off line at step zero, 2000 steps/s, clock at zero.
    pub fn new() -> Self {
        Self {
            online: false,
            vanished: false,
            position_steps: 0.0,
            speed_steps_per_s: 2000,
            motion: None,
            now_s: 0.0,
        }
    }

    /// Simulated time since creation, seconds.
    pub fn now_s(&self) -> f64 {
        self.now_s
    }

    /// Where the stage is, steps (fractional mid-step).
    pub fn exact_position_steps(&self) -> f64 {
        self.position_steps
    }

    /// Whether a move is under way.
    pub fn is_moving(&self) -> bool {
        self.motion.is_some()
    }

    /// Makes every command fail with [`FakeStageError::Disconnected`] (or stops doing so);
    /// the stage keeps its position, as a VXM does when its USB link drops.
    pub fn set_vanished(&mut self, vanished: bool) {
        self.vanished = vanished;
    }

    /// Lets `dt` of simulated time pass.
    pub fn advance(&mut self, dt: Duration) {
        let dt_s = dt.as_secs_f64();
        self.now_s += dt_s;
        if let Some(motion) = &mut self.motion {
            motion.elapsed_s += dt_s;
            let distance = motion.to_steps - motion.from_steps;
            let travelled = f64::from(self.speed_steps_per_s) * motion.elapsed_s;
            if travelled >= distance.abs() {
                self.position_steps = motion.to_steps;
                self.motion = None;
            } else {
                self.position_steps = motion.from_steps + travelled.copysign(distance);
            }
        }
    }

    /// Simulated time until the current move ends.
    pub fn remaining(&self) -> Duration {
        self.motion.map_or(Duration::ZERO, |motion| {
            let distance = (motion.to_steps - self.position_steps).abs();
            Duration::from_secs_f64(distance / f64::from(self.speed_steps_per_s))
        })
    }

    fn ready(&self) -> Result<(), FakeStageError> {
        if self.vanished {
            Err(FakeStageError::Disconnected)
        } else if !self.online {
            Err(FakeStageError::Offline)
        } else {
            Ok(())
        }
    }

    fn start(&mut self, to_steps: f64) {
        self.motion = (to_steps != self.position_steps).then_some(Motion {
            from_steps: self.position_steps,
            to_steps,
            elapsed_s: 0.0,
        });
    }
}

impl Stage for FakeStage {
    type Error = FakeStageError;

    fn online(&mut self) -> Result<(), FakeStageError> {
        if self.vanished {
            return Err(FakeStageError::Disconnected);
        }
        self.online = true;
        Ok(())
    }

    fn zero(&mut self) -> Result<(), FakeStageError> {
        self.ready()?;
        self.motion = None;
        self.position_steps = 0.0;
        Ok(())
    }

    fn set_speed_steps_per_s(&mut self, speed_steps_per_s: u32) -> Result<(), FakeStageError> {
        self.ready()?;
        if speed_steps_per_s == 0 {
            return Err(FakeStageError::ZeroSpeed);
        }
        // A move under way goes on from here at the new speed.
        if let Some(motion) = &mut self.motion {
            motion.from_steps = self.position_steps;
            motion.elapsed_s = 0.0;
        }
        self.speed_steps_per_s = speed_steps_per_s;
        Ok(())
    }

    fn start_relative_steps(&mut self, steps: i32) -> Result<(), FakeStageError> {
        self.ready()?;
        self.start(self.position_steps.round() + f64::from(steps));
        Ok(())
    }

    fn start_absolute_steps(&mut self, position_steps: i32) -> Result<(), FakeStageError> {
        self.ready()?;
        self.start(f64::from(position_steps));
        Ok(())
    }

    fn wait_done(&mut self, timeout: Duration) -> Result<(), FakeStageError> {
        self.ready()?;
        let remaining = self.remaining();
        if remaining <= timeout {
            self.advance(remaining);
            // Rounding in the conversion to Duration may leave a sliver.
            if let Some(motion) = self.motion.take() {
                self.position_steps = motion.to_steps;
            }
            Ok(())
        } else {
            self.advance(timeout);
            Err(FakeStageError::Timeout(timeout))
        }
    }

    fn position_steps(&mut self) -> Result<i32, FakeStageError> {
        self.ready()?;
        // Positions stay within the i32 steps they were commanded between.
        Ok(self.position_steps.round() as i32)
    }

    fn kill(&mut self) -> Result<(), FakeStageError> {
        self.ready()?;
        self.motion = None;
        self.position_steps = self.position_steps.round();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stage::{LimitedStage, StageError, StageGeometry};

    #[test]
    fn moves_take_distance_over_speed_in_simulated_time() {
        let mut stage = FakeStage::new();
        assert_eq!(stage.start_relative_steps(10), Err(FakeStageError::Offline));
        stage.online().unwrap();
        stage.set_speed_steps_per_s(1000).unwrap();
        stage.start_relative_steps(500).unwrap();
        stage.advance(Duration::from_millis(100));
        assert_eq!(stage.position_steps().unwrap(), 100);
        assert_eq!(
            stage.wait_done(Duration::from_millis(100)),
            Err(FakeStageError::Timeout(Duration::from_millis(100)))
        );
        assert_eq!(stage.position_steps().unwrap(), 200);
        stage.wait_done(Duration::from_secs(1)).unwrap();
        assert_eq!(stage.position_steps().unwrap(), 500);
        assert!((stage.now_s() - 0.5).abs() < 1e-9);
        stage.start_absolute_steps(-500).unwrap();
        stage.advance(Duration::from_millis(250));
        stage.kill().unwrap();
        assert_eq!(stage.position_steps().unwrap(), 250);
        assert!(!stage.is_moving());
    }

    #[test]
    fn limited_fake_stage_refuses_moves_beyond_soft_limits() {
        let geometry = StageGeometry::new(100.0, -10.0, 300.0).unwrap();
        let stage = LimitedStage::new(FakeStage::new(), geometry);
        let mut stage = stage.online().unwrap().home().unwrap();
        stage.set_speed_mm_per_s(16.0).unwrap();
        stage
            .move_absolute_mm(250.0, Duration::from_secs(20))
            .unwrap();
        assert_eq!(stage.position_steps().unwrap(), 25_000);
        let refused = stage.start_relative_mm(60.0);
        assert!(matches!(
            refused,
            Err(StageError::BeyondSoftLimits {
                target_steps: 31_000,
                ..
            })
        ));
        assert!(!stage.stage_mut().is_moving());
        stage.stage_mut().set_vanished(true);
        assert!(matches!(
            stage.position_mm(),
            Err(StageError::Device(FakeStageError::Disconnected))
        ));
        stage.stage_mut().set_vanished(false);
        assert_eq!(stage.position_mm().unwrap(), 250.0);
    }
}
