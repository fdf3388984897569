//! How a failed Linux I2C transfer is classified ([`antenna_bus::linux_i2c::LinuxI2cError`]):
//! the errno it carries, from linux-embedded-hal's error as from a bare errno, decides
//! whether it is a missing acknowledge (a segment that does not answer) or a bus error.
#![cfg(target_os = "linux")]

use antenna_bus::linux_i2c::LinuxI2cError;
use embedded_hal::i2c::{Error as _, ErrorKind, NoAcknowledgeSource};
use linux_embedded_hal::I2CError;

#[test]
fn an_io_error_from_linux_embedded_hal_keeps_its_errno() {
    let hal = I2CError::from(i2cdev::linux::LinuxI2CError::Io(
        std::io::Error::from_raw_os_error(libc::EREMOTEIO),
    ));
    let error = LinuxI2cError::from(hal);
    assert_eq!(error.errno(), Some(libc::EREMOTEIO));
    assert_eq!(
        error.kind(),
        ErrorKind::NoAcknowledge(NoAcknowledgeSource::Unknown)
    );
    let hal = I2CError::from(i2cdev::linux::LinuxI2CError::Errno(libc::EIO));
    assert_eq!(LinuxI2cError::from(hal).kind(), ErrorKind::Bus);
}

#[test]
fn each_errno_of_the_kernel_i2c_faults_has_its_kind() {
    for (errno, kind) in [
        (
            libc::ENXIO,
            ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address),
        ),
        (
            libc::EREMOTEIO,
            ErrorKind::NoAcknowledge(NoAcknowledgeSource::Unknown),
        ),
        (
            libc::ENODEV,
            ErrorKind::NoAcknowledge(NoAcknowledgeSource::Data),
        ),
        (libc::EAGAIN, ErrorKind::ArbitrationLoss),
        (libc::EIO, ErrorKind::Bus),
        (libc::ETIMEDOUT, ErrorKind::Bus),
        (libc::EPERM, ErrorKind::Other),
    ] {
        let error = LinuxI2cError::from_errno(errno);
        assert_eq!(error.errno(), Some(errno));
        assert_eq!(error.kind(), kind, "errno {errno}");
        assert!(!error.to_string().is_empty());
    }
}
