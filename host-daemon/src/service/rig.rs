//! The daemon's rig: the stage and the base servo as the configuration names them (the
//! Velmex VXM and the Pololu Maestro on their serial ports, or simulated ones), held as trait
//! objects ([`StageDevice`], [`ServoDevice`]), and, when the bus is simulated, the one
//! simulated world ([`SimWorld`]) whose antenna follows whichever stage and servo move it.
//!
//! The stage is always driven through [`crate::hardware::stage::LimitedStage`], so the soft
//! limits hold whatever a trial or a client asks. A serial device that vanishes (unplugged,
//! USB reset) makes its part unavailable: the calls fail at once with
//! [`DeviceError::Unavailable`], the port is reopened at most every [`REOPEN_INTERVAL`], and when
//! it opens again the controller is put back on line (the VXM keeps its position register
//! across a lost USB link) and the part is available again
//! ([`crate::hardware::vxm_device`], [`crate::hardware::maestro_device`]).
//!
//! The stage is homed against its limit switch before its first move
//! ([`crate::hardware::homing::HomingStage`]), on the simulated rig too, and again after the
//! controller shows signs of a power cycle (the VXM echoing a command, see
//! [`crate::hardware::vxm`]); until then every move is refused with [`DeviceError::NotHomed`] and
//! no stage position is sampled.

use crate::config::{Config, HomingDirection};
use crate::hardware::device::{DeviceError, ServoDevice, StageDevice, StageMove};
use crate::hardware::homing::{HomingEvent, HomingSettings, HomingState};
use crate::hardware::maestro::MaestroConfig;
use crate::hardware::maestro_device::MaestroDevice;
use crate::hardware::vxm::{MAX_SPEED_STEPS_PER_S, VxmKill};
use crate::hardware::vxm_device::VxmDevice;
use crate::service::acquisition::Shared;
use crate::sim::devices::{SimServo, SimStage};
use crate::sim::rig::{PhysicsStep, SimState, SimWorld};
use crate::{FakeServo, FakeStage};
use std::time::{Duration, Instant};

pub use crate::hardware::serial_link::REOPEN_INTERVAL;

/// What went wrong with the rig: a device's error, or the simulated physics'.
#[derive(Debug, thiserror::Error)]
pub enum RigError {
    /// The stage or the servo (unavailable, not homed, homing failed, refused).
    #[error(transparent)]
    Device(#[from] DeviceError),
    /// The simulated physics failed.
    #[error("simulation: {0:#}")]
    Simulation(anyhow::Error),
}

/// The stage, the servo and the simulated antenna, as the daemon's motion thread drives them.
pub struct DaemonRig {
    stage: Box<dyn StageDevice>,
    servo: Box<dyn ServoDevice>,
    world: Option<SimWorld>,
    /// The servo's calibrated range, degrees (`servo.angle_a_deg`..`servo.angle_b_deg`).
    servo_range_deg: (f64, f64),
    last_stage_mm: f64,
    last_base_rad: f64,
    homing_toward: HomingDirection,
}

impl std::fmt::Debug for DaemonRig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DaemonRig")
            .field("stage", &self.stage_description())
            .field("servo", &self.servo_description())
            .finish_non_exhaustive()
    }
}

impl DaemonRig {
    /// The rig of `config`: a VXM on `stage.port` unless it is `sim` (put on line, not
    /// homed: the motion thread homes it, [`DaemonRig::step_homing`]), a Maestro on
    /// `servo.port` unless it is `sim`; with `physics`, the simulated antenna follows them.
    /// Errors name the configuration key.
    pub fn open(config: &Config, physics: Option<Shared<SimState>>) -> anyhow::Result<Self> {
        Self::open_with_stage(config, physics, FakeStage::new())
    }

