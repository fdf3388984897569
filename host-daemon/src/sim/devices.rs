//! The simulated stage and servo as the rig's devices ([`StageDevice`], [`ServoDevice`]): a
//! [`FakeStage`] homed against its limit switch like the VXM and a [`FakeServo`], moving in
//! real time at their set speeds as the rig's clock advances them.

use crate::hardware::device::{
    DeviceError, ServoDevice, StageDevice, StageMove, homed, stage_error,
};
use crate::hardware::homing::{HomingEvent, HomingSettings, HomingStage, HomingState};
use crate::hardware::servo::Servo;
use crate::hardware::stage::{LimitedStage, StageGeometry};
use crate::sim::fake_servo::FakeServo;
use crate::sim::fake_stage::FakeStage;
use std::time::{Duration, Instant};

/// The simulated stage.
#[derive(Debug)]
pub struct SimStage {
    stage: HomingStage<FakeStage>,
    advanced_to: Duration,
}

impl SimStage {
    /// `stage` put on line with `geometry`, not homed.
    pub fn new(
        stage: FakeStage,
        geometry: StageGeometry,
        homing: HomingSettings,
    ) -> Result<Self, String> {
        let stage = LimitedStage::new(stage, geometry)
            .online()
            .map_err(|e| e.to_string())?;
        Ok(Self {
            stage: HomingStage::new(stage, homing),
            advanced_to: Duration::ZERO,
        })
    }
}

impl StageDevice for SimStage {
    fn description(&self) -> String {
        "simulated stage".to_owned()
    }

    fn homing_state(&self) -> HomingState {
        self.stage.state()
    }

    fn retry_homing(&mut self) {
        self.stage.retry();
    }

    fn advance(&mut self, now: Duration) -> Option<f64> {
        let dt = now.saturating_sub(self.advanced_to);
        self.advanced_to = self.advanced_to.max(now);
        let steps_per_mm = self.stage.steps_per_mm();
        let fake = self.stage.driver_mut()?;
        fake.advance(dt);
        Some(fake.exact_position_steps() / steps_per_mm)
    }

    fn step_homing(&mut self, now: Instant) -> Result<Option<HomingEvent>, DeviceError> {
        self.stage.step(now).map_err(stage_error)
    }

    fn start_move(&mut self, to: StageMove, speed_mm_per_s: f64) -> Result<(), DeviceError> {
        to.start(homed(&mut self.stage)?, speed_mm_per_s)
            .map_err(stage_error)
    }

    fn is_moving(&mut self) -> Result<bool, DeviceError> {
        self.stage.is_moving().map_err(stage_error)
    }

    fn position_mm(&mut self) -> Result<f64, DeviceError> {
        homed(&mut self.stage)?.position_mm().map_err(stage_error)
    }

    fn kill(&mut self) -> Result<(), DeviceError> {
        self.stage.kill().map_err(stage_error)
    }
}

/// The simulated servo.
#[derive(Debug, Default)]
pub struct SimServo {
    servo: FakeServo,
    advanced_to: Duration,
}

impl SimServo {
    /// `servo`, advanced by the rig's clock from now on.
    pub fn new(servo: FakeServo) -> Self {
        Self {
            servo,
            advanced_to: Duration::ZERO,
        }
    }
}

impl ServoDevice for SimServo {
    fn description(&self) -> String {
        "simulated servo".to_owned()
    }

    fn advance(&mut self, now: Duration) -> Option<f64> {
        let dt = now.saturating_sub(self.advanced_to);
        self.advanced_to = self.advanced_to.max(now);
        self.servo.advance(dt);
        self.servo.angle_rad().ok()
    }

    fn set_angle_rad(&mut self, angle_rad: f64) -> Result<(), DeviceError> {
        self.servo
            .set_angle_rad(angle_rad)
            .map_err(|e| DeviceError::Refused(format!("servo: {e}")))
    }

    fn angle_rad(&mut self) -> Result<f64, DeviceError> {
        self.servo
            .angle_rad()
            .map_err(|e| DeviceError::Refused(format!("servo: {e}")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::HomingDirection;

    fn stage() -> SimStage {
        let homing = HomingSettings {
            toward: HomingDirection::Negative,
            speed_steps_per_s: 4000,
            timeout: Duration::from_secs(10),
        };
        let geometry = StageGeometry::new(80.0, 0.0, 200.0).unwrap();
        SimStage::new(FakeStage::new(), geometry, homing).unwrap()
    }

    #[test]
    fn the_simulated_stage_refuses_moves_until_homed_then_moves_with_the_clock() {
        let mut stage = stage();
        assert!(matches!(
            stage.start_move(StageMove::By(10.0), 5.0),
            Err(DeviceError::NotHomed(_))
        ));
        assert_eq!(
            stage.step_homing(Instant::now()),
            Ok(Some(HomingEvent::Started))
        );
        // The fake starts at its limit switch: homing ends at the next step.
        stage.advance(Duration::from_millis(10));
        assert_eq!(
            stage.step_homing(Instant::now()),
            Ok(Some(HomingEvent::Homed))
        );
        assert_eq!(stage.homing_state(), HomingState::Homed);
        stage.start_move(StageMove::By(10.0), 5.0).unwrap();
        assert_eq!(stage.is_moving(), Ok(true));
        let mm = stage.advance(Duration::from_millis(1010)).unwrap();
        assert!((mm - 5.0).abs() < 0.1, "{mm}");
        let mm = stage.advance(Duration::from_secs(3)).unwrap();
        assert!((mm - 10.0).abs() < 1e-9, "{mm}");
        assert_eq!(stage.position_mm(), Ok(10.0));
        assert!(matches!(
            stage.start_move(StageMove::To(500.0), 5.0),
            Err(DeviceError::Refused(why)) if why.contains("soft limits")
        ));
    }

    #[test]
    fn the_simulated_servo_follows_the_clock() {
        let mut servo = SimServo::new(FakeServo::new());
        assert_eq!(servo.description(), "simulated servo");
        servo.set_angle_rad(0.1).unwrap();
        let angle = servo.advance(Duration::from_secs(5)).unwrap();
        assert!((angle - 0.1).abs() < 1e-9, "{angle}");
        assert!(servo.available());
    }
}
