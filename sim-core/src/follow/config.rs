//! What a closed-loop run is made of: the robot ([`Robot`], its body [`BodyModel`]), the
//! controller ([`Controller`], its [`Estimator`]) and the run ([`FollowSettings`]). A scene's
//! `[robot]`, `[controller]` and `[follow]` tables (docs/scene-format.md) fill them; every
//! value is checked by [`FollowConfig::validate`].

use nalgebra::Vector2;

use super::FollowError;

/// Which side of the body the wall is on (the body frame's y axis points toward it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum WallSide {
    /// The wall on the body's left (the sweeps' geometry: the antenna reaches to +y).
    #[default]
    Left,
    /// The wall on the body's right: the run is the mirror image of a left-wall run.
    Right,
}

impl WallSide {
    /// The scene's name of the side.
    pub fn name(self) -> &'static str {
        match self {
            WallSide::Left => "left",
            WallSide::Right => "right",
        }
    }
}

/// How the body turns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BodyModel {
    /// Cowan, Lee and Full (2006)'s template: legs apply a moment `u` about the point of
    /// rotation, `J domega/dt = -b omega + u`. The controller's gains are `kp_n` and
    /// `kd_n_s` (moment per metre, per metre per second).
    Template {
        /// `J`, the body's moment of inertia about the point of rotation, kg m^2.
        inertia_kg_m2: f64,
        /// `b`, the rotational damping, N m s/rad.
        damping_n_m_s_per_rad: f64,
    },
    /// A wheeled robot whose turning rate is commanded: the rate follows the command within
    /// a rate limit and an acceleration limit. The controller's gains are
    /// `kp_rad_per_s_per_m` and `kd_rad_per_m`.
    Wheeled {
        /// The largest turning rate, rad/s.
        max_turn_rate_rad_per_s: f64,
        /// The largest turning acceleration, rad/s^2.
        max_turn_accel_rad_per_s2: f64,
    },
}

/// The robot: a body running at a constant forward speed with an antenna mounted on it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Robot {
    /// Forward speed `v`, m/s.
    pub speed_m_per_s: f64,
    /// How the body turns.
    pub body: BodyModel,
    /// The footprint, a rectangle centred on the point of rotation: `[length, width]`, m.
    pub footprint_m: [f64; 2],
    /// The antenna's base pivot in the body frame: `[ahead, toward the wall]`, m.
    pub mount_m: Vector2<f64>,
    /// The antenna's base link from the body axis, toward the wall, radians.
    pub mount_angle_rad: f64,
    /// Which side the wall is on.
    pub wall_side: WallSide,
    /// Whether the moment of the antenna's contact forces about the point of rotation acts
    /// on the body (off: the template's assumption).
    pub antenna_loads_body: bool,
}

impl Default for Robot {
    /// The `[robot]` table's defaults: the example robot, a template body.
    fn default() -> Self {
        Robot {
            speed_m_per_s: 0.3,
            body: BodyModel::Template {
                inertia_kg_m2: 2.0e-4,
                damping_n_m_s_per_rad: 4.0e-3,
            },
            footprint_m: [0.12, 0.06],
            mount_m: Vector2::new(0.04, 0.02),
            mount_angle_rad: 30f64.to_radians(),
            wall_side: WallSide::Left,
            antenna_loads_body: false,
        }
    }
}

/// From what is sensed to the wall's distance in the body frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Estimator {
    /// The mapped contact points of the last `window_s` seconds, carried into the current
    /// body frame by odometry, fitted by a line (at least 2 points spanning 1 cm).
    ContactLine {
        /// How far back the points are kept, seconds.
        window_s: f64,
    },
    /// The sensed point of bend mapped to a distance by a calibration table made for this
    /// antenna (no angle).
    Bend,
    /// The template's `d` at `preview_m` ahead of the point of rotation, from the true
    /// geometry: the check against theory, not a sensor.
    IdealPreview {
        /// The preview distance `l`, m.
        preview_m: f64,
    },
}

impl Estimator {
    /// The scene's name of the estimator.
    pub fn name(&self) -> &'static str {
        match self {
            Estimator::ContactLine { .. } => "contact-line",
            Estimator::Bend => "bend",
            Estimator::IdealPreview { .. } => "ideal-preview",
        }
    }
}

/// The names `[controller] estimator` takes.
pub const ESTIMATOR_NAMES: &[&str] = &["contact-line", "bend", "ideal-preview"];

