//! `[controller]` (a follow scene, issue #47): the estimator that turns what the antenna
//! senses into the wall's distance, and the PD controller on it (setpoint, gains, delay, the
//! search turn without an estimate). Unset keys take sim-core's [`Controller::default`]; the
//! gains that apply depend on `[robot] body` (the template body's moments, the wheeled
//! body's turning rates).

use std::ops::Range;

use serde::Deserialize;
use sim_core::follow::config::CONTACT_WINDOW_S_DEFAULT;
use sim_core::follow::{Controller, ESTIMATOR_NAMES, Estimator};
use toml::Spanned;

use super::follow::KeyLocations;
use super::robot::ROBOT;
use super::source::{Source, finite, non_negative, one_of, positive};
use crate::error::SceneError;

pub(crate) const CONTROLLER: &str = "[controller]";

/// The template body's gain keys (moments: N m per m, N m per m/s).
pub const TEMPLATE_GAIN_KEYS: &[&str] = &["kp_n", "kd_n_s"];
/// The wheeled body's gain keys (turning rates: rad/s per m, rad/s per m/s).
pub const WHEELED_GAIN_KEYS: &[&str] = &["kp_rad_per_s_per_m", "kd_rad_per_m"];

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawController {
    estimator: Option<Spanned<String>>,
    window_s: Option<Spanned<f64>>,
    preview_m: Option<Spanned<f64>>,
    setpoint_m: Option<Spanned<f64>>,
    kp_n: Option<Spanned<f64>>,
    kd_n_s: Option<Spanned<f64>>,
    kp_rad_per_s_per_m: Option<Spanned<f64>>,
    kd_rad_per_m: Option<Spanned<f64>>,
    delay_s: Option<Spanned<f64>>,
    search_turn_rate_deg_per_s: Option<Spanned<f64>>,
}

