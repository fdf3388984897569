//! The follow stress suite: seeded random closed-loop runs (issue #47), each started, run to
//! its end and judged against the loop's contract: a run either refuses to start with a typed
//! [`FollowError`] or ends with a status of [`STATUS_NAMES`]; it never panics, never hangs,
//! and every step it reports is finite.
//!
//! A case ([`FollowCase`]) is a pure function of `(seed, index, sample)`:
//! - the antenna: `N` in {4, 9, 18, 36} links of `0.36 / N` m, one of the seven Table 4.1
//!   profiles, no hairs or distal hairs (half of them with a compliant root), as the contact
//!   suite builds it ([`super::case::antenna`]), mounted 0-6 cm ahead and 0-3 cm toward the
//!   wall at 10-60 deg;
//! - one wall of the contact suite's kinds ([`super::walls`]: a line, a polyline with convex
//!   and concave corners, a sinusoid, a digitized line or trapezoid), its baseline at -15 to
//!   +15 deg, smooth with `mu` in 0-1 or rough (hair tips anchor) with holding forces of
//!   1-100 mN;
//! - the robot: 0.05-2 m/s, a footprint of 6-20 x 3-10 cm, the template body (`J`
//!   2e-5-2e-3 kg m^2, `b` 0 or 4e-4-4e-2 N m s/rad with `b h / J` within what RK4 takes)
//!   or a wheeled one (rate limit 30-720 deg/s, acceleration 100-10,000 deg/s^2), the wall
//!   on the left or the right (a mirror image of a left-wall case), `antenna_loads_body` on
//!   40 % of the template bodies;
//! - the controller: the contact-line (window 0.05-1 s), bend or ideal-preview (0-0.3 m)
//!   estimator, gains zero a tenth of the time, large a tenth, else log-uniform about the
//!   example's, a delay of 0 or up to 0.05 s, a search turn of 0-90 deg/s, a setpoint of
//!   3-30 cm;
//! - the sensors: Hall noise 0-3 counts, calibration spreads of 0-8 counts and 0-3 %, a touch
//!   threshold of 0 or 1-50 mN, debouncing over 1-4 reads, every step or 20-500 Hz;
//! - the start: the body 0-15 deg off the wall's baseline, its point of rotation from just
//!   clear of the wall to the antenna's reach away; a tenth of the cases put the point of
//!   rotation inside the wall (the run must refuse with [`FollowError::StartsInWall`]); the
//!   antenna placed by the follow scene's default approach, at rest, or tip on the wall;
//! - the run: 0.5-2 s (the soak: 1-4 s) at 0.01 s, `lost_after_s` 0.1-2 s.
//!
//! With the ideal preview, the body alone (`Follow::without_antenna`) is run first and held to
//! the same contract. [`run_follow_case`] runs a case in this process; [`run_follow_cases`] runs many on every
//! core, each in a child process with a time limit (the contact suite's machinery,
//! [`super::parallel`]); [`follow_table`] writes the table of statuses.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::Instant;

use nalgebra::{Rotation2, Vector2};
use rand::Rng;
use rand::rngs::StdRng;
use sim_core::follow::config::RK4_DAMPING_LIMIT;
use sim_core::follow::{
    BodyModel, Controller, Estimator, Follow, FollowConfig, FollowError, FollowSettings,
    FollowStep, Robot, STATUS_NAMES, WallSide,
};
use sim_core::sweep::{Placement, SweepScene};
use sim_core::{
    CalibrationError, InitialGuess, SensorSettings, StiffnessProfile, Surface, SurfaceMap, Wall,
};

use super::case::{ANTENNA_LENGTH_M, MUS, Sample, antenna, weighted, with_compliant_roots};
use super::parallel::{ChildCommand, TimeLimit, last_progress, on_workers, run_child, stderr_tail};
use super::walls::{
    Profile, WallFrame, WallKind, WallSpec, draw_digitized, draw_polyline, draw_sinusoid,
};
use super::wire::{BEGIN, END, PROGRESS, escape, unescape};
use super::{StressError, case_rng};
use crate::reproduce::TABLE_4_1_PROFILES;

/// The link counts `N` of follow cases (the base link included).
pub const FOLLOW_LINK_COUNTS: [usize; 4] = [4, 9, 18, 36];
/// Mixed into the seed so that follow cases draw from streams of their own.
const FOLLOW_STREAM: u64 = 0x666f_6c6c_6f77;
/// The step of every run, seconds (the `[follow]` default).
pub const FOLLOW_STEP_S: f64 = 0.01;
/// The speeds, m/s (log-uniform).
pub const SPEED_RANGE_M_PER_S: (f64, f64) = (0.05, 2.0);
/// The share of cases whose point of rotation starts inside the wall.
pub const INSIDE_SHARE: f64 = 0.1;

/// How the antenna is placed at the start.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum FollowPlacement {
    /// The follow scene's default: an approach onto wall 0 (`antenna_scene`).
    DefaultApproach,
    /// The rest posture where the mount is.
    Rest,
    /// The tip held on the wall and let go (from a C).
    TipOnWall,
}

impl FollowPlacement {
    /// Its name in replay lines.
    pub fn name(self) -> &'static str {
        match self {
            FollowPlacement::DefaultApproach => "approach",
            FollowPlacement::Rest => "rest",
            FollowPlacement::TipOnWall => "tip-on-wall",
        }
    }
}

/// What the footprint at the start is, by an independent check (the footprint's edges
/// sampled every millimetre against the walls, and the walls' vertices inside it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StartCheck {
    /// Part of the footprint is inside a wall: the run must refuse to start.
    Inside,
    /// Every sampled point is at least [`CLEAR_MARGIN_M`] clear and no vertex is inside:
    /// the run must not refuse with [`FollowError::StartsInWall`].
    Clear,
    /// Too close to call.
    Grazing,
}

