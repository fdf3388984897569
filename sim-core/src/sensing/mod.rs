//! What the antenna senses and what it tells about the wall (thesis 2.3.1, 4.2; docs/model.md
//! 8): the sensors as they are, wall-following metrics of a posture, wall maps estimated from
//! the sensor readings, and how much of the wall a map covers.
//!
//! - [`sensor`]: the departures of real sensors from the ideal joint angles and touch switches.
//! - [`metrics`]: point of bend, point of contact, preview distance, flip detection and
//!   correlations.
//! - [`mapping`]: wall contact points estimated from 12-bit joint angles and touch bits, and
//!   their error against the true wall (thesis 4.2.2).
//! - [`coverage`]: how much of the wall section passed a map captured.

pub mod coverage;
pub mod mapping;
pub mod metrics;
pub mod sensor;
