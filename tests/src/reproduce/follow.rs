//! The thesis's closing claim in the closed loop (issue #47, item 7): "antennae with an
//! exponentially decreasing stiffness profile accompanied by distally pointing anisotropic
//! mechano-hairs ... greatly facilitate stable high-speed wall following" (thesis, abstract
//! and 4.2.1, after Cowan, Lee and Full 2006).
//!
//! The robot of `examples/follow/reproduce/*.toml` (the thesis's 4.2.1 antenna on Cowan's
//! template body, the thesis robot's sensors, the contact-line estimator, one set of PD
//! gains) runs along five walls after Cowan et al.'s protocol ([`FollowWall`]) with each of
//! Table 4.1's seven profiles, with and without distal hairs. Per profile and wall: the
//! highest speed at which it still follows ([`v_max`]) and the RMS error at a common speed.
//!
//! # What counts as following
//! A run covers a fixed distance ([`Protocol::distance_m`], past the wall's feature) whatever
//! its speed. It is good when its status is `"ok"` (no collision, never lost, the solver
//! through every step) **and** it still follows at the end: over the last
//! [`Protocol::final_stretch_m`] of travel the true distance to the wall stays within
//! [`Protocol::final_band_m`] of the setpoint. Otherwise its status is the run's, or
//! `"drifted"` for an `"ok"` run that ended away from the setpoint (a robot that turned away
//! from the wall and never came back neither collides nor, within a short fast run, gets
//! lost: the collision-free criterion alone would call it good).
//!
//! # The estimator's window
//! The contact-line estimator fits the contact points of the last `window_s` seconds and
//! reports the wall's distance at their mean forward coordinate: a window fixed in time is a
//! lag that grows with the speed (at 2 m/s a 0.5 s window reaches 1 m behind the robot, a
//! negative preview that no antenna can make up for). The protocol fixes the window in
//! travel instead ([`Protocol::window_m`], at least two sensor samples), so the preview the
//! controller sees is the antenna's.

use std::panic::{AssertUnwindSafe, catch_unwind};

use antenna_cli::follow::v_max::search;
use nalgebra::Vector2;
use rayon::prelude::*;
use sim_core::follow::{Estimator, Follow, FollowConfig};
use sim_core::sweep::SweepScene;
use sim_core::{Hair, SensorSettings, StiffnessProfile, Surface, SurfaceMap, Wall};

use super::{ReproduceError, example_path, with_profile};

/// The walls of the protocol (Cowan, Lee and Full 2006: straight, angled inward, a convex
/// corner; the thesis's 4.2.2 sinusoid).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FollowWall {
    /// A straight wall.
    Straight,
    /// Straight, then angled 30 degrees toward the robot's path: it must turn away.
    Inward30,
    /// The same at 45 degrees.
    Inward45,
    /// Straight, then turning 90 degrees away from the robot: it must turn toward it.
    Convex90,
    /// The thesis's 4.2.2 sinusoid (10 mm amplitude) at 6.3 cycles/m.
    Sinusoid,
}

impl FollowWall {
    /// Every wall, in the tables' order.
    pub const ALL: [FollowWall; 5] = [
        FollowWall::Straight,
        FollowWall::Inward30,
        FollowWall::Inward45,
        FollowWall::Convex90,
        FollowWall::Sinusoid,
    ];

    /// The wall's name in tables and figures.
    pub fn name(self) -> &'static str {
        match self {
            FollowWall::Straight => "straight",
            FollowWall::Inward30 => "30 deg inward",
            FollowWall::Inward45 => "45 deg inward",
            FollowWall::Convex90 => "90 deg convex",
            FollowWall::Sinusoid => "sinusoid 6.3 /m",
        }
    }

    /// The scene file under `examples/`.
    pub fn file(self) -> &'static str {
        match self {
            FollowWall::Straight => "follow/reproduce/straight.toml",
            FollowWall::Inward30 => "follow/reproduce/inward_30.toml",
            FollowWall::Inward45 => "follow/reproduce/inward_45.toml",
            FollowWall::Convex90 => "follow/reproduce/convex_90.toml",
            FollowWall::Sinusoid => "follow/reproduce/sinusoid_6_3.toml",
        }
    }
}

