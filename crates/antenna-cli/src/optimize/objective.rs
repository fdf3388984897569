//! What `antenna optimize` maximizes: a number per sweep, in metres, averaged over the
//! scenes. Every objective is maximized; an error to minimize enters with its sign changed.

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
}

file_names!(Objective {
    PreviewMean => "preview-mean",
    MappingError => "mapping-error",
    FlipFreePreview => "flip-free-preview",
});

impl Objective {
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
        if value.is_finite() {
            Ok(value)
        } else {
            Err(format!("the objective is {value}"))
        }
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
        }
    }
}
