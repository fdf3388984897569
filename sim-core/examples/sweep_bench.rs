//! The cost of a quasi-static sweep (issue 5): writes the "Sweeps" section of BENCHMARKS.md
//! (between `<!-- sweep:begin -->` and `<!-- sweep:end -->`, appended when missing).
//!
//! 1. The seed's 4.2.1 sweep (9 links of 40 mm: 8 flexible joints, base angle 30 deg, joint
//!    limits +-90 deg, 0.004..0.082 N m/rad; a smooth wall at 8 deg, mu = 0.3; 16.7 mm/s for
//!    50 s at 100 Hz: 5000 steps; the tip placed on the wall above the base), for the
//!    fast-exponential and the constant profile: the whole sweep, per step, per contact.
//! 2. What a scene pays for: the same antenna with no wall, with a wall it never reaches, with
//!    hairs and no wall, with hairs and a wall it never reaches; and the 4.2.1 sweep
//!    frictionless (mu = 0) and with distal hairs.
//! 3. Curved and cornered walls (seed 4.2.2): the same motion along a sinusoid (1 cm, 14.2 1/m,
//!    baseline 0.17 m) and along the trapezoid of `examples/wall_polyline.toml`, where crests
//!    and corners press on links between their joints.
//!
//! Times are medians of repeated runs (`std::time::Instant`, one thread); the placement is
//! not timed. Run by `scripts/bench-sweep` (release build).

mod bench_common;

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use bench_common::{human, write_section};
use nalgebra::Vector2;
use sim_core::profile::{SEED_K_MAX_N_M_PER_RAD, SEED_K_MIN_N_M_PER_RAD, StiffnessProfile};
use sim_core::sweep::{Motion, Placement, Sweep, SweepScene};
use sim_core::{
    Chain, Hair, HairDirection, InitialGuess, JointLimit, Line, SolidSide, Surface, SurfaceMap,
    Wall,
};

type BoxResult<T> = Result<T, Box<dyn std::error::Error>>;

const BEGIN: &str = "<!-- sweep:begin -->";
const END: &str = "<!-- sweep:end -->";
/// Runs per scenario (the median is reported).
const REPEATS: usize = 5;

/// The seed's robot with `profile`, hairs on every flexible link if `hairs`.
fn antenna(profile: StiffnessProfile, hairs: bool) -> BoxResult<Chain> {
    let n = 8;
    let lengths = vec![0.04; n + 1];
    let k =
        profile.stiffness_n_m_per_rad(&lengths, SEED_K_MIN_N_M_PER_RAD, SEED_K_MAX_N_M_PER_RAD)?;
    let limit = JointLimit::new((-90f64).to_radians(), 90f64.to_radians());
    let mut builder = Chain::builder(n)
        .link_length_m(0.04)
        .base_angle_rad(30f64.to_radians())
        .stiffnesses_nm_per_rad(k)
        .joint_limit(limit);
    if hairs {
        for link in 1..=n {
            let hair = Hair {
                direction: HairDirection::Distal,
                ..Hair::seed(0.04)
            };
            builder = builder.hair(link, hair);
        }
    }
    Ok(builder.build()?)
}

/// The 4.2.1 wall (through (0, 0.2) m, closing in at 8 deg), smooth with `mu`, moved `away_m`
/// farther from the base.
fn wall(mu: f64, away_m: f64) -> BoxResult<Wall> {
    Ok(Wall::new(
        Line::new(
            Vector2::new(0.0, 0.2 + away_m),
            (-8f64).to_radians(),
            SolidSide::Left,
        )?,
        SurfaceMap::uniform(Surface::Smooth { mu })?,
    ))
}

struct Scenario {
    name: &'static str,
    scene: SweepScene,
}

struct Measured {
    name: &'static str,
    steps: usize,
    sweep_s: f64,
    contact_steps: usize,
    contacts: usize,
    iterations: usize,
    fixed_point_solves: usize,
    snaps: usize,
}