/// How far clear of the walls a footprint is called clear, m.
pub const CLEAR_MARGIN_M: f64 = 1e-3;

/// One follow case: what was drawn, and the run's parts.
#[derive(Clone, Debug)]
pub struct FollowCase {
    /// The seed.
    pub seed: u64,
    /// The index under the seed.
    pub index: u64,
    /// The sample.
    pub sample: Sample,
    /// `N`, the links (the base link included).
    pub links: usize,
    /// The stiffness profile.
    pub profile: StiffnessProfile,
    /// Distal hairs on every flexible link.
    pub hairs: bool,
    /// The wall as drawn (the left-wall frame: a right-wall case is its mirror image).
    pub wall: WallSpec,
    /// A rough surface's holding forces `(shear, tension)`, N (`None`: smooth).
    pub rough: Option<(f64, f64)>,
    /// The point of rotation was put inside the wall.
    pub drawn_inside: bool,
    /// The footprint at the start, by the independent check.
    pub start_check: StartCheck,
    /// The antenna's placement.
    pub placement: FollowPlacement,
    /// The antenna and walls (in the scene's frame: mirrored for a right-wall case).
    pub scene: SweepScene,
    /// The sensors.
    pub sensors: SensorSettings,
    /// The robot, controller and run.
    pub config: FollowConfig,
}

/// A log-uniform draw from `[lo, hi]`.
fn log_uniform(rng: &mut StdRng, lo: f64, hi: f64) -> f64 {
    (lo.ln() + (hi.ln() - lo.ln()) * rng.random::<f64>()).exp()
}

/// A gain: zero a tenth of the time, large (`large`) a tenth, else log-uniform in `normal`.
fn gain(rng: &mut StdRng, normal: (f64, f64), large: (f64, f64)) -> f64 {
    match weighted(rng, &[0.1, 0.1, 0.8]) {
        0 => 0.0,
        1 => log_uniform(rng, large.0, large.1),
        _ => log_uniform(rng, normal.0, normal.1),
    }
}

/// A body: the template (its damping within what RK4 at [`FOLLOW_STEP_S`] takes,
/// [`RK4_DAMPING_LIMIT`]) or a wheeled one.
fn draw_body(rng: &mut StdRng) -> BodyModel {
    if rng.random_bool(0.7) {
        let inertia_kg_m2 = log_uniform(rng, 2e-5, 2e-3);
        let most = (0.98 * RK4_DAMPING_LIMIT * inertia_kg_m2 / FOLLOW_STEP_S).min(4e-2);
        BodyModel::Template {
            inertia_kg_m2,
            damping_n_m_s_per_rad: if rng.random_bool(0.1) {
                0.0
            } else {
                log_uniform(rng, 4e-4, most)
            },
        }
    } else {
        BodyModel::Wheeled {
            max_turn_rate_rad_per_s: rng.random_range(30.0_f64..=720.0).to_radians(),
            max_turn_accel_rad_per_s2: log_uniform(rng, 100.0, 10_000.0).to_radians(),
        }
    }
}

fn draw_estimator(rng: &mut StdRng) -> Estimator {
    match weighted(rng, &[0.45, 0.25, 0.30]) {
        0 => Estimator::ContactLine {
            window_s: rng.random_range(0.05..=1.0),
        },
        1 => Estimator::Bend,
        _ => Estimator::IdealPreview {
            preview_m: if rng.random_bool(0.1) {
                0.0
            } else {
                rng.random_range(0.0..=0.3)
            },
        },
    }
}

fn draw_controller(rng: &mut StdRng) -> Controller {
    Controller {
        estimator: draw_estimator(rng),
        setpoint_m: rng.random_range(0.03..=0.30),
        kp_n: gain(rng, (0.005, 0.2), (0.5, 5.0)),
        kd_n_s: gain(rng, (2e-4, 0.01), (0.02, 0.2)),
        kp_rad_per_s_per_m: gain(rng, (5.0, 100.0), (500.0, 5_000.0)),
        kd_rad_per_m: gain(rng, (0.1, 5.0), (20.0, 200.0)),
        delay_s: if rng.random_bool(0.4) {
            0.0
        } else {
            rng.random_range(0.0..=0.05)
        },
        search_turn_rate_rad_per_s: rng.random_range(0.0_f64..=90.0).to_radians(),
    }
}

fn draw_sensors(rng: &mut StdRng, hairs: bool) -> SensorSettings {
    SensorSettings {
        angle_noise_counts: rng.random_range(0.0..=3.0),
        offset_counts: CalibrationError::Spread(rng.random_range(0.0..=8.0)),
        gain_error: CalibrationError::Spread(rng.random_range(0.0..=0.03)),
        touch_threshold_n: if rng.random_bool(0.3) {
            0.0
        } else {
            log_uniform(rng, 0.001, 0.05)
        },
        touch_debounce_samples: rng.random_range(1..=4),
        sample_rate_hz: if rng.random_bool(0.3) {
            None
        } else {
            Some(log_uniform(rng, 20.0, 500.0))
        },
        seed: rng.random(),
        hair_tip_points: hairs && rng.random_bool(0.5),
    }
}

/// The footprint's rectangle at `por_m` and `heading_rad`: its corners, counter-clockwise.
fn footprint_corners(
    por_m: &Vector2<f64>,
    heading_rad: f64,
    size_m: [f64; 2],
) -> [Vector2<f64>; 4] {
    let r = Rotation2::new(heading_rad);
    let (a, b) = (0.5 * size_m[0], 0.5 * size_m[1]);
    [(-a, -b), (a, -b), (a, b), (-a, b)].map(|(x, y)| por_m + r * Vector2::new(x, y))
}

