//! Quasi-static contact with walls: non-penetration of every link and hair tip, Coulomb
//! friction that truly sticks, anchoring hairs, snaps (docs/model.md 6-7, thesis 3.2-3.3, 4.2).
//!
//! # The model
//! The base moves in small steps; inertia is neglected (the thesis's base speeds are
//! 2-17 mm/s). A sweep's base only moves ([`QuasiStatic::step_to`]: its pivot steps, the
//! base link's angle `theta_0` stays); a mobile robot's base moves and turns at every step
//! ([`QuasiStatic::step_to_pose`]: pivot and `theta_0` together; the joint angles
//! `theta_1..theta_n` are relative, so the chain turns with its base, and a hand holding
//! the tip turns with it too). Each step finds the posture where the spring torques balance
//! the contact forces, with
//! - **non-penetration** of every link (its ends and, against a wall corner or crest, its
//!   interior) and of every hair tip: normal force `N >= 0` complementary to the gap, one
//!   per feature pair (`pair.rs`: a chain point against a wall's surface, a convex corner
//!   or crest against a link, and a point on a convex corner against the line of the edge
//!   it lies on, where its own distance would turn its normal without bound; without
//!   friction a loaded point slips off a convex corner, as it does in the world);
//! - **Coulomb friction per step**: a contact's material point does not move along the wall
//!   while `|T| < mu N` (stuck: exactly, no creep) and slides with `T = -mu N sign(slip)`
//!   otherwise; the slip is measured from where the point was at the start of the step
//!   (the committed state: the base pivot and the base angle the step starts from, while
//!   the broad phase and the predictor look at the goal's), so the friction state carries
//!   from step to step, and a contact stuck on a wall stays there while the base turns;
//! - **hairs** (docs/model.md 7): each hair angle is a coordinate with its spring and its range
//!   `[0, open]`, taking part only while its tip is near a wall. On a rough surface a hair
//!   tip open against its stop and loaded toward opening **anchors**: it sticks and holds up
//!   to the surface's shear and tension strengths; a load that folds it lets it collapse and
//!   slide with the surface's Coulomb friction.
//!
//! The equations of a step are a nonlinear complementarity problem, solved by a semismooth
//! Newton method on the coordinates and the contact forces together (`step_solver/`). A step that
//! fails to converge, or moves a joint by more than [`ContactSettings::jump_rad`], is split
//! in halves, its displacement and its turn together (a step's size is
//! `max(|d base|, reach |d angle|)`, [`QuasiStatic::reach_m`] the farthest a point of the
//! chain is from the pivot: a pure turn is split too); where the posture's branch of
//! equilibria ends (the antenna flips or springs forward) the posture follows the downhill
//! path by implicit steps of the friction-aware gradient flow and the step reports a snap.
//! Every accepted solve has its residuals (equilibrium, gaps, slips, the complementarity of
//! forces, joint-limit multipliers of the right sign) below [`ContactSettings::tolerance_m`];
//! [`QuasiStatic::check`] re-derives them independently (each contact's slip too, from the
//! committed state the step started from).
//!
//! A scene pays only for what it has: without walls a step does no contact work, hair angles
//! are coordinates only while their tips are near a wall, and a frictionless contact has no
//! stick state to carry.
//!
//! # The stages
//! The solver is three stages (the broad phase, the step solver, the certifier), the driver
//! that passes values between them, and the two states they read (the world, the committed
//! state). Each owns its state, its fields private to its module
//! (`tests/tests/cross/contact_stages.rs` checks that no module writes a field it does not
//! own):
//!
//! | stage | owns | reads | gives |
//! |---|---|---|---|
//! | `world.rs` | the chain, the walls and their contact pieces, the loads, the settings | | every stage's inputs |
//! | `committed.rs` | the equilibrium reached: base pose, joint and hair angles, contacts, the hand's force, the state the last (sub)step started from | an accepted answer | the start of the next step |
//! | `broad_phase/` | the start and probe postures | the world, the committed state, the goal pose, the secant prediction | a step's candidate pairs; after a solve, pairs missed, let go, passed on or handed over |
//! | `step_solver/` | the Newton scratch space, the last repair, its counters | a `StepProblem`, a start and the pairs | the answer and an outcome (converged, iterations, residual) |
//! | `certifier.rs` | nothing | the world and the committed state | an [`EquilibriumCheck`] |
//! | `driver/` ([`QuasiStatic`]) | the secant, friction dropped or locked, anchoring blocked | | the public API: steps split in substeps, snaps followed downhill, anchors, jams |
//!
//! One (sub)step (`driver/substep.rs`): the broad phase gives the pairs; rounds of the step
//! solver's solve and the broad phase's revision (and the driver's anchoring) until the pairs
//! stand; the answer, if no joint jumps, is committed; the certifier checks the state.
//!
//! # Example: a flexible antenna dragged along a smooth wall
//! ```
//! use nalgebra::Vector2;
//! use sim_core::contact::{ContactSettings, QuasiStatic, Slip};
//! use sim_core::{Chain, Line, SolidSide, Wall};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let chain = Chain::builder(4)
//!     .link_length_m(0.04)
//!     .base_angle_rad(30f64.to_radians())
//!     .stiffness_nm_per_rad(0.01)
//!     .build()?;
//! // A wall along x at y = 0.09 m, solid above: the straight antenna reaches y = 0.1.
//! let wall = Wall::smooth(Line::new(Vector2::new(0.0, 0.12), 0.0, SolidSide::Left)?);
//! let theta = chain.rest_theta();
//! let mut sim = QuasiStatic::new(chain, vec![wall], Vector2::zeros(), &theta, ContactSettings::default())?;
//! // Bring the wall's distance down to 0.09 m by moving the base up, 0.5 mm at a time.
//! for k in 1..=60 {
//!     sim.step_to(Vector2::new(0.0, 0.0005 * k as f64))?;
//! }
//! let contacts = sim.contacts();
//! assert!(!contacts.is_empty());
//! for c in &contacts {
//!     assert!(c.normal_force_n >= 0.0);
//!     assert!(c.shear_force_n.abs() <= 0.3 * c.normal_force_n + 1e-12);
//! }
//! // Now drag it along the wall: the tip slides backward relative to the base.
//! sim.step_to(Vector2::new(0.001, 0.03))?;
//! assert!(sim.contacts().iter().any(|c| c.slip != Slip::Stuck));
//! // A robot's base turns as it moves: 2 mm ahead and 1 degree toward the wall.
//! let turned_rad = sim.base_angle_rad() + 1f64.to_radians();
//! sim.step_to_pose(Vector2::new(0.003, 0.03), turned_rad)?;
//! assert_eq!(sim.chain().base_angle_rad(), turned_rad);
//! assert!(!sim.contacts().is_empty());
//! # Ok(())
//! # }
//! ```

// The stages, each owning its state (private to its module): `world` (what a step is taken
// in), `committed` (the equilibrium the last step reached), `broad_phase` (which pairs take
// part), `step_solver` (a step's equations, solved), `certifier` (the independent check,
// no state) and `driver` (substeps, snaps, anchoring, placement: `QuasiStatic`). The rest
// are the values they pass: pairs, postures, geometry, the settings, the report, errors.
mod broad_phase;
mod certifier;
mod committed;
mod driver;
mod error;
mod feature;
mod geometry;
mod pair;
mod pieces;
mod posture;
mod report;
mod settings;
mod step_solver;
mod world;

pub use certifier::{CertifyTolerances, EquilibriumCheck};
pub use driver::{Jam, JammedContact, QuasiStatic};
pub use error::ContactError;
pub use feature::{Contact, Feature, FrictionLaw, Slip};
pub use report::StepReport;
pub use settings::ContactSettings;
