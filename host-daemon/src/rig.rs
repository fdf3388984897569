//! The daemon's rig: the stage and the base servo as the configuration names them (the
//! Velmex VXM and the Pololu Maestro on their serial ports, or simulated ones), and, when the
//! bus is simulated, the antenna's physics following whichever stage and servo move it.
//!
//! The stage is always driven through [`LimitedStage`], so the soft limits hold whatever a
//! trial or a client asks. A serial device that vanishes (unplugged, USB reset) makes its
//! part unavailable: the calls fail at once with [`RigError::Unavailable`], the port is
//! reopened at most every [`REOPEN_INTERVAL`], and when it opens again the controller is put
//! back on line (the VXM keeps its position register across a lost USB link) and the part is
//! available again.

use crate::acquisition::Shared;
use crate::config::Config;
use crate::maestro::{Maestro, MaestroConfig, MaestroError};
use crate::servo::Servo;
use crate::sim_rig::{SimPhysics, SimState};
use crate::stage::{Homed, LimitedStage, StageError};
use crate::vxm::{Vxm, VxmError, VxmStatus};
use crate::{FakeServo, FakeStage};
use serialport::SerialPort;
use std::time::{Duration, Instant};

/// How often a vanished serial device is looked for again.
pub const REOPEN_INTERVAL: Duration = Duration::from_millis(250);
/// Read timeout of the serial ports (the drivers' own deadlines are built from these reads).
const PORT_READ_TIMEOUT: Duration = Duration::from_millis(5);

/// What went wrong with the rig.
#[derive(Debug, thiserror::Error)]
pub enum RigError {
    /// The device's serial port is gone; it is being reopened.
    #[error("the {part} is unavailable ({path}: {reason})")]
    Unavailable {
        /// `"stage"` or `"servo"`.
        part: &'static str,
        /// The configured port.
        path: String,
        /// Why.
        reason: String,
    },
    /// A move beyond the soft limits, a speed or angle out of range, a device error.
    #[error("{0}")]
    Refused(String),
    /// The simulated physics failed.
    #[error("simulation: {0:#}")]
    Simulation(anyhow::Error),
}

/// A port opened from a configured path; the error names the key.
fn open_serial(key: &str, path: &str, baud: u32) -> Result<Box<dyn SerialPort>, String> {
    serialport::new(path, baud)
        .data_bits(serialport::DataBits::Eight)
        .parity(serialport::Parity::None)
        .stop_bits(serialport::StopBits::One)
        .flow_control(serialport::FlowControl::None)
        .timeout(PORT_READ_TIMEOUT)
        .open()
        .map_err(|e| format!("`{key}` = {path:?}: cannot open the serial port: {e}"))
}

/// A serial device that may vanish and come back.
#[derive(Debug)]
struct Link {
    part: &'static str,
    path: String,
    baud: u32,
    available: bool,
    reason: String,
    next_try: Instant,
}

impl Link {
    fn unavailable(&self) -> RigError {
        RigError::Unavailable {
            part: self.part,
            path: self.path.clone(),
            reason: self.reason.clone(),
        }
    }

    /// A new port if the device is gone and it is time to look for it again.
    fn reopen(&mut self) -> Result<Option<Box<dyn SerialPort>>, RigError> {
        if self.available {
            return Ok(None);
        }
        let now = Instant::now();
        if now < self.next_try {
            return Err(self.unavailable());
        }
        self.next_try = now + REOPEN_INTERVAL;
        match serialport::new(&self.path, self.baud)
            .timeout(PORT_READ_TIMEOUT)
            .open()
        {
            Ok(port) => Ok(Some(port)),
            Err(e) => {
                self.reason = format!("reopening: {e}");
                Err(self.unavailable())
            }
        }
    }

    fn lost(&mut self, reason: String) -> RigError {
        self.available = false;
        self.reason = reason;
        self.next_try = Instant::now() + REOPEN_INTERVAL;
        self.unavailable()
    }
}

type VxmStage = LimitedStage<Vxm<Box<dyn SerialPort>>, Homed>;

enum StageDevice {
    Sim(LimitedStage<FakeStage, Homed>),
    Vxm { stage: Box<VxmStage>, link: Link },
}

