//! The antenna segments' I2C bus as the host sees it, shared by `antennad` (which polls it)
//! and the `antenna` command (which commissions it), so that neither depends on the other:
//!
//! - [`SimBus`]: a virtual bus whose segments run `firmware-segment`'s own logic
//!   (oversampling, debouncing and the I2C target state machine), their Hall sensors ideal
//!   or as they are ([`hall_sensor`]: calibration errors, seeded noise on each conversion);
//! - `linux_i2c::LinuxI2cBus` (Linux only): `/dev/i2c-N`, with a failed transfer's errno
//!   sorted into a NACK (`ENXIO`, `EREMOTEIO`) or a bus error;
//! - [`commission`]: scan, assign addresses, measure `zero_counts` and read the firmware's
//!   status and version, on any embedded-hal [`embedded_hal::i2c::I2c`];
//! - [`config`]: the `[bus]` table of antennad's configuration (the device, the poll, the
//!   segments' addresses and calibrations), which `antenna segments` reads too.
//!
//! # Example
//!
//! ```
//! use antenna_bus::commission::{ASSIGNABLE, scan};
//! use antenna_bus::{SimBus, SimSegment};
//! use antenna_protocol::Calibration;
//!
//! let mut bus = SimBus::new(vec![SimSegment::new(0x21, Calibration::default())]);
//! bus.sample_all();
//! let found = scan(&mut bus, ASSIGNABLE).expect("the simulated bus has no faults");
//! assert_eq!(found.len(), 1);
//! assert_eq!(found[0].address, 0x21);
//! ```

pub mod commission;
pub mod config;
pub mod hall_sensor;
#[cfg(target_os = "linux")]
pub mod linux_i2c;
pub mod sim_bus;

pub use hall_sensor::{HallErrors, HallSensor, HallSensorError};
pub use sim_bus::{SegmentFault, SimBus, SimBusError, SimSegment};
