//! Opening the hardware I2C bus (`bus.device = "/dev/i2c-N"`) through linux-embedded-hal,
//! whose `I2cdev` implements embedded-hal 1.0's [`I2c`].
//!
//! linux-embedded-hal's `I2cdev` reopens the device whenever the target address changes;
//! polling nine segments a millisecond would do that nine thousand times a second. So
//! [`LinuxI2cBus`] opens one `I2cdev` per segment address at start (each keeps its address)
//! plus one for any other address.
//!
//! A failed transfer's errno is sorted as the kernel's I2C fault codes say
//! (Documentation/i2c/fault-codes): `ENXIO` (no acknowledge of the address) and
//! `EREMOTEIO` (what several controller drivers answer for a missing acknowledge, which
//! linux-embedded-hal leaves as `ErrorKind::Other`) are NACKs; `ENODEV` a data NACK, `EAGAIN`
//! a lost arbitration, `EIO`, `EBUSY`, `EINVAL`, `ETIMEDOUT` and the rest bus errors
//! ([`LinuxI2cError`]).
//!
//! ```
//! use antenna_bus::linux_i2c::LinuxI2cBus;
//!
//! let error = LinuxI2cBus::open("/dev/i2c-250", &[0x20]).unwrap_err();
//! assert!(error.to_string().starts_with("`bus.device` = \"/dev/i2c-250\": cannot open"));
//! ```

use embedded_hal::i2c::{Error as _, ErrorKind, ErrorType, I2c, NoAcknowledgeSource, Operation};
use linux_embedded_hal::{I2CError, I2cdev};

/// The I2C device named by `bus.device` could not be opened.
#[derive(Debug, thiserror::Error)]
#[error(
    "`bus.device` = {path:?}: cannot open the I2C bus: {reason} (is the i2c-dev module loaded, \
     the bus enabled and this user allowed to open it? bus.device = \"sim\" runs the \
     simulated rig)"
)]
pub struct BusOpenError {
    /// The device path from the configuration.
    pub path: String,
    /// What the kernel said.
    pub reason: String,
}

/// A Linux I2C character device, one open file per segment address.
pub struct LinuxI2cBus {
    path: String,
    devices: Vec<(u8, I2cdev)>,
    other: I2cdev,
}

impl std::fmt::Debug for LinuxI2cBus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LinuxI2cBus")
            .field("path", &self.path)
            .field("addresses", &self.addresses())
            .finish_non_exhaustive()
    }
}

impl LinuxI2cBus {
    /// Opens the I2C character device at `path` (e.g. `/dev/i2c-1`) once per address in
    /// `addresses` and once more for any other address.
    pub fn open(path: &str, addresses: &[u8]) -> Result<Self, BusOpenError> {
        let open = || {
            I2cdev::new(path).map_err(|e| BusOpenError {
                path: path.to_owned(),
                reason: e.to_string(),
            })
        };
        let other = open()?;
        let devices = addresses
            .iter()
            .map(|&a| open().map(|d| (a, d)))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            path: path.to_owned(),
            devices,
            other,
        })
    }

    /// The device path.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// The addresses with their own open device.
    pub fn addresses(&self) -> Vec<u8> {
        self.devices.iter().map(|(a, _)| *a).collect()
    }
}

/// A failed transfer on a Linux I2C device: its errno, sorted into an [`ErrorKind`].
///
/// ```
/// use embedded_hal::i2c::{Error, ErrorKind, NoAcknowledgeSource};
/// use antenna_bus::linux_i2c::LinuxI2cError;
///
/// // EREMOTEIO (121): a missing acknowledge on drivers that say so.
/// let error = LinuxI2cError::from_errno(121);
/// assert_eq!(error.kind(), ErrorKind::NoAcknowledge(NoAcknowledgeSource::Unknown));
/// assert_eq!(LinuxI2cError::from_errno(5).kind(), ErrorKind::Bus); // EIO
/// ```
#[derive(Debug, thiserror::Error)]
#[error("{message}")]
pub struct LinuxI2cError {
    errno: Option<i32>,
    kind: ErrorKind,
    message: String,
}

impl LinuxI2cError {
    /// The error of a transfer that failed with `errno`.
    pub fn from_errno(errno: i32) -> Self {
        Self {
            errno: Some(errno),
            kind: errno_kind(errno),
            message: std::io::Error::from_raw_os_error(errno).to_string(),
        }
    }

    /// The errno, when the failure had one.
    pub fn errno(&self) -> Option<i32> {
        self.errno
    }
}

impl From<I2CError> for LinuxI2cError {
    fn from(error: I2CError) -> Self {
        let errno = match error.inner() {
            i2cdev::linux::LinuxI2CError::Errno(errno) => Some(*errno),
            i2cdev::linux::LinuxI2CError::Io(e) => e.raw_os_error(),
        };
        match errno {
            Some(errno) => Self::from_errno(errno),
            None => Self {
                errno: None,
                kind: error.kind(),
                message: error.to_string(),
            },
        }
    }
}

impl embedded_hal::i2c::Error for LinuxI2cError {
    fn kind(&self) -> ErrorKind {
        self.kind
    }
}

/// The kind of a failed I2C transfer's errno (the kernel's I2C fault codes).
fn errno_kind(errno: i32) -> ErrorKind {
    match errno {
        libc::ENXIO => ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address),
        libc::EREMOTEIO => ErrorKind::NoAcknowledge(NoAcknowledgeSource::Unknown),
        libc::ENODEV => ErrorKind::NoAcknowledge(NoAcknowledgeSource::Data),
        libc::EAGAIN => ErrorKind::ArbitrationLoss,
        libc::EIO | libc::EBUSY | libc::EINVAL | libc::ETIMEDOUT | libc::EPROTO => ErrorKind::Bus,
        _ => ErrorKind::Other,
    }
}

impl ErrorType for LinuxI2cBus {
    type Error = LinuxI2cError;
}

impl I2c for LinuxI2cBus {
    fn transaction(
        &mut self,
        address: u8,
        operations: &mut [Operation<'_>],
    ) -> Result<(), Self::Error> {
        let device = match self.devices.iter_mut().find(|(a, _)| *a == address) {
            Some((_, device)) => device,
            None => &mut self.other,
        };
        device
            .transaction(address, operations)
            .map_err(LinuxI2cError::from)
    }
}