fn scenarios() -> BoxResult<Vec<Scenario>> {
    let motion = Motion::default();
    let on_wall = Placement::TipOnWall {
        wall: 0,
        ahead_m: 0.0,
        start: InitialGuess::C,
    };
    let scene = |chain: Chain, walls: Vec<Wall>, placement: Placement| SweepScene {
        motion,
        placement,
        ..SweepScene::new(chain, walls)
    };
    let fast = || antenna(StiffnessProfile::FastExponential, false);
    Ok(vec![
        Scenario {
            name: "4.2.1, fast-exponential",
            scene: scene(fast()?, vec![wall(0.3, 0.0)?], on_wall.clone()),
        },
        Scenario {
            name: "4.2.1, constant",
            scene: scene(
                antenna(StiffnessProfile::Constant, false)?,
                vec![wall(0.3, 0.0)?],
                on_wall.clone(),
            ),
        },
        Scenario {
            name: "4.2.1, fast-exponential, frictionless (mu = 0)",
            scene: scene(fast()?, vec![wall(0.0, 0.0)?], on_wall.clone()),
        },
        Scenario {
            name: "4.2.1, fast-exponential, distal hairs",
            scene: scene(
                antenna(StiffnessProfile::FastExponential, true)?,
                vec![wall(0.3, 0.0)?],
                on_wall.clone(),
            ),
        },
        Scenario {
            name: "4.2.2 sinusoid 14.2 1/m, fast-exponential",
            scene: scene(
                fast()?,
                vec![bench_common::sinusoid_14_2(0.3)?],
                on_wall.clone(),
            ),
        },
        Scenario {
            name: "4.2.2 trapezoid, fast-exponential",
            scene: scene(fast()?, vec![bench_common::trapezoid_4_2_2(0.3)?], on_wall),
        },
        Scenario {
            name: "no wall",
            scene: scene(fast()?, Vec::new(), Placement::Rest),
        },
        Scenario {
            name: "a wall never reached (1 m farther)",
            scene: scene(fast()?, vec![wall(0.3, 1.0)?], Placement::Rest),
        },
        Scenario {
            name: "hairs, no wall",
            scene: scene(
                antenna(StiffnessProfile::FastExponential, true)?,
                Vec::new(),
                Placement::Rest,
            ),
        },
        Scenario {
            name: "hairs, a wall never reached",
            scene: scene(
                antenna(StiffnessProfile::FastExponential, true)?,
                vec![wall(0.3, 1.0)?],
                Placement::Rest,
            ),
        },
    ])
}

fn measure(s: &Scenario) -> BoxResult<Measured> {
    let mut times = Vec::new();
    let mut out = None;
    for _ in 0..REPEATS {
        let mut sweep = Sweep::new(s.scene.clone())?;
        let mut m = Measured {
            name: s.name,
            steps: 0,
            sweep_s: 0.0,
            contact_steps: 0,
            contacts: 0,
            iterations: 0,
            fixed_point_solves: 0,
            snaps: 0,
        };
        let started = Instant::now();
        while let Some(step) = sweep.next_step() {
            let step = step.map_err(|e| format!("{}: {e}", s.name))?;
            m.steps += 1;
            m.contacts += step.contacts.len();
            m.contact_steps += usize::from(!step.contacts.is_empty());
            m.iterations += step.report.iterations;
            m.fixed_point_solves += step.report.fixed_point_solves;
            m.snaps += usize::from(step.report.snapped);
        }
        times.push(started.elapsed().as_secs_f64());
        out = Some(m);
    }
    times.sort_by(f64::total_cmp);
    let mut m = out.ok_or("no run")?;
    m.sweep_s = times[times.len() / 2];
    Ok(m)
}

