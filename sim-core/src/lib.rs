//! Kinematics of a planar antenna: a serial chain of rigid links with joint springs, after
//! the thesis (2.2, 3.2.1, appendix 6.1) and the contract `docs/model.md`
//! (sections 1-4 and 7), which wins where the two differ.
//!
//! # Conventions
//! - **Links.** `n + 1` rigid links: link 0 is the base link, links `1..=n` the flagellum.
//!   Link `i` is `l_i` metres long ([`Chain::link_lengths_m`]).
//! - **Angles.** `theta` has `n + 1` entries, radians, counter-clockwise positive.
//!   `theta_0` is the base angle from the ground x-axis (the direction of base motion);
//!   `theta_j` (`j >= 1`) is joint `j`'s angle relative to link `j - 1`. The absolute
//!   angle of link `i` is `phi_i = theta_0 + ... + theta_i`.
//! - **Frames** ([`Frame`]). The ground frame `C_G` has index `-1` and sits at the base
//!   attachment. Frame `C_i` (`i = 0..=n`) sits at the distal end of link `i`, x-axis along
//!   the link: `p_i = sum_{k <= i} l_k (cos phi_k, sin phi_k)`. `C_n` is the tip. Joint `j`
//!   sits at the origin of `C_{j-1}` (joint 0 at the base).
//! - **Pairs `(s, b)`.** Any frame can be the spatial frame `s`; results about a body frame
//!   `b` are relative to `C_s` and written in `C_s` (the thesis's `p_sb`, `theta_sb`,
//!   `J_sb`). Per-frame lists hold frames `-1..=n` in order: entry `b + 1` is frame `b`.
//! - **Velocities** are hybrid (the thesis's `V_h`): `(p_dot_sb, omega_sb)` in `C_s`; body and
//!   spatial Jacobians are in [`JacobianKind`](kinematics::jacobian::JacobianKind).
//! - **Units** are SI and named: `_m`, `_rad`, `_nm` (newton-metres), `_n` (newtons),
//!   `_per_s`.
//!
//! # What is where
//! The crate is organized by concept, one folder each; the root re-exports what the toolkit's
//! other crates use (the chain, its kinematics, equilibria, walls, profiles, wires,
//! identification, sensing and mapping), everything else is reached by its path.
//! - [`kinematics`]: the validated chain ([`Chain`], its
//!   [`ChainBuilder`](kinematics::chain::ChainBuilder), [`JointLimit`]), frame indices
//!   ([`Frame`]), poses ([`kinematics::positions`]), hybrid velocities
//!   ([`kinematics::velocity`]) and Jacobians ([`kinematics::jacobian`](mod@kinematics::jacobian)) of any frame pair in
//!   `O(n)`, the joint-limit map, the hairs' kinematics ([`kinematics::hair`]), the thesis's
//!   matrix forms (the reference the fast paths are tested against), and the typed errors
//!   ([`KinematicsError`], [`ChainError`]).
//! - [`statics`]: spring energy and tip load with gradient and Hessian
//!   ([`statics::energy`]), static equilibria ([`statics::equilibrium`]), the tip force at a
//!   posture ([`statics::tip_force`](mod@statics::tip_force)) and Castigliano's deflection
//!   ([`statics::castigliano`]), chains that stand for a beam with Richardson extrapolation
//!   ([`statics::beam`]), and the elastica they converge to ([`statics::elastica`]).
//! - [`walls`]: walls (line, polyline, sinusoid) with a solid side and surface zones
//!   (docs/model.md 6): the dispatch over shapes ([`Wall`], [`WallShape`]) and what the
//!   queries answer ([`walls::WallPoint`], [`walls::SegmentContact`], convex features) at the
//!   top, each shape a folder with one query a file (signed distance, a segment's deepest
//!   point, convex corners or crests, bounds, rays), and the bounding boxes over a long
//!   polyline's edges that make its queries cost what is near them.
//! - [`contact`]: quasi-static contact of the chain and its hairs with walls, in stages that
//!   own their state: the broad phase (which pairs take part), the step solver (the step's
//!   equations, semismooth Newton, Tresca's fixed point), the certifier (the independent
//!   check of a state), and the driver ([`contact::QuasiStatic`]: substeps, snaps,
//!   anchoring) that passes values between them.
//! - [`sweep`]: quasi-static sweeps: a placement, then the base moved in fixed steps, each a
//!   contact step with the wall-following metrics.
//! - [`follow`]: closed-loop wall following (a robot, its controller, the antenna as its only
//!   sensor).
//! - [`sensing`]: sensors as they are ([`sensing::sensor`]), wall-following metrics of a
//!   posture ([`sensing::metrics`]: point of bend, point of contact, preview distance, flip),
//!   contact points estimated from 12-bit joint angles and touch bits scored against the true
//!   wall ([`sensing::mapping`]), and the wall's coverage ([`sensing::coverage`])
//!   (docs/model.md 8, thesis 4.2.2).
//! - `numerics` (crate-private): the building blocks of the solvers, one per file, each with its
//!   tests: a Gragg-Bulirsch-Stoer extrapolation step and Carlson's elliptic integrals (the
//!   elastica's integrator and closed form).
//! - [`design`]: joint stiffness profiles ([`design::profile`]), Nitinol wires per joint
//!   ([`design::nitinol`]), and joint stiffness identified from a free-oscillation recording
//!   ([`design::identify`], docs/model.md 9, thesis 6.2).
//!
//! Every function checks its arguments against the chain and returns a typed error
//! ([`KinematicsError`], [`ChainError`]) rather than panicking. Functions that produce one
//! frame or one Jacobian touch only the links between `s` and `b`; `_into` variants write
//! into caller-supplied buffers.
//!
//! # Example: the tip Jacobian
//! ```
//! use sim_core::kinematics::jacobian::tip_jacobian;
//! use sim_core::{tip_pose, Chain, JointLimit};
//! use std::f64::consts::FRAC_PI_2;
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! // Eight 40 mm flagellar links on a 40 mm base link at 30 degrees.
//! let chain = Chain::builder(8)
//!     .link_length_m(0.04)
//!     .base_angle_rad(30f64.to_radians())
//!     .joint_limit(JointLimit::new(-FRAC_PI_2, FRAC_PI_2))
//!     .stiffness_nm_per_rad(0.01)
//!     .build()?;
//! let mut theta = vec![0.1; chain.dof()];
//! theta[0] = chain.base_angle_rad();
//!
//! let j = tip_jacobian(&chain, &theta)?; // 3 x 9: (x_dot, y_dot, omega) per joint rate
//! assert_eq!((j.nrows(), j.ncols()), (3, 9));
//!
//! // Column j is R90 (p_tip - p_joint_j) and 1: the last joint moves the tip by
//! // l_8 perpendicular to the last link.
//! let tip = tip_pose(&chain, &theta)?;
//! let phi_8 = tip.angle_rad;
//! assert!((j[(0, 8)] + 0.04 * phi_8.sin()).abs() < 1e-15);
//! assert!((j[(1, 8)] - 0.04 * phi_8.cos()).abs() < 1e-15);
//! assert_eq!(j[(2, 8)], 1.0);
//!
//! // The tip velocity for a joint rate vector is J theta_dot.
//! // The base is fixed (theta_dot_0 = 0); the eight joints turn at 0.5 rad/s each.
//! let mut theta_dot = nalgebra::DVector::from_element(9, 0.5);
//! theta_dot[0] = 0.0;
//! let v = &j * &theta_dot;
//! assert!((v[2] - 4.0).abs() < 1e-12); // the tip turns at 8 x 0.5 rad/s
//! # Ok(())
//! # }
//! ```