    /// [`DaemonRig::open`], with `sim_stage` as the simulated stage (e.g. one away from its
    /// limit switch) if the stage is simulated.
    pub fn open_with_stage(
        config: &Config,
        physics: Option<Shared<SimState>>,
        sim_stage: FakeStage,
    ) -> anyhow::Result<Self> {
        use anyhow::{Context, anyhow};
        let geometry = config.stage_geometry().context("`stage.steps_per_mm`")?;
        let homing = HomingSettings {
            toward: config.stage.homing_direction,
            speed_steps_per_s: (config.stage.homing_speed_mm_per_s * config.stage.steps_per_mm)
                .round()
                .clamp(1.0, f64::from(MAX_SPEED_STEPS_PER_S)) as u32,
            timeout: Duration::from_secs_f64(config.stage.homing_timeout_s),
        };
        let stage: Box<dyn StageDevice> = if config.stage.port == "sim" {
            Box::new(SimStage::new(sim_stage, geometry, homing).map_err(|e| anyhow!(e))?)
        } else {
            Box::new(
                VxmDevice::open(
                    &config.stage.port,
                    config.stage.baud,
                    Duration::from_millis(config.stage.reply_timeout_ms),
                    geometry,
                    homing,
                )
                .map_err(|e| anyhow!(e))?,
            )
        };
        let servo: Box<dyn ServoDevice> = if config.servo.port == "sim" {
            Box::new(SimServo::new(FakeServo::new()))
        } else {
            let calibration = config.pulse_calibration().context("`servo.pulse_b_us`")?;
            let maestro_config =
                MaestroConfig::new(config.servo.channel, calibration).context("`servo.channel`")?;
            Box::new(
                MaestroDevice::open(&config.servo.port, maestro_config).map_err(|e| anyhow!(e))?,
            )
        };
        let world = match physics {
            Some(state) => Some(SimWorld::new(config, state)?),
            None => None,
        };
        let mut rig = Self {
            stage,
            servo,
            world,
            servo_range_deg: config.servo_range_deg(),
            last_stage_mm: 0.0,
            last_base_rad: 0.0,
            homing_toward: config.stage.homing_direction,
        };
        rig.advance(Duration::ZERO)
            .map_err(|e| anyhow!("starting the rig: {e}"))?;
        Ok(rig)
    }

    /// `"simulated stage"` or `"VXM on /dev/ttyUSB0"`.
    pub fn stage_description(&self) -> String {
        self.stage.description()
    }

    /// `"simulated servo"` or `"Maestro on /dev/ttyACM0"`.
    pub fn servo_description(&self) -> String {
        self.servo.description()
    }

    /// The kill line of a VXM stage (a second handle on its port that only sends `K`), for a
    /// `stop_all` that must not wait behind a query; `None` for a simulated stage.
    pub fn stage_kill(&self) -> Option<VxmKill> {
        self.stage.kill_line()
    }

    /// Where the stage's homing is.
    pub fn homing_state(&self) -> HomingState {
        self.stage.homing_state()
    }

    /// Why the stage lost its home (a power cycle) since the last call, if it did.
    pub fn take_home_lost(&mut self) -> Option<String> {
        self.stage.take_home_lost()
    }

    /// A failed homing is tried again (when a trial starts).
    pub fn retry_homing(&mut self) {
        self.stage.retry_homing();
    }

    /// Steps the stage's homing (starts it when not homed, finishes it when the stage has
    /// stopped); says what changed, for the log.
    pub fn step_homing(&mut self, now: Duration) -> Result<Option<String>, RigError> {
        self.advance(now)?;
        let description = self.stage_description();
        let event = self.stage.step_homing(Instant::now())?;
        let toward = match self.homing_toward {
            HomingDirection::Negative => "negative",
            HomingDirection::Positive => "positive",
        };
        Ok(event.map(|event| match event {
            HomingEvent::Started => format!(
                "homing the stage ({description}): indexing to its {toward} limit switch, zeroed \
                 there, before anything else"
            ),
            HomingEvent::Homed => {
                format!("stage homed ({description}): step zero is the limit switch")
            }
            HomingEvent::Failed(why) => format!("homing the stage failed: {why}"),
        }))
    }

    /// Whether the stage answers (a simulated one always does).
    pub fn stage_available(&self) -> bool {
        self.stage.available()
    }

    /// Whether the servo answers (a simulated one always does).
    pub fn servo_available(&self) -> bool {
        self.servo.available()
    }

    /// Lets the simulated parts move until `now` and moves the simulated antenna with the
    /// stage and the base.
    fn advance(&mut self, now: Duration) -> Result<(), RigError> {
        if let Some(mm) = self.stage.advance(now) {
            self.last_stage_mm = mm;
        }
        if let Some(rad) = self.servo.advance(now) {
            self.last_base_rad = rad;
        }
        if let Some(world) = &mut self.world {
            world
                .move_to(self.last_stage_mm * 1e-3, self.last_base_rad, now)
                .map_err(RigError::Simulation)?;
        }
        Ok(())
    }

