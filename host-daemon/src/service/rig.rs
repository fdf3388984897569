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
//!
//! The stage is homed against its limit switch before its first move ([`HomingStage`]), on
//! the simulated rig too, and again after the controller shows signs of a power cycle (the
//! VXM echoing a command, see [`crate::hardware::vxm`]); until then every move is refused with
//! [`RigError::NotHomed`] and no stage position is sampled.

use crate::hardware::homing::{HomingEvent, HomingSettings, HomingStage, HomingState};
use crate::hardware::maestro::{Maestro, MaestroConfig, MaestroError};
use crate::hardware::servo::Servo;
use crate::hardware::stage::{LimitedStage, StageError};
use crate::hardware::vxm::{Vxm, VxmError, VxmKill};
use crate::service::acquisition::Shared;
use crate::service::config::Config;
use crate::sim::rig::{SimPhysics, SimState};
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
    /// The stage is not homed yet (homing starts or is under way); nothing moved.
    #[error("the stage is not homed yet ({0})")]
    NotHomed(String),
    /// Homing failed; nothing moves until it is tried again (when a trial starts).
    #[error("the stage is not homed: homing failed ({0})")]
    HomingFailed(String),
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

type VxmStage = HomingStage<Vxm<Box<dyn SerialPort>>>;

enum StageDevice {
    Sim(HomingStage<FakeStage>),
    Vxm {
        stage: Box<VxmStage>,
        link: Link,
        kill: VxmKill,
    },
}

/// What went wrong inside a stage call: the stage's own error or the rig's verdict.
enum Fail<E> {
    Stage(StageError<E>),
    Rig(RigError),
}

impl<E> From<StageError<E>> for Fail<E> {
    fn from(e: StageError<E>) -> Self {
        Self::Stage(e)
    }
}

impl<E> From<RigError> for Fail<E> {
    fn from(e: RigError) -> Self {
        Self::Rig(e)
    }
}

/// The homed stage, or the rig's reason to refuse a move.
fn homed<S: crate::Stage>(
    stage: &mut HomingStage<S>,
) -> Result<&mut LimitedStage<S, crate::hardware::stage::Homed>, RigError> {
    stage.homed().map_err(|state| match state {
        HomingState::Failed(why) => RigError::HomingFailed(why),
        HomingState::Homing => RigError::NotHomed("homing under way".to_owned()),
        _ => RigError::NotHomed("homing starts at the next stage sample".to_owned()),
    })
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
    /// Why the stage lost its home since the motion thread last asked.
    home_lost: Option<String>,
    homing_toward: crate::hardware::stage::HomingDirection,
}

impl std::fmt::Debug for DaemonRig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DaemonRig")
            .field("stage", &self.stage_description())
            .field("servo", &self.servo_description())
            .finish_non_exhaustive()
    }
}

/// A stage move: by a distance from where the stage is, or to a position from home.
#[derive(Clone, Copy)]
enum StageMove {
    By(f64),
    To(f64),
}

impl StageMove {
    fn start<S: crate::Stage>(
        self,
        stage: &mut LimitedStage<S, crate::hardware::stage::Homed>,
        speed_mm_per_s: f64,
    ) -> Result<(), StageError<S::Error>> {
        stage.set_speed_mm_per_s(speed_mm_per_s)?;
        match self {
            Self::By(distance_mm) => stage.start_relative_mm(distance_mm),
            Self::To(position_mm) => stage.start_absolute_mm(position_mm),
        }
    }
}

