//! What `antenna optimize` maximizes: a number per sweep, in metres, averaged over the
//! scenes. Every objective is maximized; an error to minimize enters with its sign changed.
//! The follow objectives evaluate a follow scene's closed loop instead of a sweep: the
//! highest speed at which the robot follows the wall (m/s), or minus the RMS of its error
//! (m).

use sim_core::follow::{FollowStatus, FollowSummary};

use crate::follow::v_max::VMax;
use crate::sweep::SweepSummary;

/// The task metric of a sweep (thesis 4.2), metres, larger is better.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Objective {
    /// The mean preview distance over the steps with a contact (`preview_mean_m`): how far
    /// ahead of the base the antenna feels the wall (thesis 4.2.1, Table 4.1).
    PreviewMean,
    /// Minus the mean distance of the mapped contact points (from the sensed 12-bit angles
    /// and touch bits) to the true wall (`-mapping_mean_error_mm / 1000`; thesis 4.2.2).
    MappingError,
    /// The preview mean times the share of the sweep before the distal segment first flips
    /// (`first_flip_t_s / sweep_time_s`; 1 without a flip): a sweep that never flips scores
    /// its preview, one that flips halfway half of it.
    FlipFreePreview,
    /// A follow scene's `v_max_m_per_s` (m/s, maximized): the highest speed at which the
    /// robot follows the wall without trouble, by the search of the file's `[v_max]` table
    /// ([`crate::follow::v_max`]); infeasible when the slowest grid speed already fails.
    FollowVMax,
    /// Minus a follow scene's `rms_error_m` (m, minimized): the RMS of the true distance's
    /// error against the setpoint after the settling window, at the scene's speed and
    /// gains; infeasible when the run is not `ok` (collided, lost, the solver's outcome).
    FollowRms,
}

file_names!(Objective {
    PreviewMean => "preview-mean",
    MappingError => "mapping-error",
    FlipFreePreview => "flip-free-preview",
    FollowVMax => "follow-v-max",
    FollowRms => "follow-rms",
});

impl Objective {
    /// The objective named `name`.
    pub fn by_name(name: &str) -> Option<Objective> {
        Self::NAMES
            .iter()
            .position(|n| *n == name)
            .map(|i| Self::ALL[i])
    }

    /// Whether it evaluates a follow scene's closed loop (not a sweep).
    pub fn is_follow(self) -> bool {
        matches!(self, Objective::FollowVMax | Objective::FollowRms)
    }

    /// The unit values are shown in (`mm`, or `m/s` for `follow-v-max`) and the factor from
    /// the value's SI unit to it.
    pub fn display_unit(self) -> (&'static str, f64) {
        match self {
            Objective::FollowVMax => ("m/s", 1.0),
            _ => ("mm", 1e3),
        }
    }

    /// A value as shown: `12.3456 mm`, `0.8125 m/s`.
    pub fn show(self, value: f64) -> String {
        let (unit, factor) = self.display_unit();
        format!("{:.4} {unit}", value * factor)
    }

    /// The SI unit of the value: `m`, or `m/s` for `follow-v-max`.
    pub fn si_unit(self) -> &'static str {
        match self {
            Objective::FollowVMax => "m/s",
            _ => "m",
        }
    }

    /// `follow-rms` of a closed-loop run: minus its RMS error, m.
    ///
    /// # Errors
    /// A sentence when the run is not `ok` or did not get past the settling window.
    pub fn of_follow(summary: &FollowSummary) -> Result<f64, String> {
        match &summary.status {
            FollowStatus::Ok => {}
            FollowStatus::Solver { kind, message } => return Err(format!("{kind}: {message}")),
            other => {
                return Err(format!(
                    "the run ended {}{}",
                    other.name(),
                    summary
                        .first_collision_s
                        .map_or(String::new(), |t| format!(" (first collision at {t:.3} s)"))
                ));
            }
        }
        let rms = summary.rms_error_m.ok_or_else(|| {
            format!(
                "the run travelled {:.3} m, not past the settling window: no RMS error",
                summary.travel_m
            )
        })?;
        finite(-rms)
    }

    /// `follow-v-max` of a search: its `v_max_m_per_s`, m/s.
    ///
    /// # Errors
    /// A sentence when the slowest grid speed already fails.
    pub fn of_v_max(result: &VMax) -> Result<f64, String> {
        let v = result.v_max_m_per_s.ok_or_else(|| {
            format!(
                "the slowest grid speed already fails ({})",
                result.failure.as_deref().unwrap_or("no status")
            )
        })?;
        finite(v)
    }

    /// The objective of a sweep that finished, metres, or why it has none (the sweep never
    /// touched the wall, or mapped no point).
    ///
    /// # Errors
    /// A sentence saying why the value is undefined.
    pub fn of_summary(self, summary: &SweepSummary) -> Result<f64, String> {
        let preview = || {
            summary
                .preview_mean_m
                .ok_or_else(|| "no step touched a wall: no preview distance".to_string())
        };
        let value = match self {
            Objective::PreviewMean => preview()?,
            Objective::MappingError => {
                let error_mm = summary
                    .mapping_mean_error_mm
                    .ok_or_else(|| "no contact point was mapped".to_string())?;
                -error_mm / 1000.0
            }
            Objective::FollowVMax | Objective::FollowRms => {
                return Err(format!(
                    "{} evaluates a follow scene's closed loop, not a sweep",
                    self.name()
                ));
            }
            Objective::FlipFreePreview => {
                let share = match summary.first_flip_t_s {
                    Some(t_s) if summary.sweep_time_s > 0.0 => {
                        (t_s / summary.sweep_time_s).clamp(0.0, 1.0)
                    }
                    Some(_) => 0.0,
                    None => 1.0,
                };
                preview()? * share
            }
        };
        finite(value)
    }
}