/// The independent check of the footprint against `walls` (see [`StartCheck`]).
pub fn check_start(
    walls: &[Wall],
    vertices_m: &[Vector2<f64>],
    por_m: &Vector2<f64>,
    heading_rad: f64,
    size_m: [f64; 2],
) -> StartCheck {
    let corners = footprint_corners(por_m, heading_rad, size_m);
    let mut least = f64::INFINITY;
    for k in 0..4 {
        let (p, q) = (corners[k], corners[(k + 1) % 4]);
        let samples = ((q - p).norm() / 1e-3).ceil().max(1.0) as usize;
        for i in 0..=samples {
            let x = p + (q - p) * (i as f64 / samples as f64);
            for w in walls {
                least = least.min(w.signed_distance(&x).gap_m);
            }
        }
    }
    // A vertex strictly inside the rectangle pokes into the footprint.
    let r = Rotation2::new(-heading_rad);
    let vertex_inside = vertices_m.iter().any(|v| {
        let local = r * (v - por_m);
        local.x.abs() < 0.5 * size_m[0] && local.y.abs() < 0.5 * size_m[1]
    });
    if least < -1e-9 || vertex_inside {
        StartCheck::Inside
    } else if least >= CLEAR_MARGIN_M {
        StartCheck::Clear
    } else {
        StartCheck::Grazing
    }
}

impl FollowCase {
    /// Draws case `index` of `sample` under `seed`.
    ///
    /// # Errors
    /// [`StressError`] when a part cannot be built (a bug of the generator).
    pub fn generate(seed: u64, index: u64, sample: Sample) -> Result<FollowCase, StressError> {
        let rng = &mut case_rng(seed ^ FOLLOW_STREAM, index);
        let links = match sample {
            // Every 8 cases: 3 of N = 4, 3 of 9, one each of 18 and 36.
            Sample::Ci => [4, 9, 4, 18, 9, 4, 36, 9][(index % 8) as usize],
            Sample::Soak | Sample::SoakWide => {
                FOLLOW_LINK_COUNTS[weighted(rng, &[30.0, 35.0, 20.0, 15.0])]
            }
        };
        let link_m = ANTENNA_LENGTH_M / links as f64;
        let profile = TABLE_4_1_PROFILES[rng.random_range(0..TABLE_4_1_PROFILES.len())].clone();
        let hairs = rng.random_bool(0.4);
        let mount_m = Vector2::new(rng.random_range(0.0..=0.06), rng.random_range(0.0..=0.03));
        let mount_angle_rad = rng.random_range(10.0_f64..=60.0).to_radians();
        let chain = with_compliant_roots(antenna(links, &profile, hairs, mount_angle_rad)?, rng)?;
        let footprint_m = [rng.random_range(0.06..=0.20), rng.random_range(0.03..=0.10)];
        let speed_m_per_s = log_uniform(rng, SPEED_RANGE_M_PER_S.0, SPEED_RANGE_M_PER_S.1);
        let duration_s = match sample {
            Sample::Ci => rng.random_range(0.5..=2.0),
            Sample::Soak | Sample::SoakWide => rng.random_range(1.0..=4.0),
        };
        let travel_m = speed_m_per_s * duration_s;
        let body = draw_body(rng);
        let robot = Robot {
            speed_m_per_s,
            body,
            footprint_m,
            mount_m,
            mount_angle_rad,
            wall_side: if rng.random_bool(0.5) {
                WallSide::Left
            } else {
                WallSide::Right
            },
            // Only a template body takes a moment (a wheeled one's rate is commanded).
            antenna_loads_body: rng.random_bool(0.4) && matches!(body, BodyModel::Template { .. }),
        };
        let controller = draw_controller(rng);
        // The wall, in the left-wall frame: the point of rotation at the origin.
        let heading_rad = rng.random_range(-15.0_f64..=15.0).to_radians();
        let wall_angle_rad = rng.random_range(-15.0_f64..=15.0).to_radians();
        let drawn_inside = rng.random_bool(INSIDE_SHARE);
        let half_width_m = 0.5 * footprint_m[1];
        let distance_m = if drawn_inside {
            -rng.random_range(0.0..=0.03)
        } else {
            rng.random_range(half_width_m + 0.005..=mount_m.y + 0.7 * ANTENNA_LENGTH_M)
        };
        let frame = WallFrame {
            origin_m: Vector2::new(0.0, distance_m / wall_angle_rad.cos()),
            angle_rad: wall_angle_rad,
        };
        let (u0, _) = frame.to_wall(&Vector2::zeros());
        let span = (u0 - 0.3, u0 + 0.5 + 1.2 * travel_m);
        let kind = WallKind::ALL[weighted(rng, &[0.25, 0.35, 0.2, 0.2])];
        let wall_profile = match kind {
            WallKind::Line => Profile::Line,
            WallKind::Polyline => draw_polyline(rng, link_m, span),
            WallKind::Sinusoid => draw_sinusoid(rng, link_m),
            WallKind::Digitized => draw_digitized(rng, link_m, span, &frame)?,
        };
        let mu = if rng.random_bool(0.5) {
            MUS[rng.random_range(0..MUS.len())]
        } else {
            rng.random_range(0.0..=1.0)
        };
        let mut spec = WallSpec {
            kind,
            frame,
            profile: wall_profile,
            mu,
            corner_at: None,
        };
        // The point of rotation inside the wall whatever its shape: the frame moved toward
        // the body by the wall's depth there.
        if drawn_inside {
            let gap = spec.build()?.signed_distance(&Vector2::zeros()).gap_m;
            if gap > -1e-3 {
                spec = spec.shifted_into_solid(gap - rng.random_range(1e-3..=0.03));
            }
        }
        let rough = rng
            .random_bool(0.25)
            .then(|| (log_uniform(rng, 1e-3, 0.1), log_uniform(rng, 1e-3, 0.1)));
        let mut wall = spec.build()?;
        if let Some((hold_shear_n, hold_tension_n)) = rough {
            wall = Wall::new(
                wall.shape,
                SurfaceMap::uniform(Surface::Rough {
                    mu,
                    hold_shear_n,
                    hold_tension_n,
                })?,
            );
        }
        let start_check = check_start(
            std::slice::from_ref(&wall),
            &spec.vertices_m(),
            &Vector2::zeros(),
            heading_rad,
            footprint_m,
        );
        // The default step (FOLLOW_STEP_S), and the defaults of keys added later.
        let settings = FollowSettings {
            duration_s,
            pose_m: Vector2::zeros(),
            heading_rad,
            lost_after_s: rng.random_range(0.1..=2.0),
            settling_window_m: rng.random_range(0.0..=0.5),
            settling_band_m: rng.random_range(0.005..=0.02),
            antenna_step_m: if rng.random_bool(0.8) {
                0.002
            } else {
                rng.random_range(0.001..=0.005)
            },
            ..FollowSettings::default()
        };
        let placement_kind = [
            FollowPlacement::DefaultApproach,
            FollowPlacement::Rest,
            FollowPlacement::TipOnWall,
        ][weighted(rng, &[0.7, 0.15, 0.15])];
        let placement = match placement_kind {
            FollowPlacement::DefaultApproach => {
                antenna_scene::follow::default_placement(&chain, &settings)
            }
            FollowPlacement::Rest => Placement::Rest,
            FollowPlacement::TipOnWall => Placement::TipOnWall {
                wall: 0,
                ahead_m: rng.random_range(-0.05..=0.10),
                start: InitialGuess::C,
            },
        };
        let sensors = draw_sensors(rng, hairs);
        let mirror = robot.wall_side == WallSide::Right;
        let config = FollowConfig {
            robot,
            controller,
            settings: FollowSettings {
                pose_m: Vector2::zeros(),
                heading_rad: if mirror { -heading_rad } else { heading_rad },
                ..settings
            },
        };
        let walls = vec![if mirror {
            wall.mirrored_about_x_axis()
        } else {
            wall
        }];
        let mut scene = SweepScene::new(chain, walls);
        scene.placement = placement;
        Ok(FollowCase {
            seed,
            index,
            sample,
            links,
            profile,
            hairs,
            wall: spec,
            rough,
            drawn_inside,
            start_check,
            placement: placement_kind,
            scene,
            sensors,
            config,
        })
    }

