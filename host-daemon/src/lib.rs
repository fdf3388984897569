//! `antennad`, the antenna host daemon: polls the segments on the I2C bus and decodes their
//! samples with `antenna-protocol`.
//!
//! The bus is any embedded-hal 1.0 [`embedded_hal::i2c::I2c`]. With no hardware configured
//! the daemon runs on [`SimBus`], a virtual bus whose segments run `firmware-segment`'s own
//! logic (oversampling, debouncing and the I2C target state machine), so the whole path from
//! sensor to sample is the one the robot uses.
//!
//! # Example
//!
//! ```
//! use antenna_protocol::Calibration;
//! use host_daemon::{Poller, SimBus, SimSegment};
//!
//! let bus = SimBus::new(vec![SimSegment::new(0x21, Calibration::default())]);
//! let mut poller = Poller::new(bus, &[0x21]);
//! poller.bus_mut().segment_mut(0).map(|s| s.set_angle_rad(0.5));
//! poller.bus_mut().sample_all();
//! let readings = poller.poll_all();
//! let word = readings[0].result.as_ref().expect("the segment answers");
//! assert!((Calibration::default().angle_rad(word.angle_counts()) - 0.5).abs() < 0.002);
//! ```

pub mod acquisition;
pub mod bus_budget;
pub mod clock;
pub mod commission;
pub mod config;
pub mod config_source;
pub mod daemon;
pub mod emulator;
mod fake_servo;
mod fake_stage;
pub mod free_space;
pub mod homing;
#[cfg(target_os = "linux")]
pub mod i2c_bus;
pub mod maestro;
mod motion;
pub mod net;
mod poll;
pub mod realtime;
pub mod rig;
pub mod samples;
pub mod service;
pub mod servo;
mod sim_bus;
pub mod sim_rig;
pub mod stage;
pub mod stdout_lines;
mod trial_script;
pub mod vxm;
pub mod watchdog;

pub use fake_servo::{FakeServo, FakeServoError};
pub use fake_stage::{FakeStage, FakeStageError};
pub use maestro::{Maestro, MaestroConfig, MaestroError};
pub use net::{ControlHandler, ControlToken, StreamServer};
pub use poll::{CounterCheck, PollError, Poller, SegmentHealth, SegmentReading};
pub use servo::{PulseCalibration, Servo};
pub use sim_bus::{SegmentFault, SimBus, SimBusError, SimSegment};
pub use stage::{LimitedStage, Stage, StageError, StageGeometry};
pub use vxm::{Vxm, VxmError};
