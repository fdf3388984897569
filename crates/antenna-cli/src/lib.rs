//! The `antenna` command's library, on scene files read by [`antenna_scene`]: their equilibria
//! ([`solve`], and [`solve_walls`] for scenes with walls), sweeps along walls
//! ([`sweep`]), studies of many sweeps ([`study`]), the stiffness profile that maximizes a
//! task's metric ([`optimize`]), Nitinol wire designs ([`design`]),
//! stiffness identification from recordings ([`recording`], [`identify`]), the export of
//! recorded trials ([`export`]), digitized walls drawn from a polyline ([`digitize`]) and the
//! commissioning of the robot's segments ([`segments`]).
//! What every figure shares (its font, PNG files) is [`antenna_figure`].
//!
//! The binary (`src/bin/antenna/`) parses the command line, prints and picks the exit status;
//! everything it computes is here so that it can be tested and documented.

pub mod design;
pub mod digitize;
pub mod export;
pub mod follow;
pub mod identify;
pub mod optimize;
pub mod progress;
pub mod recording;
pub mod segments;
pub mod solve;
pub mod solve_walls;
pub mod study;
pub mod sweep;
