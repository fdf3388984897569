//! The one scene model of the toolkit: the TOML description of one antenna, its base, and what
//! acts on it (`docs/scene-format.md`), parsed with serde and validated into a [`Scene`]. The
//! `antenna` command (solve, sweep, study, optimize), the monitor's simulated sweeps and the
//! simulated rig all read scenes through this crate, so a scene means the same everywhere.
//!
//! Besides the core tables (`[antenna]`, `[antenna.stiffness]`, `[tip_pin]`, `[solver]`), the
//! tables for sweeps along walls: `[antenna.hairs]`, `[[walls]]` with `[[walls.zones]]`,
//! `[sweep]`, `[start]`, `[contact]` and `[sensors]`. [`Scene::sweep_scene`] turns a scene into
//! sim-core's [`SweepScene`](sim_core::sweep::SweepScene); a sweep's failure is worded with the
//! scene's file and keys by [`SweepFailure`].
//!
//! A scene with any of `[robot]`, `[controller]` and `[follow]` is a follow scene (issue #47:
//! a robot following the walls with the antenna as its only sensor): the three tables fill
//! sim-core's [`FollowConfig`](sim_core::follow::FollowConfig) (defaults for what they leave
//! out), [`Scene::follow`] holds it with the place of every key ([`FollowScene`]), and
//! [`Scene::follow_parts`] gives what the closed loop runs: the sweep scene, the configuration
//! and the sensors. An error the run finds when it starts is put at its key by
//! [`FollowScene::locate`]. The body carries the antenna: `[base]`, `[sweep]`, `[tip_pin]` and
//! `[antenna] base_angle_deg` are refused there, and `[start]` defaults to an approach. What a
//! follow run writes, its JSON lines, is [`follow_lines`] (made from sim-core's run there, for
//! the CLI and the monitor alike).
//!
//! Every error names the file, the key and, where the parser knows it, the line and column;
//! see [`SceneError`]. Unknown keys are errors that list the keys allowed in their table.
//! Other TOML files that describe runs of scenes (studies, optimizations) give their errors
//! the same way through [`source`].
//!
//! One file per table: [`keys`] (what each table allows), `antenna.rs` (`[antenna]`,
//! `[antenna.stiffness]`), [`hairs`], [`walls`] with [`surface`] and [`points_file`] (a
//! digitized wall's CSV file of points, read by [`csv_lines`]), [`motion`] (`[sweep]`),
//! [`start`], [`contact`], [`sensors`] (with [`sensors::CalibrationValue`], the "number or
//! list" calibration value), `solver.rs` (`[solver]`), [`robot`], [`controller`] and
//! [`follow`] (`[follow]` and the follow scene as a whole), `sweep_scene.rs` (the
//! conversions), [`source`] and [`error`] (located errors) and [`failure`] (a sweep's
//! failure).
//!
//! ```
//! use antenna_scene::{Scene, Start};
//!
//! let text = r#"
//! [antenna]
//! links = 9
//! link_length_m = 0.04
//! base_angle_deg = 30.0
//! joint_limits_deg = [-90.0, 90.0]
//!
//! [antenna.stiffness]
//! profile = "fast-exponential"
//! min_n_m_per_rad = 0.004
//! max_n_m_per_rad = 0.082
//!
//! [tip_pin]
//! position_m = [0.26, 0.10]
//!
//! [solver]
//! initial = "C"
//! "#;
//! let scene = Scene::parse(text, "scene.toml").unwrap();
//! assert_eq!(scene.chain.n(), 8); // 9 links = base link + 8 flexible joints
//! assert_eq!(scene.solver.initial, Start::C);
//!
//! let error = Scene::parse("[antenna]\nlinks = 9\nfoo = 1\n", "scene.toml").unwrap_err();
//! assert!(error.to_string().starts_with("scene.toml:3:1: unknown key `foo` in [antenna]; allowed: links,"));
//! ```
//!
//! A scene with a wall, swept:
//!
//! ```
//! use antenna_scene::Scene;
//! use sim_core::sweep::Placement;
//!
//! let text = r#"
//! [antenna]
//! links = 9
//! link_length_m = 0.04
//! base_angle_deg = 30.0
//! [antenna.stiffness]
//! profile = "linear"
//! min_n_m_per_rad = 0.004
//! max_n_m_per_rad = 0.082
//!
//! [[walls]]
//! shape = "line"
//! point_m = [0.0, 0.2]
//! angle_deg = -8.0
//! solid = "left"
//!
//! [sweep]
//! velocity_m_per_s = [0.0167, 0.0]
//! duration_s = 0.1
//!
//! [start]
//! placement = "tip-on-wall"
//! "#;
//! let scene = Scene::parse(text, "wall.toml").unwrap();
//! let sweep = scene.sweep_scene().unwrap();
//! assert_eq!(sweep.walls.len(), 1);
//! assert_eq!(sweep.motion.steps(), 10);
//! assert!(matches!(sweep.placement, Placement::TipOnWall { wall: 0, .. }));
//! ```
//!
//! A follow scene, the issue's robot along a straight wall (`examples/follow/straight_wall.toml`
//! has every key):
//!
//! ```
//! use antenna_scene::Scene;
//! use sim_core::follow::FollowError;
//!
//! let text = r#"
//! [antenna]
//! links = 9
//! link_length_m = 0.04
//! [antenna.stiffness]
//! profile = "fast-exponential"
//! min_n_m_per_rad = 0.004
//! max_n_m_per_rad = 0.082
//!
//! [[walls]]
//! shape = "line"
//! point_m = [0.0, 0.2]
//! solid = "left"
//!
//! [robot]
//! speed_m_per_s = 0.3
//! mount_angle_deg = 30.0
//! [controller]
//! estimator = "contact-line"
//! setpoint_m = 0.10
//! [follow]
//! pose_m = [0.0, 0.12]
//! "#;
//! let scene = Scene::parse(text, "follow.toml").unwrap();
//! let (sweep, config, _sensors) = scene.follow_parts().unwrap();
//! assert_eq!(config.controller.setpoint_m, 0.10);
//! assert_eq!(sweep.chain.base_angle_rad(), 30f64.to_radians());
//!
//! // The run finds the footprint in a wall: the error is put at [follow] pose_m.
//! let follow = scene.follow.as_ref().unwrap();
//! let error = follow.locate(&FollowError::StartsInWall { wall: 0, depth_m: 0.01 });
//! assert!(error.to_string().starts_with("follow.toml:22:10: `pose_m` in [follow]:"));
//!
//! let error = Scene::parse(&text.replace("0.3", "-0.3"), "follow.toml").unwrap_err();
//! assert_eq!(error.to_string(), "follow.toml:16:17: `speed_m_per_s` in [robot]: -0.3 must be > 0");
//! ```

