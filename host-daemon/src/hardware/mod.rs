//! The devices on the robot and their drivers: the segments' I2C bus (the Linux bus, the
//! poller and the bus budget), the Velmex VXM linear stage with its homing, the Pololu Maestro
//! servo, and real-time scheduling for the polling thread. Each device sits behind a trait
//! (embedded-hal's `I2c`, [`stage::Stage`], [`servo::Servo`]) with a fake in [`crate::sim`].

pub mod bus_budget;
pub mod homing;
#[cfg(target_os = "linux")]
pub mod i2c_bus;
pub mod maestro;
pub(crate) mod poll;
pub mod realtime;
pub mod servo;
pub mod stage;
pub mod vxm;
