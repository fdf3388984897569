//! The device layer's simulated side: the rig antennad runs with no hardware configured, and
//! the stand-ins the tests use. The virtual I2C bus whose segments run the firmware's own
//! logic ([`SimBus`](crate::SimBus)), the simulated stage and servo as the rig's devices
//! ([`devices`], on the fakes [`FakeStage`](crate::FakeStage) and
//! [`FakeServo`](crate::FakeServo)), the one simulated world whose physics they move and
//! the segments sense ([`rig`]), and pseudo-terminal emulators of the VXM and the Maestro
//! ([`emulator`]).
//!
//! It builds on [`crate::config`] and the hardware traits ([`crate::hardware`]) only.

pub(crate) use antenna_bus::sim_bus as bus;
pub mod devices;
pub mod emulator;
pub(crate) mod fake_servo;
pub(crate) mod fake_stage;
pub mod rig;
