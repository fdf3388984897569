//! The Maestro as the rig's [`ServoDevice`], reopened when its port vanished.

use crate::hardware::device::{DeviceError, ServoDevice};
use crate::hardware::maestro::{Maestro, MaestroConfig, MaestroError};
use crate::hardware::serial_link::{Link, open_serial};
use crate::hardware::servo::Servo;
use serialport::SerialPort;

/// The Maestro's serial rate (its USB command port ignores it; the TTL port is set to it).
pub const MAESTRO_BAUD: u32 = 9600;

/// A Maestro on a serial port.
#[derive(Debug)]
pub struct MaestroDevice {
    servo: Box<Maestro<Box<dyn SerialPort>>>,
    link: Link,
}

impl MaestroDevice {
    /// The Maestro on `path` (`servo.port`); the error names the key.
    pub fn open(path: &str, config: MaestroConfig) -> Result<Self, String> {
        let port = open_serial("servo.port", path, MAESTRO_BAUD)?;
        Ok(Self {
            servo: Box::new(Maestro::new(port, config)),
            link: Link::new("servo", path.to_owned(), MAESTRO_BAUD),
        })
    }

    /// Runs `f` on the Maestro, reopening its port first if it had vanished.
    fn with<T>(
        &mut self,
        f: impl FnOnce(&mut Maestro<Box<dyn SerialPort>>) -> Result<T, MaestroError>,
    ) -> Result<T, DeviceError> {
        if let Some(port) = self.link.reopen()? {
            self.servo.reconnect(port);
            self.link.back();
        }
        match f(&mut self.servo) {
            Ok(v) => Ok(v),
            Err(MaestroError::Disconnected(e)) => Err(self.link.lost(e.to_string())),
            Err(e) => Err(DeviceError::Refused(format!("servo: {e}"))),
        }
    }
}

impl ServoDevice for MaestroDevice {
    fn description(&self) -> String {
        format!("Maestro on {}", self.link.path())
    }

    fn available(&self) -> bool {
        self.link.available()
    }

    fn set_angle_rad(&mut self, angle_rad: f64) -> Result<(), DeviceError> {
        self.with(|m| m.set_angle_rad(angle_rad))
    }

    fn angle_rad(&mut self) -> Result<f64, DeviceError> {
        self.with(|m| m.angle_rad())
    }
}
