//! The simulated rig's physics: the antenna against its flat wall, on sim-core's quasi-static
//! contact solver ([`sim_core::contact::QuasiStatic`]).
//!
//! `antennad`'s simulated segments sense the posture [`SimPhysics`] computes for the stage
//! position and base angle, and `antenna-monitor` predicts the chain with the same code for
//! the rig a stream or a recording describes. Every link and joint is kept out of the wall,
//! Coulomb friction sticks and slips (`mu`), snaps are followed downhill. Each new base
//! position is one step of a sweep; a new base angle rebuilds the solver from the current
//! posture, backed off the wall if the turn would put the antenna into it, and steps back. A
//! segment's touch switches close where its link touches the wall
//! (`sim_core::touch_bits_from_contacts`), every contact or, with a touch threshold
//! ([`SimPhysics::set_touch_threshold_n`]), those pressing at least that hard.
//!
//! # Example
//!
//! ```
//! use antenna_sim_physics::{AntennaSpec, FlatWallSpec, SimPhysics};
//!
//! let antenna = AntennaSpec::default();
//! let mut physics = SimPhysics::new(&antenna, &FlatWallSpec::default())?;
//! let base_rad = antenna.base_angle_deg.to_radians();
//! let free = physics.update(0.0, base_rad)?;
//! assert_eq!(free.tip_force_n, 0.0);
//! let pressed = physics.update(0.15, base_rad)?;
//! assert!(pressed.tip_force_n > 0.0);
//! # Ok::<(), antenna_sim_physics::PhysicsError>(())
//! ```

mod physics;
mod spec;

pub use physics::{PhysicsError, SimPhysics, SimState};
pub use spec::{AntennaSpec, FlatWallSpec};
