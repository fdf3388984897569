//! `antenna optimize OPT.toml`: the stiffness profile that maximizes a task's metric over a
//! set of sweeps (thesis 4.2: which profile makes the best antenna), searched by argmin's
//! derivative-free solvers. The seven named profiles of the thesis's Table 4.1 are swept first
//! and the search starts from the best of them, so it never reports worse; every evaluation
//! is a certified sweep of each scene, and a sweep that fails (or jams, or never touches the
//! wall) makes its evaluation infeasible, counted and reported.
//!
//! ```toml
//! [optimize]
//! scenes = ["../wall_following_4_2_1.toml"]  # base scenes, relative to this file; the
//!                                             # objective is averaged over them
//! objective = "preview-mean"       # maximized: "preview-mean", "mapping-error",
//!                                  # "flip-free-preview"; on follow scenes "follow-v-max"
//!                                  # or "follow-rms" (see Objective)
//! parameters = "per-joint"         # one stiffness per joint, or "exponential-taper"
//! stiffness_bounds_n_m_per_rad = [0.004, 0.082]  # default: the first scene's profile bounds
//! wires = "any"                    # or "available": only stiffnesses a Nitinol wire makes
//! method = "nelder-mead"           # or "particle-swarm"
//! budget = 300                     # sweeps at most (the named profiles' included)
//! seed = 1                         # the particle swarm's random numbers
//! duration_s = 20.0                # optional: replaces every scene's [sweep] duration_s
//!                                  # (a follow scene's [follow] duration_s)
//!
//! [v_max]                          # follow-v-max only (optional): the speed search
//! speeds_m_per_s = [0.2, 0.4, 0.6] # the coarse grid, m/s (default 0.1 to 2.0 by 0.1)
//! distance_m = 1.5                 # every run covers this distance, m
//! tolerance_m_per_s = 0.01         # the bisection's bracket, m/s
//! ```
//!
//! The follow objectives (issue #47) run each scene's closed loop (`antenna follow`) with the
//! scene's robot and gains and the stiffnesses under test: `follow-v-max` is the highest
//! speed found by [`crate::follow::v_max`] (m/s), `follow-rms` minus the RMS error at the
//! scene's speed (m); a run that is not `ok` (or a search whose slowest speed fails) makes
//! its evaluation infeasible, as a failed sweep does.
//!
//! The pieces: the file ([`OptimizeSpec`], errors located like a scene's), the objective
//! ([`Objective`]), the search space ([`Space`]), the sweeps of one evaluation run in
//! parallel with a budget ([`Evaluator`]), argmin's solvers ([`run_optimization`]) and the
//! report ([`OptimizeReport`], [`plot`]).
//!
//! ```
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use antenna_cli::optimize::{OptimizeOptions, OptimizeSpec, run_optimization};
//!
//! let folder = std::env::temp_dir().join(format!("optimize-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&folder)?;
//! std::fs::write(
//!     folder.join("wall.toml"),
//!     "[antenna]\nlinks = 3\nlink_length_m = 0.04\nbase_angle_deg = 30.0\n\
//!      [antenna.stiffness]\nprofile = \"linear\"\nmin_n_m_per_rad = 0.004\nmax_n_m_per_rad = 0.082\n\
//!      [[walls]]\nshape = \"line\"\npoint_m = [0.0, 0.1]\nangle_deg = -8.0\nsolid = \"left\"\n\
//!      [sweep]\nvelocity_m_per_s = [0.02, 0.0]\nduration_s = 0.5\nstep_s = 0.05\n\
//!      [start]\nplacement = \"tip-on-wall\"\nwall = 0\nshape = \"C\"\n",
//! )?;
//! let text = "[optimize]\nscenes = [\"wall.toml\"]\nobjective = \"preview-mean\"\n\
//!             parameters = \"exponential-taper\"\nmethod = \"nelder-mead\"\nbudget = 12\n";
//! let spec = OptimizeSpec::parse(text, "opt.toml", &folder)?;
//! let options = OptimizeOptions { jobs: 2, ..OptimizeOptions::default() };
//! let report = run_optimization(&spec, &options)?;
//! assert!(report.sweeps <= 12);
//! let best_named = report
//!     .best_named_profile
//!     .and_then(|n| n.objective_value)
//!     .unwrap_or(f64::NEG_INFINITY);
//! assert!(report.objective_value.unwrap_or(f64::NEG_INFINITY) >= best_named);
//! # std::fs::remove_dir_all(&folder)?;
//! # Ok(())
//! # }
//! ```