mod antenna;
pub mod contact;
pub mod controller;
pub mod csv_lines;
pub mod error;
pub mod failure;
pub mod follow;
pub mod follow_lines;
pub mod hairs;
pub mod keys;
pub mod motion;
pub mod points_file;
pub mod robot;
pub mod sensors;
mod solver;
pub mod source;
pub mod start;
pub mod surface;
mod sweep_scene;
pub mod walls;

use std::path::Path;

use nalgebra::Vector2;
use serde::Deserialize;
use sim_core::contact::ContactSettings;
use sim_core::sweep::{Motion, Placement};
use sim_core::{Chain, SensorSettings, StiffnessProfile, Wall};
use toml::Spanned;

use antenna::RawAntenna;
use contact::RawContact;
use controller::RawController;
pub use error::{Location, SceneError, SceneErrorKind};
pub use failure::SweepFailure;
pub use follow::{FollowLocations, FollowScene};
use follow::{RawFollow, RawFollowTables};
pub use hairs::HairSpec;
pub use keys::*;
use motion::RawSweep;
use robot::RawRobot;
use sensors::RawSensors;
use solver::RawSolver;
use source::{Source, point};
use start::RawStart;
use walls::RawWall;

/// Joint limits used when `joint_limits_deg` is absent, degrees.
pub const DEFAULT_JOINT_LIMITS_DEG: [f64; 2] = [-90.0, 90.0];
/// Most links a scene may have.
pub const MAX_LINKS: usize = 100_000;

/// The names `initial` accepts (besides a list of angles), and `[start] shape`.
pub const START_NAMES: &[&str] = &["straight", "C", "S", "mirror-C", "mirror-S"];

