//! The contact stress suite: seeded random walls and antennae swept along them, every sweep
//! classified (finished with every step certified, jammed, placement refused, solver
//! failure, uncertified), summarized in a markdown table.
//!
//! A case ([`Case`]) is a pure function of `(seed, index, sample)`: the antenna (`N` links of
//! `0.36 / N` m, one of the seven Table 4.1 stiffness profiles, with or without distal
//! hairs), one wall ([`walls`]: a line, a polyline with steps and bumps, a sinusoid, or a
//! noisy digitized line or trapezoid) with a smooth surface of friction `mu`, a placement
//! (rest, explicit angles, approach, tip on the wall from a C or an S start) and a motion
//! along `+x`. [`run_case`] runs its sweep and re-checks every step independently;
//! [`run_cases`] runs many on every core, each in a child process with a time limit;
//! [`summary_markdown`] writes the table.
//!
//! `tests/tests/stress_contact.rs` runs a fixed sample in CI and, with `ANTENNA_SOAK=1`, a
//! soak of at least 2,000 sweeps.

pub mod case;
pub mod follow;
pub mod outcome;
pub mod parallel;
pub mod step_cost;
pub mod table;
pub mod trajectory;
pub mod walls;
pub mod wire;

pub use case::{Case, PlacementKind, Sample};
pub use outcome::{Outcome, SweepRecord, run_case};
pub use parallel::{
    CHILD_ENV, ChildCommand, RunOptions, TimeLimit, child_main, default_threads, run_cases,
    run_in_child, run_index,
};
pub use step_cost::{EXPENSIVE_ITERATIONS, StepCost, expensive_by_kind};
pub use table::{summary_markdown, unfinished_report};
pub use trajectory::{GOLDEN_FILE, STEP_TOLERANCE, Trajectory, compare, golden_file, parse_golden};
pub use walls::{Corner, Profile, WallFrame, WallKind, WallSpec};

use rand::SeedableRng;
use rand::rngs::StdRng;

/// Why a case could not be built (a bug in the generator, not an outcome of a sweep).
#[derive(Debug, thiserror::Error)]
pub enum StressError {
    /// A chain could not be built.
    #[error(transparent)]
    Chain(#[from] sim_core::ChainError),
    /// A stiffness profile could not be applied.
    #[error(transparent)]
    Profile(#[from] sim_core::ProfileError),
    /// A wall could not be built.
    #[error(transparent)]
    Wall(#[from] sim_core::WallError),
    /// The chain's kinematics failed.
    #[error(transparent)]
    Kinematics(#[from] sim_core::KinematicsError),
    /// Anything else, in words.
    #[error("{0}")]
    Other(String),
}

/// SplitMix64's finalizer: a bijective mix of 64 bits.
fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The random stream of case `index` under `seed` (independent streams for different
/// indices; the same stream for the same pair).
pub fn case_rng(seed: u64, index: u64) -> StdRng {
    StdRng::seed_from_u64(mix64(seed ^ mix64(index)))
}
