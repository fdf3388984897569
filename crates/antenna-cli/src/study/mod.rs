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
//! Errors name the study file (or the scene file), the line, the column, the key and the
//! table, as scene errors do.

pub mod axes;
pub mod grid;
pub mod row;
pub mod run;

use std::path::{Path, PathBuf};

use serde::Deserialize;
use sim_core::StiffnessProfile;
use toml::Spanned;

use antenna_scene::error::SceneError;
use antenna_scene::source::{Source, finite_list, list_of_len, non_negative, positive, read_input};
use antenna_scene::surface::RawSurfaceKeys;
use antenna_scene::{Scene, StiffnessSpec};
pub use axes::{HairLayout, SurfaceChoice, Variant, VariantError};
pub use grid::Shard;
pub use row::{CSV_COLUMNS, StudyFormat, StudyRow};
pub use run::{RunOptions, run_study};

const STUDY: &str = "[study]";
const AXES: &str = "[axes]";

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStudyFile {
    study: Spanned<RawStudy>,
    axes: Option<RawAxes>,
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
        if let Some(d) = &study.duration_s {
            scene.motion.duration_s = non_negative(&source, STUDY, "duration_s", d)?;
        }
        if let Some(s) = &study.step_s {
            scene.motion.step_s = positive(&source, STUDY, "step_s", s)?;
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
            Some(a) => a.validate(&source, &scene, bounds)?,
            None => Axes::default(),
        };
        Ok(Study {
            path: PathBuf::from(path),
            scene_path,
            scene,
            bounds,
            axes,
        })
    }

    /// The number of values of each axis (1 for an absent axis), in grid order: profiles,
    /// base angles, wall distances, hairs, surfaces.
    pub fn axis_lengths(&self) -> [usize; 5] {
        [
            self.axes.profiles.len(),
            self.axes.base_angles_deg.len(),
            self.axes.wall_distances_m.len(),
            self.axes.hairs.len(),
            self.axes.surfaces.len(),
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
        let [_, a, d, h, s] = self.axis_lengths();
        let mut rest = index;
        let mut take = |len: usize| {
            let i = rest % len;
            rest /= len;
            i
        };
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
        }
    }
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
    ) -> Result<Axes, SceneError> {
        let mut axes = Axes::default();
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
        Ok(axes)
    }
}