/// Where every angled wall and the corner turn: x of the corner, m (the scenes' comments say
/// so too).
pub const FEATURE_X_M: f64 = 0.8;

/// A scene's parts: the antenna and walls, the sensors, the robot and controller.
#[derive(Clone, Debug)]
pub struct FollowCase {
    /// The antenna, the walls and the placement.
    pub scene: SweepScene,
    /// The robot's sensors.
    pub sensors: SensorSettings,
    /// The robot, the controller and the run (speed and duration set per run).
    pub config: FollowConfig,
}

/// The case of `wall`'s scene file as written (the fast-exponential antenna, no hairs).
///
/// # Errors
/// [`ReproduceError::Scene`] when the file cannot be read or is not a follow scene.
pub fn load_case(wall: FollowWall) -> Result<FollowCase, ReproduceError> {
    let path = example_path(wall.file());
    let scene_error = |message: String| ReproduceError::Scene {
        path: path.display().to_string(),
        message,
    };
    let scene = antenna_scene::Scene::from_path(&path).map_err(|e| scene_error(e.to_string()))?;
    let (scene, config, sensors) = scene
        .follow_parts()
        .map_err(|e| scene_error(e.to_string()))?;
    Ok(FollowCase {
        scene,
        sensors,
        config,
    })
}

/// What the hairs and the walls' surface are.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Hairs {
    /// The scenes as written: no hairs, smooth walls.
    None,
    /// The thesis's distally pointing hair (18 mm, open 45 deg, `Hair::seed`) on the wall's
    /// side of every flagellar link, the walls rough (hair tips anchor, holding up to
    /// [`ROUGH_HOLD_N`] along and away from the wall, as `examples/hairs_distal.toml`); the
    /// robot knows its hairs: a touch under a hair is mapped to the hair's open tip
    /// (`SensorSettings::hair_tip_points`), where the wall is.
    DistalRough,
}

impl Hairs {
    /// The variant's name in tables.
    pub fn name(self) -> &'static str {
        match self {
            Hairs::None => "no hairs, smooth",
            Hairs::DistalRough => "distal hairs, rough",
        }
    }
}

/// What an anchored hair tip holds on the rough walls, N (`examples/hairs_distal.toml`).
pub const ROUGH_HOLD_N: f64 = 0.05;

/// `base` with the stiffness of `profile` (Table 4.1's range) and the hairs of `hairs`.
///
/// # Errors
/// [`ReproduceError`] for a chain or wall that cannot be built.
pub fn case_for(
    base: &FollowCase,
    profile: StiffnessProfile,
    hairs: Hairs,
) -> Result<FollowCase, ReproduceError> {
    let mut chain = with_profile(&base.scene.chain, profile)?;
    let mut walls = base.scene.walls.clone();
    let mut sensors = base.sensors.clone();
    if hairs == Hairs::DistalRough {
        sensors.hair_tip_points = true;
        let mut builder = chain.to_builder().without_hairs();
        for link in 1..=chain.n() {
            builder = builder.hair(link, Hair::seed(chain.link_lengths_m()[link]));
        }
        chain = builder.build()?;
        for wall in &mut walls {
            let mu = match wall.surfaces.first() {
                Surface::Smooth { mu } | Surface::Rough { mu, .. } => mu,
            };
            *wall = Wall::new(
                wall.shape.clone(),
                SurfaceMap::uniform(Surface::Rough {
                    mu,
                    hold_shear_n: ROUGH_HOLD_N,
                    hold_tension_n: ROUGH_HOLD_N,
                })?,
            );
        }
    }
    Ok(FollowCase {
        scene: SweepScene {
            chain,
            walls,
            ..base.scene.clone()
        },
        sensors,
        config: base.config,
    })
}

