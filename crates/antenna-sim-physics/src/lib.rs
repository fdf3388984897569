//! The simulated rig's physics: a scene's antenna (hairs included) against its walls (of any
//! shape, with their zones and friction), on sim-core's quasi-static contact solver
//! ([`sim_core::contact::QuasiStatic`]), its base carried by a stage and turned by a servo.
//!
//! `antennad`'s simulated segments sense the posture [`SimPhysics`] computes, and
//! `antenna-monitor` predicts the chain with the same code for the scene a stream or a
//! recording describes. The physics is built from sim-core's [`SweepScene`](sim_core::sweep::SweepScene) (what a scene
//! file's `Scene::sweep_scene` gives):
//!
//! - stage position `s` puts the base pivot at `base_start_m + s * u`, `u` the unit vector of
//!   the scene's direction of motion (`motion.velocity_m_per_s`; `+x` when it is zero);
//! - the servo angle turns the base link: its angle is the scene's base angle plus the servo
//!   angle ([`sim_core::sweep::turn_base`]: the joint angles kept, backed off the walls);
//! - the scene's placement ([`SweepScene::placement`](sim_core::sweep::SweepScene::placement)) is done when the physics is built (the
//!   stage at 0, the servo at 0) and again whenever [`SimPhysics::place`] is called (a trial
//!   starting), at the stage and servo of that moment ([`sim_core::sweep::place_at`]);
//! - every other new pose is one quasi-static step from the last one
//!   ([`sim_core::sweep::step_base_to`]), with the scene's contact settings.
//!
//! Every link and joint is kept out of the walls, Coulomb friction sticks and slips, snaps are
//! followed downhill. A segment's touch switches close where its link touches a wall
//! (`sim_core::touch_bits_from_contacts`), every contact or, with a touch threshold
//! ([`SimPhysics::set_touch_threshold_n`]), those pressing at least that hard.
//!
//! With [`SimPhysics::record_steps`] on, every placement and step is kept as a
//! [`PhysicsStep`] (its base pose and the joint angles it gave), so that a run can be replayed
//! through sim-core's own stepper and checked.
//!
//! # Example
//!
//! ```
//! use antenna_sim_physics::SimPhysics;
//! use nalgebra::Vector2;
//! use sim_core::sweep::{Placement, SweepScene};
//! use sim_core::{Chain, InitialGuess, Line, SolidSide, Wall};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let chain = Chain::builder(8)
//!     .link_length_m(0.04)
//!     .base_angle_rad(30f64.to_radians())
//!     .stiffness_nm_per_rad(0.01)
//!     .build()?;
//! let wall = Wall::smooth(Line::new(Vector2::new(0.0, 0.2), -8f64.to_radians(), SolidSide::Left)?);
//! let scene = SweepScene {
//!     placement: Placement::TipOnWall { wall: 0, ahead_m: 0.0, start: InitialGuess::C },
//!     ..SweepScene::new(chain, vec![wall])
//! };
//! let mut physics = SimPhysics::new(scene)?;
//! let placed = physics.state().clone();
//! assert!(placed.tip_force_n > 0.0);
//! let ahead = physics.update(0.05, 0.0)?;
//! assert_ne!(ahead.joint_angles_rad, placed.joint_angles_rad);
//! # Ok(())
//! # }
//! ```

mod physics;

pub use physics::{PhysicsError, PhysicsStep, SimPhysics, SimState, StepKind};
