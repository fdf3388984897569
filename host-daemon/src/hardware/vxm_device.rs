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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hardware::stage::HomingDirection;
    use crate::sim::emulator::{VxmEmulator, VxmFault};
    use serialport::TTYPort;
    use std::path::Path;

    /// Only a hang takes this long, however loaded the machine.
    const PATIENCE: Duration = Duration::from_secs(60);

    /// An emulated VXM on a new pseudo-terminal, its slave side reached through `link`.
    fn vxm_behind(link: &Path, fault: VxmFault) -> VxmEmulator {
        let (master, slave) = TTYPort::pair().unwrap();
        let path = slave.name().unwrap();
        drop(slave);
        let vxm = VxmEmulator::spawn(master);
        vxm.set_fault(fault);
        std::os::unix::fs::symlink(path, link).unwrap();
        vxm
    }

    /// Calls `is_moving` until it answers `Ok`, and returns the errors on the way.
    fn until_it_answers(device: &mut VxmDevice) -> Vec<DeviceError> {
        let deadline = Instant::now() + PATIENCE;
        let mut errors = Vec::new();
        loop {
            match device.is_moving() {
                Ok(_) => return errors,
                Err(e) => errors.push(e),
            }
            assert!(
                Instant::now() < deadline,
                "it never answered again: {:?}",
                errors.last()
            );
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    #[test]
    fn a_vxm_whose_first_handshake_fails_after_it_vanished_is_reopened_until_it_answers() {
        let dir = std::env::temp_dir().join(format!("antennad-vxm-device-{}", std::process::id()));
        std::fs::remove_dir_all(&dir).ok();
        std::fs::create_dir_all(&dir).unwrap();
        let link = dir.join("vxm");
        let vxm = vxm_behind(&link, VxmFault::None);
        let homing = HomingSettings {
            toward: HomingDirection::Negative,
            speed_steps_per_s: 800,
            timeout: Duration::from_secs(10),
        };
        let geometry = StageGeometry::new(80.0, 0.0, 60.0).unwrap();
        let mut device = VxmDevice::open(
            link.to_str().unwrap(),
            9600,
            Duration::from_millis(200),
            geometry,
            homing,
        )
        .unwrap();
        assert!(until_it_answers(&mut device).is_empty());

        // It vanishes: unavailable from the next call on.
        vxm.close();
        std::fs::remove_file(&link).unwrap();
        let gone = until_it_answers_not(&mut device);
        assert!(matches!(gone, DeviceError::Unavailable { .. }), "{gone}");
        assert!(!device.available());

        // It comes back hung: the handshake on the new port (`V`) goes unanswered.
        let vxm = vxm_behind(&link, VxmFault::Stall);
        let deadline = Instant::now() + PATIENCE;
        while !vxm.received().contains(&b'V') {
            assert!(Instant::now() < deadline, "the port was never reopened");
            let _ = device.is_moving();
            std::thread::sleep(Duration::from_millis(5));
        }
        let deadline = Instant::now() + PATIENCE;
        let failed = loop {
            match device.is_moving() {
                Err(e @ DeviceError::Unavailable { .. })
                    if e.to_string().contains("back on line") =>
                {
                    break e;
                }
                other => assert!(Instant::now() < deadline, "{other:?}"),
            }
            std::thread::sleep(Duration::from_millis(5));
        };
        assert!(!device.available(), "{failed}");

        // Then it answers: the port is opened anew (the failed one closed, with its lock) and
        // the VXM put on line.
        vxm.set_fault(VxmFault::None);
        let errors = until_it_answers(&mut device);
        assert!(device.available(), "{errors:?}");
        assert!(vxm.is_online(), "{errors:?}");
        assert!(
            errors.iter().all(|e| !e.to_string().contains("lock")),
            "{errors:?}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }

    /// Calls `is_moving` until it fails, and returns the error.
    fn until_it_answers_not(device: &mut VxmDevice) -> DeviceError {
        let deadline = Instant::now() + PATIENCE;
        loop {
            if let Err(e) = device.is_moving() {
                return e;
            }
            assert!(Instant::now() < deadline, "it never vanished");
            std::thread::sleep(Duration::from_millis(5));
        }
    }
}