/// The default window of the contact-line estimator, seconds.
pub const CONTACT_WINDOW_S_DEFAULT: f64 = 0.5;

/// A PD controller on the estimated distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Controller {
    /// The estimator.
    pub estimator: Estimator,
    /// The wanted distance from the point of rotation to the wall, m.
    pub setpoint_m: f64,
    /// Template body: moment per metre of error, N m/m (`kp_n`).
    pub kp_n: f64,
    /// Template body: moment per m/s of the error's rate, N m s/m (`kd_n_s`).
    pub kd_n_s: f64,
    /// Wheeled body: turning rate per metre of error, rad/s per m.
    pub kp_rad_per_s_per_m: f64,
    /// Wheeled body: turning rate per m/s of the error's rate, rad/m.
    pub kd_rad_per_m: f64,
    /// From sensing to actuation, seconds (rounded to whole steps, half up).
    pub delay_s: f64,
    /// With no estimate, the body turns toward the wall's side at this rate, rad/s.
    pub search_turn_rate_rad_per_s: f64,
}

impl Default for Controller {
    /// The `[controller]` table's defaults.
    fn default() -> Self {
        Controller {
            estimator: Estimator::ContactLine {
                window_s: CONTACT_WINDOW_S_DEFAULT,
            },
            setpoint_m: 0.10,
            kp_n: 0.05,
            kd_n_s: 0.002,
            kp_rad_per_s_per_m: 40.0,
            kd_rad_per_m: 2.0,
            delay_s: 0.0,
            search_turn_rate_rad_per_s: 0.5,
        }
    }
}

/// The run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FollowSettings {
    /// How long the robot runs, seconds.
    pub duration_s: f64,
    /// The control and integration step, seconds (0.0005 to 0.05).
    pub step_s: f64,
    /// The point of rotation's start, ground frame, m.
    pub pose_m: Vector2<f64>,
    /// The body's start heading, ground frame, counter-clockwise, radians.
    pub heading_rad: f64,
    /// With no estimate for this long, the run ends `lost`, seconds.
    pub lost_after_s: f64,
    /// Farther than this from every wall (the point of rotation's true distance), the run
    /// ends `lost`, m (`None`: three times the setpoint). A fast robot that drifts away
    /// keeps a stale estimate for a while; the judge does not wait for it.
    pub lost_beyond_m: Option<f64>,
    /// The error statistics start after this much travel, m.
    pub settling_window_m: f64,
    /// The run has settled once the true error stays within this band, m.
    pub settling_band_m: f64,
    /// The antenna is solved at least every this much travel of its base, m.
    pub antenna_step_m: f64,
}

impl Default for FollowSettings {
    /// The `[follow]` table's defaults.
    fn default() -> Self {
        FollowSettings {
            duration_s: 10.0,
            step_s: 0.01,
            pose_m: Vector2::new(0.0, 0.12),
            heading_rad: 0.0,
            lost_after_s: 2.0,
            lost_beyond_m: None,
            settling_window_m: 0.5,
            settling_band_m: 0.01,
            antenna_step_m: 0.002,
        }
    }
}

/// The largest `b h / J` of a template body (`b` its damping, `J` its inertia, `h` the
/// step): RK4 is stable on `domega/dt = -(b / J) omega` up to 2.785; this keeps a margin.
pub const RK4_DAMPING_LIMIT: f64 = 2.5;

/// The smallest and largest `step_s`.
pub const STEP_S_RANGE: [f64; 2] = [0.0005, 0.05];

/// A whole closed-loop run's description (besides the antenna and walls of its sweep scene).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FollowConfig {
    /// The robot.
    pub robot: Robot,
    /// The controller.
    pub controller: Controller,
    /// The run.
    pub settings: FollowSettings,
}

impl FollowConfig {
    /// The number of steps: `round(duration / step)`.
    pub fn steps(&self) -> usize {
        (self.settings.duration_s / self.settings.step_s)
            .round()
            .max(0.0) as usize
    }

    /// The distance beyond which a run is lost: `lost_beyond_m`, or three times the
    /// setpoint.
    pub fn lost_beyond_m(&self) -> f64 {
        self.settings
            .lost_beyond_m
            .unwrap_or(3.0 * self.controller.setpoint_m)
    }