/// `NAMES`, `ALL` and `name()` of an enum whose values are named in the file, each name
/// given once.
macro_rules! file_names {
    ($ty:ident { $($variant:ident => $name:literal),+ $(,)? }) => {
        impl $ty {
            /// The names in the file, in the order of [`Self::ALL`].
            pub const NAMES: [&'static str; [$($name),+].len()] = [$($name),+];
            /// Every value, in the order of [`Self::NAMES`].
            pub const ALL: [$ty; [$($name),+].len()] = [$($ty::$variant),+];

            /// The name in the file.
            pub fn name(self) -> &'static str {
                match self {
                    $($ty::$variant => $name),+
                }
            }
        }
    };
}

mod best_scene;
mod evaluator;
pub mod log;
mod objective;
pub mod plot;
mod report;
mod search;
mod space;

use std::path::{Path, PathBuf};

use serde::Deserialize;
use toml::Spanned;

use antenna_scene::error::{SceneError, SceneErrorKind};
use antenna_scene::follow::MAX_FOLLOW_STEPS;
use antenna_scene::motion::MAX_SWEEP_STEPS;
use antenna_scene::source::{Source, list_of_len, one_of, positive, read_input};
use antenna_scene::{Scene, StiffnessSpec};
pub use best_scene::best_scene_text;
pub use evaluator::{Evaluation, Evaluator, STALL_CALLS, SceneResult, Stop, with_stiffness};
pub use log::{LogError, LogHeader};
pub use objective::Objective;
pub use report::{FailedEvaluation, NamedResult, OptimizeReport};
pub use search::{OptimizeError, OptimizeOptions, TABLE_4_1, run_optimization};
pub use space::{Family, Space, Wires};

use crate::follow::v_max::VMaxOptions;
use crate::study::follow::RawVMax;

const OPTIMIZE: &str = "[optimize]";

/// The search method: one of argmin's derivative-free solvers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// Nelder-Mead's simplex, from the best named profile with a first step of a quarter of
    /// the (logarithmic) stiffness range along each coordinate.
    NelderMead,
    /// A particle swarm, the best named profile one of its particles, the others uniform in
    /// the box (seeded).
    ParticleSwarm,
}

file_names!(Method {
    NelderMead => "nelder-mead",
    ParticleSwarm => "particle-swarm",
});

impl Method {
    /// The particles of a swarm over `dim` coordinates: `10 + 2 sqrt(dim)`, rounded (the
    /// standard particle swarm's rule).
    pub fn particles(dim: usize) -> usize {
        (10.0 + 2.0 * (dim as f64).sqrt()).round() as usize
    }

