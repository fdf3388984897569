//! The `antenna` command's library: scene files ([`scene`], errors in [`error`]), their
//! equilibria ([`solve`], and [`solve_walls`] for scenes with walls), sweeps along walls
//! ([`sweep`]), studies of many sweeps ([`study`]), the stiffness profile that maximizes a
//! task's metric ([`optimize`]), Nitinol wire designs ([`design`]),
//! stiffness identification from recordings ([`recording`], [`identify`]), the export of
//! recorded trials ([`export`]) and digitized walls drawn from a polyline ([`digitize`]);
//! what every figure shares ([`figure`]: its font, PNG files).
//!
//! The binary (`src/bin/antenna/`) parses the command line, prints and picks the exit status;
//! everything it computes is here so that it can be tested and documented.

mod csv_lines;
pub mod design;
pub mod digitize;
pub mod error;
pub mod export;
pub mod figure;
pub mod identify;
pub mod optimize;
pub mod progress;
pub mod recording;
pub mod scene;
pub mod solve;
pub mod solve_walls;
pub mod study;
pub mod sweep;

pub use error::{Location, SceneError, SceneErrorKind};
pub use scene::{HairSpec, Scene, SceneLocations, SolverSettings, Start, StiffnessSpec};
