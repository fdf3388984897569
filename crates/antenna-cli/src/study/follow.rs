//! The rows of a follow study (a study whose base scene is a follow scene, issue #47): each
//! grid point a closed-loop run ([`crate::follow::run_summary`]) with the run's summary as
//! columns, or, with a `[v_max]` table, the highest speed at which it follows the wall
//! ([`crate::follow::v_max::v_max`]).
//!
//! ```toml
//! [v_max]                              # optional; the study then has no speeds_m_per_s axis
//! speeds_m_per_s = [0.2, 0.4, 0.6]     # the coarse grid, m/s (default 0.1 to 2.0 by 0.1)
//! distance_m = 1.0                     # every run covers this distance, m (default 1.5)
//! tolerance_m_per_s = 0.02             # the bisection's bracket, m/s (default 0.01)
//! ```

use std::ops::Range;

use serde::{Deserialize, Serialize};
use sim_core::follow::FollowSummary;
use toml::Spanned;

use antenna_scene::error::SceneError;
use antenna_scene::source::{Source, finite_list, positive};

use crate::follow::v_max::{VMax, VMaxOptions};

/// The `[v_max]` table's name in errors.
pub const V_MAX: &str = "[v_max]";

/// A `[v_max]` table as written (a study's or an optimization's).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawVMax {
    speeds_m_per_s: Option<Spanned<Vec<f64>>>,
    distance_m: Option<Spanned<f64>>,
    tolerance_m_per_s: Option<Spanned<f64>>,
    final_stretch_m: Option<Spanned<f64>>,
    final_band_m: Option<Spanned<f64>>,
}

impl RawVMax {
    /// The search's options: the keys written, [`VMaxOptions::default`]'s for the others;
    /// `span` is the table's (for a key that has no place of its own).
    ///
    /// # Errors
    /// A located [`SceneError`] naming the key: an empty grid, a speed that is not positive,
    /// a distance or tolerance that is not positive.
    pub fn validate(
        &self,
        source: &Source<'_>,
        span: Range<usize>,
    ) -> Result<VMaxOptions, SceneError> {
        let mut options = VMaxOptions::default();
        if let Some(list) = &self.speeds_m_per_s {
            let speeds = finite_list(source, V_MAX, "speeds_m_per_s", list)?;
            if speeds.is_empty() {
                return Err(source.invalid(
                    list.span(),
                    V_MAX,
                    "speeds_m_per_s",
                    "no speeds: give the coarse grid, e.g. [0.2, 0.4, 0.6, 0.8]",
                ));
            }
            if let Some(bad) = speeds.iter().find(|v| **v <= 0.0) {
                return Err(source.invalid(
                    list.span(),
                    V_MAX,
                    "speeds_m_per_s",
                    format!("{bad} m/s: every speed must be > 0"),
                ));
            }
            options.speeds_m_per_s = speeds;
        }
        if let Some(d) = &self.distance_m {
            options.distance_m = positive(source, V_MAX, "distance_m", d)?;
        }
        if let Some(t) = &self.tolerance_m_per_s {
            options.tolerance_m_per_s = positive(source, V_MAX, "tolerance_m_per_s", t)?;
        }
        if let Some(f) = &self.final_stretch_m {
            options.final_stretch_m = positive(source, V_MAX, "final_stretch_m", f)?;
        }
        if let Some(b) = &self.final_band_m {
            options.final_band_m = positive(source, V_MAX, "final_band_m", b)?;
        }
        options
            .validate()
            .map_err(|why| source.invalid(span, V_MAX, "speeds_m_per_s", why))?;
        Ok(options)
    }
}