    /// New points the search evaluates before its first iteration: the simplex's other `dim`
    /// vertices, or the swarm's other particles.
    pub fn first_points(self, dim: usize) -> usize {
        match self {
            Method::NelderMead => dim,
            Method::ParticleSwarm => Self::particles(dim) - 1,
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawOptimizeFile {
    optimize: Spanned<RawOptimize>,
    v_max: Option<Spanned<RawVMax>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawOptimize {
    scenes: Option<Spanned<Vec<Spanned<String>>>>,
    objective: Option<Spanned<String>>,
    parameters: Option<Spanned<String>>,
    stiffness_bounds_n_m_per_rad: Option<Spanned<Vec<f64>>>,
    wires: Option<Spanned<String>>,
    method: Option<Spanned<String>>,
    budget: Option<Spanned<i64>>,
    seed: Option<Spanned<i64>>,
    duration_s: Option<Spanned<f64>>,
}

/// A validated optimization file: the scenes, what to maximize, over what, and how.
#[derive(Debug, Clone)]
pub struct OptimizeSpec {
    /// The file as given.
    pub path: PathBuf,
    /// The base scenes (resolved against the file's folder) and the scenes themselves (with
    /// `duration_s` applied).
    pub scenes: Vec<(PathBuf, Scene)>,
    /// What to maximize.
    pub objective: Objective,
    /// The search space: the family of profiles, the bounds, the wires.
    pub space: Space,
    /// The solver.
    pub method: Method,
    /// Sweeps at most (an evaluation sweeps every scene once).
    pub budget: usize,
    /// The seed of the swarm's random numbers.
    pub seed: u64,
    /// The speed search of `follow-v-max` (`[v_max]`, else its defaults).
    pub v_max: VMaxOptions,
}

impl OptimizeSpec {
    /// Reads an optimization file and its scenes.
    ///
    /// # Errors
    /// [`SceneError`] naming the file (or a scene file), the key and where.
    pub fn from_path(path: &Path) -> Result<OptimizeSpec, SceneError> {
        let (text, label, folder) = read_input(path)?;
        OptimizeSpec::parse(&text, &label, folder)
    }

    /// Parses an optimization file; `path` names it in errors and `folder` resolves its
    /// `scenes`.
    ///
    /// # Errors
    /// As [`Self::from_path`].
    pub fn parse(text: &str, path: &str, folder: &Path) -> Result<OptimizeSpec, SceneError> {
        let source = Source { text, path };
        let raw: RawOptimizeFile = toml::from_str(text).map_err(|e| source.toml_error(&e))?;
        let raw_v_max = raw.v_max;
        let span = raw.optimize.span();
        let raw = raw.optimize.into_inner();
        let required = |key: &str| source.missing(span.clone(), OPTIMIZE, key);

        let objective_key = raw
            .objective
            .as_ref()
            .ok_or_else(|| required("objective"))?;
        let objective = Objective::ALL[one_of(
            &source,
            OPTIMIZE,
            "objective",
            objective_key,
            &Objective::NAMES,
        )?];
        let family = match &raw.parameters {
            Some(p) => Family::ALL[one_of(&source, OPTIMIZE, "parameters", p, &Family::NAMES)?],
            None => Family::PerJoint,
        };
        let wires = match &raw.wires {
            Some(w) => Wires::ALL[one_of(&source, OPTIMIZE, "wires", w, &Wires::NAMES)?],
            None => Wires::Any,
        };
        let method = match &raw.method {
            Some(m) => Method::ALL[one_of(&source, OPTIMIZE, "method", m, &Method::NAMES)?],
            None => Method::NelderMead,
        };
        let seed = match &raw.seed {
            Some(s) => u64::try_from(*s.get_ref())
                .map_err(|_| source.invalid(s.span(), OPTIMIZE, "seed", "the seed must be >= 0"))?,
            None => 1,
        };
        let v_max = match &raw_v_max {
            Some(table) if objective != Objective::FollowVMax => {
                return Err(source.error(
                    Some(table.span()),
                    SceneErrorKind::Run {
                        message: format!(
                            "[v_max]: the speed search belongs to the objective \"follow-v-max\", \
                             not \"{}\"",
                            objective.name()
                        ),
                    },
                ));
            }
            Some(table) => table.get_ref().validate(&source, table.span())?,
            None => VMaxOptions::default(),
        };
        let duration_s = match &raw.duration_s {
            Some(d) if objective == Objective::FollowVMax => {
                return Err(source.invalid(
                    d.span(),
                    OPTIMIZE,
                    "duration_s",
                    "follow-v-max runs every speed over [v_max] distance_m: remove duration_s",
                ));
            }
            Some(d) => Some((positive(&source, OPTIMIZE, "duration_s", d)?, d.span())),
            None => None,
        };
        let scene_keys = raw.scenes.as_ref().ok_or_else(|| required("scenes"))?;
        let scenes = read_scenes(&source, folder, scene_keys, objective, duration_s)?;
        let first = &scenes[0].1;

        let bounds = match (&raw.stiffness_bounds_n_m_per_rad, &first.stiffness) {
            (Some(list), _) => {
                let v = list_of_len(
                    &source,
                    OPTIMIZE,
                    "stiffness_bounds_n_m_per_rad",
                    list,
                    2,
                    "[min, max], N m/rad",
                )?;
                if !(v[0] > 0.0 && v[0] < v[1]) {
                    return Err(source.invalid(
                        list.span(),
                        OPTIMIZE,
                        "stiffness_bounds_n_m_per_rad",
                        format!("[{}, {}] needs 0 < min < max", v[0], v[1]),
                    ));
                }
                (v[0], v[1])
            }
            (
                None,
                StiffnessSpec::Profile {
                    min_n_m_per_rad,
                    max_n_m_per_rad,
                    ..
                },
            ) if min_n_m_per_rad < max_n_m_per_rad => (*min_n_m_per_rad, *max_n_m_per_rad),
            (None, _) => {
                return Err(source.invalid(
                    span,
                    OPTIMIZE,
                    "stiffness_bounds_n_m_per_rad",
                    format!(
                        "{} gives no stiffness range (values_n_m_per_rad, or min = max): give \
                         stiffness_bounds_n_m_per_rad = [min, max]",
                        scenes[0].0.display()
                    ),
                ));
            }
        };
        let wires_span = raw.wires.as_ref().map_or(span.clone(), Spanned::span);
        let space = Space::new(family, bounds, wires, first.chain.link_lengths_m())
            .map_err(|why| source.invalid(wires_span, OPTIMIZE, "wires", why))?;

        let budget_key = raw.budget.as_ref().ok_or_else(|| required("budget"))?;
        let least = scenes.len() * (TABLE_4_1.len() + method.first_points(space.dim()));
        let budget = usize::try_from(*budget_key.get_ref())
            .ok()
            .filter(|&b| b >= least)
            .ok_or_else(|| {
                source.invalid(
                    budget_key.span(),
                    OPTIMIZE,
                    "budget",
                    format!(
                        "{} sweep(s) is too few: the {} named profiles and the {} first points of \
                         {} over {} coordinate(s), on {} scene(s), take {least}",
                        budget_key.get_ref(),
                        TABLE_4_1.len(),
                        method.first_points(space.dim()),
                        method.name(),
                        space.dim(),
                        scenes.len()
                    ),
                )
            })?;
        Ok(OptimizeSpec {
            path: PathBuf::from(path),
            scenes,
            objective,
            space,
            method,
            budget,
            seed,
            v_max,
        })
    }
}

/// Reads the `scenes`: each sweepable, with walls, with the first one's number of joints.
fn read_scenes(
    source: &Source<'_>,
    folder: &Path,
    keys: &Spanned<Vec<Spanned<String>>>,
    objective: Objective,
    duration_s: Option<(f64, std::ops::Range<usize>)>,
) -> Result<Vec<(PathBuf, Scene)>, SceneError> {
    if keys.get_ref().is_empty() {
        return Err(source.invalid(
            keys.span(),
            OPTIMIZE,
            "scenes",
            "no scenes: give at least one scene file",
        ));
    }
    let mut scenes: Vec<(PathBuf, Scene)> = Vec::new();
    for key in keys.get_ref() {
        let scene_path = folder.join(key.get_ref());
        let mut scene = Scene::from_path(&scene_path)?;
        let bad = |why: String| source.invalid(key.span(), OPTIMIZE, "scenes", why);
        match (&scene.follow, objective.is_follow()) {
            (None, true) => {
                return Err(bad(format!(
                    "{} is not a follow scene (no [robot], [controller] or [follow]): the \
                     objective \"{}\" runs a robot's closed loop",
                    scene_path.display(),
                    objective.name()
                )));
            }
            (Some(_), false) => {
                return Err(bad(format!(
                    "{} is a follow scene: its objectives are \"follow-v-max\" and \
                     \"follow-rms\", not \"{}\" (a sweep's)",
                    scene_path.display(),
                    objective.name()
                )));
            }
            _ => {}
        }
        if let Some(follow) = scene.follow.as_mut() {
            if let Some((d, span)) = &duration_s {
                let step_s = follow.config.settings.step_s;
                if (d / step_s).round() > MAX_FOLLOW_STEPS as f64 {
                    return Err(source.invalid(
                        span.clone(),
                        OPTIMIZE,
                        "duration_s",
                        format!(
                            "{d} s is more than {MAX_FOLLOW_STEPS} steps of {step_s} s of {}",
                            scene_path.display()
                        ),
                    ));
                }
                follow.config.settings.duration_s = *d;
            }
        } else if let Some((d, span)) = &duration_s {
            if (d / scene.motion.step_s).round() > MAX_SWEEP_STEPS as f64 {
                return Err(source.invalid(
                    span.clone(),
                    OPTIMIZE,
                    "duration_s",
                    format!(
                        "{d} s is more than {MAX_SWEEP_STEPS} steps of {} s of {}",
                        scene.motion.step_s,
                        scene_path.display()
                    ),
                ));
            }
            scene.motion.duration_s = *d;
        }
        if scene.walls.is_empty() {
            return Err(bad(format!(
                "{} has no [[walls]]: the objective \"{}\" is measured against a wall",
                scene_path.display(),
                objective.name()
            )));
        }
        if let Err(e) = scene.sweep_scene() {
            return Err(bad(format!(
                "{} cannot be swept: {e}",
                scene_path.display()
            )));
        }
        if let Some((first_path, first)) = scenes.first()
            && first.n() != scene.n()
        {
            return Err(bad(format!(
                "{} has {} joint(s) but {} has {}: the scenes share one stiffness per joint",
                scene_path.display(),
                scene.n(),
                first_path.display(),
                first.n()
            )));
        }
        scenes.push((scene_path, scene));
    }
    Ok(scenes)
}