enum ServoDevice {
    Sim(FakeServo),
    Maestro {
        servo: Box<Maestro<Box<dyn SerialPort>>>,
        link: Link,
    },
}

/// The stage, the servo and the simulated antenna, as the daemon's motion thread drives them.
pub struct DaemonRig {
    stage: StageDevice,
    servo: ServoDevice,
    physics: Option<(SimPhysics, Shared<SimState>)>,
    mount_rad: f64,
    /// The servo's calibrated range, degrees (`servo.angle_a_deg`..`servo.angle_b_deg`).
    servo_range_deg: (f64, f64),
    advanced_to: Duration,
    solved_for: Option<(f64, f64)>,
    last_stage_mm: f64,
    last_base_rad: f64,
}

impl std::fmt::Debug for DaemonRig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DaemonRig")
            .field("stage", &self.stage_description())
            .field("servo", &self.servo_description())
            .finish_non_exhaustive()
    }
}

fn stage_error<E: core::error::Error>(e: StageError<E>) -> String {
    match e {
        StageError::Device(e) => format!("stage: {e}"),
        other => other.to_string(),
    }
}

impl DaemonRig {
    /// The rig of `config`: a VXM on `stage.port` unless it is `sim` (put on line and homed
    /// where it stands), a Maestro on `servo.port` unless it is `sim`; with `physics`, the
    /// simulated antenna follows them. Errors name the configuration key.
    pub fn open(config: &Config, physics: Option<Shared<SimState>>) -> anyhow::Result<Self> {
        use anyhow::{Context, anyhow};
        let geometry = config.stage_geometry().context("`stage.steps_per_mm`")?;
        let stage = if config.stage.port == "sim" {
            let stage = LimitedStage::new(FakeStage::new(), geometry)
                .online()
                .map_err(|e| anyhow!("{e}"))?
                .home()
                .map_err(|e| anyhow!("{e}"))?;
            StageDevice::Sim(stage)
        } else {
            let path = config.stage.port.clone();
            let port =
                open_serial("stage.port", &path, config.stage.baud).map_err(|e| anyhow!(e))?;
            let vxm = Vxm::new(port)
                .with_reply_timeout(Duration::from_millis(config.stage.reply_timeout_ms));
            let stage = LimitedStage::new(vxm, geometry)
                .online()
                .map_err(|e| anyhow!("`stage.port` = {path:?}: {e}"))?
                .home()
                .map_err(|e| anyhow!("`stage.port` = {path:?}: {e}"))?;
            StageDevice::Vxm {
                stage: Box::new(stage),
                link: Link {
                    part: "stage",
                    path,
                    baud: config.stage.baud,
                    available: true,
                    reason: String::new(),
                    next_try: Instant::now(),
                },
            }
        };
        let servo = if config.servo.port == "sim" {
            ServoDevice::Sim(FakeServo::new())
        } else {
            let path = config.servo.port.clone();
            let calibration = config.pulse_calibration().context("`servo.pulse_b_us`")?;
            let maestro_config =
                MaestroConfig::new(config.servo.channel, calibration).context("`servo.channel`")?;
            let port = open_serial("servo.port", &path, 9600).map_err(|e| anyhow!(e))?;
            ServoDevice::Maestro {
                servo: Box::new(Maestro::new(port, maestro_config)),
                link: Link {
                    part: "servo",
                    path,
                    baud: 9600,
                    available: true,
                    reason: String::new(),
                    next_try: Instant::now(),
                },
            }
        };
        let physics = match physics {
            Some(state) => Some((crate::sim_rig::sim_physics(config)?, state)),
            None => None,
        };
        let mut rig = Self {
            stage,
            servo,
            physics,
            mount_rad: config.sim.antenna.base_angle_deg.to_radians(),
            servo_range_deg: config.servo_range_deg(),
            advanced_to: Duration::ZERO,
            solved_for: None,
            last_stage_mm: 0.0,
            last_base_rad: 0.0,
        };
        rig.advance(Duration::ZERO)
            .map_err(|e| anyhow!("starting the rig: {e}"))?;
        Ok(rig)
    }