    /// The travel of the base over the run, m.
    pub fn travel_m(&self) -> f64 {
        self.config.robot.speed_m_per_s * self.config.settings.duration_s
    }

    /// About how many times the antenna is solved (the travel in steps of
    /// `antenna_step_m`, and every step at least once).
    pub fn antenna_solves(&self) -> usize {
        let by_travel = self.travel_m() / self.config.settings.antenna_step_m;
        by_travel.ceil() as usize + self.config.steps()
    }

    /// The replay line: how to run the case again, and what it is.
    pub fn replay_line(&self) -> String {
        let c = &self.config;
        let r = &c.robot;
        let k = &c.controller;
        let s = &self.sensors;
        let body = match r.body {
            BodyModel::Template {
                inertia_kg_m2,
                damping_n_m_s_per_rad,
            } => format!(
                "template J={inertia_kg_m2:.3e} b={damping_n_m_s_per_rad:.3e} kp={:.3e} kd={:.3e}",
                k.kp_n, k.kd_n_s
            ),
            BodyModel::Wheeled {
                max_turn_rate_rad_per_s,
                max_turn_accel_rad_per_s2,
            } => format!(
                "wheeled rate<={:.0}deg/s accel<={:.0}deg/s2 kp={:.3e} kd={:.3e}",
                max_turn_rate_rad_per_s.to_degrees(),
                max_turn_accel_rad_per_s2.to_degrees(),
                k.kp_rad_per_s_per_m,
                k.kd_rad_per_m
            ),
        };
        let estimator = match k.estimator {
            Estimator::ContactLine { window_s } => format!("contact-line window={window_s:.3}s"),
            Estimator::Bend => "bend".to_string(),
            Estimator::IdealPreview { preview_m } => format!("ideal-preview l={preview_m:.3}m"),
        };
        let surface = match self.rough {
            Some((shear, tension)) => format!(" rough hold={shear:.3e}N/{tension:.3e}N"),
            None => String::new(),
        };
        format!(
            "ANTENNA_STRESS_REPLAY={}:{}:{} | N={} profile={} hairs={} mount=({:.3},{:.3})m@{:.1}deg \
             | v={:.3}m/s for {:.2}s side={} loads-body={} footprint={:.3}x{:.3}m heading={:.1}deg \
             | {body} | {estimator} setpoint={:.3}m delay={:.3}s search={:.1}deg/s lost-after={:.2}s \
             | sensors noise={:.2} offset-sd={:?} gain-sd={:?} touch>={:.3e}N debounce={} rate={:?} \
             | start {} {}{} | wall: {}{surface}",
            self.sample.name(),
            self.seed,
            self.index,
            self.links,
            self.profile.name(),
            if self.hairs { "distal" } else { "none" },
            r.mount_m.x,
            r.mount_m.y,
            r.mount_angle_rad.to_degrees(),
            r.speed_m_per_s,
            c.settings.duration_s,
            r.wall_side.name(),
            r.antenna_loads_body,
            r.footprint_m[0],
            r.footprint_m[1],
            c.settings.heading_rad.to_degrees(),
            k.setpoint_m,
            k.delay_s,
            k.search_turn_rate_rad_per_s.to_degrees(),
            c.settings.lost_after_s,
            s.angle_noise_counts,
            s.offset_counts,
            s.gain_error,
            s.touch_threshold_n,
            s.touch_debounce_samples,
            s.sample_rate_hz,
            self.placement.name(),
            match self.start_check {
                StartCheck::Inside => "footprint-inside",
                StartCheck::Clear => "footprint-clear",
                StartCheck::Grazing => "footprint-grazing",
            },
            if self.drawn_inside {
                " (drawn inside)"
            } else {
                ""
            },
            self.wall.describe()
        )
    }

