//! Run time against error for quasi-static sweeps (issue 13, item 6): writes the "Sweeps: run
//! time against error" section of docs/benchmarks/sweeps.md (between `<!-- sweep-accuracy:begin -->` and
//! `<!-- sweep-accuracy:end -->`, appended when missing) and the plot
//! `docs/figures/sweep_time_vs_error.svg`.
//!
//! Three walls, each swept by the thesis's robot (9 links of 40 mm: 8 flexible joints, base angle
//! 30 deg, joint limits +-90 deg, fast-exponential stiffness 0.004..0.082 N m/rad) at
//! 16.7 mm/s from the tip placed on the wall above the base (a C, let go and settled):
//!
//! - the 4.2.1 line (through (0, 0.2) m, closing in at 8 deg, mu = 0.3), 50 s;
//! - the trapezoid of `examples/wall_polyline.toml` (mu = 0.3), 50 s, over the whole bump;
//! - the thesis 4.2.2 sinusoid (baseline y = 0.17 m, amplitude 10 mm, 14.2 cycles/m, mu = 0.3),
//!   [`SINE_DURATION_S`] (its steps cost a hundred times the line's).
//!
//! Each sweep is run with the time step (the base moves 16.7 mm/s x the step per step) from
//! [`STEPS_S`] at the default solver settings, and with the Newton tolerance
//! (`ContactSettings::tolerance_m`) from [`TOLERANCES_M`] at the default step (0.01 s). The
//! reference is the [`REFERENCE_STEP_S`] sweep at the default settings. Errors against it at
//! the reference's base positions that the run also visits (every step of the reference is a
//! whole number of the run's steps): the joint angles, the contact points (the symmetric
//! Hausdorff distance between the two sets of touching points, where both touch), whether the
//! same features touch, and the thesis's sweep metrics: the mean preview distance over the
//! steps with a contact, and the Pearson correlation of the point of bend with the base's
//! distance to the wall (as `antenna sweep` summarizes them, the placed posture included).
//!
//! Run time: the sweep's steps (the placement is not timed), the median of [`ROUNDS`] runs,
//! the configurations interleaved round by round (`std::time::Instant`, one thread). Run by
//! `scripts/bench-sweep` (release build); `-- --rounds N` sets the rounds.

mod bench_common;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use bench_common::{date, human, median, write_section};
use nalgebra::Vector2;
use plotters::prelude::*;
use sim_core::contact::{ContactSettings, Feature};
use sim_core::design::profile::{SEED_K_MAX_N_M_PER_RAD, SEED_K_MIN_N_M_PER_RAD, StiffnessProfile};
use sim_core::sweep::{Motion, Placement, Sweep, SweepScene, SweepStep};
use sim_core::{
    Chain, InitialGuess, JointLimit, Line, SolidSide, Surface, SurfaceMap, Wall,
    pearson_correlation,
};

type BoxResult<T> = Result<T, Box<dyn std::error::Error>>;

const BEGIN: &str = "<!-- sweep-accuracy:begin -->";
const END: &str = "<!-- sweep-accuracy:end -->";
const FIGURE: &str = "docs/figures/sweep_time_vs_error.svg";
/// Runs per configuration (the median time is reported).
const ROUNDS: usize = 5;
/// The reference's time step, seconds.
const REFERENCE_STEP_S: f64 = 0.001;
/// Time steps swept at the default settings, seconds (each a whole number of the
/// reference's).
const STEPS_S: [f64; 9] = [0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5];
/// A half step, for the reference's own error (the line and the trapezoid only).
const HALF_REFERENCE_STEP_S: f64 = 0.0005;
/// The default step (`Motion::default`), seconds.
const DEFAULT_STEP_S: f64 = 0.01;
/// Newton tolerances tried at the default step (the default, 1e-12, is in [`STEPS_S`]).
const TOLERANCES_M: [f64; 5] = [1e-10, 1e-9, 1e-8, 1e-7, 1e-6];
/// Base speed, m/s.
const SPEED_M_PER_S: f64 = 0.0167;
/// The sinusoid's sweep, seconds.
const SINE_DURATION_S: f64 = 20.0;
/// Errors below this are drawn at it on the log plot.
const PLOT_FLOOR: f64 = 1e-13;

