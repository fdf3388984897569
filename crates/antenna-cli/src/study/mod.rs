//! `antenna study STUDY.toml`: a grid of sweeps of one base scene. The study file names the
//! scene and the axes; the grid is the product of the axes (the last one varies fastest),
//! one result row per grid point ([`row`]), run in parallel ([`run`]) and split into shards
//! for a cluster's array jobs ([`grid::Shard`]).
//!
//! ```toml
//! [study]
//! scene = "../sweep_line_wall.toml"     # the base scene, relative to this file
//! duration_s = 10.0                     # optional: replaces the scene's [sweep] duration_s
//! step_s = 0.01                         # optional: replaces the scene's [sweep] step_s
//! stiffness_bounds_n_m_per_rad = [0.004, 0.082]  # optional: for `profiles` (default: the scene's)
//!
//! [axes]                                # each optional; absent = the scene's own value
//! profiles = ["constant", "linear"]     # stiffness profiles (docs/model.md 5)
//! base_angles_deg = [20.0, 30.0]        # the base angle theta_0
//! wall_distances_m = [0.15, 0.2]        # the base pivot's start distance from the wall
//! hairs = ["none", "distal", "proximal", "distal-without-3"]
//! surfaces = [{ surface = "smooth", mu = 0.3 },
//!             { surface = "rough", mu = 0.3, hold_shear_n = 0.05, hold_tension_n = 0.02 }]
//! ```
//!
//! A **follow study** is a study whose base scene is a follow scene (`[robot]`,
//! `[controller]`, `[follow]`: `antenna follow`, issue #47): each grid point is a closed-loop
//! run, its row the run's summary ([`follow::FOLLOW_COLUMNS`]). `duration_s` and `step_s`
//! then replace `[follow]`'s, and the axes are `profiles`, `hairs`, `surfaces` and
//!
//! ```toml
//! [axes]
//! speeds_m_per_s = [0.2, 0.4]           # [robot] speed_m_per_s
//! kp_n = [0.03, 0.05]                   # [controller] kp_n (template body)
//! kd_n_s = [0.001, 0.002]               # [controller] kd_n_s (template body)
//! kp_rad_per_s_per_m = [20.0, 40.0]     # [controller] kp_rad_per_s_per_m (wheeled body)
//! kd_rad_per_m = [1.0, 2.0]             # [controller] kd_rad_per_m (wheeled body)
//! delays_s = [0.0, 0.02]                # [controller] delay_s
//! ```
//!
//! in grid order after the sweep axes. With a `[v_max]` table ([`follow::RawVMax`]) each row
//! is instead the highest speed at which the robot follows the wall ([`V_MAX_COLUMNS`]); such
//! a study has no `speeds_m_per_s` axis and no `duration_s`. An axis that does not fit the
//! scene (`base_angles_deg` or `wall_distances_m` in a follow study, a follow axis or
//! `[v_max]` in a sweep study, a gain of the other body) is an error at its key.
//!
//! Errors name the study file (or the scene file), the line, the column, the key and the
//! table, as scene errors do.

pub mod axes;
pub mod follow;
pub mod grid;
pub mod row;
pub mod run;

use std::path::{Path, PathBuf};

use serde::Deserialize;
use sim_core::StiffnessProfile;
use toml::Spanned;

use antenna_scene::error::{SceneError, SceneErrorKind};
use antenna_scene::follow::MAX_FOLLOW_STEPS;
use antenna_scene::source::{Source, finite_list, list_of_len, non_negative, positive, read_input};
use antenna_scene::surface::RawSurfaceKeys;
use antenna_scene::{Scene, StiffnessSpec};
pub use axes::{HairLayout, SurfaceChoice, Variant, VariantError};
pub use follow::{FOLLOW_COLUMNS, FollowRow, V_MAX_COLUMNS};
pub use grid::Shard;
pub use row::{CSV_COLUMNS, Row, StudyFormat, StudyRow};
pub use run::{RunCounts, RunOptions, run_study};

use crate::follow::v_max::VMaxOptions;