    /// The estimator's name.
    pub fn estimator(&self) -> &'static str {
        self.config.controller.estimator.name()
    }
}

/// How a follow case ended.
#[derive(Clone, Debug, PartialEq)]
pub enum FollowOutcome {
    /// The run started and ended with `status` (a name of [`STATUS_NAMES`]); `refusal` is
    /// the solver's refusal that ended it, if one did.
    Ran {
        /// The summary's status.
        status: String,
        /// The refusal returned by `next_step`, in words.
        refusal: Option<String>,
    },
    /// The run refused to start with a typed error (`kind`: `starts-in-wall`, `placement`,
    /// `sensors`, `calibration`).
    Refused {
        /// The error's kind.
        kind: String,
        /// Its message.
        message: String,
    },
    /// The contract is broken: a step not finite, a status outside [`STATUS_NAMES`], a run
    /// that went on after a refusal or past its steps, a start the independent check
    /// disagrees with, an invalid description from valid values.
    Violation {
        /// What broke.
        message: String,
    },
    /// The loop panicked.
    Panicked {
        /// The panic's message.
        message: String,
    },
    /// The case ran past its time limit and was killed.
    TimedOut {
        /// The limit, seconds.
        limit_s: f64,
        /// The last step it reported, if any.
        last_step: Option<usize>,
    },
    /// The case could not be built or run (a bug of the suite).
    Invalid {
        /// Why.
        message: String,
    },
}

impl FollowOutcome {
    /// Its row in the table: the status, the refusal's kind, or the failure.
    pub fn label(&self) -> String {
        match self {
            FollowOutcome::Ran { status, .. } => status.clone(),
            FollowOutcome::Refused { kind, .. } => format!("refused: {kind}"),
            FollowOutcome::Violation { .. } => "FAILED: contract".to_string(),
            FollowOutcome::Panicked { .. } => "FAILED: panic".to_string(),
            FollowOutcome::TimedOut { .. } => "FAILED: timed out".to_string(),
            FollowOutcome::Invalid { .. } => "FAILED: invalid case".to_string(),
        }
    }

    /// Whether the suite asserts against it.
    pub fn is_failure(&self) -> bool {
        !matches!(
            self,
            FollowOutcome::Ran { .. } | FollowOutcome::Refused { .. }
        )
    }

    /// In words.
    pub fn message(&self) -> String {
        match self {
            FollowOutcome::Ran { status, refusal } => match refusal {
                Some(r) => format!("{status}: {r}"),
                None => status.clone(),
            },
            FollowOutcome::Refused { kind, message } => format!("{kind}: {message}"),
            FollowOutcome::Violation { message }
            | FollowOutcome::Panicked { message }
            | FollowOutcome::Invalid { message } => message.clone(),
            FollowOutcome::TimedOut { limit_s, last_step } => format!(
                "still running after {limit_s:.1} s (last step reported: {}): killed",
                last_step.map_or("none".to_string(), |s| s.to_string())
            ),
        }
    }
}

/// A case's record.
#[derive(Clone, Debug, PartialEq)]
pub struct FollowRecord {
    /// The seed.
    pub seed: u64,
    /// The index.
    pub index: u64,
    /// The sample.
    pub sample: Sample,
    /// The estimator's name.
    pub estimator: String,
    /// The replay line.
    pub replay: String,
    /// How it ended.
    pub outcome: FollowOutcome,
    /// Steps reported.
    pub steps: usize,
    /// Steps planned.
    pub planned_steps: usize,
    /// Seconds it took.
    pub wall_clock_s: f64,
}

impl FollowRecord {
    /// The record of `case` before it is run.
    pub fn new(case: &FollowCase) -> FollowRecord {
        FollowRecord {
            seed: case.seed,
            index: case.index,
            sample: case.sample,
            estimator: case.estimator().to_string(),
            replay: case.replay_line(),
            outcome: FollowOutcome::Invalid {
                message: "not run".to_string(),
            },
            steps: 0,
            planned_steps: case.config.steps(),
            wall_clock_s: 0.0,
        }
    }

    fn invalid(seed: u64, index: u64, sample: Sample, message: String) -> FollowRecord {
        FollowRecord {
            seed,
            index,
            sample,
            estimator: "-".to_string(),
            replay: format!("ANTENNA_STRESS_REPLAY={}:{seed}:{index}", sample.name()),
            outcome: FollowOutcome::Invalid { message },
            steps: 0,
            planned_steps: 0,
            wall_clock_s: 0.0,
        }
    }

    /// The outcome in one line.
    pub fn outcome_line(&self) -> String {
        format!(
            "{}:{}:{}: {} after {}/{} steps ({:.2} s): {}",
            self.sample.name(),
            self.seed,
            self.index,
            self.outcome.label(),
            self.steps,
            self.planned_steps,
            self.wall_clock_s,
            self.outcome.message()
        )
    }

