//! The tests that span crates, one test binary (`cargo test -p antenna-tests --test cross`; a
//! module's tests alone: `cargo test -p antenna-tests --test cross reproduce_mapping::`). Each
//! module was a test file of its own; one binary links once instead of once per file.
//!
//! Two stay binaries of their own, each with every core to itself: `stress_contact` (the
//! contact stress sample, a child process per sweep on every core) and `s51_vectors` (the
//! 8051 simulator on every core).

mod c_shim_bit_exact;
mod contact_compliant_hairs;
mod contact_geometry;
mod contact_newton_iterations;
mod contact_stages;
mod crate_boundaries;
mod docs;
mod reproduce_flipping;
mod reproduce_follow;
mod reproduce_mapping;
mod reproduce_tip_forces;
mod reproduce_wall_following;