/// One wall and how long it is swept.
struct SceneDef {
    name: &'static str,
    walls: Vec<Wall>,
    duration_s: f64,
    /// Whether the half-step run (the reference's own error) is affordable.
    half_step: bool,
}

/// What is varied.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Config {
    step_s: f64,
    tolerance_m: f64,
}

impl Config {
    fn is_default_tolerance(&self) -> bool {
        self.tolerance_m == ContactSettings::default().tolerance_m
    }
}

/// One recorded step.
struct Sample {
    t_s: f64,
    theta: Vec<f64>,
    features: Vec<Feature>,
    points: Vec<Vector2<f64>>,
    preview_m: Option<f64>,
    bend_joint: Option<usize>,
    wall_distance_m: Option<f64>,
}

/// One sweep of one configuration.
struct Run {
    config: Config,
    times_s: Vec<f64>,
    samples: Vec<Sample>,
    iterations: usize,
    substeps: usize,
    snaps: usize,
    relaxed_steps: usize,
    failure: Option<String>,
}

impl Run {
    fn time_s(&self) -> f64 {
        median(&self.times_s)
    }

    fn steps(&self) -> usize {
        self.samples.len().saturating_sub(1)
    }

    fn preview_mean_m(&self) -> Option<f64> {
        let p: Vec<f64> = self.samples.iter().filter_map(|s| s.preview_m).collect();
        (!p.is_empty()).then(|| p.iter().sum::<f64>() / p.len() as f64)
    }

    fn bend_correlation(&self) -> Option<f64> {
        let (d, j): (Vec<f64>, Vec<f64>) = self
            .samples
            .iter()
            .filter_map(|s| Some((s.wall_distance_m?, s.bend_joint? as f64)))
            .unzip();
        pearson_correlation(&d, &j)
    }
}

/// A run's errors against the reference.
#[derive(Clone, Copy, Debug, Default)]
struct Errors {
    compared: usize,
    theta_max_rad: f64,
    theta_rms_rad: f64,
    contact_max_m: f64,
    contact_rms_m: f64,
    features_differ: usize,
    preview_mean_m: Option<f64>,
    bend_correlation: Option<f64>,
}

fn antenna() -> BoxResult<Chain> {
    let n = 8;
    let lengths = vec![0.04; n + 1];
    let k = StiffnessProfile::FastExponential.stiffness_n_m_per_rad(
        &lengths,
        SEED_K_MIN_N_M_PER_RAD,
        SEED_K_MAX_N_M_PER_RAD,
    )?;
    Ok(Chain::builder(n)
        .link_length_m(0.04)
        .base_angle_rad(30f64.to_radians())
        .stiffnesses_nm_per_rad(k)
        .joint_limit(JointLimit::new((-90f64).to_radians(), 90f64.to_radians()))
        .build()?)
}

fn smooth() -> BoxResult<SurfaceMap> {
    Ok(SurfaceMap::uniform(Surface::Smooth { mu: 0.3 })?)
}

fn scene_defs() -> BoxResult<Vec<SceneDef>> {
    Ok(vec![
        SceneDef {
            name: "4.2.1 line",
            walls: vec![Wall::new(
                Line::new(
                    Vector2::new(0.0, 0.2),
                    (-8f64).to_radians(),
                    SolidSide::Left,
                )?,
                smooth()?,
            )],
            duration_s: 50.0,
            half_step: true,
        },
        SceneDef {
            name: "trapezoid",
            walls: vec![bench_common::trapezoid_4_2_2(0.3)?],
            duration_s: 50.0,
            half_step: true,
        },
        SceneDef {
            name: "sinusoid 14.2 1/m",
            walls: vec![bench_common::sinusoid_14_2(0.3)?],
            duration_s: SINE_DURATION_S,
            half_step: false,
        },
    ])
}

fn sweep_scene(chain: &Chain, def: &SceneDef, config: Config) -> SweepScene {
    let settings = ContactSettings {
        tolerance_m: config.tolerance_m,
        ..ContactSettings::default()
    };
    SweepScene {
        motion: Motion {
            velocity_m_per_s: Vector2::new(SPEED_M_PER_S, 0.0),
            duration_s: def.duration_s,
            step_s: config.step_s,
        },
        placement: Placement::TipOnWall {
            wall: 0,
            ahead_m: 0.0,
            start: InitialGuess::C,
        },
        settings,
        ..SweepScene::new(chain.clone(), def.walls.clone())
    }
}