/// How the runs go and how they are judged.
#[derive(Clone, Debug, PartialEq)]
pub struct Protocol {
    /// The coarse grid of the v_max search, m/s.
    pub speeds_m_per_s: Vec<f64>,
    /// The bisection stops when the bracket is this narrow, m/s.
    pub tolerance_m_per_s: f64,
    /// Every run's travel, m (the features are at [`FEATURE_X_M`]).
    pub distance_m: f64,
    /// The contact-line estimator's window, in travel, m (at least two sensor samples).
    pub window_m: f64,
    /// The stretch at the end over which a good run still follows, m of travel.
    pub final_stretch_m: f64,
    /// How near the setpoint it must stay there, m.
    pub final_band_m: f64,
    /// The speed of the RMS comparison, m/s.
    pub common_speed_m_per_s: f64,
    /// The controller's search turn (with no estimate, toward the wall), deg/s (`None`:
    /// the scene's, 30 deg/s).
    pub search_turn_rate_deg_per_s: Option<f64>,
}

impl Protocol {
    /// The full reproduction: 0.1 to 4 m/s (10 speeds), bisection to 0.05 m/s, 1.8 m of
    /// travel (1.0 m past the features), a 4 cm window, within 20 mm over the last 0.3 m,
    /// the RMS at 0.5 m/s.
    pub fn full() -> Protocol {
        Protocol {
            speeds_m_per_s: vec![0.1, 0.2, 0.3, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0],
            tolerance_m_per_s: 0.05,
            distance_m: 1.8,
            window_m: 0.04,
            final_stretch_m: 0.3,
            final_band_m: 0.02,
            common_speed_m_per_s: 0.5,
            search_turn_rate_deg_per_s: None,
        }
    }

    /// The CI test's: the full protocol on a coarse grid (0.25 to 2 m/s), no bisection.
    pub fn coarse() -> Protocol {
        Protocol {
            speeds_m_per_s: vec![0.25, 0.5, 1.0, 2.0],
            tolerance_m_per_s: f64::INFINITY,
            ..Protocol::full()
        }
    }

    /// The window in seconds at `speed_m_per_s` for sensors sampling at `sample_rate_hz`.
    pub fn window_s(&self, speed_m_per_s: f64, sample_rate_hz: Option<f64>) -> f64 {
        let samples = sample_rate_hz.map_or(0.0, |r| 2.0 / r);
        (self.window_m / speed_m_per_s).max(samples)
    }
}

/// One run at one speed.
#[derive(Clone, Debug, PartialEq)]
pub struct SpeedRun {
    /// The speed, m/s.
    pub speed_m_per_s: f64,
    /// `"ok"`, `"drifted"` (an `"ok"` run that ended away from the setpoint), or the run's
    /// status (`"collided"`, `"lost"`, the solver's).
    pub status: String,
    /// The RMS of the true error after the settling window, m.
    pub rms_error_m: Option<f64>,
    /// The largest |error| over the final stretch, m.
    pub final_max_error_m: Option<f64>,
    /// The mean preview of the estimates (their forward coordinate from the point of
    /// rotation), m.
    pub mean_preview_m: Option<f64>,
    /// The share of steps with an estimate.
    pub estimate_share: f64,
    /// The point of rotation's path, every step, ground frame, m.
    pub path_m: Vec<Vector2<f64>>,
    /// Antenna postures (base pivot, then every link end), ground frame, m, every
    /// [`POSTURE_EVERY_M`] of travel.
    pub postures_m: Vec<Vec<Vector2<f64>>>,
}

impl SpeedRun {
    /// Whether the run counts as following.
    pub fn good(&self) -> bool {
        self.status == "ok"
    }
}

/// The travel between the antenna postures a run keeps, m.
pub const POSTURE_EVERY_M: f64 = 0.15;

