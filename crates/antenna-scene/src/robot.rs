//! `[robot]` (a follow scene, issue #47): the body that carries the antenna, its speed, how
//! it turns (the template body of Cowan, Lee and Full 2006, or a wheeled robot), its
//! footprint, where the antenna is mounted on it and which side the wall is on. Unset keys
//! take sim-core's [`Robot::default`]; the wheeled body's limits default to
//! [`DEFAULT_MAX_TURN_RATE_DEG_PER_S`] and [`DEFAULT_MAX_TURN_ACCEL_DEG_PER_S2`].

use std::ops::Range;

use serde::Deserialize;
use sim_core::follow::{BodyModel, Robot, WallSide};
use toml::Spanned;

use super::follow::KeyLocations;
use super::source::{Source, finite, list_of_len, non_negative, not_for, one_of, point, positive};
use crate::error::SceneError;

pub(crate) const ROBOT: &str = "[robot]";

/// The names `[robot] body` takes.
pub const BODY_NAMES: &[&str] = &["template", "wheeled"];
/// The names `[robot] wall_side` takes.
pub const WALL_SIDE_NAMES: &[&str] = &["left", "right"];
/// The keys only the template body takes.
pub const TEMPLATE_KEYS: &[&str] = &["inertia_kg_m2", "damping_n_m_s_per_rad"];
/// The keys only the wheeled body takes.
pub const WHEELED_KEYS: &[&str] = &["max_turn_rate_deg_per_s", "max_turn_accel_deg_per_s2"];
/// The wheeled body's largest turning rate when `max_turn_rate_deg_per_s` is not given.
pub const DEFAULT_MAX_TURN_RATE_DEG_PER_S: f64 = 180.0;
/// The wheeled body's largest turning acceleration when `max_turn_accel_deg_per_s2` is not
/// given.
pub const DEFAULT_MAX_TURN_ACCEL_DEG_PER_S2: f64 = 720.0;

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawRobot {
    speed_m_per_s: Option<Spanned<f64>>,
    body: Option<Spanned<String>>,
    inertia_kg_m2: Option<Spanned<f64>>,
    damping_n_m_s_per_rad: Option<Spanned<f64>>,
    max_turn_rate_deg_per_s: Option<Spanned<f64>>,
    max_turn_accel_deg_per_s2: Option<Spanned<f64>>,
    footprint_m: Option<Spanned<Vec<f64>>>,
    mount_m: Option<Spanned<Vec<f64>>>,
    mount_angle_deg: Option<Spanned<f64>>,
    wall_side: Option<Spanned<String>>,
    antenna_loads_body: Option<Spanned<bool>>,
}

/// Whether the body is the wheeled one.
pub(crate) fn is_wheeled(robot: &Robot) -> bool {
    matches!(robot.body, BodyModel::Wheeled { .. })
}

impl RawRobot {
    /// Where each given key's value is, for errors found later.
    pub(crate) fn spans(&self) -> Vec<(&'static str, Range<usize>)> {
        let f = |key: &'static str, v: &Option<Spanned<f64>>| v.as_ref().map(|v| (key, v.span()));
        let l =
            |key: &'static str, v: &Option<Spanned<Vec<f64>>>| v.as_ref().map(|v| (key, v.span()));
        let s =
            |key: &'static str, v: &Option<Spanned<String>>| v.as_ref().map(|v| (key, v.span()));
        [
            f("speed_m_per_s", &self.speed_m_per_s),
            s("body", &self.body),
            f("inertia_kg_m2", &self.inertia_kg_m2),
            f("damping_n_m_s_per_rad", &self.damping_n_m_s_per_rad),
            f("max_turn_rate_deg_per_s", &self.max_turn_rate_deg_per_s),
            f("max_turn_accel_deg_per_s2", &self.max_turn_accel_deg_per_s2),
            l("footprint_m", &self.footprint_m),
            l("mount_m", &self.mount_m),
            f("mount_angle_deg", &self.mount_angle_deg),
            s("wall_side", &self.wall_side),
            self.antenna_loads_body
                .as_ref()
                .map(|v| ("antenna_loads_body", v.span())),
        ]
        .into_iter()
        .flatten()
        .collect()
    }

