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
//!   spatial Jacobians are in [`JacobianKind`].
//! - **Units** are SI and named: `_m`, `_rad`, `_nm` (newton-metres), `_n` (newtons),
//!   `_per_s`.
//!
//! # What is where
//! - [`chain`]: the validated description ([`Chain`], [`ChainBuilder`], [`JointLimit`]).
//! - [`positions`]: poses of one frame (`O(|b - s|)`) or of all frames (`O(n)`).
//! - [`velocity`]: hybrid velocities of one frame or of all frames (`O(n)`).
//! - [`jacobian`](mod@jacobian): hybrid, body and spatial Jacobians of any pair (`O(n)`), and all frames'
//!   Jacobians at once (`O(n^2)`).
//! - [`joint_limits`]: the limit map `theta = g(q)`, its inverse and derivatives.
//! - [`hair`]: hair parameters and hair tip kinematics.
//! - [`energy`]: spring energy and tip load with gradient and Hessian, in `theta` and `q`.
//! - [`tip_force`](mod@tip_force): the tip force at a posture (least squares `J^T F = -tau`,
//!   and the free-body system with stop torques, base reaction and servo torque), and
//!   [`castigliano`]: the deflection `K^-1 J^T (F, M)` of a small tip load (thesis 3.2.2).
//! - [`active_frames`] and [`matrix_forms`]: the thesis's bookkeeping (`alpha_sb`, `A_sb`, `A`)
//!   and matrix formulas, `O(n^2)` or worse: the reference the fast paths are tested against.
//! - [`profile`]: joint stiffness profiles normalized to `[k_min, k_max]` (docs/model.md 5).
//! - [`nitinol`]: the wire law `k = C r^4 + k_cable` and the nearest available wire per joint.
//! - [`identify`]: joint stiffness from a free-oscillation recording (docs/model.md 9, thesis 6.2).
//! - [`elastica`]: the reference solver for the clamped inextensible beam under a tip load.
//! - [`wall`]: walls (line, polyline, sinusoid) with a solid side and surface zones; signed
//!   distance and the deepest point of a link against a wall (docs/model.md 6).
//! - [`metrics`]: point of bend, point of contact, preview distance, flip detection and
//!   correlations (docs/model.md 8); [`mapping`]: wall contact points estimated from 12-bit joint
//!   angles and touch bits, and their error against the true wall (thesis 4.2.2).
//! - [`follow`]: closed-loop wall following (a robot, its controller, the antenna as its only
//!   sensor).
//! - [`beam`]: chains that stand for a beam (the first-order equal-links and the second-order
//!   Hencky layouts) and Richardson extrapolation over the number of links.
//!
//! Every function checks its arguments against the chain and returns a typed error
//! ([`KinematicsError`], [`ChainError`]) rather than panicking. Functions that produce one
//! frame or one Jacobian touch only the links between `s` and `b`; `_into` variants write
//! into caller-supplied buffers.
//!
//! # Example: the tip Jacobian
//! ```
//! use sim_core::{tip_jacobian, tip_pose, Chain, JointLimit};
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

pub mod active_frames;
pub mod beam;
pub mod castigliano;
pub mod chain;
pub mod contact;
pub mod coverage;
pub mod elastica;
pub mod energy;
pub mod equilibrium;
pub mod error;
pub mod follow;
pub mod frame;
pub mod hair;
pub mod identify;
pub mod jacobian;
pub mod joint_limits;
pub mod mapping;
pub mod matrix_forms;
pub mod metrics;
pub mod nitinol;
pub mod positions;
pub mod profile;
pub mod sensor;
pub mod sweep;
pub mod tip_force;
pub mod velocity;
pub mod wall;

pub use active_frames::{
    active_frames_matrix, active_frames_matrix_from_vector, active_frames_vector,
    all_frames_active_matrix, all_frames_matrix, all_frames_matrix_from_extremes,
};
pub use beam::{
    Beam, BeamError, BeamLayout, BeamTip, RichardsonOptions, RichardsonTip, richardson_tip,
    solve_beam_chain,
};
pub use castigliano::castigliano_deflection_rad;
pub use chain::{Chain, ChainBuilder, JointLimit};
pub use coverage::{
    Coverage, CoverageAccumulator, CoverageError, CoverageSettings, MAX_SAMPLES, Section,
    WallSample, wall_coverage,
};
pub use elastica::{
    BendingStiffness, ElasticaError, ElasticaOptions, ElasticaProblem, ElasticaSolution,
    PerpendicularLoadClosedForm, ShapePoint, perpendicular_load_closed_form,
    solve as solve_elastica,
};
pub use energy::{Potential, joint_torques_nm, strain_energy_j};
pub use equilibrium::{
    Equilibrium, EquilibriumError, EquilibriumProblem, InitialGuess, LimitSide, MinimaSearch,
    SolveOptions, all_minima, solve_equilibrium,
};
pub use error::{ChainError, ChainField, KinematicsError};
pub use frame::Frame;
pub use hair::{
    HAIR_BEND_MARGIN_RAD, Hair, HairDirection, HairPose, HairSide, HairVelocity, hair_pose,
    hair_poses, hair_tip_jacobian, hair_velocities,
};
pub use identify::{
    DampingSource, FrequencySource, Identification, IdentifyError, IdentifyOptions,
    identify_stiffness, wire_constant,
};
pub use jacobian::{
    JacobianKind, all_jacobians, all_jacobians_into, body_jacobian, hybrid_jacobian, jacobian,
    jacobian_into, spatial_jacobian, tip_jacobian, tip_jacobian_into,
};
pub use joint_limits::{d2theta_dq2, dtheta_dq, q_from_theta, theta_from_q};
pub use mapping::{
    EstimatedContact, MappingAccumulator, MappingError, MappingScore, SWITCHES_PER_SEGMENT,
    TouchLayout, estimate_contacts, mapping_score, point_error_mm, quantize_angle_rad,
    sensed_theta_rad, switch_for_fraction, touch_bits_from_contacts,
};
pub use metrics::{
    ChainContact, FlipState, PointOfContact, angle_to_wall_rad, flip_state, pearson_correlation,
    point_of_bend, point_of_contact, preview_distance_m, spearman_correlation,
};
pub use nitinol::{
    Design, JointWire, NitinolError, RangeFlag, WireDiameter, WireModel, available_wires,
    design as design_wires, wire_stiffness_n_m_per_rad,
};
pub use positions::{FramePoses, Pose2, frame_pose, frame_poses, frame_poses_into, tip_pose};
pub use profile::{ProfileError, StiffnessProfile, joint_positions};
pub use sensor::{
    CalibrationError, FIRMWARE_DEBOUNCE_SAMPLES, SensorError, SensorField, SensorSettings, Sensors,
    closes_switch,
};
pub use tip_force::{
    FreeBodyForces, TIP_FORCE_RANK_TOLERANCE, TipForce, TipForceError, joints_on_limit,
    tip_force_free_body, tip_force_least_squares, tip_wrench_least_squares,
};
pub use velocity::{
    FrameVelocities, Twist2, frame_velocities, frame_velocities_into, frame_velocity,
};
pub use wall::{
    ConcavePiece, ConvexFeature, FeatureContact, Line, Polyline, SMOOTH_MU_DEFAULT, SegmentContact,
    Sinusoid, SolidSide, Surface, SurfaceMap, Wall, WallError, WallPoint, WallShape, ZoneAxis,
};
