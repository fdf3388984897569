//! `antennad`, the antenna host daemon: polls the segments on the I2C bus and decodes their
//! samples with `antenna-protocol`.
//!
//! The bus is any embedded-hal 1.0 [`embedded_hal::i2c::I2c`]. With no hardware configured
//! the daemon runs on [`SimBus`], a virtual bus whose segments run `firmware-segment`'s own
//! logic (oversampling, debouncing and the I2C target state machine), so the whole path from
//! sensor to sample is the one the robot uses.
//!
//! # Layout
//!
//! Five layers, lowest first; a module imports its own layer and the ones below it, never
//! one above (`tests/layers.rs` checks every `use` and `crate::` path, the re-exports below
//! resolved), so no circle of imports closes between them:
//!
//! 1. [`config`]: the configuration (schema, validation, where a key is written) and the
//!    values it must build to be valid (the control token, the stage's and servo's geometry,
//!    the bus budget); it imports no other layer;
//! 2. [`hardware`]: the drivers (the Linux I2C bus and the poller, the VXM stage and its
//!    homing, the Maestro servo) behind their traits, and the rig's view of a stage and a
//!    servo as trait objects ([`hardware::device`]);
//! 3. [`sim`]: the device layer's simulated side: the simulated stage, servo and bus, the one
//!    simulated world whose physics they move, the fakes, and the pseudo-terminal emulators
//!    of the serial devices;
//! 4. [`net`]: the TCP server (token, throttle, admission); it needs only `config`;
//! 5. [`service`]: the daemon (the rig, the hub, control, the polling thread and watchdog,
//!    the motion loop and trial script, systemd).
//!
//! The segments' bus itself (the Linux bus, the simulated bus, commissioning) is the
//! `antenna-bus` crate, shared with the `antenna` command.
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

pub mod config;
pub mod hardware;
pub mod net;
pub mod service;
pub mod sim;

pub use hardware::maestro::{Maestro, MaestroConfig, MaestroError};
pub use hardware::poll::{CounterCheck, PollError, Poller, SegmentHealth, SegmentReading};
pub use hardware::servo::{PulseCalibration, Servo};
pub use hardware::stage::{LimitedStage, Stage, StageError, StageGeometry};
pub use hardware::vxm::{Vxm, VxmError};
pub use net::{ControlHandler, ControlToken, StreamServer};
pub use sim::bus::{SegmentFault, SimBus, SimBusError, SimSegment};
pub use sim::fake_servo::{FakeServo, FakeServoError};
pub use sim::fake_stage::{FakeStage, FakeStageError};