    /// The robot, every given key checked; `locations` gets each key's place.
    pub(crate) fn validate(
        &self,
        source: &Source<'_>,
        locations: &mut KeyLocations,
    ) -> Result<Robot, SceneError> {
        for (key, span) in self.spans() {
            locations.insert(source, "robot", key, span);
        }
        let mut robot = Robot::default();
        if let Some(v) = &self.speed_m_per_s {
            robot.speed_m_per_s = positive(source, ROBOT, "speed_m_per_s", v)?;
        }
        let wheeled = match &self.body {
            Some(b) => one_of(source, ROBOT, "body", b, BODY_NAMES)? == 1,
            None => false,
        };
        let (name, takes, refused) = if wheeled {
            ("body \"wheeled\"", WHEELED_KEYS, TEMPLATE_KEYS)
        } else {
            ("body \"template\"", TEMPLATE_KEYS, WHEELED_KEYS)
        };
        for (key, span) in self.spans() {
            if refused.contains(&key) {
                return Err(not_for(source, span, ROBOT, key, name, takes));
            }
        }
        if wheeled {
            let rate = match &self.max_turn_rate_deg_per_s {
                Some(v) => positive(source, ROBOT, "max_turn_rate_deg_per_s", v)?,
                None => DEFAULT_MAX_TURN_RATE_DEG_PER_S,
            };
            let accel = match &self.max_turn_accel_deg_per_s2 {
                Some(v) => positive(source, ROBOT, "max_turn_accel_deg_per_s2", v)?,
                None => DEFAULT_MAX_TURN_ACCEL_DEG_PER_S2,
            };
            robot.body = BodyModel::Wheeled {
                max_turn_rate_rad_per_s: rate.to_radians(),
                max_turn_accel_rad_per_s2: accel.to_radians(),
            };
        } else if let BodyModel::Template {
            inertia_kg_m2,
            damping_n_m_s_per_rad,
        } = &mut robot.body
        {
            // The default body is the template: its values are the defaults.
            if let Some(v) = &self.inertia_kg_m2 {
                *inertia_kg_m2 = positive(source, ROBOT, "inertia_kg_m2", v)?;
            }
            if let Some(v) = &self.damping_n_m_s_per_rad {
                *damping_n_m_s_per_rad = non_negative(source, ROBOT, "damping_n_m_s_per_rad", v)?;
            }
        }
        if let Some(list) = &self.footprint_m {
            let v = list_of_len(
                source,
                ROBOT,
                "footprint_m",
                list,
                2,
                "[length, width] of the rectangle centred on the point of rotation",
            )?;
            if let Some((i, l)) = v.iter().enumerate().find(|(_, l)| **l <= 0.0) {
                let what = if i == 0 { "length" } else { "width" };
                return Err(source.invalid(
                    list.span(),
                    ROBOT,
                    "footprint_m",
                    format!("the {what} is {l}; it must be > 0"),
                ));
            }
            robot.footprint_m = [v[0], v[1]];
        }
        if let Some(p) = &self.mount_m {
            robot.mount_m = point(source, ROBOT, "mount_m", p)?;
        }
        if let Some(a) = &self.mount_angle_deg {
            let deg = finite(source, ROBOT, "mount_angle_deg", a)?;
            if deg.abs() > 180.0 {
                return Err(source.invalid(
                    a.span(),
                    ROBOT,
                    "mount_angle_deg",
                    format!("{deg} is outside -180..=180 degrees"),
                ));
            }
            robot.mount_angle_rad = deg.to_radians();
        }
        if let Some(side) = &self.wall_side {
            robot.wall_side = match one_of(source, ROBOT, "wall_side", side, WALL_SIDE_NAMES)? {
                0 => WallSide::Left,
                _ => WallSide::Right,
            };
        }
        if let Some(b) = &self.antenna_loads_body {
            robot.antenna_loads_body = *b.get_ref();
        }
        Ok(robot)
    }
}