fn sample(step: &SweepStep, walls: &[Wall]) -> Sample {
    Sample {
        t_s: step.t_s,
        theta: step.theta_rad.clone(),
        features: step.contacts.iter().map(|c| c.feature).collect(),
        points: step.contacts.iter().map(|c| c.point_m).collect(),
        preview_m: step.preview_m,
        bend_joint: step.bend_joint,
        wall_distance_m: walls
            .iter()
            .map(|w| w.signed_distance(&step.base_m).gap_m)
            .reduce(f64::min),
    }
}

/// Sweeps once; the steps are timed, the placement not.
fn sweep_once(chain: &Chain, def: &SceneDef, config: Config) -> BoxResult<Run> {
    let mut sweep = Sweep::new(sweep_scene(chain, def, config))?;
    let placed = sweep.placed().ok_or("no placed posture")?.clone();
    let mut steps = Vec::with_capacity(sweep.steps() + 1);
    steps.push(Ok(placed));
    let started = Instant::now();
    while let Some(step) = sweep.next_step() {
        let failed = step.is_err();
        steps.push(step);
        if failed {
            break;
        }
    }
    let time_s = started.elapsed().as_secs_f64();
    let mut run = Run {
        config,
        times_s: vec![time_s],
        samples: Vec::with_capacity(steps.len()),
        iterations: 0,
        substeps: 0,
        snaps: 0,
        relaxed_steps: 0,
        failure: None,
    };
    for step in steps {
        match step {
            Ok(step) => {
                if step.step > 0 {
                    run.iterations += step.report.iterations;
                    run.substeps += step.report.substeps;
                    run.snaps += usize::from(step.report.snapped);
                    run.relaxed_steps += usize::from(step.report.relaxed());
                }
                run.samples.push(sample(&step, &def.walls));
            }
            Err(e) => run.failure = Some(e.to_string()),
        }
    }
    Ok(run)
}