    /// The delay in whole steps: `round(delay_s / step_s)`, halves rounded up.
    pub fn delay_steps(&self) -> usize {
        // The ratio of two decimals can land a rounding error below a half (0.005 / 0.01).
        (self.controller.delay_s / self.settings.step_s + 0.5 + 1e-9)
            .floor()
            .max(0.0) as usize
    }

    /// Checks every value; the error names the table and key (the scene crate adds the
    /// file, line and column).
    ///
    /// # Errors
    /// [`FollowError::Invalid`] for the first value out of range.
    pub fn validate(&self) -> Result<(), FollowError> {
        let r = &self.robot;
        let c = &self.controller;
        let s = &self.settings;
        let bad = |table: &'static str, key: &'static str, reason: String| {
            Err(FollowError::Invalid { table, key, reason })
        };
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let non_negative = |v: f64| v.is_finite() && v >= 0.0;
        if !positive(r.speed_m_per_s) {
            return bad("robot", "speed_m_per_s", must("positive", r.speed_m_per_s));
        }
        match r.body {
            BodyModel::Template {
                inertia_kg_m2,
                damping_n_m_s_per_rad,
            } => {
                if !positive(inertia_kg_m2) {
                    return bad("robot", "inertia_kg_m2", must("positive", inertia_kg_m2));
                }
                if !non_negative(damping_n_m_s_per_rad) {
                    return bad(
                        "robot",
                        "damping_n_m_s_per_rad",
                        must("zero or positive", damping_n_m_s_per_rad),
                    );
                }
            }
            BodyModel::Wheeled {
                max_turn_rate_rad_per_s,
                max_turn_accel_rad_per_s2,
            } => {
                if !positive(max_turn_rate_rad_per_s) {
                    return bad(
                        "robot",
                        "max_turn_rate_deg_per_s",
                        must("positive", max_turn_rate_rad_per_s.to_degrees()),
                    );
                }
                if !positive(max_turn_accel_rad_per_s2) {
                    return bad(
                        "robot",
                        "max_turn_accel_deg_per_s2",
                        must("positive", max_turn_accel_rad_per_s2.to_degrees()),
                    );
                }
            }
        }
        if r.antenna_loads_body && matches!(r.body, BodyModel::Wheeled { .. }) {
            return bad(
                "robot",
                "antenna_loads_body",
                "a wheeled robot's turning rate is commanded, so the antenna's moment cannot \
                 turn it: antenna_loads_body needs body = \"template\""
                    .to_string(),
            );
        }
        for (k, v) in r.footprint_m.iter().enumerate() {
            if !positive(*v) {
                let what = if k == 0 { "length" } else { "width" };
                return bad(
                    "robot",
                    "footprint_m",
                    format!("the footprint's {what} must be positive, not {v}"),
                );
            }
        }
        if !(r.mount_m.x.is_finite() && r.mount_m.y.is_finite()) {
            return bad("robot", "mount_m", "must be two finite numbers".to_string());
        }
        if !(r.mount_angle_rad.is_finite() && r.mount_angle_rad.abs() <= std::f64::consts::PI) {
            return bad(
                "robot",
                "mount_angle_deg",
                must("within -180 to 180", r.mount_angle_rad.to_degrees()),
            );
        }
        match c.estimator {
            Estimator::ContactLine { window_s } if !positive(window_s) => {
                return bad("controller", "window_s", must("positive", window_s));
            }
            Estimator::IdealPreview { preview_m } if !non_negative(preview_m) => {
                return bad(
                    "controller",
                    "preview_m",
                    must("zero or positive", preview_m),
                );
            }
            _ => {}
        }
        if !positive(c.setpoint_m) {
            return bad("controller", "setpoint_m", must("positive", c.setpoint_m));
        }
        for (key, v) in [
            ("kp_n", c.kp_n),
            ("kd_n_s", c.kd_n_s),
            ("kp_rad_per_s_per_m", c.kp_rad_per_s_per_m),
            ("kd_rad_per_m", c.kd_rad_per_m),
            ("delay_s", c.delay_s),
            (
                "search_turn_rate_deg_per_s",
                c.search_turn_rate_rad_per_s.to_degrees(),
            ),
        ] {
            if !non_negative(v) {
                return bad("controller", key, must("zero or positive", v));
            }
        }
        if !positive(s.duration_s) {
            return bad("follow", "duration_s", must("positive", s.duration_s));
        }
        if !(s.step_s >= STEP_S_RANGE[0] && s.step_s <= STEP_S_RANGE[1]) {
            return bad(
                "follow",
                "step_s",
                format!(
                    "must be within {} to {} s, not {}",
                    STEP_S_RANGE[0], STEP_S_RANGE[1], s.step_s
                ),
            );
        }
        if let BodyModel::Template {
            inertia_kg_m2,
            damping_n_m_s_per_rad,
        } = r.body
        {
            // RK4 on `domega/dt = -(b / J) omega` is stable for `(b / J) h` up to 2.785
            // (its stability region on the negative real axis); a margin keeps the turning
            // rate from ringing near it.
            let ratio = damping_n_m_s_per_rad * s.step_s / inertia_kg_m2;
            if ratio > RK4_DAMPING_LIMIT {
                return bad(
                    "follow",
                    "step_s",
                    format!(
                        "{} s is too long for this body: RK4 needs damping x step / inertia \
                         below {RK4_DAMPING_LIMIT} (here {ratio:.3}); take step_s below {:.3e} s",
                        s.step_s,
                        RK4_DAMPING_LIMIT * inertia_kg_m2 / damping_n_m_s_per_rad
                    ),
                );
            }
        }
        if !(s.pose_m.x.is_finite() && s.pose_m.y.is_finite()) {
            return bad("follow", "pose_m", "must be two finite numbers".to_string());
        }
        if !s.heading_rad.is_finite() {
            return bad(
                "follow",
                "heading_deg",
                must("finite", s.heading_rad.to_degrees()),
            );
        }
        for (key, v) in [
            ("lost_after_s", s.lost_after_s),
            ("settling_band_m", s.settling_band_m),
            ("antenna_step_m", s.antenna_step_m),
        ] {
            if !positive(v) {
                return bad("follow", key, must("positive", v));
            }
        }
        if let Some(beyond) = s.lost_beyond_m
            && !(positive(beyond) && beyond > c.setpoint_m)
        {
            return bad(
                "follow",
                "lost_beyond_m",
                format!(
                    "must be greater than the setpoint ({} m), not {beyond}",
                    c.setpoint_m
                ),
            );
        }
        if !non_negative(s.settling_window_m) {
            return bad(
                "follow",
                "settling_window_m",
                must("zero or positive", s.settling_window_m),
            );
        }
        Ok(())
    }
}