fn stage_error<E: core::error::Error>(e: StageError<E>) -> String {
    match e {
        StageError::Device(e) => format!("stage: {e}"),
        other => other.to_string(),
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
                .clamp(1.0, f64::from(crate::hardware::vxm::MAX_SPEED_STEPS_PER_S))
                as u32,
            timeout: Duration::from_secs_f64(config.stage.homing_timeout_s),
        };
        let stage = if config.stage.port == "sim" {
            let stage = LimitedStage::new(sim_stage, geometry)
                .online()
                .map_err(|e| anyhow!("{e}"))?;
            StageDevice::Sim(HomingStage::new(stage, homing))
        } else {
            let path = config.stage.port.clone();
            let port =
                open_serial("stage.port", &path, config.stage.baud).map_err(|e| anyhow!(e))?;
            let kill = VxmKill::new();
            kill.arm(port.as_ref())
                .map_err(|e| anyhow!("`stage.port` = {path:?}: cloning the port for kill: {e}"))?;
            let vxm = Vxm::new(port)
                .with_reply_timeout(Duration::from_millis(config.stage.reply_timeout_ms));
            let stage = LimitedStage::new(vxm, geometry)
                .online()
                .map_err(|e| anyhow!("`stage.port` = {path:?}: {e}"))?;
            StageDevice::Vxm {
                kill,
                stage: Box::new(HomingStage::new(stage, homing)),
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
            Some(state) => Some((crate::sim::rig::sim_physics(config)?, state)),
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
            home_lost: None,
            homing_toward: config.stage.homing_direction,
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

    /// The kill line of a VXM stage (a second handle on its port that only sends `K`), for a
    /// `stop_all` that must not wait behind a query; `None` for a simulated stage.
    pub fn stage_kill(&self) -> Option<VxmKill> {
        match &self.stage {
            StageDevice::Sim(_) => None,
            StageDevice::Vxm { kill, .. } => Some(kill.clone()),
        }
    }

    /// Where the stage's homing is.
    pub fn homing_state(&self) -> HomingState {
        match &self.stage {
            StageDevice::Sim(stage) => stage.state(),
            StageDevice::Vxm { stage, .. } => stage.state(),
        }
    }

    /// Why the stage lost its home (a power cycle) since the last call, if it did.
    pub fn take_home_lost(&mut self) -> Option<String> {
        self.home_lost.take()
    }

    /// A failed homing is tried again (when a trial starts).
    pub fn retry_homing(&mut self) {
        match &mut self.stage {
            StageDevice::Sim(stage) => stage.retry(),
            StageDevice::Vxm { stage, .. } => stage.retry(),
        }
    }

    /// Steps the stage's homing (starts it when not homed, finishes it when the stage has
    /// stopped); says what changed, for the log.
    pub fn step_homing(&mut self, now: Duration) -> Result<Option<String>, RigError> {
        self.advance(now)?;
        let description = self.stage_description();
        let event = match &mut self.stage {
            StageDevice::Sim(stage) => stage
                .step(Instant::now())
                .map_err(|e| RigError::Refused(stage_error(e)))?,
            StageDevice::Vxm { stage, link, kill } => {
                Self::with_vxm(stage, link, kill, &mut self.home_lost, |s| {
                    Ok(s.step(Instant::now())?)
                })?
            }
        };
        let toward = match self.homing_toward {
            crate::hardware::stage::HomingDirection::Negative => "negative",
            crate::hardware::stage::HomingDirection::Positive => "positive",
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
            let steps_per_mm = stage.steps_per_mm();
            if let Some(fake) = stage.driver_mut() {
                fake.advance(dt);
                self.last_stage_mm = fake.exact_position_steps() / steps_per_mm;
            }
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

    /// Runs `f` on the VXM, reopening its port first if it had vanished (a VXM that comes
    /// back echoing was power-cycled: its home is lost); a vanished device makes the stage
    /// unavailable, an echo loses the home.
    fn with_vxm<T>(
        stage: &mut VxmStage,
        link: &mut Link,
        kill: &VxmKill,
        home_lost: &mut Option<String>,
        f: impl FnOnce(&mut VxmStage) -> Result<T, Fail<VxmError>>,
    ) -> Result<T, RigError> {
        if let Some(port) = link.reopen()? {
            // The kill line first: a stop must reach the VXM as soon as it is back.
            let _ = kill.arm(port.as_ref());
            let reconnected = match stage.driver_mut() {
                Some(vxm) => vxm.reconnect(port),
                None => Err(VxmError::Disconnected(std::io::Error::other("no driver"))),
            };
            match reconnected {
                Ok((_old, power_cycled)) => {
                    if power_cycled {
                        stage.lose_home();
                        *home_lost = Some(format!(
                            "the VXM on {} came back off line, echoing (power-cycled): its                              position is lost",
                            link.path
                        ));
                    }
                }
                Err(e) => {
                    kill.disarm();
                    return Err(link.lost(format!("back on line: {e}")));
                }
            }
            link.available = true;
            link.reason.clear();
        }
        match f(stage) {
            Ok(v) => Ok(v),
            Err(Fail::Stage(StageError::Device(VxmError::Disconnected(e)))) => {
                kill.disarm();
                Err(link.lost(e.to_string()))
            }
            Err(Fail::Stage(StageError::Device(e @ VxmError::PowerCycled { .. }))) => {
                stage.lose_home();
                let why = format!("the VXM on {}: {e}", link.path);
                *home_lost = Some(why.clone());
                Err(RigError::NotHomed(why))
            }
            Err(Fail::Stage(e)) => Err(RigError::Refused(stage_error(e))),
            Err(Fail::Rig(e)) => Err(e),
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
        self.start_stage_move(StageMove::By(distance_mm), speed_mm_per_s, now)
    }

    /// Starts a stage move to `position_mm` from home; refused beyond the soft limits.
    pub fn start_move_to_mm(
        &mut self,
        position_mm: f64,
        speed_mm_per_s: f64,
        now: Duration,
    ) -> Result<(), RigError> {
        self.start_stage_move(StageMove::To(position_mm), speed_mm_per_s, now)
    }

    /// Starts `to` at `speed_mm_per_s` on a homed stage, simulated or the VXM.
    fn start_stage_move(
        &mut self,
        to: StageMove,
        speed_mm_per_s: f64,
        now: Duration,
    ) -> Result<(), RigError> {
        self.advance(now)?;
        match &mut self.stage {
            StageDevice::Sim(stage) => to
                .start(homed(stage)?, speed_mm_per_s)
                .map_err(|e| RigError::Refused(stage_error(e))),
            StageDevice::Vxm { stage, link, kill } => {
                Self::with_vxm(stage, link, kill, &mut self.home_lost, |s| {
                    Ok(to.start(homed(s)?, speed_mm_per_s)?)
                })
            }
        }
    }

    /// Whether the stage is still moving.
    pub fn stage_moving(&mut self, now: Duration) -> Result<bool, RigError> {
        self.advance(now)?;
        match &mut self.stage {
            StageDevice::Sim(stage) => stage
                .is_moving()
                .map_err(|e| RigError::Refused(stage_error(e))),
            StageDevice::Vxm { stage, link, kill } => {
                Self::with_vxm(stage, link, kill, &mut self.home_lost, |s| {
                    Ok(s.is_moving()?)
                })
            }
        }
    }

    /// The stage position, millimetres from home; [`RigError::NotHomed`] (or
    /// [`RigError::HomingFailed`]) before it is homed, as a position from an unknown origin
    /// means nothing.
    pub fn stage_mm(&mut self, now: Duration) -> Result<f64, RigError> {
        if let StageDevice::Vxm { stage, link, kill } = &mut self.stage {
            self.last_stage_mm = Self::with_vxm(stage, link, kill, &mut self.home_lost, |s| {
                Ok(homed(s)?.position_mm()?)
            })?;
        }
        self.advance(now)?;
        match &mut self.stage {
            StageDevice::Sim(stage) => homed(stage)?
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

    /// Stops the stage at once (the VXM's kill); a homing under way fails.
    pub fn stop(&mut self, now: Duration) -> Result<(), RigError> {
        self.advance(now)?;
        match &mut self.stage {
            StageDevice::Sim(stage) => stage.kill().map_err(|e| RigError::Refused(stage_error(e))),
            StageDevice::Vxm { stage, link, kill } => {
                Self::with_vxm(stage, link, kill, &mut self.home_lost, |s| Ok(s.kill()?))
            }
        }
    }
}
