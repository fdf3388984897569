//! The VXM as the rig's [`StageDevice`]: homed before it moves, with its kill line for a
//! `stop_all` that must not wait behind a query, reopened when its port vanished, and its home
//! lost when it comes back power-cycled (echoing, see [`crate::hardware::vxm`]).

use crate::hardware::device::{DeviceError, StageDevice, StageMove, homed, stage_error};
use crate::hardware::homing::{HomingEvent, HomingSettings, HomingStage, HomingState};
use crate::hardware::serial_link::{Link, open_serial};
use crate::hardware::stage::{LimitedStage, StageError, StageGeometry};
use crate::hardware::vxm::{Vxm, VxmError, VxmKill};
use serialport::SerialPort;
use std::time::{Duration, Instant};

type VxmStage = HomingStage<Vxm<Box<dyn SerialPort>>>;

/// What went wrong inside a call on the VXM: its own error or the device's verdict.
enum Fail {
    Stage(StageError<VxmError>),
    Device(DeviceError),
}

impl From<StageError<VxmError>> for Fail {
    fn from(e: StageError<VxmError>) -> Self {
        Self::Stage(e)
    }
}

impl From<DeviceError> for Fail {
    fn from(e: DeviceError) -> Self {
        Self::Device(e)
    }
}

/// A VXM on a serial port (see the module documentation).
#[derive(Debug)]
pub struct VxmDevice {
    stage: Box<VxmStage>,
    link: Link,
    kill: VxmKill,
    /// Why the stage lost its home since the rig last asked.
    home_lost: Option<String>,
}

impl VxmDevice {
    /// The VXM on `path` (`stage.port`) at `baud`, put on line, not homed; the error names
    /// the key.
    pub fn open(
        path: &str,
        baud: u32,
        reply_timeout: Duration,
        geometry: StageGeometry,
        homing: HomingSettings,
    ) -> Result<Self, String> {
        let port = open_serial("stage.port", path, baud)?;
        let kill = VxmKill::new();
        kill.arm(port.as_ref())
            .map_err(|e| format!("`stage.port` = {path:?}: cloning the port for kill: {e}"))?;
        let vxm = Vxm::new(port).with_reply_timeout(reply_timeout);
        let stage = LimitedStage::new(vxm, geometry)
            .online()
            .map_err(|e| format!("`stage.port` = {path:?}: {e}"))?;
        Ok(Self {
            stage: Box::new(HomingStage::new(stage, homing)),
            link: Link::new("stage", path.to_owned(), baud),
            kill,
            home_lost: None,
        })
    }

    /// Runs `f` on the VXM, reopening its port first if it had vanished (a VXM that comes
    /// back echoing was power-cycled: its home is lost); a vanished device makes the stage
    /// unavailable, an echo loses the home.
    fn with<T>(
        &mut self,
        f: impl FnOnce(&mut VxmStage) -> Result<T, Fail>,
    ) -> Result<T, DeviceError> {
        let Self {
            stage,
            link,
            kill,
            home_lost,
        } = self;
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
                            "the VXM on {} came back off line, echoing (power-cycled): its \
                             position is lost",
                            link.path()
                        ));
                    }
                }
                Err(e) => {
                    kill.disarm();
                    return Err(link.lost(format!("back on line: {e}")));
                }
            }
            link.back();
        }
        match f(stage) {
            Ok(v) => Ok(v),
            Err(Fail::Stage(StageError::Device(VxmError::Disconnected(e)))) => {
                kill.disarm();
                Err(link.lost(e.to_string()))
            }
            Err(Fail::Stage(StageError::Device(e @ VxmError::PowerCycled { .. }))) => {
                stage.lose_home();
                let why = format!("the VXM on {}: {e}", link.path());
                *home_lost = Some(why.clone());
                Err(DeviceError::NotHomed(why))
            }
            Err(Fail::Stage(e)) => Err(stage_error(e)),
            Err(Fail::Device(e)) => Err(e),
        }
    }
}

impl StageDevice for VxmDevice {
    fn description(&self) -> String {
        format!("VXM on {}", self.link.path())
    }

    fn available(&self) -> bool {
        self.link.available()
    }

    fn kill_line(&self) -> Option<VxmKill> {
        Some(self.kill.clone())
    }

    fn homing_state(&self) -> HomingState {
        self.stage.state()
    }

    fn retry_homing(&mut self) {
        self.stage.retry();
    }

    fn take_home_lost(&mut self) -> Option<String> {
        self.home_lost.take()
    }

    fn step_homing(&mut self, now: Instant) -> Result<Option<HomingEvent>, DeviceError> {
        self.with(|s| Ok(s.step(now)?))
    }

    fn start_move(&mut self, to: StageMove, speed_mm_per_s: f64) -> Result<(), DeviceError> {
        self.with(|s| Ok(to.start(homed(s)?, speed_mm_per_s)?))
    }

    fn is_moving(&mut self) -> Result<bool, DeviceError> {
        self.with(|s| Ok(s.is_moving()?))
    }

    fn position_mm(&mut self) -> Result<f64, DeviceError> {
        self.with(|s| Ok(homed(s)?.position_mm()?))
    }

    fn kill(&mut self) -> Result<(), DeviceError> {
        self.with(|s| Ok(s.kill()?))
    }
}