    /// `"simulated stage"` or `"VXM on /dev/ttyUSB0"`.
    pub fn stage_description(&self) -> String {
        match &self.stage {
            StageDevice::Sim(_) => "simulated stage".to_owned(),
            StageDevice::Vxm { link, .. } => format!("VXM on {}", link.path),
        }
    }

    /// `"simulated servo"` or `"Maestro on /dev/ttyACM0"`.
    pub fn servo_description(&self) -> String {
        match &self.servo {
            ServoDevice::Sim(_) => "simulated servo".to_owned(),
            ServoDevice::Maestro { link, .. } => format!("Maestro on {}", link.path),
        }
    }

    /// Whether the stage answers (a simulated one always does).
    pub fn stage_available(&self) -> bool {
        match &self.stage {
            StageDevice::Sim(_) => true,
            StageDevice::Vxm { link, .. } => link.available,
        }
    }

    /// Whether the servo answers (a simulated one always does).
    pub fn servo_available(&self) -> bool {
        match &self.servo {
            ServoDevice::Sim(_) => true,
            ServoDevice::Maestro { link, .. } => link.available,
        }
    }

    /// Lets the simulated parts move until `now` and updates the simulated antenna.
    fn advance(&mut self, now: Duration) -> Result<(), RigError> {
        let dt = now.saturating_sub(self.advanced_to);
        self.advanced_to = self.advanced_to.max(now);
        if let StageDevice::Sim(stage) = &mut self.stage {
            stage.stage_mut().advance(dt);
            self.last_stage_mm =
                stage.stage_mut().exact_position_steps() / stage.geometry().steps_per_mm();
        }
        if let ServoDevice::Sim(servo) = &mut self.servo {
            servo.advance(dt);
            self.last_base_rad = servo.angle_rad().unwrap_or(self.last_base_rad);
        }
        if let Some((physics, state)) = &mut self.physics {
            let key = (
                self.last_stage_mm * 1e-3,
                self.mount_rad + self.last_base_rad,
            );
            if self.solved_for != Some(key) {
                let solved = physics
                    .update(key.0, key.1)
                    .map_err(|e| RigError::Simulation(e.into()))?;
                self.solved_for = Some(key);
                if let Ok(mut shared) = state.lock() {
                    *shared = solved;
                }
            }
        }
        Ok(())
    }

    /// Runs `f` on the VXM, reopening its port first if it had vanished; a vanished device
    /// makes the stage unavailable.
    fn with_vxm<T>(
        stage: &mut VxmStage,
        link: &mut Link,
        f: impl FnOnce(&mut VxmStage) -> Result<T, StageError<VxmError>>,
    ) -> Result<T, RigError> {
        if let Some(port) = link.reopen()? {
            if let Err(e) = stage.stage_mut().reconnect(port) {
                return Err(link.lost(format!("back on line: {e}")));
            }
            link.available = true;
            link.reason.clear();
        }
        match f(stage) {
            Ok(v) => Ok(v),
            Err(StageError::Device(VxmError::Disconnected(e))) => Err(link.lost(e.to_string())),
            Err(e) => Err(RigError::Refused(stage_error(e))),
        }
    }

    fn with_maestro<T>(
        servo: &mut Maestro<Box<dyn SerialPort>>,
        link: &mut Link,
        f: impl FnOnce(&mut Maestro<Box<dyn SerialPort>>) -> Result<T, MaestroError>,
    ) -> Result<T, RigError> {
        if let Some(port) = link.reopen()? {
            servo.reconnect(port);
            link.available = true;
            link.reason.clear();
        }
        match f(servo) {
            Ok(v) => Ok(v),
            Err(MaestroError::Disconnected(e)) => Err(link.lost(e.to_string())),
            Err(e) => Err(RigError::Refused(format!("servo: {e}"))),
        }
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
        match &mut self.stage {
            StageDevice::Sim(stage) => stage
                .set_speed_mm_per_s(speed_mm_per_s)
                .and_then(|()| stage.start_relative_mm(distance_mm))
                .map_err(|e| RigError::Refused(stage_error(e))),
            StageDevice::Vxm { stage, link } => Self::with_vxm(stage, link, |s| {
                s.set_speed_mm_per_s(speed_mm_per_s)?;
                s.start_relative_mm(distance_mm)
            }),
        }
    }