fn must(what: &str, value: f64) -> String {
    format!("must be {what}, not {value}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_are_valid_and_bad_values_name_their_key() {
        assert_eq!(FollowConfig::default().validate(), Ok(()));
        let mut c = FollowConfig::default();
        c.robot.speed_m_per_s = -0.1;
        assert!(matches!(
            c.validate(),
            Err(FollowError::Invalid {
                table: "robot",
                key: "speed_m_per_s",
                ..
            })
        ));
        let mut c = FollowConfig::default();
        c.controller.kp_n = f64::NAN;
        assert!(matches!(
            c.validate(),
            Err(FollowError::Invalid { key: "kp_n", .. })
        ));
        let mut c = FollowConfig::default();
        c.robot.body = BodyModel::Template {
            inertia_kg_m2: 1e-5,
            damping_n_m_s_per_rad: 4e-3,
        };
        match c.validate() {
            Err(FollowError::Invalid {
                key: "step_s",
                reason,
                ..
            }) => assert!(reason.contains("below 6.250e-3 s"), "{reason}"),
            other => panic!("{other:?}"),
        }
        let mut c = FollowConfig::default();
        c.robot.antenna_loads_body = true;
        c.robot.body = BodyModel::Wheeled {
            max_turn_rate_rad_per_s: 3.0,
            max_turn_accel_rad_per_s2: 10.0,
        };
        assert!(matches!(
            c.validate(),
            Err(FollowError::Invalid {
                key: "antenna_loads_body",
                ..
            })
        ));
        let mut c = FollowConfig::default();
        c.settings.step_s = 0.0001;
        assert!(matches!(
            c.validate(),
            Err(FollowError::Invalid { key: "step_s", .. })
        ));
    }

    #[test]
    fn the_delay_rounds_half_up_to_whole_steps() {
        let mut c = FollowConfig::default();
        for (delay_s, steps) in [(0.0, 0), (0.004, 0), (0.005, 1), (0.014, 1), (0.015, 2)] {
            c.controller.delay_s = delay_s;
            assert_eq!(c.delay_steps(), steps, "{delay_s}");
        }
    }
}