/// Where the solver starts (`[solver] initial`).
#[derive(Debug, Clone, PartialEq)]
pub enum Start {
    /// `"straight"`: every flexible joint at its rest angle (clamped into its limits).
    Straight,
    /// `"C"`: every flexible joint bent the same way.
    C,
    /// `"S"`: the first half bent one way, the rest the other.
    S,
    /// `"mirror-C"`: the C start with every flexible joint's sign flipped.
    MirrorC,
    /// `"mirror-S"`: the S start with every flexible joint's sign flipped.
    MirrorS,
    /// A list of `n` flexible joint angles (`theta_1..theta_n`), converted to radians.
    AnglesRad(Vec<f64>),
}

/// How the joint stiffnesses were given.
#[derive(Debug, Clone, PartialEq)]
pub enum StiffnessSpec {
    /// A named profile normalized to `[min, max]` over the joints.
    Profile {
        /// The profile.
        profile: StiffnessProfile,
        /// `min_n_m_per_rad`.
        min_n_m_per_rad: f64,
        /// `max_n_m_per_rad`.
        max_n_m_per_rad: f64,
    },
    /// `values_n_m_per_rad`, one per flexible joint.
    Values,
}

/// The `[solver]` table.
#[derive(Debug, Clone, PartialEq)]
pub struct SolverSettings {
    /// `tolerance` on the KKT residual (`None`: the solver's default).
    pub tolerance: Option<f64>,
    /// `max_iterations` (`None`: the solver's default).
    pub max_iterations: Option<usize>,
    /// `initial` (default [`Start::Straight`]).
    pub initial: Start,
}

/// A validated scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// The chain: `links - 1` flexible joints, lengths, base angle, limits, stiffness, rest
    /// angles, hairs (sim-core works relative to the base attachment point).
    pub chain: Chain,
    /// How the stiffness was given (the values are in `chain`).
    pub stiffness: StiffnessSpec,
    /// `[base] position_m`: the attachment point in the ground frame, m (for a sweep: where
    /// the base pivot starts).
    pub base_position_m: Vector2<f64>,
    /// `[tip_load] force_n`: dead load at the tip, ground frame, N (zero when absent).
    pub tip_force_n: Vector2<f64>,
    /// `[tip_pin] position_m`: the pin in the ground frame (not relative to the base), m.
    pub tip_pin_m: Option<Vector2<f64>>,
    /// `[solver]`.
    pub solver: SolverSettings,
    /// `[antenna.hairs]`: how the chain's hairs were given (`None`: no hairs).
    pub hairs: Option<HairSpec>,
    /// `[[walls]]` in file order (wall 0 first).
    pub walls: Vec<Wall>,
    /// `[sweep]` ([`Motion::default`] where silent).
    pub motion: Motion,
    /// `[start]` ([`Placement::Rest`] without the table).
    pub placement: Placement,
    /// `[contact]` ([`ContactSettings::default`] where silent).
    pub contact: ContactSettings,
    /// `[sensors]` ([`SensorSettings::IDEAL`] where silent): how a sweep's mapping senses the
    /// joint angles and the touch switches.
    pub sensors: SensorSettings,
    /// Where some keys are in the file, for errors found only when solving.
    pub locations: SceneLocations,
    /// A follow scene's closed-loop run (`[robot]`, `[controller]`, `[follow]`; issue #47),
    /// `None` for a scene with none of the three tables. In a follow scene the chain's base
    /// angle is `[robot] mount_angle_deg`, `base_position_m` is where the mount starts in the
    /// ground frame ([`FollowScene::mount_start_m`]), `motion` is the run without the
    /// controller ([`FollowScene::open_loop_motion`]) and `placement` without `[start]` is
    /// [`follow::default_placement`].
    pub follow: Option<FollowScene>,
}

/// Where keys whose trouble shows only when solving sit in the file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SceneLocations {
    /// The file name as given (for errors found after parsing).
    pub path: String,
    /// `[tip_pin] position_m` (an unreachable pin).
    pub tip_pin_position_m: Option<Location>,
    /// `[solver] initial`.
    pub solver_initial: Option<Location>,
    /// `[start]` (its `placement` key, or the table when the key is absent): a placement that
    /// fails.
    pub start_placement: Option<Location>,
    /// Each `[[walls]]` table, in file order: a wall through the base link.
    pub walls: Vec<Option<Location>>,
}

