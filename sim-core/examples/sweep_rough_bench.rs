//! Rough and finely sampled walls (issue #49): writes the "Sweeps: rough and sampled walls"
//! section of docs/benchmarks/sweeps.md (between `<!-- sweep-rough:begin -->` and
//! `<!-- sweep-rough:end -->`, appended when missing).
//!
//! The thesis's 4.2.2 antenna and motion (`examples/wall_polyline.toml`: 9 links of 40 mm,
//! fast-exponential 0.004..0.082 N m/rad, 16.7 mm/s for 50 s at 100 Hz, the tip placed on
//! the wall above the base) along:
//! - the trapezoid's 6 vertices (`examples/wall_polyline.toml`), the reference;
//! - the trapezoid digitized at 10,000 points with 0.1 mm of noise
//!   (`examples/wall_digitized.toml`, `examples/walls/trapezoid_10k.csv`);
//! - the trapezoid sampled with no noise at 2,000 and at 1,999 points an edge
//!   (`examples/wall_sampled_2000.toml`, `examples/wall_sampled_1999.toml`);
//! - and, for the time per Newton iteration, the 4.2.1 line for 10 s.
//!
//! Each whole sweep is timed (the placement not), the scenes interleaved round by round
//! (`--rounds R`, default 3); ratios are taken within a round and their median reported with
//! the Newton iterations beside them, and each sampled sweep is compared with the 6-vertex
//! one step for step (the largest difference of a joint angle). `--skip-digitized` leaves
//! the noisy wall out (it takes minutes a round). Run by `scripts/bench-sweep` (release).

mod bench_common;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use bench_common::{human, median, write_section};
use nalgebra::Vector2;
use sim_core::sweep::{Motion, Placement, Sweep, SweepScene};
use sim_core::{Chain, InitialGuess, Line, Polyline, SolidSide, Surface, SurfaceMap, Wall};

type BoxResult<T> = Result<T, Box<dyn std::error::Error>>;

const BEGIN: &str = "<!-- sweep-rough:begin -->";
const END: &str = "<!-- sweep-rough:end -->";

const TRAPEZOID: &str = "trapezoid, 6 vertices";
const DIGITIZED: &str = "trapezoid digitized, 10,000 points, 0.1 mm noise";
const SAMPLED_2000: &str = "trapezoid sampled, 2,000 points an edge, no noise";
const SAMPLED_1999: &str = "trapezoid sampled, 1,999 points an edge, no noise";
const LINE: &str = "4.2.1 line, 10 s";

/// The thesis's antenna (9 links of 40 mm, fast-exponential).
fn antenna() -> BoxResult<Chain> {
    bench_common::scaled_antenna(9)
}

/// A polyline wall from a points file of `examples/walls/` (read here: the scene reader
/// lives in antenna-cli, above sim-core), smooth, mu = 0.3, solid on the left.
fn points_wall(workspace: &Path, file: &str) -> BoxResult<Wall> {
    let path = workspace.join("examples/walls").join(file);
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut vertices = Vec::new();
    for line in text.lines().skip(1).filter(|l| !l.trim().is_empty()) {
        let (x, y) = line.split_once(',').ok_or("a line without a comma")?;
        vertices.push(Vector2::new(x.trim().parse()?, y.trim().parse()?));
    }
    Ok(Wall::new(
        Polyline::new(vertices, SolidSide::Left)?,
        SurfaceMap::uniform(Surface::Smooth { mu: 0.3 })?,
    ))
}

struct Scenario {
    name: &'static str,
    scene: SweepScene,
}

#[derive(Clone, Default)]
struct Measured {
    sweep_s: f64,
    steps: usize,
    iterations: usize,
    snaps: usize,
    theta_rad: Vec<Vec<f64>>,
}

