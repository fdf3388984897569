//! `[follow]` and the follow scene as a whole (issue #47): a scene with any of `[robot]`,
//! `[controller]` and `[follow]` describes a closed-loop run, a robot following the walls with
//! the antenna as its only sensor. All three tables then take sim-core's defaults for the
//! keys they leave out ([`FollowConfig::default`]); the result, checked key by key and then by
//! [`FollowConfig::validate`], is a [`FollowScene`]: the configuration with the place of every
//! key, so that an error found when the run starts ([`FollowError`]) is reported at the key
//! that caused it ([`FollowScene::locate`]).
//!
//! In a follow scene the body carries the antenna: `[base]`, `[sweep]`, `[tip_pin]` and
//! `[antenna] base_angle_deg` are refused, the chain's base angle is `[robot] mount_angle_deg`
//! (the angle the sensors see), and `[start]` defaults to an approach onto wall 0
//! ([`default_placement`]).

use std::collections::BTreeMap;
use std::ops::Range;

use nalgebra::{Rotation2, Vector2};
use serde::Deserialize;
use sim_core::Chain;
use sim_core::follow::{FollowConfig, FollowError, FollowSettings, Robot, WallSide};
use sim_core::sweep::{Motion, Placement};
use toml::Spanned;

use super::controller::RawController;
use super::robot::{RawRobot, is_wheeled};
use super::source::{Source, finite, non_negative, point, positive};
use super::start::DEFAULT_APPROACH_STEPS;
use crate::error::{Location, SceneError, SceneErrorKind};

const FOLLOW: &str = "[follow]";

/// Most steps a follow run may take (`duration_s / step_s`).
pub const MAX_FOLLOW_STEPS: usize = 10_000_000;

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawFollow {
    duration_s: Option<Spanned<f64>>,
    step_s: Option<Spanned<f64>>,
    pose_m: Option<Spanned<Vec<f64>>>,
    heading_deg: Option<Spanned<f64>>,
    lost_after_s: Option<Spanned<f64>>,
    lost_beyond_m: Option<Spanned<f64>>,
    settling_window_m: Option<Spanned<f64>>,
    settling_band_m: Option<Spanned<f64>>,
    antenna_step_m: Option<Spanned<f64>>,
}

/// A follow scene's closed-loop run: what sim-core's follow run takes besides the sweep scene
/// (the antenna, the walls, the placement, the contact solver) and the sensors, with where
/// each of its keys is in the file.
#[derive(Debug, Clone, PartialEq)]
pub struct FollowScene {
    /// The robot, the controller and the run, checked by [`FollowConfig::validate`].
    pub config: FollowConfig,
    /// Where the keys are.
    pub locations: FollowLocations,
}

/// Where a follow scene's tables and keys are in the file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FollowLocations {
    /// The file name as given (for errors found after parsing).
    pub path: String,
    /// Each written table (`"robot"`, `"controller"`, `"follow"`, `"start"`, `"sensors"`,
    /// without brackets): its header.
    pub tables: BTreeMap<String, Location>,
    /// Each written key of `[robot]`, `[controller]` and `[follow]`, as `"table.key"`: its
    /// value.
    pub keys: BTreeMap<String, Location>,
    /// `[start] placement` (or the `[start]` table when the key is absent); `None` when the
    /// scene has no `[start]` and takes the default approach.
    pub start_placement: Option<Location>,
}

/// What [`FollowLocations`] collects while the tables are read.
pub(crate) type KeyLocations = FollowLocations;

impl FollowLocations {
    /// Records that `key` of `table` (without brackets) has its value at `span`.
    pub(crate) fn insert(
        &mut self,
        source: &Source<'_>,
        table: &str,
        key: &str,
        span: Range<usize>,
    ) {
        if let Some(at) = source.at(span) {
            self.keys.insert(format!("{table}.{key}"), at);
        }
    }

    /// Where `key` of `table` (without brackets) is, or else its table, or else the first
    /// of `[follow]`, `[robot]`, `[controller]` the file has.
    pub fn key_or_table(&self, table: &str, key: &str) -> Option<Location> {
        self.keys
            .get(&format!("{table}.{key}"))
            .or_else(|| self.tables.get(table))
            .or_else(|| {
                ["follow", "robot", "controller"]
                    .iter()
                    .find_map(|t| self.tables.get(*t))
            })
            .copied()
    }
}

