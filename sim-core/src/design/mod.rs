//! Designing the antenna's joint springs (docs/model.md 5 and 9; thesis 2.3.2, 3.3.2, 6.2):
//! stiffness profiles along the antenna, the Nitinol wires that realize them, and the
//! identification of a built joint's stiffness from a free-oscillation recording.
//!
//! - [`profile`]: joint stiffness profiles normalized to `[k_min, k_max]`.
//! - [`nitinol`]: the wire law `k = C r^4 + k_cable` and the nearest available wire per joint.
//! - [`identify`]: joint stiffness from a free-oscillation recording.

pub mod identify;
pub mod nitinol;
pub mod profile;