fn run_once(s: &Scenario) -> BoxResult<Measured> {
    let mut sweep = Sweep::new(s.scene.clone())?;
    let mut m = Measured::default();
    let started = Instant::now();
    while let Some(step) = sweep.next_step() {
        let step = step.map_err(|e| format!("{}: {e}", s.name))?;
        m.steps += 1;
        m.iterations += step.report.iterations;
        m.snaps += usize::from(step.report.snapped);
        m.theta_rad.push(step.theta_rad);
    }
    m.sweep_s = started.elapsed().as_secs_f64();
    Ok(m)
}

/// The largest difference of a joint angle between two sweeps, step for step (infinite if
/// they have different numbers of steps).
fn max_angle_difference_rad(a: &Measured, b: &Measured) -> f64 {
    if a.theta_rad.len() != b.theta_rad.len() {
        return f64::INFINITY;
    }
    a.theta_rad
        .iter()
        .zip(&b.theta_rad)
        .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).abs()))
        .fold(0.0, f64::max)
}

fn main() -> BoxResult<()> {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let workspace = manifest.join("..");
    let mut rounds = 3usize;
    let mut skip_digitized = false;
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--rounds" => rounds = args.next().ok_or("--rounds needs a number")?.parse()?,
            "--skip-digitized" => skip_digitized = true,
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    let placement = Placement::TipOnWall {
        wall: 0,
        ahead_m: 0.0,
        start: InitialGuess::C,
    };
    let scene = |wall: Wall, duration_s: f64| -> BoxResult<SweepScene> {
        Ok(SweepScene {
            motion: Motion {
                duration_s,
                ..Motion::default()
            },
            placement: placement.clone(),
            ..SweepScene::new(antenna()?, vec![wall])
        })
    };
    let line = Wall::new(
        Line::new(
            Vector2::new(0.0, 0.2),
            (-8f64).to_radians(),
            SolidSide::Left,
        )?,
        SurfaceMap::uniform(Surface::Smooth { mu: 0.3 })?,
    );
    let mut scenarios = vec![
        Scenario {
            name: TRAPEZOID,
            scene: scene(bench_common::trapezoid_4_2_2(0.3)?, 50.0)?,
        },
        Scenario {
            name: SAMPLED_2000,
            scene: scene(
                points_wall(&workspace, "trapezoid_2000_per_edge.csv")?,
                50.0,
            )?,
        },
        Scenario {
            name: SAMPLED_1999,
            scene: scene(
                points_wall(&workspace, "trapezoid_1999_per_edge.csv")?,
                50.0,
            )?,
        },
        Scenario {
            name: LINE,
            scene: scene(line, 10.0)?,
        },
    ];
    if !skip_digitized {
        scenarios.push(Scenario {
            name: DIGITIZED,
            scene: scene(points_wall(&workspace, "trapezoid_10k.csv")?, 50.0)?,
        });
    }
    let mut runs: Vec<Vec<Measured>> = scenarios.iter().map(|_| Vec::new()).collect();
    for round in 0..rounds {
        for (s, out) in scenarios.iter().zip(&mut runs) {
            let m = run_once(s)?;
            eprintln!(
                "round {}: {}: {} ({} steps, {} Newton iterations, {} per step)",
                round + 1,
                s.name,
                human(m.sweep_s),
                m.steps,
                m.iterations,
                human(m.sweep_s / m.steps.max(1) as f64)
            );
            out.push(m);
        }
    }
    let index = |name: &str| scenarios.iter().position(|s| s.name == name);
    let trapezoid = index(TRAPEZOID).ok_or("no trapezoid")?;
    let line = index(LINE).ok_or("no line")?;
    // Per round: a / b of the whole sweeps, per step, per Newton iteration.
    let ratio = |a: usize, b: usize, per: fn(&Measured) -> f64| -> Vec<f64> {
        (0..rounds)
            .map(|r| per(&runs[a][r]) / per(&runs[b][r]))
            .collect()
    };
    let whole = |m: &Measured| m.sweep_s;
    let per_step = |m: &Measured| m.sweep_s / m.steps.max(1) as f64;
    let per_iteration = |m: &Measured| m.sweep_s / m.iterations.max(1) as f64;
    let spread = |v: &[f64]| {
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(0.0, f64::max);
        format!("{:.2} [{lo:.2}..{hi:.2}]", median(v))
    };
    let mut out = String::new();
    writeln!(out, "{BEGIN}")?;
    writeln!(out, "## Sweeps: rough and sampled walls")?;
    writeln!(out)?;
    writeln!(
        out,
        "Regenerate with `scripts/bench-sweep` (`cargo run -p sim-core --release --example \
         sweep_rough_bench`; measured {}). Issue #49's goals: the thesis's 4.2.2 antenna and \
         motion (`examples/wall_polyline.toml`: 16.7 mm/s for 50 s, 5,000 steps) along the \
         trapezoid's 6 vertices, the same trapezoid digitized at 10,000 points with 0.1 mm of \
         noise (`examples/wall_digitized.toml`) and sampled with no noise at 2,000 and 1,999 \
         points an edge (`examples/wall_sampled_2000.toml`, `examples/wall_sampled_1999.toml`), \
         and the 4.2.1 line for 10 s (the time per Newton iteration's reference). Whole sweeps \
         (the placement not timed), {rounds} rounds, the scenes interleaved; ratios within a \
         round, their median [min..max]. One thread, release build, a 2-core machine shared \
         with other builds.",
        bench_common::date()
    )?;
    writeln!(out)?;
    writeln!(
        out,
        "| scene | whole sweep (median) | per step | steps | Newton iterations | snaps |"
    )?;
    writeln!(out, "|---|---:|---:|---:|---:|---:|")?;
    for (s, r) in scenarios.iter().zip(&runs) {
        let times: Vec<f64> = r.iter().map(|m| m.sweep_s).collect();
        let t = median(&times);
        let m = &r[0];
        writeln!(
            out,
            "| {} | {} | {} | {} | {} | {} |",
            s.name,
            human(t),
            human(t / m.steps.max(1) as f64),
            m.steps,
            m.iterations,
            m.snaps
        )?;
    }
    writeln!(out)?;
    writeln!(out, "| goal | latest | met |")?;
    writeln!(out, "|---|---|:---:|")?;
    for name in [SAMPLED_2000, SAMPLED_1999] {
        let Some(i) = index(name) else { continue };
        let per = ratio(i, trapezoid, per_step);
        let diff = max_angle_difference_rad(&runs[i][0], &runs[trapezoid][0]);
        let met = median(&per) <= 2.0 && diff <= 1e-9;
        writeln!(
            out,
            "| {name}: time per step / the 6-vertex trapezoid's <= 2, and the sweep the same \
             step for step (joint angles within 1e-9 rad) | {} ({} against {} Newton \
             iterations); largest joint-angle difference {diff:.1e} rad | {} |",
            spread(&per),
            runs[i][0].iterations,
            runs[trapezoid][0].iterations,
            if met { "yes" } else { "no" }
        )?;
    }
    if let Some(d) = index(DIGITIZED) {
        let w = ratio(d, trapezoid, whole);
        writeln!(
            out,
            "| {DIGITIZED}: the whole 50 s sweep / the 6-vertex trapezoid's <= 150 | {} ({} \
             against {} Newton iterations) | {} |",
            spread(&w),
            runs[d][0].iterations,
            runs[trapezoid][0].iterations,
            if median(&w) <= 150.0 { "yes" } else { "no" }
        )?;
        let it = ratio(d, line, per_iteration);
        writeln!(
            out,
            "| {DIGITIZED}: time per Newton iteration / the line's <= 10 | {} | {} |",
            spread(&it),
            if median(&it) <= 10.0 { "yes" } else { "no" }
        )?;
    }
    writeln!(out)?;
    writeln!(out, "{END}")?;
    print!("{out}");
    if std::env::var_os("SWEEP_ROUGH_NO_WRITE").is_none() {
        write_section(&workspace, BEGIN, END, &out)?;
    }
    Ok(())
}