impl FollowScene {
    /// The error of a run that could not start or go on, worded as a scene error at the key
    /// that caused it: a value out of range ([`FollowError::Invalid`]) at its key (or its
    /// table when the key is not written: a default), a footprint overlapping a wall at the
    /// start ([`FollowError::StartsInWall`]) at `[follow] pose_m`, a placement that fails at
    /// `[start] placement` (or, for the default approach, at `[follow] pose_m`), the bend
    /// estimator's calibration at `[controller] estimator`, the sensors at `[sensors]`; a
    /// step the antenna's solver refused has no key to blame and no location.
    pub fn locate(&self, error: &FollowError) -> SceneError {
        let at = |table: &str, key: &str| self.locations.key_or_table(table, key);
        let invalid =
            |table: &str, key: &str, location: Option<Location>, reason: String| SceneError {
                path: self.locations.path.clone(),
                location,
                kind: Box::new(SceneErrorKind::Invalid {
                    key: key.to_string(),
                    table: table.to_string(),
                    reason,
                }),
            };
        match error {
            FollowError::Invalid { table, key, reason } => {
                invalid(&format!("[{table}]"), key, at(table, key), reason.clone())
            }
            FollowError::StartsInWall { .. } => {
                invalid(FOLLOW, "pose_m", at("follow", "pose_m"), error.to_string())
            }
            FollowError::Placement(e) => match self.locations.start_placement {
                Some(location) => invalid("[start]", "placement", Some(location), e.to_string()),
                None => invalid(
                    FOLLOW,
                    "pose_m",
                    at("follow", "pose_m"),
                    format!(
                        "the default placement of a follow scene (an approach onto wall 0) \
                         failed: {e}; move the robot or write a [start] table"
                    ),
                ),
            },
            FollowError::Calibration(_) => invalid(
                "[controller]",
                "estimator",
                at("controller", "estimator"),
                error.to_string(),
            ),
            FollowError::Sensors(_) => SceneError {
                path: self.locations.path.clone(),
                location: self.locations.tables.get("sensors").copied(),
                kind: Box::new(SceneErrorKind::Run {
                    message: error.to_string(),
                }),
            },
            _ => SceneError {
                path: self.locations.path.clone(),
                location: None,
                kind: Box::new(SceneErrorKind::Run {
                    message: error.to_string(),
                }),
            },
        }
    }

    /// The antenna's base pivot at the start in the ground frame: `[follow] pose_m` plus
    /// `[robot] mount_m` turned by the start heading (its second value toward the wall's
    /// side).
    pub fn mount_start_m(&self) -> Vector2<f64> {
        mount_position_m(&self.config.robot, &self.config.settings)
    }

    /// The open-loop counterpart of the run, the base carried straight on at the robot's
    /// speed along its start heading for `[follow] duration_s` in steps of `step_s`: the
    /// follow scene's [`Motion`] (what `Scene::sweep_scene` gives, so that the sweep of a
    /// follow scene is the run without the controller).
    pub fn open_loop_motion(&self) -> Motion {
        let s = &self.config.settings;
        let (sin, cos) = s.heading_rad.sin_cos();
        Motion {
            velocity_m_per_s: self.config.robot.speed_m_per_s * Vector2::new(cos, sin),
            duration_s: s.duration_s,
            step_s: s.step_s,
        }
    }
}

/// The mount's ground position at the start.
fn mount_position_m(robot: &Robot, settings: &FollowSettings) -> Vector2<f64> {
    let side = match robot.wall_side {
        WallSide::Left => 1.0,
        WallSide::Right => -1.0,
    };
    let body = Vector2::new(robot.mount_m.x, side * robot.mount_m.y);
    settings.pose_m + Rotation2::new(settings.heading_rad) * body
}

/// The placement of a follow scene without `[start]`: an approach onto wall 0 from as far
/// back as the antenna is long (the sum of its link lengths, the base link included: clear
/// of a straight wall whatever the posture), coming straight in (`along_m = 0`) in
/// [`DEFAULT_APPROACH_STEPS`] steps, or more where that would move the base more than
/// `[follow] antenna_step_m` per step.
pub fn default_placement(chain: &Chain, settings: &FollowSettings) -> Placement {
    let distance_m = chain.total_length_m();
    let by_step = (distance_m / settings.antenna_step_m).ceil();
    let steps = if by_step.is_finite() && by_step > DEFAULT_APPROACH_STEPS as f64 {
        // Bounded: antenna_step_m is positive and the chain at most MAX_LINKS links long.
        (by_step as usize).min(super::start::MAX_APPROACH_STEPS)
    } else {
        DEFAULT_APPROACH_STEPS
    };
    Placement::Approach {
        wall: 0,
        distance_m,
        along_m: 0.0,
        steps,
    }
}

impl RawFollow {
    /// Where each given key's value is.
    fn spans(&self) -> Vec<(&'static str, Range<usize>)> {
        let f = |key: &'static str, v: &Option<Spanned<f64>>| v.as_ref().map(|v| (key, v.span()));
        [
            f("duration_s", &self.duration_s),
            f("step_s", &self.step_s),
            self.pose_m.as_ref().map(|v| ("pose_m", v.span())),
            f("heading_deg", &self.heading_deg),
            f("lost_after_s", &self.lost_after_s),
            f("lost_beyond_m", &self.lost_beyond_m),
            f("settling_window_m", &self.settling_window_m),
            f("settling_band_m", &self.settling_band_m),
            f("antenna_step_m", &self.antenna_step_m),
        ]
        .into_iter()
        .flatten()
        .collect()
    }