    /// Starts a stage move to `position_mm` from home; refused beyond the soft limits.
    pub fn start_move_to_mm(
        &mut self,
        position_mm: f64,
        speed_mm_per_s: f64,
        now: Duration,
    ) -> Result<(), RigError> {
        self.advance(now)?;
        match &mut self.stage {
            StageDevice::Sim(stage) => stage
                .set_speed_mm_per_s(speed_mm_per_s)
                .and_then(|()| stage.start_absolute_mm(position_mm))
                .map_err(|e| RigError::Refused(stage_error(e))),
            StageDevice::Vxm { stage, link } => Self::with_vxm(stage, link, |s| {
                s.set_speed_mm_per_s(speed_mm_per_s)?;
                s.start_absolute_mm(position_mm)
            }),
        }
    }

    /// Whether the stage is still moving.
    pub fn stage_moving(&mut self, now: Duration) -> Result<bool, RigError> {
        self.advance(now)?;
        match &mut self.stage {
            StageDevice::Sim(stage) => Ok(stage.stage_mut().is_moving()),
            StageDevice::Vxm { stage, link } => Self::with_vxm(stage, link, |s| {
                s.stage_mut()
                    .status()
                    .map(|status| status != VxmStatus::Ready)
                    .map_err(StageError::Device)
            }),
        }
    }

    /// The stage position, millimetres from home.
    pub fn stage_mm(&mut self, now: Duration) -> Result<f64, RigError> {
        if let StageDevice::Vxm { stage, link } = &mut self.stage {
            self.last_stage_mm = Self::with_vxm(stage, link, |s| s.position_mm())?;
        }
        self.advance(now)?;
        match &mut self.stage {
            StageDevice::Sim(stage) => stage
                .position_mm()
                .map_err(|e| RigError::Refused(stage_error(e))),
            StageDevice::Vxm { .. } => Ok(self.last_stage_mm),
        }
    }

    /// Sets the base (servo) angle, radians; an angle outside the servo's calibrated range
    /// (`servo.angle_a_deg`..`servo.angle_b_deg`) is refused and nothing moves.
    pub fn set_base_angle_rad(&mut self, angle_rad: f64, now: Duration) -> Result<(), RigError> {
        let (min_deg, max_deg) = self.servo_range_deg;
        let angle_deg = angle_rad.to_degrees();
        // A hair of slack for the round trip through radians.
        if !(min_deg - 1e-9..=max_deg + 1e-9).contains(&angle_deg) {
            return Err(RigError::Refused(format!(
                "{angle_deg} deg is outside the servo's calibrated range {min_deg}..={max_deg} \
                 deg (servo.angle_a_deg, servo.angle_b_deg)"
            )));
        }
        self.advance(now)?;
        match &mut self.servo {
            ServoDevice::Sim(servo) => servo
                .set_angle_rad(angle_rad)
                .map_err(|e| RigError::Refused(format!("servo: {e}"))),
            ServoDevice::Maestro { servo, link } => {
                Self::with_maestro(servo, link, |m| m.set_angle_rad(angle_rad))
            }
        }
    }

    /// The base (servo) angle, radians.
    pub fn base_angle_rad(&mut self, now: Duration) -> Result<f64, RigError> {
        if let ServoDevice::Maestro { servo, link } = &mut self.servo {
            self.last_base_rad = Self::with_maestro(servo, link, |m| m.angle_rad())?;
        }
        self.advance(now)?;
        Ok(self.last_base_rad)
    }

    /// Stops the stage at once (the VXM's kill).
    pub fn stop(&mut self, now: Duration) -> Result<(), RigError> {
        self.advance(now)?;
        match &mut self.stage {
            StageDevice::Sim(stage) => stage.kill().map_err(|e| RigError::Refused(stage_error(e))),
            StageDevice::Vxm { stage, link } => Self::with_vxm(stage, link, |s| s.kill()),
        }
    }
}
