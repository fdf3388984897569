//! A serial device that may vanish (unplugged, USB reset) and come back: while it is gone its
//! calls fail at once with [`DeviceError::Unavailable`], and its port is reopened at most every
//! [`REOPEN_INTERVAL`].

use crate::hardware::device::DeviceError;
use serialport::SerialPort;
use std::time::{Duration, Instant};

/// How often a vanished serial device is looked for again.
pub const REOPEN_INTERVAL: Duration = Duration::from_millis(250);
/// Read timeout of the serial ports (the drivers' own deadlines are built from these reads).
const PORT_READ_TIMEOUT: Duration = Duration::from_millis(5);

/// A port opened from a configured path (8N1, no flow control); the error names the key.
pub fn open_serial(key: &str, path: &str, baud: u32) -> Result<Box<dyn SerialPort>, String> {
    serialport::new(path, baud)
        .data_bits(serialport::DataBits::Eight)
        .parity(serialport::Parity::None)
        .stop_bits(serialport::StopBits::One)
        .flow_control(serialport::FlowControl::None)
        .timeout(PORT_READ_TIMEOUT)
        .open()
        .map_err(|e| format!("`{key}` = {path:?}: cannot open the serial port: {e}"))
}

/// The state of a serial device's port: there, or gone and looked for again.
#[derive(Debug)]
pub struct Link {
    part: &'static str,
    path: String,
    baud: u32,
    available: bool,
    reason: String,
    next_try: Instant,
}

impl Link {
    /// The `part` (`"stage"`, `"servo"`) on the port at `path`, open now.
    pub fn new(part: &'static str, path: String, baud: u32) -> Self {
        Self {
            part,
            path,
            baud,
            available: true,
            reason: String::new(),
            next_try: Instant::now(),
        }
    }

    /// The configured port.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// Whether the device answers.
    pub fn available(&self) -> bool {
        self.available
    }

    fn unavailable(&self) -> DeviceError {
        DeviceError::Unavailable {
            part: self.part,
            path: self.path.clone(),
            reason: self.reason.clone(),
        }
    }

    /// A new port if the device is gone and it is time to look for it again; the device is
    /// available again once the caller has put it back on line ([`Link::back`]).
    pub fn reopen(&mut self) -> Result<Option<Box<dyn SerialPort>>, DeviceError> {
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

    /// The device answers again.
    pub fn back(&mut self) {
        self.available = true;
        self.reason.clear();
    }

    /// The device is gone (`reason`): unavailable until its port opens again.
    pub fn lost(&mut self, reason: String) -> DeviceError {
        self.available = false;
        self.reason = reason;
        self.next_try = Instant::now() + REOPEN_INTERVAL;
        self.unavailable()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lost_device_is_unavailable_until_its_port_opens_again() {
        let mut link = Link::new("stage", "/dev/nonexistent-antennad-port".to_owned(), 9600);
        assert!(link.available());
        assert!(matches!(link.reopen(), Ok(None)));
        let e = link.lost("unplugged".to_owned());
        assert_eq!(
            e.to_string(),
            "the stage is unavailable (/dev/nonexistent-antennad-port: unplugged)"
        );
        assert!(!link.available());
        // Too soon to look again: the same reason, at once.
        assert_eq!(link.reopen().unwrap_err(), e);
        link.back();
        assert!(link.available());
    }
}