    /// The run's settings, every given key checked.
    fn validate(
        &self,
        source: &Source<'_>,
        locations: &mut KeyLocations,
    ) -> Result<FollowSettings, SceneError> {
        for (key, span) in self.spans() {
            locations.insert(source, "follow", key, span);
        }
        let mut s = FollowSettings::default();
        let pos = |key: &str, v: &Option<Spanned<f64>>, default: f64| match v {
            Some(v) => positive(source, FOLLOW, key, v),
            None => Ok(default),
        };
        s.duration_s = pos("duration_s", &self.duration_s, s.duration_s)?;
        s.step_s = pos("step_s", &self.step_s, s.step_s)?;
        if let Some(p) = &self.pose_m {
            s.pose_m = point(source, FOLLOW, "pose_m", p)?;
        }
        if let Some(h) = &self.heading_deg {
            s.heading_rad = finite(source, FOLLOW, "heading_deg", h)?.to_radians();
        }
        s.lost_after_s = pos("lost_after_s", &self.lost_after_s, s.lost_after_s)?;
        if let Some(b) = &self.lost_beyond_m {
            s.lost_beyond_m = Some(positive(source, FOLLOW, "lost_beyond_m", b)?);
        }
        if let Some(w) = &self.settling_window_m {
            s.settling_window_m = non_negative(source, FOLLOW, "settling_window_m", w)?;
        }
        s.settling_band_m = pos("settling_band_m", &self.settling_band_m, s.settling_band_m)?;
        s.antenna_step_m = pos("antenna_step_m", &self.antenna_step_m, s.antenna_step_m)?;
        let steps = s.duration_s / s.step_s;
        if steps.round() > MAX_FOLLOW_STEPS as f64 {
            let (key, span) = match (&self.duration_s, &self.step_s) {
                (Some(d), _) => ("duration_s", d.span()),
                (None, Some(st)) => ("step_s", st.span()),
                (None, None) => ("duration_s", 0..0),
            };
            return Err(source.invalid(
                span,
                FOLLOW,
                key,
                format!(
                    "duration_s / step_s = {steps:.0} steps; at most {MAX_FOLLOW_STEPS} are \
                     allowed"
                ),
            ));
        }
        Ok(s)
    }
}

/// A follow scene's three tables as written (each `None` when absent).
pub(crate) struct RawFollowTables<'a> {
    pub(crate) robot: Option<&'a Spanned<RawRobot>>,
    pub(crate) controller: Option<&'a Spanned<RawController>>,
    pub(crate) follow: Option<&'a Spanned<RawFollow>>,
}

impl RawFollowTables<'_> {
    /// The span of the first of the three tables in the file.
    pub(crate) fn first_span(&self) -> Option<Range<usize>> {
        [
            self.robot.map(Spanned::span),
            self.controller.map(Spanned::span),
            self.follow.map(Spanned::span),
        ]
        .into_iter()
        .flatten()
        .min_by_key(|s| s.start)
    }

    /// The follow scene: every key checked where it is written, then the whole by
    /// [`FollowConfig::validate`], whose error is put at its key. `start` and `sensors` are
    /// the spans of the `[start]` placement (or table) and the `[sensors]` table, if written.
    pub(crate) fn validate(
        &self,
        source: &Source<'_>,
        start: Option<Range<usize>>,
        sensors: Option<Range<usize>>,
    ) -> Result<FollowScene, SceneError> {
        let mut locations = FollowLocations {
            path: source.path.to_string(),
            start_placement: start.and_then(|s| source.at(s)),
            ..FollowLocations::default()
        };
        for (table, span) in [
            ("robot", self.robot.map(Spanned::span)),
            ("controller", self.controller.map(Spanned::span)),
            ("follow", self.follow.map(Spanned::span)),
            ("sensors", sensors),
        ] {
            if let Some(at) = span.and_then(|s| source.at(s)) {
                locations.tables.insert(table.to_string(), at);
            }
        }
        let default_robot = RawRobot::default();
        let robot = self
            .robot
            .map_or(&default_robot, |r| r.get_ref())
            .validate(source, &mut locations)?;
        let default_controller = RawController::default();
        let controller = self
            .controller
            .map_or(&default_controller, |c| c.get_ref())
            .validate(
                source,
                self.controller.map(Spanned::span),
                is_wheeled(&robot),
                &mut locations,
            )?;
        let default_follow = RawFollow::default();
        let settings = self
            .follow
            .map_or(&default_follow, |f| f.get_ref())
            .validate(source, &mut locations)?;
        let scene = FollowScene {
            config: FollowConfig {
                robot,
                controller,
                settings,
            },
            locations,
        };
        scene.config.validate().map_err(|e| scene.locate(&e))?;
        Ok(scene)
    }
}