impl Scene {
    /// Reads and validates a scene file; errors carry `path` as given, and a wall's
    /// `points_file` is read relative to the file's folder.
    ///
    /// # Errors
    /// [`SceneError`] when the file cannot be read or is not a valid scene.
    pub fn from_path(path: &Path) -> Result<Scene, SceneError> {
        let (text, label, folder) = source::read_input(path)?;
        Scene::parse_in(&text, &label, folder)
    }

    /// Parses and validates scene text; `path` names the scene in error messages, and a
    /// wall's `points_file` is read relative to `path`'s folder (the current folder for a
    /// bare file name).
    ///
    /// # Errors
    /// [`SceneError`] naming the key and, where known, its line and column.
    pub fn parse(text: &str, path: &str) -> Result<Scene, SceneError> {
        let folder = Path::new(path).parent().unwrap_or_else(|| Path::new(""));
        Scene::parse_in(text, path, folder)
    }

    /// [`Self::parse`] with the folder that a wall's relative `points_file` is read from.
    ///
    /// # Errors
    /// As [`Self::parse`].
    pub fn parse_in(text: &str, path: &str, folder: &Path) -> Result<Scene, SceneError> {
        let source = Source { text, path };
        let raw: RawScene = toml::from_str(text).map_err(|e| source.toml_error(&e))?;
        raw.validate(&source, folder)
    }

    /// Number of flexible joints `n` (`links - 1`).
    pub fn n(&self) -> usize {
        self.chain.n()
    }

    /// The pin relative to the base attachment point (what sim-core takes), m.
    pub fn tip_pin_relative_m(&self) -> Option<Vector2<f64>> {
        self.tip_pin_m.map(|p| p - self.base_position_m)
    }

    /// Whether the scene has walls (`antenna solve` then places the antenna by `[start]`
    /// and reports the settled posture).
    pub fn has_walls(&self) -> bool {
        !self.walls.is_empty()
    }
}