    /// The record as text between [`BEGIN`] and [`END`] (one field per line, escaped).
    pub fn to_wire(&self) -> String {
        let (kind, a, b) = match &self.outcome {
            FollowOutcome::Ran { status, refusal } => (
                "ran",
                status.clone(),
                refusal.clone().unwrap_or_else(|| "-".to_string()),
            ),
            FollowOutcome::Refused { kind, message } => ("refused", kind.clone(), message.clone()),
            FollowOutcome::Violation { message } => ("violation", message.clone(), String::new()),
            FollowOutcome::Panicked { message } => ("panicked", message.clone(), String::new()),
            FollowOutcome::TimedOut { limit_s, last_step } => (
                "timedout",
                format!("{limit_s:?}"),
                last_step.map_or("-".to_string(), |s| s.to_string()),
            ),
            FollowOutcome::Invalid { message } => ("invalid", message.clone(), String::new()),
        };
        let mut out = format!("{BEGIN}\n");
        for (key, values) in [
            ("seed", vec![self.seed.to_string()]),
            ("index", vec![self.index.to_string()]),
            ("sample", vec![self.sample.name().to_string()]),
            ("estimator", vec![self.estimator.clone()]),
            ("replay", vec![self.replay.clone()]),
            ("outcome", vec![kind.to_string(), a, b]),
            ("steps", vec![self.steps.to_string()]),
            ("planned_steps", vec![self.planned_steps.to_string()]),
            ("wall_clock_s", vec![format!("{:?}", self.wall_clock_s)]),
        ] {
            out += key;
            for v in values {
                let _ = write!(out, "\t{}", escape(&v));
            }
            out.push('\n');
        }
        out + END + "\n"
    }

    /// The first whole record in `text`.
    pub fn from_wire(text: &str) -> Option<FollowRecord> {
        let mut fields: BTreeMap<&str, Vec<String>> = BTreeMap::new();
        let mut inside = false;
        let mut complete = false;
        for line in text.lines() {
            if line.ends_with(BEGIN) {
                inside = true;
            } else if inside && line == END {
                complete = true;
                break;
            } else if inside {
                let mut parts = line.split('\t');
                let key = parts.next()?;
                fields.insert(key, parts.map(unescape).collect());
            }
        }
        if !complete {
            return None;
        }
        let one = |key: &str, i: usize| fields.get(key).and_then(|v| v.get(i)).cloned();
        let (a, b) = (one("outcome", 1)?, one("outcome", 2).unwrap_or_default());
        let outcome = match one("outcome", 0)?.as_str() {
            "ran" => FollowOutcome::Ran {
                status: a,
                refusal: (b != "-").then_some(b),
            },
            "refused" => FollowOutcome::Refused {
                kind: a,
                message: b,
            },
            "violation" => FollowOutcome::Violation { message: a },
            "panicked" => FollowOutcome::Panicked { message: a },
            "timedout" => FollowOutcome::TimedOut {
                limit_s: a.parse().ok()?,
                last_step: b.parse().ok(),
            },
            "invalid" => FollowOutcome::Invalid { message: a },
            _ => return None,
        };
        Some(FollowRecord {
            seed: one("seed", 0)?.parse().ok()?,
            index: one("index", 0)?.parse().ok()?,
            sample: Sample::parse(&one("sample", 0)?)?,
            estimator: one("estimator", 0)?,
            replay: one("replay", 0)?,
            outcome,
            steps: one("steps", 0)?.parse().ok()?,
            planned_steps: one("planned_steps", 0)?.parse().ok()?,
            wall_clock_s: one("wall_clock_s", 0)?.parse().ok()?,
        })
    }
}

/// What is not finite in a step, if anything.
pub fn non_finite(step: &FollowStep) -> Option<String> {
    let mut bad = Vec::new();
    let mut check = |name: &str, v: f64| {
        if !v.is_finite() {
            bad.push(format!("{name} = {v}"));
        }
    };
    check("t_s", step.t_s);
    check("pose_m.x", step.pose_m.x);
    check("pose_m.y", step.pose_m.y);
    check("heading_rad", step.heading_rad);
    check("omega_rad_per_s", step.omega_rad_per_s);
    check("command", step.command.value());
    check("antenna_moment_n_m", step.antenna_moment_n_m);
    if let Some(e) = &step.estimate {
        check("estimate.distance_m", e.distance_m);
    }
    for (j, t) in step.theta_rad.iter().enumerate() {
        check(&format!("theta_rad[{j}]"), *t);
    }
    (!bad.is_empty()).then(|| bad.join(", "))
}

/// The kind of a start error, as the table names it.
pub fn start_error_kind(e: &FollowError) -> &'static str {
    match e {
        FollowError::Invalid { .. } => "invalid",
        FollowError::StartsInWall { .. } => "starts-in-wall",
        FollowError::Placement(_) => "placement",
        FollowError::Sensors(_) => "sensors",
        FollowError::Calibration(_) => "calibration",
        FollowError::Contact { .. } => "contact",
    }
}

/// Runs `case` in this process: starts it, runs it to its end and checks the contract
/// (printing a progress line every 10 steps if `echo_progress`). Panics are the caller's
/// ([`run_follow_index`] catches them).
pub fn run_follow_case(case: &FollowCase, echo_progress: bool) -> FollowRecord {
    let started = Instant::now();
    let mut rec = FollowRecord::new(case);
    rec.outcome = drive(case, &mut rec.steps, echo_progress);
    rec.wall_clock_s = started.elapsed().as_secs_f64();
    rec
}

fn violation(message: String) -> FollowOutcome {
    FollowOutcome::Violation { message }
}