    /// Whether the rig has a simulated antenna.
    pub fn is_simulated(&self) -> bool {
        self.world.is_some()
    }

    /// Places the simulated antenna as its scene's `[start]` says, with the stage and the
    /// servo where they are now (a trial starting, after homing); what the placement did, in
    /// words, or `None` without a simulated antenna (on hardware a placement means nothing).
    pub fn place_antenna(&mut self, now: Duration) -> Result<Option<String>, RigError> {
        self.advance(now)?;
        let Some(world) = &mut self.world else {
            return Ok(None);
        };
        world
            .place(self.last_stage_mm * 1e-3, self.last_base_rad, now)
            .map_err(RigError::Simulation)?;
        Ok(Some(world.placement_note().to_owned()))
    }

    /// The simulated antenna's placements and steps since the last call, each with its
    /// time on the daemon's clock (none without a simulated antenna).
    pub fn take_physics_steps(&mut self) -> Vec<(Duration, PhysicsStep)> {
        self.world
            .as_mut()
            .map(SimWorld::take_steps)
            .unwrap_or_default()
    }

    /// Starts a relative stage move at `speed_mm_per_s`; one ending beyond the soft limits is
    /// refused and nothing moves.
    pub fn start_move_mm(
        &mut self,
        distance_mm: f64,
        speed_mm_per_s: f64,
        now: Duration,
    ) -> Result<(), RigError> {
        self.advance(now)?;
        Ok(self
            .stage
            .start_move(StageMove::By(distance_mm), speed_mm_per_s)?)
    }

    /// Starts a stage move to `position_mm` from home; refused beyond the soft limits.
    pub fn start_move_to_mm(
        &mut self,
        position_mm: f64,
        speed_mm_per_s: f64,
        now: Duration,
    ) -> Result<(), RigError> {
        self.advance(now)?;
        Ok(self
            .stage
            .start_move(StageMove::To(position_mm), speed_mm_per_s)?)
    }

    /// Whether the stage is still moving.
    pub fn stage_moving(&mut self, now: Duration) -> Result<bool, RigError> {
        self.advance(now)?;
        Ok(self.stage.is_moving()?)
    }

    /// The stage position, millimetres from home; [`DeviceError::NotHomed`] (or
    /// [`DeviceError::HomingFailed`]) before it is homed, as a position from an unknown origin
    /// means nothing.
    pub fn stage_mm(&mut self, now: Duration) -> Result<f64, RigError> {
        if self.stage.advance(now).is_none() {
            // A real stage is asked first, so the simulated antenna follows where it is.
            let mm = self.stage.position_mm()?;
            self.last_stage_mm = mm;
            self.advance(now)?;
            return Ok(mm);
        }
        self.advance(now)?;
        Ok(self.stage.position_mm()?)
    }

    /// Sets the base (servo) angle, radians; an angle outside the servo's calibrated range
    /// (`servo.angle_a_deg`..`servo.angle_b_deg`) is refused and nothing moves.
    pub fn set_base_angle_rad(&mut self, angle_rad: f64, now: Duration) -> Result<(), RigError> {
        let (min_deg, max_deg) = self.servo_range_deg;
        let angle_deg = angle_rad.to_degrees();
        // A hair of slack for the round trip through radians.
        if !(min_deg - 1e-9..=max_deg + 1e-9).contains(&angle_deg) {
            return Err(DeviceError::Refused(format!(
                "{angle_deg} deg is outside the servo's calibrated range {min_deg}..={max_deg} \
                 deg (servo.angle_a_deg, servo.angle_b_deg)"
            ))
            .into());
        }
        self.advance(now)?;
        Ok(self.servo.set_angle_rad(angle_rad)?)
    }

    /// The base (servo) angle, radians.
    pub fn base_angle_rad(&mut self, now: Duration) -> Result<f64, RigError> {
        if self.servo.advance(now).is_none() {
            // A real servo is asked first, so the simulated antenna follows it.
            self.last_base_rad = self.servo.angle_rad()?;
        }
        self.advance(now)?;
        Ok(self.last_base_rad)
    }

    /// Stops the stage at once (the VXM's kill); a homing under way fails.
    pub fn stop(&mut self, now: Duration) -> Result<(), RigError> {
        self.advance(now)?;
        Ok(self.stage.kill()?)
    }
}