pub mod contact;
pub mod design;
pub mod follow;
pub mod kinematics;
pub(crate) mod numerics;
pub mod sensing;
pub mod statics;
pub mod sweep;
pub mod walls;

// The curated root: every item here is used by another crate of the workspace (the CLI, the
// monitor, antennad, the cross-crate tests); everything else is reached by its path above.
pub use design::identify::{
    DampingSource, FrequencySource, Identification, IdentifyError, IdentifyOptions,
    identify_stiffness,
};
pub use design::nitinol::{
    NitinolError, RangeFlag, WireDiameter, available_wires, design as design_wires,
    wire_stiffness_n_m_per_rad,
};
pub use design::profile::{ProfileError, StiffnessProfile, joint_positions};
pub use kinematics::chain::{Chain, JointLimit};
pub use kinematics::error::{ChainError, KinematicsError};
pub use kinematics::frame::Frame;
pub use kinematics::hair::{Hair, HairDirection, HairSide, hair_poses};
pub use kinematics::positions::{frame_poses, tip_pose};
pub use sensing::coverage::{
    Coverage, CoverageAccumulator, CoverageError, CoverageSettings, Section, WallSample,
    wall_coverage,
};
pub use sensing::mapping::{
    EstimatedContact, MappingAccumulator, MappingError, MappingScore, SWITCHES_PER_SEGMENT,
    TouchLayout, estimate_contacts, point_error_mm, sensed_theta_rad, switch_for_fraction,
    touch_bits_from_contacts,
};
pub use sensing::metrics::{ChainContact, pearson_correlation, spearman_correlation};
pub use sensing::sensor::{
    CalibrationError, FIRMWARE_DEBOUNCE_SAMPLES, SensorError, SensorField, SensorSettings, Sensors,
    closes_switch,
};
pub use statics::energy::strain_energy_j;
pub use statics::equilibrium::{
    Equilibrium, EquilibriumError, EquilibriumProblem, InitialGuess, LimitSide, MinimaSearch,
    SolveOptions, all_minima, solve_equilibrium,
};
pub use walls::{
    Line, Polyline, SMOOTH_MU_DEFAULT, Sinusoid, SolidSide, Surface, SurfaceMap, Wall, WallError,
    WallShape, ZoneAxis,
};