/// The start's contract: refused with [`FollowError::StartsInWall`] exactly where the
/// independent check says so; a broken one in words.
fn check_started(case: &FollowCase, started: &Result<Follow, FollowError>) -> Result<(), String> {
    let starts_in_wall = matches!(started, Err(FollowError::StartsInWall { .. }));
    match (case.start_check, starts_in_wall, started) {
        (StartCheck::Inside, false, _) => Err(format!(
            "the footprint starts inside the wall, yet the start gave {}",
            match started {
                Ok(_) => "no error".to_string(),
                Err(e) => format!("another error: {e}"),
            }
        )),
        (StartCheck::Clear, true, Err(e)) => Err(format!(
            "the footprint starts at least {CLEAR_MARGIN_M} m clear of the wall, yet the \
             start refused: {e}"
        )),
        (_, _, Err(e @ FollowError::Invalid { .. })) => {
            Err(format!("a valid description refused: {e}"))
        }
        _ => Ok(()),
    }
}

/// Runs `run` to its end, checking every step and the summary: the status's name and the
/// refusal that ended it, if one did; a broken contract in words. `steps` counts the steps.
fn run_to_end(
    run: &mut Follow,
    steps: &mut usize,
    echo_progress: bool,
) -> Result<(&'static str, Option<String>), String> {
    let planned = run.steps();
    let mut refusal = None;
    while let Some(step) = run.next_step() {
        match step {
            Ok(step) => {
                *steps += 1;
                if let Some(what) = non_finite(&step) {
                    return Err(format!("step {}: not finite: {what}", *steps - 1));
                }
                if *steps > planned {
                    return Err(format!("more steps than the {planned} planned"));
                }
                if echo_progress && steps.is_multiple_of(10) {
                    println!("{PROGRESS}{steps}");
                }
            }
            Err(e) => {
                let message = e.to_string();
                if let Some(next) = run.next_step() {
                    return Err(format!(
                        "after step {}'s refusal ({message}) the run went on ({})",
                        *steps,
                        match next {
                            Ok(_) => "a step".to_string(),
                            Err(e) => format!("another refusal: {e}"),
                        }
                    ));
                }
                refusal = Some(message);
                break;
            }
        }
    }
    let summary = run.summary();
    let status = summary.status.name();
    let Some(status) = STATUS_NAMES.iter().copied().find(|s| *s == status) else {
        return Err(format!("status {status:?} is not one of {STATUS_NAMES:?}"));
    };
    for (name, v) in [
        ("rms_error_m", summary.rms_error_m),
        ("max_error_m", summary.max_error_m),
        ("settling_distance_m", summary.settling_distance_m),
        ("first_collision_s", summary.first_collision_s),
        ("estimate_rms_error_m", summary.estimate_rms_error_m),
        ("contact_share", Some(summary.contact_share)),
        ("estimate_share", Some(summary.estimate_share)),
        ("travel_m", Some(summary.travel_m)),
    ] {
        if v.is_some_and(|v| !v.is_finite()) {
            return Err(format!("the summary's {name} is not finite: {v:?}"));
        }
    }
    // Lost and unstable runs end early by design (the robot is off the wall, or the loop
    // turned the body more than sim-core's MAX_TURN_PER_STEP_RAD in a step).
    let ended_early = refusal.is_some() || matches!(status, "lost" | "unstable");
    if !ended_early && *steps != planned {
        return Err(format!(
            "status {status} after {} of {planned} steps",
            *steps
        ));
    }
    if refusal.is_some() && matches!(status, "ok" | "lost" | "unstable") {
        return Err(format!(
            "a refusal ended the run, yet its status is {status}"
        ));
    }
    Ok((status, refusal))
}

/// Runs `case`: with the ideal preview, first the body alone (`Follow::without_antenna`,
/// the same contract), then the run with its antenna, whose outcome it is.
fn drive(case: &FollowCase, steps: &mut usize, echo_progress: bool) -> FollowOutcome {
    if let Estimator::IdealPreview { .. } = case.config.controller.estimator {
        let alone = Follow::without_antenna(case.scene.walls.clone(), &case.config);
        let checked = check_started(case, &alone).and_then(|()| match alone {
            Ok(mut run) => run_to_end(&mut run, &mut 0, false).map(|_| ()),
            Err(_) => Ok(()),
        });
        if let Err(message) = checked {
            return violation(format!("without the antenna: {message}"));
        }
    }
    let started = Follow::new(&case.scene, &case.sensors, &case.config);
    if let Err(message) = check_started(case, &started) {
        return violation(message);
    }
    let mut run = match started {
        Ok(run) => run,
        Err(e) => {
            return FollowOutcome::Refused {
                kind: start_error_kind(&e).to_string(),
                message: e.to_string(),
            };
        }
    };
    match run_to_end(&mut run, steps, echo_progress) {
        Ok((status, refusal)) => FollowOutcome::Ran {
            status: status.to_string(),
            refusal,
        },
        Err(message) => violation(message),
    }
}

/// Builds and runs case `index` in this process; a generator error or a panic becomes the
/// record's outcome.
pub fn run_follow_index(
    seed: u64,
    index: u64,
    sample: Sample,
    echo_progress: bool,
) -> FollowRecord {
    let case = match FollowCase::generate(seed, index, sample) {
        Ok(c) => c,
        Err(e) => return FollowRecord::invalid(seed, index, sample, e.to_string()),
    };
    match catch_unwind(AssertUnwindSafe(|| run_follow_case(&case, echo_progress))) {
        Ok(rec) => rec,
        Err(panic) => {
            let mut rec = FollowRecord::new(&case);
            rec.outcome = FollowOutcome::Panicked {
                message: super::outcome::panic_message(panic.as_ref()),
            };
            rec
        }
    }
}

/// The child's side: runs the case `spec` (`<sample>:<seed>:<index>`) and prints its record.
///
/// # Errors
/// [`StressError::Other`] for a malformed `spec`.
pub fn follow_child_main(spec: &str) -> Result<(), StressError> {
    let bad = || StressError::Other(format!("{spec}: expected <sample>:<seed>:<index>"));
    let mut parts = spec.trim().split(':');
    let sample = parts.next().and_then(Sample::parse).ok_or_else(bad)?;
    let seed = parts.next().and_then(|s| s.parse().ok()).ok_or_else(bad)?;
    let index = parts.next().and_then(|s| s.parse().ok()).ok_or_else(bad)?;
    let rec = run_follow_index(seed, index, sample, true);
    print!("\n{}", rec.to_wire());
    Ok(())
}

