//! The highest speed at which a robot follows a scene's walls without trouble: a coarse grid
//! of speeds, then bisection between the last good speed below the first failing one and
//! that one. Every run covers the same distance (`distance_m`, set it past the wall's
//! feature: a corner, an angled wall), not `[follow] duration_s`: a slow run would otherwise
//! never reach the corner.
//!
//! A speed is good when its run's status is `"ok"` (no collision, not lost, the solver
//! through every step) and the robot still follows at the end: over the last `final_stretch_m`
//! of its travel the true distance stays within `final_band_m` of the setpoint; an `"ok"` run
//! that does not is `"drifted"`. `v_max_m_per_s` is the boundary below the **first** failing grid
//! speed, so every grid speed below it is good; where a faster grid speed is good again, the
//! result says so (`monotone: false`).

use sim_core::SensorSettings;
use sim_core::follow::{Follow, FollowConfig, FollowError};
use sim_core::sweep::SweepScene;

/// How the search goes.
#[derive(Clone, Debug, PartialEq)]
pub struct VMaxOptions {
    /// The coarse grid, m/s (sorted and deduplicated before use; positive).
    pub speeds_m_per_s: Vec<f64>,
    /// The distance every run covers, m.
    pub distance_m: f64,
    /// The bisection stops when the bracket is this narrow, m/s.
    pub tolerance_m_per_s: f64,
    /// The stretch at the end of each run over which it must still follow, m of travel.
    pub final_stretch_m: f64,
    /// How near the setpoint the true distance must stay there, m.
    pub final_band_m: f64,
}

impl Default for VMaxOptions {
    /// 0.1 to 2.0 m/s in steps of 0.1, 1.5 m, 0.01 m/s; within 20 mm of the setpoint over
    /// the last 0.3 m.
    fn default() -> Self {
        VMaxOptions {
            speeds_m_per_s: (1..=20).map(|k| 0.1 * k as f64).collect(),
            distance_m: 1.5,
            tolerance_m_per_s: 0.01,
            final_stretch_m: 0.3,
            final_band_m: 0.02,
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
        for (key, v) in [
            ("final_stretch_m", self.final_stretch_m),
            ("final_band_m", self.final_band_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{key}: must be positive, not {v}"));
            }
        }
        Ok(())
    }
}

/// The status of a run at `speed_m_per_s` over the options' distance: the run's status, or
/// `"drifted"` for an `"ok"` run that does not stay within the band over the final stretch.
///
/// # Errors
/// [`FollowError`] when the run cannot start.
pub fn judged_status(
    scene: &SweepScene,
    sensors: &SensorSettings,
    config: &FollowConfig,
    options: &VMaxOptions,
    speed_m_per_s: f64,
) -> Result<String, FollowError> {
    let mut c = *config;
    c.robot.speed_m_per_s = speed_m_per_s;
    c.settings.duration_s = options.distance_m / speed_m_per_s;
    let mut follow = Follow::new(scene, sensors, &c)?;
    let stretch_from_m = options.distance_m - options.final_stretch_m;
    let mut following = true;
    while let Some(step) = follow.next_step() {
        let Ok(step) = step else { break };
        if speed_m_per_s * step.t_s >= stretch_from_m {
            following &= step
                .wall_distance_m
                .is_some_and(|d| (d - c.controller.setpoint_m).abs() <= options.final_band_m);
        }
    }
    let status = follow.summary().status.name().to_string();
    Ok(if status == "ok" && !following {
        "drifted".to_string()
    } else {
        status
    })
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
    search(&options.speeds_m_per_s, options.tolerance_m_per_s, |v| {
        judged_status(scene, sensors, config, options, v)
    })
}

/// The search itself, for any judgement of a speed: `status_at(v)` runs at `v` and returns
/// the run's status (`"ok"` is good). The grid (`speeds_m_per_s`, sorted and deduplicated,
/// positive speeds only) is run in full, then the boundary below its first failing speed is
/// bisected to `tolerance_m_per_s` (`infinity`: no bisection).
///
/// # Errors
/// The first error of `status_at`.
pub fn search<E>(
    speeds_m_per_s: &[f64],
    tolerance_m_per_s: f64,
    mut status_at: impl FnMut(f64) -> Result<String, E>,
) -> Result<VMax, E> {
    let mut speeds = speeds_m_per_s.to_vec();
    speeds.retain(|v| v.is_finite() && *v > 0.0);
    speeds.sort_by(f64::total_cmp);
    speeds.dedup();
    let mut runs = Vec::new();
    let mut run_at = |v: f64| -> Result<String, E> {
        let status = status_at(v)?;
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
    let monotone = first_bad.is_none_or(|i| statuses[i..].iter().all(|s| s != "ok"));
    let (v_max_m_per_s, failure) = match first_bad {
        None => (speeds.last().copied(), None),
        Some(0) => (None, Some(statuses[0].clone())),
        Some(i) => {
            let (mut good, mut bad) = (speeds[i - 1], speeds[i]);
            let mut failure = statuses[i].clone();
            while bad - good > tolerance_m_per_s {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A judgement good below 1.234 m/s (and, with a hole, bad at 0.5 too).
    fn judge(hole: bool) -> impl FnMut(f64) -> Result<String, ()> {
        move |v| {
            Ok(if v < 1.234 && !(hole && v == 0.5) {
                "ok".to_string()
            } else {
                "collided".to_string()
            })
        }
    }

    #[test]
    fn the_search_bisects_below_the_first_failing_grid_speed() {
        let found = search(&[2.0, 0.5, 1.0, 0.5, -1.0], 0.001, judge(false)).unwrap();
        let v = found.v_max_m_per_s.unwrap();
        assert!(v < 1.234 && v > 1.234 - 0.001, "{v}");
        assert_eq!(found.failure.as_deref(), Some("collided"));
        assert!(found.monotone);
        // The grid (sorted, deduplicated, positive) ran first, in order.
        let grid: Vec<f64> = found.runs.iter().take(3).map(|r| r.speed_m_per_s).collect();
        assert_eq!(grid, [0.5, 1.0, 2.0]);
    }

    #[test]
    fn a_good_speed_above_a_failing_one_is_flagged_and_the_top_is_a_lower_bound() {
        let found = search(&[0.25, 0.5, 1.0], f64::INFINITY, judge(true)).unwrap();
        assert_eq!(found.v_max_m_per_s, Some(0.25));
        assert!(!found.monotone);
        assert_eq!(found.runs.len(), 3);
        let all_good = search(&[0.25, 1.0], 0.01, judge(false)).unwrap();
        assert_eq!(all_good.v_max_m_per_s, Some(1.0));
        assert_eq!(all_good.failure, None);
        let none = search(&[1.5, 2.0], 0.01, judge(false)).unwrap();
        assert_eq!(none.v_max_m_per_s, None);
    }

    #[test]
    fn an_ok_run_that_ends_off_the_setpoint_is_drifted() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/follow/straight_wall.toml"
        );
        let scene = antenna_scene::Scene::from_path(std::path::Path::new(path)).unwrap();
        let (sweep, config, sensors) = scene.follow_parts().unwrap();
        // 0.2 m at 0.3 m/s: the robot, started 20 mm off the setpoint, has not settled.
        let options = |final_band_m| VMaxOptions {
            distance_m: 0.2,
            final_band_m,
            ..VMaxOptions::default()
        };
        let status = |band| judged_status(&sweep, &sensors, &config, &options(band), 0.3).unwrap();
        assert_eq!(status(0.005), "drifted");
        assert_eq!(status(0.05), "ok");
    }
}
