//! `[sweep]`: how the base moves during `antenna sweep` (a constant velocity for a set time
//! in fixed steps); unset keys take [`Motion::default`] (the thesis's 4.2.1 sweep: 16.7 mm/s
//! along x for 50 s at 100 Hz).

use serde::Deserialize;
use sim_core::sweep::Motion;
use toml::Spanned;

use super::source::{Source, non_negative, point, positive};
use crate::error::SceneError;

const SWEEP: &str = "[sweep]";

/// Most steps a sweep may take (`duration_s / step_s`).
pub const MAX_SWEEP_STEPS: usize = 10_000_000;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSweep {
    velocity_m_per_s: Option<Spanned<Vec<f64>>>,
    duration_s: Option<Spanned<f64>>,
    step_s: Option<Spanned<f64>>,
}

impl RawSweep {
    pub(crate) fn validate(&self, source: &Source<'_>) -> Result<Motion, SceneError> {
        let mut motion = Motion::default();
        if let Some(v) = &self.velocity_m_per_s {
            motion.velocity_m_per_s = point(source, SWEEP, "velocity_m_per_s", v)?;
        }
        if let Some(d) = &self.duration_s {
            motion.duration_s = non_negative(source, SWEEP, "duration_s", d)?;
        }
        if let Some(s) = &self.step_s {
            motion.step_s = positive(source, SWEEP, "step_s", s)?;
        }
        let steps = motion.duration_s / motion.step_s;
        if steps.round() > MAX_SWEEP_STEPS as f64 {
            let (key, span) = match (&self.step_s, &self.duration_s) {
                (Some(s), _) => ("step_s", s.span()),
                (None, Some(d)) => ("duration_s", d.span()),
                (None, None) => ("step_s", 0..0),
            };
            return Err(source.invalid(
                span,
                SWEEP,
                key,
                format!(
                    "duration_s / step_s = {steps:.0} steps; at most {MAX_SWEEP_STEPS} are allowed"
                ),
            ));
        }
        Ok(motion)
    }
}