/// The result of one closed-loop run (or one v_max search) of a follow study. The columns a
/// study writes are [`FOLLOW_COLUMNS`] (a run per row) or [`V_MAX_COLUMNS`] (a search per
/// row); an absent value is an empty CSV field and a JSON `null`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FollowRow {
    /// The grid point, `0..` (the last axis varies fastest).
    pub index: usize,
    /// The stiffness profile (`custom` for explicit values).
    pub profile: String,
    /// The hair layout (`scene` when the axis is absent).
    pub hairs: String,
    /// The walls' surface (`scene` when the axis is absent).
    pub surface: String,
    /// The robot's forward speed, m/s (`null` in a v_max study).
    pub speed_m_per_s: Option<f64>,
    /// The template body's proportional gain, N m per m (`null` for a wheeled body).
    pub kp_n: Option<f64>,
    /// The template body's derivative gain, N m per m/s (`null` for a wheeled body).
    pub kd_n_s: Option<f64>,
    /// The wheeled body's proportional gain, rad/s per m (`null` for a template body).
    pub kp_rad_per_s_per_m: Option<f64>,
    /// The wheeled body's derivative gain, rad per m (`null` for a template body).
    pub kd_rad_per_m: Option<f64>,
    /// The sensing-to-actuation delay, s.
    pub delay_s: f64,
    /// The run's status (`ok`, `collided`, `lost`, `unstable`, or the antenna solver's outcome:
    /// `no-convergence`, `jammed`, `uncertified`, `solver-error`), or `failed` when the run
    /// could not start (`error` says why). In a v_max study: `ok` when the search ran.
    pub status: String,
    /// Why the run failed or what the solver said (`null` otherwise).
    pub error: Option<String>,
    /// Steps run.
    pub steps: Option<usize>,
    /// Simulated time, s.
    pub duration_s: Option<f64>,
    /// Distance travelled by the point of rotation, m.
    pub travel_m: Option<f64>,
    /// RMS of the true distance's error against the setpoint after the settling window, m.
    pub rms_error_m: Option<f64>,
    /// The largest such error, m.
    pub max_error_m: Option<f64>,
    /// The travel after which the error stayed within the settling band, m.
    pub settling_distance_m: Option<f64>,
    /// How many times the footprint entered a wall.
    pub collisions: Option<usize>,
    /// When it first did, s.
    pub first_collision_s: Option<f64>,
    /// Share of steps with a contact on the antenna.
    pub contact_share: Option<f64>,
    /// Share of steps with an estimate of the wall.
    pub estimate_share: Option<f64>,
    /// RMS of the estimate against the true distance at its preview, m.
    pub estimate_rms_error_m: Option<f64>,
    /// The highest good speed below the first failing grid speed, m/s (`null`: the slowest
    /// grid speed already fails).
    pub v_max_m_per_s: Option<f64>,
    /// The status of the first failing speed (`null`: every grid speed was good, and
    /// `v_max_m_per_s` is the grid's top, a lower bound).
    pub v_max_failure: Option<String>,
    /// `false` when a grid speed above a failing one is good again (collision-free speeds
    /// are not monotone).
    pub v_max_monotone: Option<bool>,
    /// Runs the search made (grid and bisection).
    pub v_max_runs: Option<usize>,
    /// Wall-clock time of the row, milliseconds.
    pub wall_clock_ms: Option<f64>,
}

/// The columns of a follow study, in order.
pub const FOLLOW_COLUMNS: &[&str] = &[
    "index",
    "profile",
    "hairs",
    "surface",
    "speed_m_per_s",
    "kp_n",
    "kd_n_s",
    "kp_rad_per_s_per_m",
    "kd_rad_per_m",
    "delay_s",
    "status",
    "error",
    "steps",
    "duration_s",
    "travel_m",
    "rms_error_m",
    "max_error_m",
    "settling_distance_m",
    "collisions",
    "first_collision_s",
    "contact_share",
    "estimate_share",
    "estimate_rms_error_m",
    "wall_clock_ms",
];

/// The columns of a follow study with `[v_max]`, in order.
pub const V_MAX_COLUMNS: &[&str] = &[
    "index",
    "profile",
    "hairs",
    "surface",
    "kp_n",
    "kd_n_s",
    "kp_rad_per_s_per_m",
    "kd_rad_per_m",
    "delay_s",
    "status",
    "error",
    "v_max_m_per_s",
    "v_max_failure",
    "v_max_monotone",
    "v_max_runs",
    "wall_clock_ms",
];