/// Runs `case` at `speed_m_per_s` over the protocol's distance.
///
/// # Errors
/// [`ReproduceError::Follow`] when the run cannot start.
pub fn run_at(
    case: &FollowCase,
    speed_m_per_s: f64,
    protocol: &Protocol,
) -> Result<SpeedRun, ReproduceError> {
    let mut config = case.config;
    config.robot.speed_m_per_s = speed_m_per_s;
    config.settings.duration_s = protocol.distance_m / speed_m_per_s;
    if let Estimator::ContactLine { window_s } = &mut config.controller.estimator {
        *window_s = protocol.window_s(speed_m_per_s, case.sensors.sample_rate_hz);
    }
    if let Some(rate) = protocol.search_turn_rate_deg_per_s {
        config.controller.search_turn_rate_rad_per_s = rate.to_radians();
    }
    let label = format!("{:.3} m/s", speed_m_per_s);
    let mut follow = Follow::new(&case.scene, &case.sensors, &config).map_err(|source| {
        ReproduceError::Follow {
            label: label.clone(),
            source,
        }
    })?;
    let setpoint_m = config.controller.setpoint_m;
    let mut path_m = Vec::new();
    let mut postures_m = Vec::new();
    let mut next_posture_m = 0.0;
    let mut final_max: Option<f64> = None;
    let mut final_missing = false;
    let (mut preview_sum, mut preview_count) = (0.0, 0usize);
    while let Some(step) = follow.next_step() {
        let Ok(step) = step else { break };
        let travel_m = speed_m_per_s * step.t_s;
        path_m.push(step.pose_m);
        if travel_m + 1e-9 >= next_posture_m {
            next_posture_m += POSTURE_EVERY_M;
            if let Some(base) = step.base_m {
                postures_m.push(chain_points(&case.scene.chain, base, &step.theta_rad));
            }
        }
        if let Some(e) = step.estimate {
            preview_sum += e.preview_m;
            preview_count += 1;
        }
        if travel_m >= protocol.distance_m - protocol.final_stretch_m {
            match step.wall_distance_m {
                Some(d) => {
                    let e = (d - setpoint_m).abs();
                    final_max = Some(final_max.map_or(e, |m: f64| m.max(e)));
                }
                None => final_missing = true,
            }
        }
    }
    let summary = follow.summary();
    let mut status = summary.status.name().to_string();
    let following = !final_missing && final_max.is_some_and(|m| m <= protocol.final_band_m);
    if status == "ok" && !following {
        status = "drifted".to_string();
    }
    Ok(SpeedRun {
        speed_m_per_s,
        status,
        rms_error_m: summary.rms_error_m,
        final_max_error_m: final_max,
        mean_preview_m: (preview_count > 0).then(|| preview_sum / preview_count as f64),
        estimate_share: summary.estimate_share,
        path_m,
        postures_m,
    })
}

/// The chain's points (base pivot, then every link end) for ground-frame joint angles.
fn chain_points(
    chain: &sim_core::Chain,
    base_m: Vector2<f64>,
    theta_rad: &[f64],
) -> Vec<Vector2<f64>> {
    let mut out = vec![base_m];
    let mut p = base_m;
    let mut angle = 0.0;
    for (length, theta) in chain.link_lengths_m().iter().zip(theta_rad) {
        angle += theta;
        p += *length * Vector2::new(angle.cos(), angle.sin());
        out.push(p);
    }
    out
}

/// What a v_max search found.
#[derive(Clone, Debug, PartialEq)]
pub struct VMax {
    /// The highest good speed below the first failing one, m/s (`None`: the slowest grid
    /// speed already fails).
    pub v_max_m_per_s: Option<f64>,
    /// The status of the first failing speed (`None`: every grid speed is good and
    /// `v_max_m_per_s` is the grid's top, a lower bound).
    pub failure: Option<String>,
    /// Whether no good grid speed lies above a failing one.
    pub monotone: bool,
    /// Every run's speed and status, in the order run.
    pub runs: Vec<(f64, String)>,
    /// The run at the protocol's common speed, if it is a grid speed.
    pub common: Option<SpeedRun>,
}

