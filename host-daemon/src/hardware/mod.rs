//! The devices on the robot and their drivers: the segments' I2C bus (the Linux bus, the
//! poller and the bus budget), the Velmex VXM linear stage with its homing, the Pololu Maestro
//! servo, and real-time scheduling for the polling thread. Each device sits behind a trait
//! (embedded-hal's `I2c`, [`stage::Stage`], [`servo::Servo`]) with a fake in [`crate::sim`];
//! the rig drives the stage and the servo as trait objects ([`device::StageDevice`],
//! [`device::ServoDevice`]: the VXM in [`vxm_device`], the Maestro in [`maestro_device`],
//! reopened through [`serial_link`] when their ports vanish).
//!
//! Above [`crate::config`] (whose [`bus_budget`], stage geometry and pulse calibration it
//! re-exports), below everything else.

pub use crate::config::bus_budget;
pub mod device;
pub mod homing;
#[cfg(target_os = "linux")]
pub mod i2c_bus;
pub mod maestro;
pub mod maestro_device;
pub(crate) mod poll;
pub mod realtime;
pub mod serial_link;
pub mod servo;
pub mod stage;
pub mod vxm;
pub mod vxm_device;
