//! The thesis's experiments run on sim-core (issue "contact, friction, hairs, sweeps"): each
//! module runs one experiment and returns its numbers; `tests/tests/cross/reproduce_*.rs` assert
//! the thesis's claims on them and `cargo run -p antenna-tests --release --example reproduce`
//! draws the figures in `docs/figures/` and writes `docs/reproduction.md`.
//!
//! Every experiment starts from a scene file in `examples/` (parsed by `antenna-cli`) and
//! varies what the thesis varied (stiffness profile, wall surface, hair layout, base angle,
//! wall frequency) in code.

pub mod flipping;
pub mod follow;
pub mod mapping;
pub mod tip_forces;
pub mod wall_following;

use std::path::PathBuf;

use sim_core::sweep::SweepScene;
use sim_core::{Chain, StiffnessProfile};

/// The thesis's stiffness range for the robot, N m / rad (thesis 4.2.1.1).
pub const K_MIN_N_M_PER_RAD: f64 = 0.004;
/// See [`K_MIN_N_M_PER_RAD`].
pub const K_MAX_N_M_PER_RAD: f64 = 0.082;

/// The seven profiles of the thesis's Table 4.1, in its row order.
pub const TABLE_4_1_PROFILES: [StiffnessProfile; 7] = [
    StiffnessProfile::Constant,
    StiffnessProfile::FastExponential,
    StiffnessProfile::Logarithmic,
    StiffnessProfile::SlowExponential,
    StiffnessProfile::Linear,
    StiffnessProfile::SlowReciprocal,
    StiffnessProfile::FastReciprocal,
];

/// Why an experiment could not run.
#[derive(Debug, thiserror::Error)]
pub enum ReproduceError {
    /// The scene file could not be read.
    #[error("{path}: {message}")]
    Scene {
        /// The file.
        path: String,
        /// What went wrong.
        message: String,
    },
    /// A chain could not be built.
    #[error(transparent)]
    Chain(#[from] sim_core::ChainError),
    /// A profile could not be applied.
    #[error(transparent)]
    Profile(#[from] sim_core::ProfileError),
    /// A wall could not be built.
    #[error(transparent)]
    Wall(#[from] sim_core::WallError),
    /// A closed-loop run could not start.
    #[error("{label}: {source}")]
    Follow {
        /// Which run.
        label: String,
        /// What went wrong.
        source: sim_core::follow::FollowError,
    },
    /// A sweep failed.
    #[error("{label}: {source}")]
    Sweep {
        /// Which run.
        label: String,
        /// What went wrong.
        source: sim_core::sweep::SweepError,
    },
}

/// `examples/<name>` in the workspace.
pub fn example_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("examples")
        .join(name)
}

/// The sweep scene of `examples/<name>`.
///
/// # Errors
/// [`ReproduceError::Scene`] when the file cannot be read or is not a sweep scene.
pub fn load_scene(name: &str) -> Result<SweepScene, ReproduceError> {
    let path = example_path(name);
    let scene = antenna_scene::Scene::from_path(&path).map_err(|e| ReproduceError::Scene {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    scene.sweep_scene().map_err(|e| ReproduceError::Scene {
        path: path.display().to_string(),
        message: e.to_string(),
    })
}

/// The `[sensors]` of the example scene `name` (ideal without the table).
///
/// # Errors
/// [`ReproduceError::Scene`] for a scene that does not parse.
pub fn load_sensors(name: &str) -> Result<sim_core::SensorSettings, ReproduceError> {
    let path = example_path(name);
    let scene = antenna_scene::Scene::from_path(&path).map_err(|e| ReproduceError::Scene {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    Ok(scene.sensors)
}

/// `chain` with the stiffness of `profile` normalized to the thesis's range.
///
/// # Errors
/// [`ReproduceError::Profile`], [`ReproduceError::Chain`].
pub fn with_profile(chain: &Chain, profile: StiffnessProfile) -> Result<Chain, ReproduceError> {
    let k = profile.stiffness_n_m_per_rad(
        chain.link_lengths_m(),
        K_MIN_N_M_PER_RAD,
        K_MAX_N_M_PER_RAD,
    )?;
    Ok(chain.to_builder().stiffnesses_nm_per_rad(k).build()?)
}

/// Mean, standard deviation (n - 1) and median of `values` (`NaN`s without values).
pub fn mean_sd_median(values: &[f64]) -> (f64, f64, f64) {
    if values.is_empty() {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    let count = values.len() as f64;
    let mean = values.iter().sum::<f64>() / count;
    let var = if values.len() > 1 {
        values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (count - 1.0)
    } else {
        0.0
    };
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let mid = sorted.len() / 2;
    let median = if sorted.len().is_multiple_of(2) {
        0.5 * (sorted[mid - 1] + sorted[mid])
    } else {
        sorted[mid]
    };
    (mean, var.sqrt(), median)
}