/// The symmetric Hausdorff distance between two non-empty point sets.
fn hausdorff(a: &[Vector2<f64>], b: &[Vector2<f64>]) -> f64 {
    let one_way = |a: &[Vector2<f64>], b: &[Vector2<f64>]| {
        a.iter()
            .map(|p| {
                b.iter()
                    .map(|q| (p - q).norm())
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0_f64, f64::max)
    };
    one_way(a, b).max(one_way(b, a))
}

fn sorted_features(f: &[Feature]) -> Vec<(usize, &'static str)> {
    let mut v: Vec<(usize, &'static str)> = f
        .iter()
        .map(|f| {
            (
                f.link(),
                match f {
                    Feature::Vertex { .. } => "vertex",
                    Feature::Link { .. } => "link",
                    Feature::HairTip { .. } => "hair",
                },
            )
        })
        .collect();
    v.sort_unstable();
    v
}

/// `run` against `reference` at the reference's samples that `run` also has.
fn compare(run: &Run, reference: &Run) -> BoxResult<Errors> {
    let ratio = run.config.step_s / reference.config.step_s;
    let every = ratio.round();
    if (ratio - every).abs() > 1e-9 || every < 1.0 {
        return Err(format!(
            "step {} is not a multiple of the reference's {}",
            run.config.step_s, reference.config.step_s
        )
        .into());
    }
    let every = every as usize;
    let mut e = Errors::default();
    let (mut theta_sq, mut theta_count) = (0.0, 0usize);
    let (mut contact_sq, mut contact_count) = (0.0, 0usize);
    for (k, s) in run.samples.iter().enumerate() {
        let Some(r) = reference.samples.get(k * every) else {
            break;
        };
        if (r.t_s - s.t_s).abs() > 1e-9 {
            return Err(format!("times differ: {} against {}", s.t_s, r.t_s).into());
        }
        e.compared += 1;
        for (a, b) in s.theta.iter().zip(&r.theta) {
            let d = (a - b).abs();
            e.theta_max_rad = e.theta_max_rad.max(d);
            theta_sq += d * d;
            theta_count += 1;
        }
        if sorted_features(&s.features) != sorted_features(&r.features) {
            e.features_differ += 1;
        }
        if !s.points.is_empty() && !r.points.is_empty() {
            let d = hausdorff(&s.points, &r.points);
            e.contact_max_m = e.contact_max_m.max(d);
            contact_sq += d * d;
            contact_count += 1;
        }
    }
    e.theta_rms_rad = (theta_sq / theta_count.max(1) as f64).sqrt();
    e.contact_rms_m = (contact_sq / contact_count.max(1) as f64).sqrt();
    e.preview_mean_m = run
        .preview_mean_m()
        .zip(reference.preview_mean_m())
        .map(|(a, b)| (a - b).abs());
    e.bend_correlation = run
        .bend_correlation()
        .zip(reference.bend_correlation())
        .map(|(a, b)| (a - b).abs());
    Ok(e)
}

/// Everything measured for one scene.
struct SceneResult {
    def: SceneDef,
    runs: Vec<Run>,
}

impl SceneResult {
    fn find(&self, config: Config) -> Option<&Run> {
        self.runs.iter().find(|r| r.config == config)
    }

    /// `run`'s errors against the reference; for the half step, the reference's own errors
    /// against it.
    fn errors(&self, run: &Run) -> BoxResult<Errors> {
        let reference = self.reference()?;
        if run.config.step_s < reference.config.step_s {
            compare(reference, run)
        } else {
            compare(run, reference)
        }
    }

    fn reference(&self) -> BoxResult<&Run> {
        self.find(Config {
            step_s: REFERENCE_STEP_S,
            tolerance_m: ContactSettings::default().tolerance_m,
        })
        .ok_or_else(|| "no reference run".into())
    }
}

fn configs(def: &SceneDef) -> Vec<Config> {
    let tol = ContactSettings::default().tolerance_m;
    let mut out = Vec::new();
    if def.half_step {
        out.push(Config {
            step_s: HALF_REFERENCE_STEP_S,
            tolerance_m: tol,
        });
    }
    out.extend(STEPS_S.iter().map(|&step_s| Config {
        step_s,
        tolerance_m: tol,
    }));
    out.extend(TOLERANCES_M.iter().map(|&tolerance_m| Config {
        step_s: DEFAULT_STEP_S,
        tolerance_m,
    }));
    out
}

fn measure(rounds: usize) -> BoxResult<Vec<SceneResult>> {
    let chain = antenna()?;
    let mut results: Vec<SceneResult> = scene_defs()?
        .into_iter()
        .map(|def| SceneResult {
            def,
            runs: Vec::new(),
        })
        .collect();
    for round in 0..rounds {
        for result in &mut results {
            let configs = configs(&result.def);
            // Interleaved: every configuration once per round, the order turned each round.
            for i in 0..configs.len() {
                let config = configs[(i + round) % configs.len()];
                let run = sweep_once(&chain, &result.def, config)?;
                eprintln!(
                    "round {round}, {}: step {} s, tolerance {:.0e} m: {:.3} s, {} steps{}",
                    result.def.name,
                    config.step_s,
                    config.tolerance_m,
                    run.times_s[0],
                    run.steps(),
                    run.failure
                        .as_deref()
                        .map_or(String::new(), |f| format!(" (failed: {f})"))
                );
                match result.runs.iter_mut().find(|r| r.config == config) {
                    Some(first) => first.times_s.push(run.times_s[0]),
                    None => result.runs.push(run),
                }
            }
        }
    }
    for result in &mut results {
        // The steps at the default tolerance, then the tolerances.
        result.runs.sort_by(|a, b| {
            (!a.config.is_default_tolerance())
                .cmp(&!b.config.is_default_tolerance())
                .then(a.config.step_s.total_cmp(&b.config.step_s))
                .then(a.config.tolerance_m.total_cmp(&b.config.tolerance_m))
        });
    }
    Ok(results)
}

fn sci(v: f64) -> String {
    if v == 0.0 {
        "0".to_owned()
    } else {
        format!("{v:.1e}")
    }
}

fn opt_sci(v: Option<f64>, scale: f64) -> String {
    v.map_or("-".to_owned(), |v| sci(v * scale))
}

/// Joint angles within this RMS of the reference count as the same sweep, radians (a
/// fifteenth of a count of the robot's 12-bit angle sensing, 2 pi / 4096 = 1.5e-3 rad).
const WITHIN_RMS_RAD: f64 = 1e-4;

/// The summary row of `result`: the steps and tolerances whose joint angles stay within
/// [`WITHIN_RMS_RAD`] (RMS) of the reference.
fn knee(md: &mut String, result: &SceneResult) -> BoxResult<()> {
    let default = result
        .find(Config {
            step_s: DEFAULT_STEP_S,
            tolerance_m: ContactSettings::default().tolerance_m,
        })
        .ok_or("no default run")?;
    let within = |run: &Run| -> BoxResult<bool> {
        Ok(run.failure.is_none() && result.errors(run)?.theta_rms_rad <= WITHIN_RMS_RAD)
    };
    // The largest step such that every step up to it is within (failed sweeps are left out:
    // they are said under the table).
    let mut largest: Option<&Run> = None;
    let mut fastest: Option<&Run> = None;
    for run in result.runs.iter().filter(|r| {
        r.config.is_default_tolerance() && r.config.step_s > REFERENCE_STEP_S && r.failure.is_none()
    }) {
        if !within(run)? {
            break;
        }
        largest = Some(run);
        if fastest.is_none_or(|f| run.time_s() < f.time_s()) {
            fastest = Some(run);
        }
    }
    let mut loosest: Option<&Run> = None;
    for run in result
        .runs
        .iter()
        .filter(|r| !r.config.is_default_tolerance() && r.config.step_s == DEFAULT_STEP_S)
    {
        if !within(run)? {
            break;
        }
        loosest = Some(run);
    }
    let step = |r: Option<&Run>| -> BoxResult<String> {
        Ok(match r {
            Some(r) => format!(
                "{} s ({:.2} mm): x{:.2}, max {}",
                r.config.step_s,
                r.config.step_s * SPEED_M_PER_S * 1e3,
                r.time_s() / default.time_s(),
                sci(result.errors(r)?.theta_max_rad)
            ),
            None => "-".to_owned(),
        })
    };
    let tighter = result
        .find(Config {
            step_s: DEFAULT_STEP_S,
            tolerance_m: 1e-10,
        })
        .ok_or("no 1e-10 run")?;
    let per_step = |r: &Run| r.iterations as f64 / r.steps().max(1) as f64;
    let moved = compare(tighter, default)?.theta_max_rad;
    writeln!(
        md,
        "| {} | {} | {} | {} / {} | {} | {:.2} -> {:.2} (x{:.2}), angles moved {} |",
        result.def.name,
        step(largest)?,
        step(fastest)?,
        sci(result.errors(default)?.theta_max_rad),
        sci(result.errors(default)?.theta_rms_rad),
        loosest.map_or("1e-12 (the default)".to_owned(), |r| format!(
            "{:.0e} m: x{:.2}",
            r.config.tolerance_m,
            r.time_s() / default.time_s()
        )),
        per_step(default),
        per_step(tighter),
        per_step(tighter) / per_step(default),
        sci(moved),
    )?;
    Ok(())
}

/// What the tables show and the defaults recommended (the errors and the Newton iterations
/// are deterministic; the times quoted are those of the run of 2026-11-27 with a failed solve's missed pairs
/// joining the step).
const READING: &str = "**Reading.** Between events the quasi-static path does not depend on \
the step: from 0.002 s to 0.02 s on the line, and at every step up to 0.5 s along the \
sinusoid, every compared posture is the reference's to within 2e-7 rad (the line's to the \
solver's tolerance, 3e-11 rad). What the step moves is where an event falls (a contact \
arriving or leaving, stick turning to slip, a snap, a jam at a corner), which shows in the \
maximum more than in the RMS: on the line from 0.05 s (0.84 mm of base travel per step) one \
event lands elsewhere (1e-2 rad at one step, RMS 5.5e-4 rad); across the trapezoid's corners \
the error grows with the step (4.2e-5 rad at 0.01 s, 6.6e-4 rad at 0.1 s; the reference \
against a half step 3.4e-6 rad), and at 0.5 s the sweep takes another branch at a corner (a \
contact point 79 mm away). The sinusoid's crests pass without a snap at every step (until a \
failed solve's missed pairs joined the step, the 0.001 s to 0.02 s sweeps each followed three \
snaps there, to the same postures). Newton iterations per step (deterministic, unlike the \
times) grow with the step: 1.45 at 0.01 s and 2.7 at 0.2 s on the line, 2.3, 8.1 and 29.5 at \
0.01, 0.05 and 0.2 s on the trapezoid, 2.2, 3.1 and 10.6 along the sinusoid, so the time \
stops falling from about 0.1 s on the line and \
0.2 s on the trapezoid. The knee, where the error leaves 1e-4 rad RMS or the time stops \
falling: 0.02 s on the line, about 0.2 s on the trapezoid and 0.5 s on the sinusoid.\n\n\
**Recommended defaults.** Keep `Motion::step_s` = 0.01 s: it is on the flat part of every \
error curve, below the line's knee (0.02 s) that one default must respect, at about twice \
that knee's time; and it is the thesis's 100 Hz recording rate, which the step also sets \
(every step is an output sample, and the summary metrics are averages over them). A study \
that needs only the summary metrics may take 0.02 s (half to two thirds of the time, the same joint \
angles to 5e-10 rad on the line and the sinusoid and to 1.1e-4 rad at the trapezoid's \
corners); above 0.05 s the line's events move. Keep `ContactSettings::tolerance_m` = 1e-12 \
m: 1e-10 m saves the last Newton iteration of some steps (x0.88 to x0.99 of the time) for \
joint angles that move by less than 1e-8 rad, and on the trapezoid it reports other touching \
features at 722 of 5,001 steps (contacts within the looser tolerance of the wall, with no \
force); as the default it left 2 of the stress soak's 2,000 sweeps (seed 4221: 1143 \
and 1351, both of 150 links) with a step the certification refuses (a loaded contact's gap \
of 1.1e-8 m and 3.4e-6 m, against 1e-8 m), where 1e-12 m leaves none; a study may pass \
1e-10 m. Looser is not worth it: at 1e-8 m the trapezoid's contact set differs at 1,458 of \
5,001 steps, and at 1e-6 m the trapezoid and the sinusoid take another branch at an event \
(0.18 rad and a contact point 70 mm away).";

/// One table row per run of `result`.
fn table(md: &mut String, result: &SceneResult) -> BoxResult<()> {
    let reference = result.reference()?;
    let default_time = result
        .find(Config {
            step_s: DEFAULT_STEP_S,
            tolerance_m: ContactSettings::default().tolerance_m,
        })
        .map_or(f64::NAN, Run::time_s);
    writeln!(
        md,
        "\n**{}**, {} s swept: reference {} steps of {} s, preview mean {}, bend correlation {}.\n",
        result.def.name,
        result.def.duration_s,
        reference.steps(),
        REFERENCE_STEP_S,
        reference
            .preview_mean_m()
            .map_or("-".to_owned(), |p| format!("{:.2} mm", p * 1e3)),
        reference
            .bend_correlation()
            .map_or("-".to_owned(), |c| format!("{c:.4}")),
    )?;
    writeln!(
        md,
        "| step (s) | base per step (mm) | Newton tolerance (m) | sweep time | x default | Newton iterations per step | substeps per step | snaps / relaxed steps | joint angles max / RMS (rad) | contact points max / RMS (mm) | steps with other features touching | preview mean (mm) | bend correlation |\n|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    )?;
    for run in &result.runs {
        let steps = run.steps().max(1) as f64;
        let is_reference = std::ptr::eq(run, reference);
        let errors = if is_reference {
            None
        } else {
            Some(result.errors(run)?)
        };
        let cell = |f: &dyn Fn(&Errors) -> String| {
            errors.as_ref().map_or_else(|| "(reference)".to_owned(), f)
        };
        let failed = if run.failure.is_some() {
            " (failed)"
        } else if run.config.step_s < REFERENCE_STEP_S {
            " (the reference against it)"
        } else {
            ""
        };
        writeln!(
            md,
            "| {}{} | {:.4} | {:.0e} | {} | {:.2} | {:.2} | {:.2} | {} / {} | {} | {} | {} | {} | {} |",
            run.config.step_s,
            failed,
            run.config.step_s * SPEED_M_PER_S * 1e3,
            run.config.tolerance_m,
            human(run.time_s()),
            run.time_s() / default_time,
            run.iterations as f64 / steps,
            run.substeps as f64 / steps,
            run.snaps,
            run.relaxed_steps,
            cell(&|e| format!("{} / {}", sci(e.theta_max_rad), sci(e.theta_rms_rad))),
            cell(&|e| format!(
                "{} / {}",
                sci(e.contact_max_m * 1e3),
                sci(e.contact_rms_m * 1e3)
            )),
            cell(&|e| format!("{} of {}", e.features_differ, e.compared)),
            cell(&|e| opt_sci(e.preview_mean_m, 1e3)),
            cell(&|e| opt_sci(e.bend_correlation, 1.0)),
        )?;
    }
    for run in &result.runs {
        if let Some(f) = &run.failure {
            writeln!(
                md,
                "\nThe {} s step with tolerance {:.0e} m failed: {f}.",
                run.config.step_s, run.config.tolerance_m
            )?;
        }
    }
    Ok(())
}

fn plot(results: &[SceneResult], path: &Path) -> BoxResult<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let root = SVGBackend::new(path, (1500, 900)).into_drawing_area();
    root.fill(&WHITE)?;
    let (title, body) = root.split_vertically(40);
    title.draw(&Text::new(
        "Quasi-static sweeps: error against the 0.001 s reference vs run time (step varied at the default tolerance; tolerance varied at 0.01 s)",
        (20, 12),
        ("sans-serif", 18).into_font(),
    ))?;
    let panels = body.split_evenly((2, results.len()));
    let step_color = RGBColor(31, 119, 180);
    let step_rms_color = RGBColor(120, 170, 220);
    let tol_color = RGBColor(214, 39, 40);
    for (col, result) in results.iter().enumerate() {
        let reference = result.reference()?;
        let mut rows = Vec::new();
        for run in &result.runs {
            if std::ptr::eq(run, reference) || run.config.step_s < REFERENCE_STEP_S {
                continue;
            }
            rows.push((run, compare(run, reference)?));
        }
        let times: Vec<f64> = rows.iter().map(|(r, _)| r.time_s()).collect();
        let t_lo = times.iter().copied().fold(f64::INFINITY, f64::min) / 2.0;
        let t_hi = reference.time_s() * 2.0;
        for (row, (label, unit, scale)) in [
            ("joint angles", "error (rad)", 1.0),
            ("contact points", "error (mm)", 1e3),
        ]
        .into_iter()
        .enumerate()
        {
            let panel = &panels[row * results.len() + col];
            let value = |e: &Errors, max: bool| {
                let v = match (row, max) {
                    (0, true) => e.theta_max_rad,
                    (0, false) => e.theta_rms_rad,
                    (_, true) => e.contact_max_m,
                    (_, false) => e.contact_rms_m,
                };
                (v * scale).max(PLOT_FLOOR)
            };
            let mut chart = ChartBuilder::on(panel)
                .caption(format!("{}: {label}", result.def.name), ("sans-serif", 16))
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(60)
                .build_cartesian_2d((t_lo..t_hi).log_scale(), (PLOT_FLOOR..1e3f64).log_scale())?;
            chart
                .configure_mesh()
                .x_desc("sweep run time (s)")
                .y_desc(unit)
                .x_label_formatter(&|v| format!("{v:.0e}"))
                .y_label_formatter(&|v| format!("{v:.0e}"))
                .label_style(("sans-serif", 12))
                .light_line_style(RGBColor(235, 235, 235))
                .draw()?;
            for (max, color, name) in [
                (true, step_color, "step, max"),
                (false, step_rms_color, "step, RMS"),
            ] {
                let series: Vec<(f64, f64, f64)> = rows
                    .iter()
                    .filter(|(r, _)| r.config.is_default_tolerance() && r.failure.is_none())
                    .map(|(r, e)| (r.time_s(), value(e, max), r.config.step_s))
                    .collect();
                chart
                    .draw_series(LineSeries::new(
                        series.iter().map(|&(x, y, _)| (x, y)),
                        color.stroke_width(2),
                    ))?
                    .label(name)
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                    });
                chart.draw_series(
                    series
                        .iter()
                        .map(|&(x, y, _)| Circle::new((x, y), 3, color.filled())),
                )?;
                if max {
                    chart.draw_series(series.iter().map(|&(x, y, s)| {
                        Text::new(format!("{s}"), (x, y), ("sans-serif", 11).into_font())
                    }))?;
                }
            }
            let series: Vec<(f64, f64, f64)> = rows
                .iter()
                .filter(|(r, _)| {
                    r.config.step_s == DEFAULT_STEP_S
                        && r.failure.is_none()
                        && (!r.config.is_default_tolerance())
                })
                .map(|(r, e)| (r.time_s(), value(e, true), r.config.tolerance_m))
                .collect();
            chart
                .draw_series(
                    series
                        .iter()
                        .map(|&(x, y, _)| TriangleMarker::new((x, y), 5, tol_color.filled())),
                )?
                .label("tolerance (0.01 s), max")
                .legend(move |(x, y)| TriangleMarker::new((x + 10, y), 5, tol_color.filled()));
            chart.draw_series(series.iter().map(|&(x, y, t)| {
                Text::new(
                    format!("{t:.0e}"),
                    (x, y),
                    ("sans-serif", 10).into_font().color(&tol_color),
                )
            }))?;
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::LowerLeft)
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK.mix(0.3))
                .label_font(("sans-serif", 11))
                .draw()?;
        }
    }
    root.present()?;
    Ok(())
}

