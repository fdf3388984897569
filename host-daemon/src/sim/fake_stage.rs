//! An in-memory stage that moves at its set speed in simulated time: the stage of the
//! simulated rig and of tests that need no serial port.

use crate::hardware::stage::{HomingDirection, Stage};
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
    /// A homing run: reaching `to_steps` (the limit switch) makes it step zero.
    homing: bool,
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
    /// Where the limit switches are, steps in the current frame (negative, positive).
    limits_steps: (f64, f64),
}

impl Default for FakeStage {
    fn default() -> Self {
        Self::new()
    }
}

impl FakeStage {
    /// Off line at step zero, on its negative limit switch (the positive one a million
    /// steps away), 2000 steps/s, clock at zero.
    pub fn new() -> Self {
        Self {
            online: false,
            vanished: false,
            position_steps: 0.0,
            speed_steps_per_s: 2000,
            motion: None,
            now_s: 0.0,
            limits_steps: (0.0, 1e6),
        }
    }

    /// The same stage `steps` away from its negative limit switch (e.g. where a restart left
    /// it), its position register reading zero there, as a controller's does after power-up.
    pub fn away_from_limit(steps: u32) -> Self {
        let mut stage = Self::new();
        stage.limits_steps = (-f64::from(steps), 1e6 - f64::from(steps));
        stage
    }

    /// Its power is cycled: off line, the motion and the position register lost (zero
    /// where it stands); the stage itself stays where it is.
    pub fn power_cycle(&mut self) {
        self.position_steps = self.position_steps.round();
        self.motion = None;
        let here = self.position_steps;
        self.limits_steps = (self.limits_steps.0 - here, self.limits_steps.1 - here);
        self.position_steps = 0.0;
        self.online = false;
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
                let homing = motion.homing;
                self.position_steps = motion.to_steps;
                self.motion = None;
                if homing {
                    self.zero_here();
                }
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
        // A move stops at a limit switch, as the real stage does.
        let to_steps = to_steps.clamp(self.limits_steps.0, self.limits_steps.1);
        self.motion = (to_steps != self.position_steps).then_some(Motion {
            from_steps: self.position_steps,
            to_steps,
            elapsed_s: 0.0,
            homing: false,
        });
    }

    /// Makes the current position step zero (the limit switches keep their places).
    fn zero_here(&mut self) {
        let here = self.position_steps;
        self.limits_steps = (self.limits_steps.0 - here, self.limits_steps.1 - here);
        self.position_steps = 0.0;
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

    fn start_homing(&mut self, toward: HomingDirection) -> Result<(), FakeStageError> {
        self.ready()?;
        let to_steps = match toward {
            HomingDirection::Negative => self.limits_steps.0,
            HomingDirection::Positive => self.limits_steps.1,
        };
        self.motion = Some(Motion {
            from_steps: self.position_steps,
            to_steps,
            elapsed_s: 0.0,
            homing: true,
        });
        if to_steps == self.position_steps {
            // Already on the switch.
            self.motion = None;
            self.zero_here();
        }
        Ok(())
    }

    fn is_moving(&mut self) -> Result<bool, FakeStageError> {
        self.ready()?;
        Ok(self.motion.is_some())
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
                if motion.homing {
                    self.zero_here();
                }
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
    use crate::hardware::stage::{LimitedStage, StageError, StageGeometry};

    #[test]
    fn homing_runs_to_the_limit_switch_and_zeroes_there_unless_killed_first() {
        let geometry = StageGeometry::new(100.0, 0.0, 300.0).unwrap();
        let stage = LimitedStage::new(FakeStage::away_from_limit(5_000), geometry);
        let mut stage = stage.online().unwrap();
        stage.stage_mut().set_speed_steps_per_s(1000).unwrap();
        stage.start_homing(HomingDirection::Negative).unwrap();
        stage.stage_mut().advance(Duration::from_secs(1));
        assert!(stage.is_moving().unwrap());
        stage.kill().unwrap();
        // Killed 4000 steps short of the switch: not home.
        let stage = match stage.finish_homing() {
            Err(e) => {
                assert!(matches!(
                    e.error,
                    StageError::NotAtHome {
                        position_steps: -1000
                    }
                ));
                e.stage
            }
            Ok(_) => panic!("a killed homing must not count"),
        };
        let mut stage = stage
            .home(HomingDirection::Negative, Duration::from_secs(10))
            .unwrap();
        assert_eq!(stage.position_steps().unwrap(), 0);
        // The switch is the origin: 50 mm out, a power cycle zeroes the register there and
        // homing again finds the switch 5000 steps back.
        stage
            .move_absolute_mm(50.0, Duration::from_secs(10))
            .unwrap();
        stage.stage_mut().power_cycle();
        let mut stage = stage.lose_home();
        Stage::online(stage.stage_mut()).unwrap();
        let mut stage = stage
            .home(HomingDirection::Negative, Duration::from_secs(10))
            .unwrap();
        assert_eq!(stage.stage_mut().exact_position_steps(), 0.0);
        assert!((stage.stage_mut().limits_steps.0).abs() < 1e-9);
    }

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
        let mut stage = stage
            .online()
            .unwrap()
            .home(HomingDirection::Negative, Duration::from_secs(1))
            .unwrap();
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
        assert!(!FakeStage::is_moving(stage.stage_mut()));
        stage.stage_mut().set_vanished(true);
        assert!(matches!(
            stage.position_mm(),
            Err(StageError::Device(FakeStageError::Disconnected))
        ));
        stage.stage_mut().set_vanished(false);
        assert_eq!(stage.position_mm().unwrap(), 250.0);
    }
}