impl RawController {
    /// The given numeric keys with their values, in table order.
    fn numbers(&self) -> [(&'static str, Option<&Spanned<f64>>); 9] {
        [
            ("window_s", self.window_s.as_ref()),
            ("preview_m", self.preview_m.as_ref()),
            ("setpoint_m", self.setpoint_m.as_ref()),
            ("kp_n", self.kp_n.as_ref()),
            ("kd_n_s", self.kd_n_s.as_ref()),
            ("kp_rad_per_s_per_m", self.kp_rad_per_s_per_m.as_ref()),
            ("kd_rad_per_m", self.kd_rad_per_m.as_ref()),
            ("delay_s", self.delay_s.as_ref()),
            (
                "search_turn_rate_deg_per_s",
                self.search_turn_rate_deg_per_s.as_ref(),
            ),
        ]
    }

    /// Where each given key's value is.
    fn spans(&self) -> Vec<(&'static str, Range<usize>)> {
        let mut spans: Vec<(&'static str, Range<usize>)> = self
            .numbers()
            .into_iter()
            .filter_map(|(key, v)| v.map(|v| (key, v.span())))
            .collect();
        if let Some(e) = &self.estimator {
            spans.push(("estimator", e.span()));
        }
        spans
    }

    /// The controller, every given key checked; `wheeled` says which gains apply,
    /// `table` is the table's span (`None` without the table); `locations` gets each key's
    /// place.
    pub(crate) fn validate(
        &self,
        source: &Source<'_>,
        table: Option<Range<usize>>,
        wheeled: bool,
        locations: &mut KeyLocations,
    ) -> Result<Controller, SceneError> {
        for (key, span) in self.spans() {
            locations.insert(source, "controller", key, span);
        }
        let mut controller = Controller::default();
        // Every number is a finite number first (a NaN gain says so), then its own range.
        for (key, value) in self.numbers() {
            if let Some(v) = value {
                finite(source, CONTROLLER, key, v)?;
            }
        }

        let which = match &self.estimator {
            Some(e) => one_of(source, CONTROLLER, "estimator", e, ESTIMATOR_NAMES)?,
            None => ESTIMATOR_NAMES
                .iter()
                .position(|n| *n == controller.estimator.name())
                .unwrap_or(0),
        };
        let name = ESTIMATOR_NAMES
            .get(which)
            .copied()
            .unwrap_or("contact-line");
        // Each estimator's own keys.
        for (key, owner) in [("window_s", "contact-line"), ("preview_m", "ideal-preview")] {
            let given = self
                .numbers()
                .into_iter()
                .find(|(k, _)| *k == key)
                .and_then(|(_, v)| v);
            if let Some(v) = given
                && name != owner
            {
                let takes = match name {
                    "contact-line" => "it takes window_s",
                    "ideal-preview" => "it takes preview_m",
                    _ => "it takes neither window_s nor preview_m",
                };
                return Err(source.invalid(
                    v.span(),
                    CONTROLLER,
                    key,
                    format!(
                        "only estimator \"{owner}\" takes {key}; this is estimator \
                         \"{name}\" ({takes})"
                    ),
                ));
            }
        }
        controller.estimator = match name {
            "contact-line" => Estimator::ContactLine {
                window_s: match &self.window_s {
                    Some(v) => positive(source, CONTROLLER, "window_s", v)?,
                    None => CONTACT_WINDOW_S_DEFAULT,
                },
            },
            "ideal-preview" => {
                let Some(v) = &self.preview_m else {
                    // Only a written estimator names "ideal-preview".
                    let at = self.estimator.as_ref().map(Spanned::span).or(table);
                    return Err(source.invalid(
                        at.unwrap_or(0..0),
                        CONTROLLER,
                        "preview_m",
                        "estimator \"ideal-preview\" needs preview_m, the preview distance l \
                         ahead of the point of rotation, m (it has no default)",
                    ));
                };
                Estimator::IdealPreview {
                    preview_m: non_negative(source, CONTROLLER, "preview_m", v)?,
                }
            }
            _ => Estimator::Bend,
        };

        // The gains of the robot's body only.
        let (body, takes, refused) = if wheeled {
            ("wheeled", WHEELED_GAIN_KEYS, TEMPLATE_GAIN_KEYS)
        } else {
            ("template", TEMPLATE_GAIN_KEYS, WHEELED_GAIN_KEYS)
        };
        for (key, value) in self.numbers() {
            if let Some(v) = value
                && refused.contains(&key)
            {
                let what = if wheeled {
                    "the template body's gain (a moment)"
                } else {
                    "the wheeled body's gain (a turning rate)"
                };
                return Err(source.invalid(
                    v.span(),
                    CONTROLLER,
                    key,
                    format!(
                        "{what}; {ROBOT} body = \"{body}\" takes the gains {}",
                        takes.join(", ")
                    ),
                ));
            }
        }
        let gain = |key: &str, v: &Option<Spanned<f64>>, default: f64| match v {
            Some(v) => non_negative(source, CONTROLLER, key, v),
            None => Ok(default),
        };
        controller.kp_n = gain("kp_n", &self.kp_n, controller.kp_n)?;
        controller.kd_n_s = gain("kd_n_s", &self.kd_n_s, controller.kd_n_s)?;
        controller.kp_rad_per_s_per_m = gain(
            "kp_rad_per_s_per_m",
            &self.kp_rad_per_s_per_m,
            controller.kp_rad_per_s_per_m,
        )?;
        controller.kd_rad_per_m =
            gain("kd_rad_per_m", &self.kd_rad_per_m, controller.kd_rad_per_m)?;
        if let Some(v) = &self.setpoint_m {
            controller.setpoint_m = positive(source, CONTROLLER, "setpoint_m", v)?;
        }
        if let Some(v) = &self.delay_s {
            controller.delay_s = non_negative(source, CONTROLLER, "delay_s", v)?;
        }
        if let Some(v) = &self.search_turn_rate_deg_per_s {
            controller.search_turn_rate_rad_per_s =
                non_negative(source, CONTROLLER, "search_turn_rate_deg_per_s", v)?.to_radians();
        }
        Ok(controller)
    }
}
