//! The `antenna` command's library: scene files ([`scene`], errors in [`error`]), their
//! equilibria ([`solve`]), Nitinol wire designs ([`design`]) and stiffness identification
//! from recordings ([`recording`], [`identify`]).
//!
//! The binary (`src/main.rs`) parses the command line, prints and picks the exit status;
//! everything it computes is here so that it can be tested and documented.

pub mod design;
pub mod error;
pub mod export;
pub mod identify;
pub mod recording;
pub mod scene;
pub mod solve;

pub use error::{Location, SceneError, SceneErrorKind};
pub use scene::{Scene, SceneLocations, SolverSettings, Start, StiffnessSpec};