/// `value`, or why not when it is not finite.
fn finite(value: f64) -> Result<f64, String> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(format!("the objective is {value}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sweep::SweepStats;

    fn summary(preview_m: Option<f64>, first_flip_t_s: Option<f64>) -> SweepSummary {
        let mut s = SweepStats::default().summary(0.0);
        s.sweep_time_s = 10.0;
        s.preview_mean_m = preview_m;
        s.first_flip_t_s = first_flip_t_s;
        s.mapping_mean_error_mm = Some(1.5);
        s
    }

    #[test]
    fn each_objective_is_metres_and_larger_is_better() {
        let s = summary(Some(0.04), None);
        assert_eq!(Objective::PreviewMean.of_summary(&s), Ok(0.04));
        assert_eq!(Objective::MappingError.of_summary(&s), Ok(-0.0015));
        assert_eq!(Objective::FlipFreePreview.of_summary(&s), Ok(0.04));
        // a flip at 2.5 s of 10 s keeps a quarter of the preview
        let flipped = summary(Some(0.04), Some(2.5));
        assert_eq!(Objective::FlipFreePreview.of_summary(&flipped), Ok(0.01));
        assert_eq!(Objective::PreviewMean.of_summary(&flipped), Ok(0.04));
    }

    #[test]
    fn an_undefined_or_non_finite_objective_says_why() {
        let none = summary(None, None);
        assert!(
            Objective::PreviewMean
                .of_summary(&none)
                .unwrap_err()
                .contains("no step touched")
        );
        assert!(Objective::FlipFreePreview.of_summary(&none).is_err());
        let mut unmapped = summary(Some(0.04), None);
        unmapped.mapping_mean_error_mm = None;
        assert!(
            Objective::MappingError
                .of_summary(&unmapped)
                .unwrap_err()
                .contains("mapped")
        );
        let nan = summary(Some(f64::NAN), None);
        assert!(
            Objective::PreviewMean
                .of_summary(&nan)
                .unwrap_err()
                .contains("NaN")
        );
        for (name, objective) in Objective::NAMES.iter().zip(Objective::ALL) {
            assert_eq!(objective.name(), *name);
            assert_eq!(Objective::by_name(name), Some(objective));
        }
    }

    #[test]
    fn the_follow_objectives_score_a_run_and_a_search() {
        let mut run = FollowSummary {
            status: FollowStatus::Ok,
            steps: 100,
            duration_s: 1.0,
            travel_m: 0.3,
            rms_error_m: Some(0.002),
            max_error_m: Some(0.003),
            settling_distance_m: None,
            collisions: 0,
            first_collision_s: None,
            contact_share: 1.0,
            estimate_share: 1.0,
            estimate_rms_error_m: None,
        };
        assert_eq!(Objective::of_follow(&run), Ok(-0.002));
        run.rms_error_m = None;
        assert!(Objective::of_follow(&run).unwrap_err().contains("settling"));
        run.status = FollowStatus::Collided;
        run.first_collision_s = Some(0.5);
        assert!(Objective::of_follow(&run).unwrap_err().contains("collided"));
        let mut search = VMax {
            v_max_m_per_s: Some(0.75),
            failure: Some("collided".into()),
            monotone: true,
            runs: Vec::new(),
        };
        assert_eq!(Objective::of_v_max(&search), Ok(0.75));
        search.v_max_m_per_s = None;
        assert!(
            Objective::of_v_max(&search)
                .unwrap_err()
                .contains("collided")
        );
        assert!(
            Objective::FollowRms
                .of_summary(&summary(Some(0.04), None))
                .is_err()
        );
        assert_eq!(Objective::FollowVMax.show(0.8125), "0.8125 m/s");
        assert_eq!(Objective::FollowRms.show(-0.002), "-2.0000 mm");
        assert!(Objective::FollowRms.is_follow() && !Objective::PreviewMean.is_follow());
    }
}