/// The highest speed at which `case` follows (`antenna-cli`'s v_max [`search`], with
/// the protocol's judgement of a run): every grid speed, then bisection between the last
/// good one below the first failing one and that one.
///
/// # Errors
/// [`ReproduceError::Follow`] when a run cannot start.
pub fn v_max(case: &FollowCase, protocol: &Protocol) -> Result<VMax, ReproduceError> {
    let mut common = None;
    let found = search(
        &protocol.speeds_m_per_s,
        protocol.tolerance_m_per_s,
        |v| -> Result<String, ReproduceError> {
            let run = run_at(case, v, protocol)?;
            let status = run.status.clone();
            if v == protocol.common_speed_m_per_s {
                common = Some(run);
            }
            Ok(status)
        },
    )?;
    Ok(VMax {
        v_max_m_per_s: found.v_max_m_per_s,
        failure: found.failure,
        monotone: found.monotone,
        runs: found
            .runs
            .into_iter()
            .map(|r| (r.speed_m_per_s, r.status))
            .collect(),
        common,
    })
}

/// One profile on one wall.
#[derive(Clone, Debug)]
pub struct Cell {
    /// The profile.
    pub profile: StiffnessProfile,
    /// The wall.
    pub wall: FollowWall,
    /// The hairs.
    pub hairs: Hairs,
    /// The v_max search.
    pub v_max: VMax,
    /// The run at the protocol's common speed.
    pub common: SpeedRun,
    /// Wall-clock time of the cell, seconds.
    pub elapsed_s: f64,
}

/// Every profile on every wall with every hair variant, in parallel on rayon's pool (a cell
/// per job), in the order profiles x walls x hairs.
///
/// # Errors
/// The first cell's error (a panic in a run is reported as one).
pub fn run_grid(
    profiles: &[StiffnessProfile],
    walls: &[FollowWall],
    hairs: &[Hairs],
    protocol: &Protocol,
) -> Result<Vec<Cell>, ReproduceError> {
    let bases: Vec<(FollowWall, FollowCase)> = walls
        .iter()
        .map(|&w| load_case(w).map(|c| (w, c)))
        .collect::<Result<_, _>>()?;
    let mut jobs = Vec::new();
    for profile in profiles {
        for (wall, base) in &bases {
            for &h in hairs {
                jobs.push((profile.clone(), *wall, base, h));
            }
        }
    }
    let cells: Vec<Result<Cell, ReproduceError>> = jobs
        .par_iter()
        .map(|(profile, wall, base, h)| {
            let label = format!("{} on the {} wall", profile.name(), wall.name());
            catch_unwind(AssertUnwindSafe(|| -> Result<Cell, ReproduceError> {
                let started = std::time::Instant::now();
                let case = case_for(base, profile.clone(), *h)?;
                let mut v_max = v_max(&case, protocol)?;
                let common = match v_max.common.take() {
                    Some(run) => run,
                    None => run_at(&case, protocol.common_speed_m_per_s, protocol)?,
                };
                Ok(Cell {
                    profile: profile.clone(),
                    wall: *wall,
                    hairs: *h,
                    v_max,
                    common,
                    elapsed_s: started.elapsed().as_secs_f64(),
                })
            }))
            .unwrap_or_else(|_| {
                Err(ReproduceError::Scene {
                    path: label,
                    message: "a run panicked".into(),
                })
            })
        })
        .collect();
    cells.into_iter().collect()
}

/// How many runs of `cells` ended in each status, sorted by name.
pub fn status_counts(cells: &[Cell]) -> Vec<(String, usize)> {
    let mut counts = std::collections::BTreeMap::new();
    for c in cells {
        for (_, s) in &c.v_max.runs {
            *counts.entry(s.clone()).or_insert(0) += 1;
        }
    }
    counts.into_iter().collect()
}