impl FollowRow {
    /// Puts a run's summary in the row (and the solver's message in `error`).
    pub fn set_summary(&mut self, summary: &FollowSummary) {
        self.status = summary.status.name().to_string();
        if let sim_core::follow::FollowStatus::Solver { message, .. } = &summary.status {
            self.error = Some(message.clone());
        }
        self.steps = Some(summary.steps);
        self.duration_s = Some(summary.duration_s);
        self.travel_m = Some(summary.travel_m);
        self.rms_error_m = summary.rms_error_m;
        self.max_error_m = summary.max_error_m;
        self.settling_distance_m = summary.settling_distance_m;
        self.collisions = Some(summary.collisions);
        self.first_collision_s = summary.first_collision_s;
        self.contact_share = Some(summary.contact_share);
        self.estimate_share = Some(summary.estimate_share);
        self.estimate_rms_error_m = summary.estimate_rms_error_m;
    }

    /// Puts a v_max search's result in the row.
    pub fn set_v_max(&mut self, result: &VMax) {
        self.status = "ok".to_string();
        self.v_max_m_per_s = result.v_max_m_per_s;
        self.v_max_failure = result.failure.clone();
        self.v_max_monotone = Some(result.monotone);
        self.v_max_runs = Some(result.runs.len());
    }

    /// The row's values of `columns`: an absent value is JSON `null`.
    fn values(&self, columns: &[&str]) -> Vec<(String, serde_json::Value)> {
        let value = serde_json::to_value(self).unwrap_or_default();
        columns
            .iter()
            .map(|c| ((*c).to_string(), value[*c].clone()))
            .collect()
    }

    /// The row's CSV fields of `columns`, as [`super::StudyRow::csv_fields`] writes them.
    pub fn csv_fields(&self, columns: &[&str]) -> Vec<String> {
        self.values(columns)
            .into_iter()
            .map(|(_, v)| match v {
                serde_json::Value::Null => String::new(),
                serde_json::Value::String(s) => s,
                other => other.to_string(),
            })
            .collect()
    }

    /// The row as one JSON line with `columns`' keys, in order.
    pub fn json_line(&self, columns: &[&str]) -> String {
        let fields: Vec<String> = self
            .values(columns)
            .into_iter()
            .map(|(k, v)| {
                format!(
                    "{}:{}",
                    serde_json::Value::String(k),
                    serde_json::to_string(&v).unwrap_or_else(|_| "null".to_string())
                )
            })
            .collect();
        format!("{{{}}}", fields.join(","))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row() -> FollowRow {
        FollowRow {
            index: 2,
            profile: "linear".into(),
            hairs: "scene".into(),
            surface: "scene".into(),
            speed_m_per_s: Some(0.3),
            kp_n: Some(0.05),
            kd_n_s: Some(0.002),
            kp_rad_per_s_per_m: None,
            kd_rad_per_m: None,
            delay_s: 0.0,
            status: "ok".into(),
            error: None,
            steps: Some(100),
            duration_s: Some(1.0),
            travel_m: Some(0.3),
            rms_error_m: Some(0.002),
            max_error_m: Some(0.003),
            settling_distance_m: Some(0.25),
            collisions: Some(0),
            first_collision_s: None,
            contact_share: Some(1.0),
            estimate_share: Some(0.9),
            estimate_rms_error_m: Some(0.001),
            v_max_m_per_s: None,
            v_max_failure: None,
            v_max_monotone: None,
            v_max_runs: None,
            wall_clock_ms: Some(5.0),
        }
    }

    #[test]
    fn every_column_is_a_field_and_the_json_keeps_the_order() {
        let value = serde_json::to_value(row()).unwrap_or_default();
        for c in FOLLOW_COLUMNS.iter().chain(V_MAX_COLUMNS) {
            assert!(value.get(*c).is_some(), "{c}");
        }
        let line = row().json_line(FOLLOW_COLUMNS);
        assert!(
            line.starts_with("{\"index\":2,\"profile\":\"linear\","),
            "{line}"
        );
        let parsed: serde_json::Value = serde_json::from_str(&line).unwrap_or_default();
        assert_eq!(
            parsed.as_object().map(|o| o.len()),
            Some(FOLLOW_COLUMNS.len())
        );
        let fields = row().csv_fields(V_MAX_COLUMNS);
        assert_eq!(fields.len(), V_MAX_COLUMNS.len());
        assert_eq!(fields[4], "0.05");
        assert_eq!(fields[7], "");
    }
}