const STUDY: &str = "[study]";
const AXES: &str = "[axes]";

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStudyFile {
    study: Spanned<RawStudy>,
    axes: Option<RawAxes>,
    v_max: Option<Spanned<follow::RawVMax>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStudy {
    scene: Option<Spanned<String>>,
    duration_s: Option<Spanned<f64>>,
    step_s: Option<Spanned<f64>>,
    stiffness_bounds_n_m_per_rad: Option<Spanned<Vec<f64>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawAxes {
    profiles: Option<Spanned<Vec<String>>>,
    base_angles_deg: Option<Spanned<Vec<f64>>>,
    wall_distances_m: Option<Spanned<Vec<f64>>>,
    hairs: Option<Spanned<Vec<String>>>,
    surfaces: Option<Spanned<Vec<Spanned<RawSurface>>>>,
    speeds_m_per_s: Option<Spanned<Vec<f64>>>,
    kp_n: Option<Spanned<Vec<f64>>>,
    kd_n_s: Option<Spanned<Vec<f64>>>,
    kp_rad_per_s_per_m: Option<Spanned<Vec<f64>>>,
    kd_rad_per_m: Option<Spanned<Vec<f64>>>,
    delays_s: Option<Spanned<Vec<f64>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSurface {
    surface: Option<Spanned<String>>,
    mu: Option<Spanned<f64>>,
    hold_shear_n: Option<Spanned<f64>>,
    hold_tension_n: Option<Spanned<f64>>,
}

/// The values of each axis; an empty list is an absent axis (the scene's own value).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Axes {
    /// Stiffness profiles, normalized to [`Study::bounds`].
    pub profiles: Vec<StiffnessProfile>,
    /// Base angles, degrees.
    pub base_angles_deg: Vec<f64>,
    /// The base pivot's start distances from the reference wall, metres.
    pub wall_distances_m: Vec<f64>,
    /// Hair layouts.
    pub hairs: Vec<HairLayout>,
    /// Wall surfaces.
    pub surfaces: Vec<SurfaceChoice>,
    /// A follow scene's forward speeds, m/s.
    pub speeds_m_per_s: Vec<f64>,
    /// A follow scene's template gains `kp_n`, N m per m.
    pub kp_n: Vec<f64>,
    /// A follow scene's template gains `kd_n_s`, N m per m/s.
    pub kd_n_s: Vec<f64>,
    /// A follow scene's wheeled gains `kp_rad_per_s_per_m`, rad/s per m.
    pub kp_rad_per_s_per_m: Vec<f64>,
    /// A follow scene's wheeled gains `kd_rad_per_m`, rad per m.
    pub kd_rad_per_m: Vec<f64>,
    /// A follow scene's delays, s.
    pub delays_s: Vec<f64>,
}

/// A validated study: the base scene (with the study's `duration_s` and `step_s`) and the
/// axes.
#[derive(Debug, Clone)]
pub struct Study {
    /// The study file as given.
    pub path: PathBuf,
    /// The base scene file (resolved against the study file's folder).
    pub scene_path: PathBuf,
    /// The base scene.
    pub scene: Scene,
    /// The stiffness bounds `profiles` are normalized to, N m/rad.
    pub bounds: Option<(f64, f64)>,
    /// The axes.
    pub axes: Axes,
    /// A follow study's v_max search (`[v_max]`): each row is a search instead of a run.
    pub v_max: Option<VMaxOptions>,
}

impl Study {
    /// Reads a study file and its base scene.
    ///
    /// # Errors
    /// [`SceneError`] naming the study file or the scene file, the key and where.
    pub fn from_path(path: &Path) -> Result<Study, SceneError> {
        let (text, label, folder) = read_input(path)?;
        Study::parse(&text, &label, folder)
    }

    /// Parses a study; `path` names it in errors and `folder` resolves its `scene`.
    ///
    /// # Errors
    /// As [`Self::from_path`].
    pub fn parse(text: &str, path: &str, folder: &Path) -> Result<Study, SceneError> {
        let source = Source { text, path };
        let raw: RawStudyFile = toml::from_str(text).map_err(|e| source.toml_error(&e))?;
        let study_span = raw.study.span();
        let study = raw.study.into_inner();
        let Some(scene_key) = &study.scene else {
            return Err(source.missing(study_span, STUDY, "scene"));
        };
        let scene_path = folder.join(scene_key.get_ref());
        let mut scene = Scene::from_path(&scene_path)?;
        let v_max = match (&raw.v_max, &scene.follow) {
            (None, _) => None,
            (Some(table), Some(_)) => Some(table.get_ref().validate(&source, table.span())?),
            (Some(table), None) => {
                return Err(source.error(
                    Some(table.span()),
                    SceneErrorKind::Run {
                        message: format!(
                            "[v_max]: {} is not a follow scene (no [robot], [controller] or \
                             [follow]): [v_max] searches a follow scene's highest speed",
                            scene_path.display()
                        ),
                    },
                ));
            }
        };
        if scene.follow.is_some() {
            apply_follow_times(&source, &study, &mut scene, v_max.is_some())?;
        } else {
            if let Some(d) = &study.duration_s {
                scene.motion.duration_s = non_negative(&source, STUDY, "duration_s", d)?;
            }
            if let Some(s) = &study.step_s {
                scene.motion.step_s = positive(&source, STUDY, "step_s", s)?;
            }
        }
        if let Err(e) = scene.sweep_scene() {
            return Err(source.invalid(
                scene_key.span(),
                STUDY,
                "scene",
                format!("the scene cannot be swept: {e}"),
            ));
        }
        let bounds = match (&study.stiffness_bounds_n_m_per_rad, &scene.stiffness) {
            (Some(list), _) => {
                let v = list_of_len(
                    &source,
                    STUDY,
                    "stiffness_bounds_n_m_per_rad",
                    list,
                    2,
                    "[min, max], N m/rad",
                )?;
                if !(v[0] > 0.0 && v[0] <= v[1]) {
                    return Err(source.invalid(
                        list.span(),
                        STUDY,
                        "stiffness_bounds_n_m_per_rad",
                        format!("[{}, {}] needs 0 < min <= max", v[0], v[1]),
                    ));
                }
                Some((v[0], v[1]))
            }
            (
                None,
                StiffnessSpec::Profile {
                    min_n_m_per_rad,
                    max_n_m_per_rad,
                    ..
                },
            ) => Some((*min_n_m_per_rad, *max_n_m_per_rad)),
            (None, StiffnessSpec::Values) => None,
        };
        let axes = match &raw.axes {
            Some(a) => a.validate(&source, &scene, bounds, v_max.is_some())?,
            None => Axes::default(),
        };
        Ok(Study {
            path: PathBuf::from(path),
            scene_path,
            scene,
            bounds,
            axes,
            v_max,
        })
    }

    /// Whether the base scene is a follow scene: each row a closed-loop run (or a v_max
    /// search).
    pub fn is_follow(&self) -> bool {
        self.scene.follow.is_some()
    }

    /// The columns of this study's rows: a sweep study's [`CSV_COLUMNS`], a follow study's
    /// [`FOLLOW_COLUMNS`], or [`V_MAX_COLUMNS`] with `[v_max]`.
    pub fn columns(&self) -> &'static [&'static str] {
        match (self.is_follow(), &self.v_max) {
            (false, _) => CSV_COLUMNS,
            (true, None) => FOLLOW_COLUMNS,
            (true, Some(_)) => V_MAX_COLUMNS,
        }
    }

    /// The number of values of each axis (1 for an absent axis), in grid order: profiles,
    /// base angles, wall distances, hairs, surfaces, speeds, `kp_n`, `kd_n_s`,
    /// `kp_rad_per_s_per_m`, `kd_rad_per_m`, delays.
    pub fn axis_lengths(&self) -> [usize; 11] {
        let a = &self.axes;
        [
            a.profiles.len(),
            a.base_angles_deg.len(),
            a.wall_distances_m.len(),
            a.hairs.len(),
            a.surfaces.len(),
            a.speeds_m_per_s.len(),
            a.kp_n.len(),
            a.kd_n_s.len(),
            a.kp_rad_per_s_per_m.len(),
            a.kd_rad_per_m.len(),
            a.delays_s.len(),
        ]
        .map(|l| l.max(1))
    }

    /// The number of grid points.
    pub fn len(&self) -> usize {
        self.axis_lengths().iter().product()
    }

    /// Whether the grid is empty (it never is: every axis has at least one value).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The axis values of grid point `index` (`0..len`; the last axis varies fastest).
    pub fn variant(&self, index: usize) -> Variant {
        let [_, a, d, h, s, v, kp, kd, kpw, kdw, dl] = self.axis_lengths();
        let mut rest = index;
        let mut take = |len: usize| {
            let i = rest % len;
            rest /= len;
            i
        };
        let dli = take(dl);
        let kdwi = take(kdw);
        let kpwi = take(kpw);
        let kdi = take(kd);
        let kpi = take(kp);
        let vi = take(v);
        let si = take(s);
        let hi = take(h);
        let di = take(d);
        let ai = take(a);
        let pi = rest;
        Variant {
            profile: self.axes.profiles.get(pi).cloned(),
            base_angle_deg: self.axes.base_angles_deg.get(ai).copied(),
            wall_distance_m: self.axes.wall_distances_m.get(di).copied(),
            hairs: self.axes.hairs.get(hi).cloned(),
            surface: self.axes.surfaces.get(si).copied(),
            speed_m_per_s: self.axes.speeds_m_per_s.get(vi).copied(),
            kp_n: self.axes.kp_n.get(kpi).copied(),
            kd_n_s: self.axes.kd_n_s.get(kdi).copied(),
            kp_rad_per_s_per_m: self.axes.kp_rad_per_s_per_m.get(kpwi).copied(),
            kd_rad_per_m: self.axes.kd_rad_per_m.get(kdwi).copied(),
            delay_s: self.axes.delays_s.get(dli).copied(),
        }
    }
}

/// A follow study's `duration_s` and `step_s` replace `[follow]`'s (checked as the scene's
/// would be); a v_max study takes no `duration_s` (each run covers `[v_max] distance_m`).
fn apply_follow_times(
    source: &Source<'_>,
    study: &RawStudy,
    scene: &mut Scene,
    v_max: bool,
) -> Result<(), SceneError> {
    let Some(follow) = scene.follow.as_mut() else {
        return Ok(());
    };
    let settings = &mut follow.config.settings;
    if let Some(d) = &study.duration_s {
        if v_max {
            return Err(source.invalid(
                d.span(),
                STUDY,
                "duration_s",
                "a study with [v_max] runs every speed over [v_max] distance_m: remove \
                 duration_s",
            ));
        }
        settings.duration_s = positive(source, STUDY, "duration_s", d)?;
    }
    if let Some(s) = &study.step_s {
        settings.step_s = positive(source, STUDY, "step_s", s)?;
    }
    if let Err(e) = follow.config.validate() {
        let key = match &e {
            sim_core::follow::FollowError::Invalid { key, .. } => *key,
            _ => "step_s",
        };
        let span = match key {
            "duration_s" => study.duration_s.as_ref().map(Spanned::span),
            _ => study.step_s.as_ref().map(Spanned::span),
        };
        if let Some(span) = span {
            return Err(source.invalid(span, STUDY, key, e.to_string()));
        }
    }
    let steps = follow.config.steps();
    if !v_max
        && steps > MAX_FOLLOW_STEPS
        && let Some(d) = &study.duration_s
    {
        return Err(source.invalid(
            d.span(),
            STUDY,
            "duration_s",
            format!("{steps} steps is more than {MAX_FOLLOW_STEPS}"),
        ));
    }
    Ok(())
}

/// A follow axis: its key, its list as written, where its values go, whether they must be
/// `> 0` (else `>= 0`).
type FollowAxis<'a> = (
    &'a str,
    &'a Option<Spanned<Vec<f64>>>,
    &'a mut Vec<f64>,
    bool,
);

