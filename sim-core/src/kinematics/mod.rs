//! Kinematics of the chain (thesis 2.2, appendix 6.1; docs/model.md 1-3 and 7): the validated
//! chain description, frame indices, poses, hybrid velocities and Jacobians of any frame pair,
//! the joint-limit map, the hairs' kinematics, and the thesis's matrix forms the fast paths are
//! tested against.
//!
//! - [`chain`]: the validated description ([`Chain`](chain::Chain), its builder, joint
//!   limits).
//! - [`frame`]: frame indices `-1..=n`.
//! - [`positions`]: poses of one frame (`O(|b - s|)`) or of all frames (`O(n)`).
//! - [`velocity`]: hybrid velocities of one frame or of all frames (`O(n)`).
//! - [`jacobian`](mod@jacobian): hybrid, body and spatial Jacobians of any pair (`O(n)`), and
//!   all frames' Jacobians at once (`O(n^2)`).
//! - [`joint_limits`]: the limit map `theta = g(q)`, its inverse and derivatives.
//! - [`hair`]: hair parameters and hair tip kinematics.
//! - [`active_frames`] and [`matrix_forms`]: the thesis's bookkeeping (`alpha_sb`, `A_sb`,
//!   `A`) and matrix formulas, `O(n^2)` or worse: the reference the fast paths are tested
//!   against.
//! - [`error`]: the typed errors of chain descriptions and kinematics arguments.

pub mod active_frames;
pub mod chain;
pub mod error;
pub mod frame;
pub mod hair;
pub mod jacobian;
pub mod joint_limits;
pub mod matrix_forms;
pub mod positions;
pub mod velocity;
