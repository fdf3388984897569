//! `[contact]`: options of sim-core's quasi-static contact solver (sweeps and the solve of a
//! scene with walls); unset keys take [`ContactSettings::default`].

use serde::Deserialize;
use sim_core::contact::ContactSettings;
use toml::Spanned;

use super::source::{Source, count, positive};
use crate::error::SceneError;

const CONTACT: &str = "[contact]";

/// Most Newton iterations per solve.
pub const MAX_CONTACT_ITERATIONS: usize = 1_000_000;
/// Most halvings of a step (sim-core's own bound).
pub const MAX_SUBSTEP_DEPTH: usize = 40;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawContact {
    tolerance_m: Option<Spanned<f64>>,
    max_iterations: Option<Spanned<i64>>,
    max_substep_depth: Option<Spanned<i64>>,
    /// The jump threshold at a joint between links of sim-core's
    /// `ContactSettings::jump_reference_link_m` (40 mm, the thesis's), degrees: sim-core
    /// scales it with each joint's links (a change of curvature), docs/scene-format.md.
    jump_deg: Option<Spanned<f64>>,
    margin_m: Option<Spanned<f64>>,
}

impl RawContact {
    pub(crate) fn validate(&self, source: &Source<'_>) -> Result<ContactSettings, SceneError> {
        let mut settings = ContactSettings::default();
        if let Some(t) = &self.tolerance_m {
            settings.tolerance_m = positive(source, CONTACT, "tolerance_m", t)?;
        }
        if let Some(m) = &self.max_iterations {
            settings.max_iterations = count(
                source,
                CONTACT,
                "max_iterations",
                m,
                1,
                MAX_CONTACT_ITERATIONS,
            )?;
        }
        if let Some(d) = &self.max_substep_depth {
            settings.max_substep_depth = count(
                source,
                CONTACT,
                "max_substep_depth",
                d,
                0,
                MAX_SUBSTEP_DEPTH,
            )?;
        }
        if let Some(j) = &self.jump_deg {
            // At the 40 mm reference link; the solver scales it to each joint's links.
            settings.jump_rad = positive(source, CONTACT, "jump_deg", j)?.to_radians();
        }
        if let Some(m) = &self.margin_m {
            settings.margin_m = positive(source, CONTACT, "margin_m", m)?;
        }
        Ok(settings)
    }
}