/// A case's time limit: `base_s + per_link_step_s * N * antenna solves`, at most `max_s`
/// ([`TimeLimit`]'s fields, a step being one solve of the antenna here).
pub fn follow_limit_s(limit: &TimeLimit, case: &FollowCase) -> f64 {
    (limit.base_s + limit.per_link_step_s * (case.links * case.antenna_solves()) as f64)
        .min(limit.max_s)
}

/// Runs case `index` in a child process, killed after its time limit.
pub fn run_follow_in_child(
    command: &ChildCommand,
    limit: &TimeLimit,
    seed: u64,
    index: u64,
    sample: Sample,
) -> FollowRecord {
    let case = match FollowCase::generate(seed, index, sample) {
        Ok(c) => c,
        Err(e) => return FollowRecord::invalid(seed, index, sample, e.to_string()),
    };
    let limit_s = follow_limit_s(limit, &case);
    let started = Instant::now();
    let mut rec = FollowRecord::new(&case);
    let spec = format!("{}:{seed}:{index}", sample.name());
    let child = match run_child(command, &spec, limit_s) {
        Ok(c) => c,
        Err(e) => {
            rec.outcome = FollowOutcome::Invalid {
                message: format!("could not start a child process: {e}"),
            };
            return rec;
        }
    };
    if !child.killed
        && let Some(r) = FollowRecord::from_wire(&child.stdout)
    {
        return r;
    }
    rec.wall_clock_s = started.elapsed().as_secs_f64();
    let last_step = last_progress(&child.stdout);
    rec.steps = last_step.unwrap_or(0);
    rec.outcome = if child.killed {
        FollowOutcome::TimedOut { limit_s, last_step }
    } else {
        FollowOutcome::Panicked {
            message: format!(
                "the child process ended ({}) without a record; its stderr ends: {}",
                child.status,
                stderr_tail(&child.stderr)
            ),
        }
    };
    rec
}

/// Runs cases `indices` on `threads` workers, each in a child process; the records in
/// index order.
pub fn run_follow_cases(
    seed: u64,
    indices: &[u64],
    sample: Sample,
    threads: usize,
    progress_every: usize,
    command: &ChildCommand,
    limit: &TimeLimit,
) -> Vec<FollowRecord> {
    on_workers(indices, threads, progress_every, "follow runs", |index| {
        run_follow_in_child(command, limit, seed, index, sample)
    })
}

/// The table of outcomes: a row per status, start refusal or failure, a column per
/// estimator, and the total.
pub fn follow_table(records: &[FollowRecord]) -> String {
    let estimators = ["contact-line", "bend", "ideal-preview"];
    let mut rows: BTreeMap<(usize, String), [usize; 4]> = BTreeMap::new();
    for r in records {
        let label = r.outcome.label();
        // Statuses in STATUS_NAMES order, then refusals, then failures.
        let order = STATUS_NAMES
            .iter()
            .position(|s| *s == label)
            .unwrap_or(if r.outcome.is_failure() { 200 } else { 100 });
        let row = rows.entry((order, label)).or_default();
        if let Some(k) = estimators.iter().position(|e| *e == r.estimator) {
            row[k] += 1;
        }
        row[3] += 1;
    }
    let mut out = String::from(
        "| outcome | contact-line | bend | ideal-preview | all | share |\n|---|---:|---:|---:|---:|---:|\n",
    );
    let total = records.len().max(1);
    for ((_, label), n) in &rows {
        let _ = writeln!(
            out,
            "| {label} | {} | {} | {} | {} | {:.0} % |",
            n[0],
            n[1],
            n[2],
            n[3],
            100.0 * n[3] as f64 / total as f64
        );
    }
    let mut column = [0usize; 4];
    for n in rows.values() {
        for k in 0..4 {
            column[k] += n[k];
        }
    }
    let _ = writeln!(
        out,
        "| **all** | {} | {} | {} | {} | 100 % |",
        column[0], column[1], column[2], column[3]
    );
    out
}

/// How many of `cases` have each wall kind, placement, wall side, body and estimator, a
/// rough wall, the point of rotation inside the wall, a sinusoid's whole cycle within the
/// travel: the axes a sample reaches, in words.
pub fn axes_reached(cases: &[FollowCase]) -> String {
    let mut kinds: BTreeMap<&str, usize> = BTreeMap::new();
    for c in cases {
        *kinds.entry(c.wall.kind.name()).or_default() += 1;
        *kinds.entry(c.placement.name()).or_default() += 1;
        *kinds.entry(c.config.robot.wall_side.name()).or_default() += 1;
        *kinds
            .entry(match c.config.robot.body {
                BodyModel::Template { .. } => "template",
                BodyModel::Wheeled { .. } => "wheeled",
            })
            .or_default() += 1;
        *kinds.entry(c.estimator()).or_default() += 1;
        if c.rough.is_some() {
            *kinds.entry("rough").or_default() += 1;
        }
        if c.drawn_inside {
            *kinds.entry("drawn inside").or_default() += 1;
        }
        if let Profile::Sinusoid {
            frequency_per_m, ..
        } = c.wall.profile
            && frequency_per_m * c.travel_m() >= 1.0
        {
            *kinds.entry("sinusoid cycles in reach").or_default() += 1;
        }
    }
    kinds
        .iter()
        .map(|(k, n)| format!("{k} {n}"))
        .collect::<Vec<_>>()
        .join(", ")
}