fn main() -> BoxResult<()> {
    let mut rounds = ROUNDS;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--rounds" => {
                rounds = args
                    .next()
                    .ok_or("--rounds needs a number")?
                    .parse::<usize>()?
                    .max(1);
            }
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    let started = Instant::now();
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let workspace = manifest.parent().ok_or("no workspace dir")?.to_path_buf();
    let results = measure(rounds)?;
    plot(&results, &workspace.join(FIGURE))?;
    let mut md = String::new();
    writeln!(
        md,
        "{BEGIN}\n## Sweeps: run time against error (sim-core)\n"
    )?;
    writeln!(
        md,
        "Regenerate with `scripts/bench-sweep` (`cargo run -p sim-core --release --example \
         sweep_accuracy_bench`; {:.0} s on this machine). Measured {}.",
        started.elapsed().as_secs_f64(),
        date()
    )?;
    writeln!(
        md,
        "\n![error against the 0.001 s reference vs the sweep's run time, one column per \
         wall](../figures/sweep_time_vs_error.svg)\n\nMedian of {rounds} runs per \
         configuration, interleaved; one thread, release build, a 2-core AMD EPYC shared with \
         other builds (times are noisy: compare within a table). The errors are deterministic. \
         Joint angles: the largest and the RMS difference over all joints and the compared \
         steps; contact points: the symmetric Hausdorff distance between the touching points \
         of the run and of the reference, where both touch; \"steps with other features \
         touching\": steps at which the set of touching features (link vertices, points \
         along links) differs; preview mean and bend correlation: the absolute difference of \
         the sweep's summary values (each sweep's own steps, so a coarse step also samples \
         fewer positions). The 0.0005 s row compares the reference against a sweep of half \
         its step: the reference's own error. A failed sweep is compared up to its failure.\n"
    )?;
    writeln!(
        md,
        "Joint angles within {WITHIN_RMS_RAD:.0e} rad RMS of the reference (a fifteenth of a \
         count of the robot's 12-bit angle sensing), with the time of the sweep as a multiple \
         of the default step's (0.01 s, tolerance 1e-12 m) and the largest joint-angle error:\n\n\
         | wall | largest step within (every smaller one too) | fastest step within | \
         0.01 s: joint angles max / RMS (rad) | loosest Newton tolerance within, at 0.01 s | \
         Newton iterations per step at 0.01 s, tolerance 1e-12 m -> 1e-10 m (the largest \
         change of a joint angle) |\n\
         |---|---:|---:|---:|---:|---:|"
    )?;
    for result in &results {
        knee(&mut md, result)?;
    }
    writeln!(md, "\n{READING}")?;
    for result in &results {
        table(&mut md, result)?;
    }
    writeln!(md, "{END}")?;
    write_section(&workspace, BEGIN, END, &md)?;
    print!("{md}");
    Ok(())
}
