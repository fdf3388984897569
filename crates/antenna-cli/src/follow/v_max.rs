//! The highest speed at which a robot follows a scene's walls without trouble: a coarse grid
//! of speeds, then bisection between the last good speed below the first failing one and
//! that one. Every run covers the same distance (`distance_m`, set it past the wall's
//! feature: a corner, an angled wall), not `[follow] duration_s`: a slow run would otherwise
//! never reach the corner.
//!
//! A speed is good when its run's status is `"ok"` (no collision, not lost, the solver
//! through every step). `v_max_m_per_s` is the boundary below the **first** failing grid
//! speed, so every grid speed below it is good; where a faster grid speed is good again, the
//! result says so (`monotone: false`).

use sim_core::SensorSettings;
use sim_core::follow::{FollowConfig, FollowError};
use sim_core::sweep::SweepScene;

use super::run_summary;

/// How the search goes.
#[derive(Clone, Debug, PartialEq)]
pub struct VMaxOptions {
    /// The coarse grid, m/s (sorted and deduplicated before use; positive).
    pub speeds_m_per_s: Vec<f64>,
    /// The distance every run covers, m.
    pub distance_m: f64,
    /// The bisection stops when the bracket is this narrow, m/s.
    pub tolerance_m_per_s: f64,
}

impl Default for VMaxOptions {
    /// 0.1 to 2.0 m/s in steps of 0.1, 1.5 m, 0.01 m/s.
    fn default() -> Self {
        VMaxOptions {
            speeds_m_per_s: (1..=20).map(|k| 0.1 * k as f64).collect(),
            distance_m: 1.5,
            tolerance_m_per_s: 0.01,
        }
    }
}

/// One run of the search.
#[derive(Clone, Debug, PartialEq)]
pub struct SpeedRun {
    /// The speed, m/s.
    pub speed_m_per_s: f64,
    /// The run's status.
    pub status: String,
}

/// What the search found.
#[derive(Clone, Debug, PartialEq)]
pub struct VMax {
    /// The highest good speed below the first failing one, m/s (`None`: the slowest grid
    /// speed already fails).
    pub v_max_m_per_s: Option<f64>,
    /// The status of the first failing speed (`None`: every grid speed is good, and
    /// `v_max_m_per_s` is the grid's top, a lower bound).
    pub failure: Option<String>,
    /// Whether no good grid speed lies above a failing one.
    pub monotone: bool,
    /// Every run, in the order run.
    pub runs: Vec<SpeedRun>,
}

impl VMaxOptions {
    /// Checks the options.
    ///
    /// # Errors
    /// A message naming the option.
    pub fn validate(&self) -> Result<(), String> {
        if self.speeds_m_per_s.is_empty()
            || self
                .speeds_m_per_s
                .iter()
                .any(|v| !(v.is_finite() && *v > 0.0))
        {
            return Err("speeds_m_per_s: needs at least one speed, each positive".to_string());
        }
        if !(self.distance_m.is_finite() && self.distance_m > 0.0) {
            return Err(format!(
                "distance_m: must be positive, not {}",
                self.distance_m
            ));
        }
        if !(self.tolerance_m_per_s.is_finite() && self.tolerance_m_per_s > 0.0) {
            return Err(format!(
                "tolerance_m_per_s: must be positive, not {}",
                self.tolerance_m_per_s
            ));
        }
        Ok(())
    }
}

/// The search for a follow scene's parts (the scene's speed and duration are replaced).
///
/// # Errors
/// [`FollowError`] when a run cannot start (the same for every speed: the first one
/// reports it).
pub fn v_max(
    scene: &SweepScene,
    sensors: &SensorSettings,
    config: &FollowConfig,
    options: &VMaxOptions,
) -> Result<VMax, FollowError> {
    let mut speeds = options.speeds_m_per_s.clone();
    speeds.retain(|v| v.is_finite() && *v > 0.0);
    speeds.sort_by(f64::total_cmp);
    speeds.dedup();
    let mut runs = Vec::new();
    let mut run_at = |v: f64| -> Result<String, FollowError> {
        let mut c = *config;
        c.robot.speed_m_per_s = v;
        c.settings.duration_s = options.distance_m / v;
        let status = run_summary(scene, sensors, &c)?.status.name().to_string();
        runs.push(SpeedRun {
            speed_m_per_s: v,
            status: status.clone(),
        });
        Ok(status)
    };
    let statuses: Vec<String> = speeds
        .iter()
        .map(|&v| run_at(v))
        .collect::<Result<_, _>>()?;
    let first_bad = statuses.iter().position(|s| s != "ok");
    let monotone = match first_bad {
        Some(i) => statuses[i..].iter().all(|s| s != "ok"),
        None => true,
    };
    let (v_max_m_per_s, failure) = match first_bad {
        None => (speeds.last().copied(), None),
        Some(0) => (None, Some(statuses[0].clone())),
        Some(i) => {
            let (mut good, mut bad) = (speeds[i - 1], speeds[i]);
            let mut failure = statuses[i].clone();
            while bad - good > options.tolerance_m_per_s {
                let mid = 0.5 * (good + bad);
                let status = run_at(mid)?;
                if status == "ok" {
                    good = mid;
                } else {
                    bad = mid;
                    failure = status;
                }
            }
            (Some(good), Some(failure))
        }
    };
    Ok(VMax {
        v_max_m_per_s,
        failure,
        monotone,
        runs,
    })
}