/// A list of values for a follow axis: finite, each `> 0` (`positive`) or `>= 0`.
fn follow_list(
    source: &Source<'_>,
    key: &str,
    list: &Spanned<Vec<f64>>,
    positive: bool,
) -> Result<Vec<f64>, SceneError> {
    non_empty(source, key, list)?;
    let values = finite_list(source, AXES, key, list)?;
    if let Some(bad) = values
        .iter()
        .find(|&&v| if positive { v <= 0.0 } else { v < 0.0 })
    {
        let need = if positive { "> 0" } else { ">= 0" };
        return Err(source.invalid(
            list.span(),
            AXES,
            key,
            format!("{bad}: every value must be {need}"),
        ));
    }
    Ok(values)
}

/// An empty list is refused: remove the key to keep the scene's value.
fn non_empty<T>(source: &Source<'_>, key: &str, list: &Spanned<Vec<T>>) -> Result<(), SceneError> {
    if list.get_ref().is_empty() {
        return Err(source.invalid(
            list.span(),
            AXES,
            key,
            "no values: give at least one, or remove the key to keep the scene's value",
        ));
    }
    Ok(())
}

impl RawAxes {
    fn validate(
        &self,
        source: &Source<'_>,
        scene: &Scene,
        bounds: Option<(f64, f64)>,
        v_max: bool,
    ) -> Result<Axes, SceneError> {
        let mut axes = Axes::default();
        self.check_kind(source, scene, v_max)?;
        if let Some(list) = &self.profiles {
            non_empty(source, "profiles", list)?;
            if bounds.is_none() {
                return Err(source.invalid(
                    list.span(),
                    AXES,
                    "profiles",
                    "the scene gives values_n_m_per_rad: add stiffness_bounds_n_m_per_rad = \
                     [min, max] to [study] to normalize the profiles",
                ));
            }
            let names: Vec<&str> = StiffnessProfile::NAMED.iter().map(|p| p.name()).collect();
            for name in list.get_ref() {
                let profile = name.parse().map_err(|e| {
                    source.invalid(
                        list.span(),
                        AXES,
                        "profiles",
                        format!("{e}; known profiles: {}", names.join(", ")),
                    )
                })?;
                axes.profiles.push(profile);
            }
        }
        if let Some(list) = &self.base_angles_deg {
            non_empty(source, "base_angles_deg", list)?;
            axes.base_angles_deg = finite_list(source, AXES, "base_angles_deg", list)?;
        }
        if let Some(list) = &self.wall_distances_m {
            non_empty(source, "wall_distances_m", list)?;
            if scene.walls.is_empty() {
                return Err(source.invalid(
                    list.span(),
                    AXES,
                    "wall_distances_m",
                    "the scene has no [[walls]] to be distant from",
                ));
            }
            let d = finite_list(source, AXES, "wall_distances_m", list)?;
            if let Some(bad) = d.iter().find(|&&d| d <= 0.0) {
                return Err(source.invalid(
                    list.span(),
                    AXES,
                    "wall_distances_m",
                    format!(
                        "{bad} m would put the base pivot in the wall; every distance must be > 0"
                    ),
                ));
            }
            axes.wall_distances_m = d;
        }
        if let Some(list) = &self.hairs {
            non_empty(source, "hairs", list)?;
            for name in list.get_ref() {
                let layout = HairLayout::parse(name, scene.n())
                    .map_err(|why| source.invalid(list.span(), AXES, "hairs", why))?;
                axes.hairs.push(layout);
            }
        }
        if let Some(list) = &self.surfaces {
            non_empty(source, "surfaces", list)?;
            if scene.walls.is_empty() {
                return Err(source.invalid(
                    list.span(),
                    AXES,
                    "surfaces",
                    "the scene has no [[walls]] to give a surface",
                ));
            }
            for (i, entry) in list.get_ref().iter().enumerate() {
                let raw = entry.get_ref();
                let table = format!("[axes] surfaces (entry {i})");
                let surface = RawSurfaceKeys {
                    surface: raw.surface.as_ref(),
                    mu: raw.mu.as_ref(),
                    hold_shear_n: raw.hold_shear_n.as_ref(),
                    hold_tension_n: raw.hold_tension_n.as_ref(),
                }
                .validate(source, &table, entry.span())?;
                axes.surfaces.push(SurfaceChoice(surface));
            }
        }
        let follow_axes: [FollowAxis<'_>; 6] = [
            (
                "speeds_m_per_s",
                &self.speeds_m_per_s,
                &mut axes.speeds_m_per_s,
                true,
            ),
            ("kp_n", &self.kp_n, &mut axes.kp_n, false),
            ("kd_n_s", &self.kd_n_s, &mut axes.kd_n_s, false),
            (
                "kp_rad_per_s_per_m",
                &self.kp_rad_per_s_per_m,
                &mut axes.kp_rad_per_s_per_m,
                false,
            ),
            (
                "kd_rad_per_m",
                &self.kd_rad_per_m,
                &mut axes.kd_rad_per_m,
                false,
            ),
            ("delays_s", &self.delays_s, &mut axes.delays_s, false),
        ];
        for (key, list, values, positive) in follow_axes {
            if let Some(list) = list {
                *values = follow_list(source, key, list, positive)?;
            }
        }
        Ok(axes)
    }

