//! The Linux I2C bus (`/dev/i2c-N`): [`antenna_bus::linux_i2c`], shared with `antenna
//! segments`; here, how the poller counts what it reports (how an errno becomes an error
//! kind is antenna-bus's, tested there: `crates/antenna-bus/tests/linux_i2c_errors.rs`).

pub use antenna_bus::linux_i2c::*;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{PollError, Poller};
    use embedded_hal::i2c::{ErrorType, I2c, Operation};

    /// A bus whose every transfer fails with one errno.
    struct FailingBus(i32);

    impl ErrorType for FailingBus {
        type Error = LinuxI2cError;
    }

    impl I2c for FailingBus {
        fn transaction(&mut self, _: u8, _: &mut [Operation<'_>]) -> Result<(), LinuxI2cError> {
            Err(LinuxI2cError::from_errno(self.0))
        }
    }

    #[test]
    fn eremoteio_is_counted_as_a_nack_and_eio_as_a_bus_error() {
        for (errno, nack) in [
            (libc::EREMOTEIO, true),
            (libc::ENXIO, true),
            (libc::EIO, false),
            (libc::ETIMEDOUT, false),
            (libc::ENODEV, false),
        ] {
            let mut poller = Poller::new(FailingBus(errno), &[0x21, 0x22]);
            let readings = poller.poll_all();
            if nack {
                assert_eq!(readings[0].result, Err(PollError::Nack { address: 0x21 }));
            } else {
                assert!(
                    matches!(
                        readings[1].result,
                        Err(PollError::Bus { address: 0x22, .. })
                    ),
                    "errno {errno}: {:?}",
                    readings[1].result
                );
            }
            for health in poller.health() {
                assert_eq!(
                    (health.nacks, health.bus_errors),
                    if nack { (1, 0) } else { (0, 1) },
                    "errno {errno}"
                );
            }
        }
    }
}