// ---------------------------------------------------------------------------------------
// Raw serde model: the keys of docs/scene-format.md and our own tables.

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    antenna: Spanned<RawAntenna>,
    base: Option<Spanned<RawBase>>,
    tip_load: Option<RawTipLoad>,
    tip_pin: Option<Spanned<RawTipPin>>,
    solver: Option<Spanned<RawSolver>>,
    walls: Option<Vec<Spanned<RawWall>>>,
    sweep: Option<Spanned<RawSweep>>,
    start: Option<Spanned<RawStart>>,
    contact: Option<RawContact>,
    sensors: Option<Spanned<RawSensors>>,
    robot: Option<Spanned<RawRobot>>,
    controller: Option<Spanned<RawController>>,
    follow: Option<Spanned<RawFollow>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBase {
    position_m: Option<Spanned<Vec<f64>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTipLoad {
    force_n: Spanned<Vec<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTipPin {
    position_m: Spanned<Vec<f64>>,
}

impl RawScene {
    fn validate(self, source: &Source<'_>, folder: &Path) -> Result<Scene, SceneError> {
        let follow_tables = RawFollowTables {
            robot: self.robot.as_ref(),
            controller: self.controller.as_ref(),
            follow: self.follow.as_ref(),
        };
        let follow_span = follow_tables.first_span();
        if follow_span.is_some() {
            self.refuse_in_follow_scene(source)?;
        }
        let antenna_span = self.antenna.span();
        let antenna = self.antenna.into_inner().validate(source, antenna_span)?;
        let chain = antenna.chain;

        let base_position_m = match self
            .base
            .as_ref()
            .and_then(|b| b.get_ref().position_m.as_ref())
        {
            Some(p) => point(source, "[base]", "position_m", p)?,
            None => Vector2::zeros(),
        };
        let tip_force_n = match &self.tip_load {
            Some(load) => point(source, "[tip_load]", "force_n", &load.force_n)?,
            None => Vector2::zeros(),
        };
        let walls = self
            .walls
            .iter()
            .flatten()
            .enumerate()
            .map(|(i, w)| w.get_ref().validate(source, i, w.span(), folder))
            .collect::<Result<Vec<Wall>, SceneError>>()?;

        let start_span = self
            .start
            .as_ref()
            .map(|s| s.get_ref().placement_span().unwrap_or_else(|| s.span()));
        let follow = match follow_span {
            Some(span) => {
                if walls.is_empty() {
                    return Err(source.invalid(
                        span,
                        "the top level",
                        "walls",
                        "a follow scene ([robot], [controller], [follow]) needs at least one \
                         [[walls]] table: the wall the robot follows",
                    ));
                }
                Some(follow_tables.validate(
                    source,
                    start_span.clone(),
                    self.sensors.as_ref().map(Spanned::span),
                )?)
            }
            None => None,
        };
        // In a follow scene the base link is at the mount angle from the body axis.
        let chain = match &follow {
            Some(f) => chain
                .with_base_angle_rad(f.config.robot.mount_angle_rad)
                .map_err(|e| {
                    f.locate(&sim_core::follow::FollowError::Invalid {
                        table: "robot",
                        key: "mount_angle_deg",
                        reason: e.to_string(),
                    })
                })?,
            None => chain,
        };
        let base_position_m = follow
            .as_ref()
            .map_or(base_position_m, FollowScene::mount_start_m);

        let tip_pin_m = match &self.tip_pin {
            Some(pin) => {
                let position = &pin.get_ref().position_m;
                if !walls.is_empty() {
                    return Err(source.error(
                        Some(pin.span()),
                        SceneErrorKind::Conflict {
                            key: "tip_pin".to_string(),
                            other: "walls".to_string(),
                            table: "the top level".to_string(),
                        },
                    ));
                }
                let p = point(source, "[tip_pin]", "position_m", position)?;
                antenna::check_reach(source, &chain, base_position_m, p, position.span())?;
                Some(p)
            }
            None => None,
        };

        let solver = match &self.solver {
            Some(raw) if !walls.is_empty() => {
                return Err(source.invalid(
                    raw.span(),
                    "the top level",
                    "solver",
                    "[solver] sets the equilibrium solver of scenes without walls; a scene \
                     with [[walls]] is placed by [start] and solved with [contact]",
                ));
            }
            Some(raw) => raw.get_ref().validate(source, &chain)?,
            None => SolverSettings {
                tolerance: None,
                max_iterations: None,
                initial: Start::Straight,
            },
        };

        let motion = match (&self.sweep, &follow) {
            (Some(raw), _) => raw.get_ref().validate(source)?,
            (None, Some(f)) => f.open_loop_motion(),
            (None, None) => Motion::default(),
        };
        let placement = match (&self.start, &follow) {
            (Some(raw), _) => raw
                .get_ref()
                .validate(source, raw.span(), &chain, walls.len())?,
            (None, Some(f)) => follow::default_placement(&chain, &f.config.settings),
            (None, None) => Placement::Rest,
        };
        let contact = match &self.contact {
            Some(raw) => raw.validate(source)?,
            None => ContactSettings::default(),
        };
        let sensors = match &self.sensors {
            Some(raw) => raw.get_ref().validate(source, raw.span(), chain.n())?,
            None => SensorSettings::IDEAL,
        };

        let locations = SceneLocations {
            path: source.path.to_string(),
            tip_pin_position_m: self
                .tip_pin
                .as_ref()
                .and_then(|p| source.at(p.get_ref().position_m.span())),
            solver_initial: self
                .solver
                .as_ref()
                .and_then(|s| s.get_ref().initial.as_ref())
                .and_then(|i| source.at(i.span())),
            walls: self
                .walls
                .iter()
                .flatten()
                .map(|w| source.at(w.span()))
                .collect(),
            start_placement: start_span.and_then(|s| source.at(s)),
        };
        Ok(Scene {
            chain,
            stiffness: antenna.stiffness,
            base_position_m,
            tip_force_n,
            tip_pin_m,
            solver,
            hairs: antenna.hairs,
            walls,
            motion,
            placement,
            contact,
            sensors,
            locations,
            follow,
        })
    }

    /// A follow scene's tables that would contradict the body carrying the antenna: the
    /// first of them in the file is an error saying why.
    fn refuse_in_follow_scene(&self, source: &Source<'_>) -> Result<(), SceneError> {
        const TOP: &str = "the top level";
        let refused = [
            (
                self.antenna.get_ref().base_angle_span(),
                "[antenna]",
                "base_angle_deg",
                "[robot] mount_angle_deg sets the base angle in a follow scene (the body \
                 carries the antenna's base, and the sensors see the mount angle)",
            ),
            (
                self.base.as_ref().map(Spanned::span),
                TOP,
                "base",
                "the body carries the antenna's base in a follow scene: [robot] mount_m puts \
                 it on the body and [follow] pose_m places the robot",
            ),
            (
                self.sweep.as_ref().map(Spanned::span),
                TOP,
                "sweep",
                "a follow scene's robot moves by itself: [robot] speed_m_per_s and the \
                 controller drive it, [follow] duration_s and step_s time the run",
            ),
            (
                self.tip_pin.as_ref().map(Spanned::span),
                TOP,
                "tip_pin",
                "the body carries the antenna in a follow scene and nothing pins its tip",
            ),
        ];
        match refused
            .into_iter()
            .filter_map(|(span, table, key, why)| span.map(|s| (s, table, key, why)))
            .min_by_key(|(span, ..)| span.start)
        {
            Some((span, table, key, why)) => Err(source.invalid(
                span,
                table,
                key,
                format!("refused in a follow scene ([robot], [controller], [follow]): {why}"),
            )),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
[antenna]
links = 9
link_length_m = 0.04
base_angle_deg = 30.0

[antenna.stiffness]
profile = "linear"
min_n_m_per_rad = 0.004
max_n_m_per_rad = 0.082
"#;

    fn err(text: &str) -> String {
        match Scene::parse(text, "s.toml") {
            Ok(_) => panic!("parsed: {text}"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn good_scene_builds_the_chain() {
        let scene = Scene::parse(GOOD, "s.toml").unwrap();
        assert_eq!(scene.n(), 8);
        let k = scene.chain.stiffness_nm_per_rad();
        assert_eq!(k.len(), 9);
        assert!((k[1] - 0.082).abs() < 1e-15 && (k[8] - 0.004).abs() < 1e-15);
        assert_eq!(scene.solver.initial, Start::Straight);
        assert_eq!(scene.tip_pin_m, None);
    }

    #[test]
    fn unknown_keys_name_key_place_and_allowed_keys() {
        let e = err(&format!("{GOOD}[solver]\nfoo = 2\n"));
        assert!(e.starts_with("s.toml:12:1: unknown key `foo` in [solver]; allowed: tolerance, max_iterations, initial"), "{e}");
        let e = err(&format!("{GOOD}[wals]\n"));
        assert!(
            e.contains("unknown key `wals` in the top level; allowed: antenna, base, tip_load, tip_pin, solver, walls, sweep, start, contact, sensors, robot, controller, follow"),
            "{e}"
        );
        let e = err(&GOOD.replace("profile =", "colour = 1\nprofile ="));
        assert!(
            e.contains(":8:1: unknown key `colour` in [antenna.stiffness]"),
            "{e}"
        );
        let e = err(&format!(
            "{GOOD}[tip_pin]\nposition_m = [0.1, 0.1]\nx = 1\n"
        ));
        assert!(
            e.contains(":13:1: unknown key `x` in [tip_pin]; allowed: position_m"),
            "{e}"
        );
    }

    #[test]
    fn type_errors_name_the_key() {
        let e = err(&GOOD.replace("links = 9", "links = \"nine\""));
        assert!(e.starts_with("s.toml:3:9: `links` in [antenna]:"), "{e}");
    }

    #[test]
    fn semantic_errors_name_the_key() {
        let e = err(&GOOD.replace(
            "link_length_m = 0.04",
            "link_length_m = 0.04\nlink_lengths_m = [0.04]",
        ));
        assert!(
            e.contains(
                "s.toml:5:18: `link_lengths_m` and `link_length_m` in [antenna] exclude each other"
            ),
            "{e}"
        );
        let e = err(&GOOD.replace("link_length_m = 0.04", "link_lengths_m = [0.04, 0.04]"));
        assert!(
            e.contains("`link_lengths_m` in [antenna]: has 2 value(s); expected 9"),
            "{e}"
        );
        let e = err(&GOOD.replace("\"linear\"", "\"lin\""));
        assert!(e.contains("`profile` in [antenna.stiffness]: unknown stiffness profile name \"lin\"; known profiles: constant, linear"), "{e}");
        let e = err(&GOOD.replace("0.082", "0.001"));
        assert!(
            e.contains("s.toml:10:19: `max_n_m_per_rad` in [antenna.stiffness]: 0.001 is below"),
            "{e}"
        );
        let e = err(&GOOD.replace("30.0", "nan"));
        assert!(
            e.contains("s.toml:5:18: `base_angle_deg` in [antenna]: NaN is not a finite number"),
            "{e}"
        );
        let e = err(&GOOD.replace("links = 9", "links = 1"));
        assert!(e.contains("`links` in [antenna]: 1 is out of range"), "{e}");
        let e = err(&format!("{GOOD}[solver]\ninitial = \"Z\"\n"));
        assert!(
            e.contains("s.toml:12:11: `initial` in [solver]: invalid value: string \"Z\""),
            "{e}"
        );
        let e = err(&format!("{GOOD}[solver]\ninitial = [1.0, 2.0]\n"));
        assert!(
            e.contains("`initial` in [solver]: has 2 value(s); expected 8"),
            "{e}"
        );
        let e = err(&format!("{GOOD}[tip_pin]\nposition_m = [1.0, 0.0]\n"));
        assert!(
            e.contains("farther than the flexible links reach (0.320000 m)"),
            "{e}"
        );
    }

    #[test]
    fn missing_keys_are_named() {
        let e = err("[antenna]\nlink_length_m = 0.04\n");
        assert!(e.contains("missing key `links` in [antenna]"), "{e}");
        let e = err(&GOOD.replace("profile = \"linear\"", ""));
        assert!(
            e.contains("missing key `profile` or `values_n_m_per_rad` in [antenna.stiffness]"),
            "{e}"
        );
        let e = err("");
        assert!(e.contains("missing key `antenna` in the top level"), "{e}");
    }

    #[test]
    fn custom_profile_is_a_values_list() {
        let values = "values_n_m_per_rad = [0.05, 0.04, 0.03, 0.02, 0.01, 0.01, 0.01, 0.01]";
        let text = GOOD
            .replace(
                "profile = \"linear\"",
                &format!("profile = \"custom\"\n{values}"),
            )
            .replace("min_n_m_per_rad = 0.004\n", "")
            .replace("max_n_m_per_rad = 0.082\n", "");
        let s = Scene::parse(&text, "s.toml").unwrap();
        assert_eq!(s.stiffness, StiffnessSpec::Values);
        assert_eq!(s.chain.stiffness_nm_per_rad()[1], 0.05);
        let e = err(&GOOD.replace("\"linear\"", "\"custom\""));
        assert!(e.contains("give it as values_n_m_per_rad"), "{e}");
        let e = err(&GOOD.replace("\"linear\"", "\"custom:0.1,0.2\""));
        assert!(e.contains("give it as values_n_m_per_rad"), "{e}");
    }

    #[test]
    fn explicit_values_and_pin_and_start() {
        let text = r#"
[antenna]
links = 3
link_lengths_m = [0.02, 0.03, 0.04]
rest_angles_deg = [10.0, -5.0]
[antenna.stiffness]
values_n_m_per_rad = [0.02, 0.01]
[base]
position_m = [1.0, 2.0]
[tip_pin]
position_m = [1.05, 2.01]
[solver]
initial = [20, -20]
max_iterations = 50
"#;
        let s = Scene::parse(text, "s.toml").unwrap();
        assert_eq!(s.chain.stiffness_nm_per_rad(), &[0.0, 0.02, 0.01]);
        assert_eq!(s.stiffness, StiffnessSpec::Values);
        assert!((s.tip_pin_relative_m().unwrap() - Vector2::new(0.05, 0.01)).norm() < 1e-12);
        match &s.solver.initial {
            Start::AnglesRad(a) => assert!((a[0] - 20f64.to_radians()).abs() < 1e-15),
            other => panic!("{other:?}"),
        }
        assert_eq!(s.solver.max_iterations, Some(50));
    }
}