    /// Refuses the axes that do not fit the scene: the sweep-only axes in a follow study, the
    /// follow axes in a sweep study, a gain of the other body, a speed axis beside
    /// `[v_max]`.
    fn check_kind(
        &self,
        source: &Source<'_>,
        scene: &Scene,
        v_max: bool,
    ) -> Result<(), SceneError> {
        let follow_axes = [
            ("speeds_m_per_s", &self.speeds_m_per_s),
            ("kp_n", &self.kp_n),
            ("kd_n_s", &self.kd_n_s),
            ("kp_rad_per_s_per_m", &self.kp_rad_per_s_per_m),
            ("kd_rad_per_m", &self.kd_rad_per_m),
            ("delays_s", &self.delays_s),
        ];
        let Some(follow) = &scene.follow else {
            if let Some((key, list)) = follow_axes
                .iter()
                .find_map(|(k, l)| l.as_ref().map(|l| (*k, l)))
            {
                return Err(source.invalid(
                    list.span(),
                    AXES,
                    key,
                    format!(
                        "{} is not a follow scene (no [robot], [controller] or [follow]): \
                         {key} is an axis of a follow study",
                        scene.locations.path
                    ),
                ));
            }
            return Ok(());
        };
        let sweep_only = [
            (
                "base_angles_deg",
                self.base_angles_deg.as_ref().map(Spanned::span),
                "the antenna sits at [robot] mount_angle_deg on the robot",
            ),
            (
                "wall_distances_m",
                self.wall_distances_m.as_ref().map(Spanned::span),
                "the robot starts at [follow] pose_m and steers its own distance",
            ),
        ];
        for (key, span, why) in sweep_only {
            if let Some(span) = span {
                return Err(source.invalid(
                    span,
                    AXES,
                    key,
                    format!(
                        "{} is a follow scene: {why}; {key} is an axis of a sweep study",
                        scene.locations.path
                    ),
                ));
            }
        }
        let wheeled = matches!(
            follow.config.robot.body,
            sim_core::follow::BodyModel::Wheeled { .. }
        );
        let (other, body, own) = if wheeled {
            (
                [("kp_n", &self.kp_n), ("kd_n_s", &self.kd_n_s)],
                "wheeled",
                "kp_rad_per_s_per_m and kd_rad_per_m",
            )
        } else {
            (
                [
                    ("kp_rad_per_s_per_m", &self.kp_rad_per_s_per_m),
                    ("kd_rad_per_m", &self.kd_rad_per_m),
                ],
                "template",
                "kp_n and kd_n_s",
            )
        };
        for (key, list) in other {
            if let Some(list) = list {
                return Err(source.invalid(
                    list.span(),
                    AXES,
                    key,
                    format!("the robot's body is \"{body}\": its gains are {own}"),
                ));
            }
        }
        if v_max && let Some(list) = &self.speeds_m_per_s {
            return Err(source.invalid(
                list.span(),
                AXES,
                "speeds_m_per_s",
                "a study with [v_max] searches the speed itself: remove the speeds_m_per_s \
                 axis (the search's grid is [v_max] speeds_m_per_s)",
            ));
        }
        Ok(())
    }
}