fn main() -> BoxResult<()> {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let workspace = manifest.parent().ok_or("no workspace dir")?.to_path_buf();
    // `SWEEP_BENCH_ONLY=<part of a scene's name>`: measure those scenes only (for a
    // profiler), print them and leave BENCHMARKS.md alone.
    let only = std::env::var("SWEEP_BENCH_ONLY").ok();
    let mut rows = Vec::new();
    for s in scenarios()? {
        if only.as_deref().is_some_and(|o| !s.name.contains(o)) {
            continue;
        }
        let m = measure(&s)?;
        eprintln!(
            "{}: {} ({} steps, {} per Newton iteration)",
            m.name,
            human(m.sweep_s),
            m.steps,
            human(m.sweep_s / m.iterations.max(1) as f64)
        );
        rows.push(m);
    }
    if only.is_some() {
        return Ok(());
    }
    let mut md = String::new();
    writeln!(md, "{BEGIN}\n## Sweeps: quasi-static contact (sim-core)\n")?;
    writeln!(
        md,
        "Regenerate with `scripts/bench-sweep` (`cargo run -p sim-core --release --example \
         sweep_bench`). The seed's 4.2.1 sweep: 9 links of 40 mm (8 flexible joints), base \
         angle 30 deg, joint limits +-90 deg, stiffness 0.004..0.082 N m/rad, a smooth wall \
         at 8 deg with mu = 0.3, 16.7 mm/s for 50 s at 100 Hz (5000 steps), the tip placed \
         on the wall above the base (not timed). Median of {REPEATS} runs, one thread, \
         release build, 2-core AMD EPYC. \"Per contact\" divides the sweep's time by the \
         contacts summed over its steps.\n"
    )?;
    writeln!(
        md,
        "| scene | sweep (5000 steps) | per step | per contact | per Newton iteration | contacts per step | Newton iterations per step | Tresca fixed points | snaps |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|"
    )?;
    for m in &rows {
        let steps = m.steps.max(1) as f64;
        writeln!(
            md,
            "| {} | {} | {} | {} | {} | {:.2} | {:.2} | {} | {} |",
            m.name,
            human(m.sweep_s),
            human(m.sweep_s / steps),
            if m.contacts > 0 {
                human(m.sweep_s / m.contacts as f64)
            } else {
                "-".to_owned()
            },
            if m.iterations > 0 {
                human(m.sweep_s / m.iterations as f64)
            } else {
                "-".to_owned()
            },
            m.contacts as f64 / steps,
            m.iterations as f64 / steps,
            m.fixed_point_solves,
            m.snaps
        )?;
    }
    let get = |name: &str| rows.iter().find(|m| m.name == name);
    let ratio = |a: &str, b: &str| match (get(a), get(b)) {
        (Some(a), Some(b)) if b.sweep_s > 0.0 => format!("{:.1}", a.sweep_s / b.sweep_s),
        _ => "-".to_owned(),
    };
    let per_iteration = |name: &str| {
        get(name)
            .filter(|m| m.iterations > 0)
            .map_or("-".to_owned(), |m| human(m.sweep_s / m.iterations as f64))
    };
    const FRICTION: &str = "4.2.1, fast-exponential";
    const FRICTIONLESS: &str = "4.2.1, fast-exponential, frictionless (mu = 0)";
    writeln!(
        md,
        "\nA scene pays only for what it has. With no wall and no load the posture cannot \
         change as the base moves: a step is a translation and the sweep's bookkeeping, no \
         contact code runs (a wall that is never reached costs x{} that: every step looks \
         for candidate contacts and solves the free posture). Hairs without a wall cost \
         nothing (x{} the bare antenna); with a wall, a distance check per hair tip and step \
         (x{} for a wall never reached, x{} along the 4.2.1 wall, which the hairs do not \
         touch): hair angles become coordinates only for hair tips near a wall. A frictionless contact \
         carries no stick state and never enters the Tresca fixed point; its sweep is another \
         trajectory (the antenna slides where it stuck, with more Newton iterations per \
         step), so compare the cost per Newton iteration: {} frictionless against {} with \
         mu = 0.3.",
        ratio("a wall never reached (1 m farther)", "no wall"),
        ratio("hairs, no wall", "no wall"),
        ratio(
            "hairs, a wall never reached",
            "a wall never reached (1 m farther)"
        ),
        ratio("4.2.1, fast-exponential, distal hairs", FRICTION),
        per_iteration(FRICTIONLESS),
        per_iteration(FRICTION),
    )?;
    const SINE: &str = "4.2.2 sinusoid 14.2 1/m, fast-exponential";
    const TRAPEZOID: &str = "4.2.2 trapezoid, fast-exponential";
    writeln!(
        md,
        "\nCurved and cornered walls: a crest or a corner pressing on a link between its \
         joints makes that contact's point slide along the link and its normal turn as the \
         posture changes; those second-order terms of the step's Jacobian are closed forms \
         (the point's slide by the envelope theorem, the wall's curvature; central \
         differences only in the tests). A Newton iteration costs {} along the sinusoid \
         and {} along the trapezoid, against {} along the line; a sweep x{} and x{} the \
         line's. Along the sinusoid each evaluation of the contacts finds the wall's nearest \
         points on the curve (a scan and Newton's method on sin and cos) where the line and \
         the polyline have them in closed form; what that costs per step is issue #14's.",
        per_iteration(SINE),
        per_iteration(TRAPEZOID),
        per_iteration(FRICTION),
        ratio(SINE, FRICTION),
        ratio(TRAPEZOID, FRICTION),
    )?;
    writeln!(md, "{END}")?;
    write_section(&workspace, BEGIN, END, &md)?;
    print!("{md}");
    Ok(())
}
