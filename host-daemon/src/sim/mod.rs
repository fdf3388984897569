//! The simulated rig antennad runs with no hardware configured, and the stand-ins the tests
//! use: the virtual I2C bus whose segments run the firmware's own logic ([`SimBus`](crate::SimBus)), the rig's
//! physics on sim-core ([`rig`]), the fake stage and servo, and pseudo-terminal emulators of
//! the VXM and the Maestro ([`emulator`]).

pub(crate) use antenna_bus::sim_bus as bus;
pub mod emulator;
pub(crate) mod fake_servo;
pub(crate) mod fake_stage;
pub mod rig;
