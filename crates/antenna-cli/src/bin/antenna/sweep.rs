//! `antenna sweep SCENE`: the scene's sweep, summarized, as JSON lines, and drawn.

use std::io::Write as _;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use antenna_cli::progress;
use antenna_cli::sweep::SweepRun;
use antenna_cli::sweep::plot::SweepPlot;
use antenna_cli::sweep::record::{PlacementRecord, StepRecord, SweepLine};
use antenna_scene::Scene;
use antenna_scene::SweepFailure;
use antenna_scene::motion::MAX_SWEEP_STEPS;
use anyhow::{Context as _, anyhow};
use clap::Args;

use crate::{Failure, bail_input, check_plot_file};

/// How often the JSON lines are flushed while a sweep runs.
const FLUSH_EVERY: Duration = Duration::from_millis(200);

/// Sweep a scene's base along its walls and report what the antenna did.
///
/// The antenna is placed as `[start]` says (step 0), then the base moves as `[sweep]` says, one
/// quasi-static step at a time with friction, hairs and snaps (sim-core's contact solver).
/// The summary reports steps, time, contacts, snaps, flips, the preview distance, the
/// correlations of the points of bend and of contact with the base-to-wall distance, and
/// the error of the wall map the robot would make from its sensed angles and touch bits.
///
/// Every step is certified by an independent check of its equilibrium (torques, stops,
/// non-penetration, Coulomb's law); what the solver relaxed to get through a step is in the
/// step's `relaxations` and counted in the summary.
///
/// Exit status: 0 swept; 1 a step found no equilibrium, or the antenna jammed against a wall
/// (a physical outcome: the message names the contacts that pin it and the joints on their
/// stops); the lines (the summary line too, with `outcome` and `stopped_by`) and the plot of
/// the steps before it are still written; 2 bad input (what and where, nothing on stdout); 3
/// numerical breakdown (a step that failed its independent check).
#[derive(Debug, Args)]
#[command(after_help = "Examples:
  antenna sweep examples/sweep_line_wall.toml
  antenna sweep examples/sweep_line_wall.toml --jsonl > steps.jsonl
  antenna sweep examples/hairs_distal.toml --plot hairs.svg
  antenna sweep examples/wall_sinusoid.toml --duration-s 5 --plot sinusoid.png --plot-every 50")]
pub(crate) struct SweepArgs {
    /// The scene file (TOML, with `[[walls]]`, `[sweep]` and `[start]`; see docs/scene-format.md).
    scene: PathBuf,
    /// Print one JSON object per line on stdout: a "placement" line, one "step" line per
    /// step (step 0 the placed posture), a "summary" line.
    #[arg(long)]
    jsonl: bool,
    /// Draw chain snapshots over the walls and the metrics over time to this file (.svg or
    /// .png).
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
    /// Steps between the chain snapshots of the plot (default: about 24 snapshots).
    #[arg(long, value_name = "K", requires = "plot", value_parser = clap::value_parser!(u64).range(1..))]
    plot_every: Option<u64>,
    /// Sweep this long instead of the scene's `[sweep]` duration_s, seconds.
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    duration_s: Option<f64>,
}

pub(crate) fn run(args: &SweepArgs) -> Result<(), Failure> {
    let mut scene = Scene::from_path(&args.scene).map_err(anyhow::Error::new)?;
    if let Some(d) = args.duration_s {
        let steps = d / scene.motion.step_s;
        if !(d.is_finite() && d >= 0.0) || steps.round() > MAX_SWEEP_STEPS as f64 {
            return bail_input(format!(
                "--duration-s {d}: must be finite, >= 0 and at most {MAX_SWEEP_STEPS} steps of \
                 {} s",
                scene.motion.step_s
            ));
        }
        scene.motion.duration_s = d;
    }
    check_plot_file(args.plot.as_deref())?;
    let label = args.scene.display().to_string();
    let mut run = SweepRun::start(&scene)?;
    let steps = run.steps();
    let mut plot = args.plot.as_ref().map(|_| {
        let every = args.plot_every.and_then(|k| usize::try_from(k).ok());
        SweepPlot::new(steps, scene.n(), every)
    });
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    let write_error = |e: std::io::Error| Failure::BadInput(anyhow!("writing to stdout: {e}"));
    if args.jsonl {
        let header = SweepLine::Placement(PlacementRecord::new(
            &label,
            run.placement_note(),
            scene.n() + 1,
            scene.walls.len(),
            &scene.motion,
        ));
        writeln!(out, "{}", json(&header)?).map_err(write_error)?;
    } else {
        writeln!(
            out,
            "{label}: {} links ({} flexible joints), {} wall(s), {steps} steps of {} s at \
             [{}, {}] m/s",
            scene.n() + 1,
            scene.n(),
            scene.walls.len(),
            scene.motion.step_s,
            scene.motion.velocity_m_per_s.x,
            scene.motion.velocity_m_per_s.y
        )
        .map_err(write_error)?;
        writeln!(out, "placement: {}", run.placement_note()).map_err(write_error)?;
    }
    out.flush().map_err(write_error)?;
    let progress = progress::bar(steps, "steps", true);
    let mut failure: Option<SweepFailure> = None;
    // JSON lines reach a reader (a pipe, `tail -f`) at least every FLUSH_EVERY.
    let mut flushed = Instant::now();
    while let Some(state) = run.next_state() {
        match state {
            Ok(state) => {
                if args.jsonl {
                    let line = SweepLine::Step(StepRecord::new(&state.step, &state.metrics));
                    writeln!(out, "{}", json(&line)?).map_err(write_error)?;
                    if flushed.elapsed() >= FLUSH_EVERY {
                        out.flush().map_err(write_error)?;
                        flushed = Instant::now();
                    }
                }
                if let Some(plot) = &mut plot {
                    plot.push(&state);
                }
                progress.set_position(state.step.step as u64);
            }
            Err(e) => {
                failure = Some(e);
                break;
            }
        }
    }
    progress.finish_and_clear();
    let summary = run.summary();
    if args.jsonl {
        // Also after a step that failed or jammed: the summary of the steps done, with its
        // `outcome` and `stopped_by`.
        writeln!(out, "{}", json(&SweepLine::Summary(summary.clone()))?).map_err(write_error)?;
    } else if failure.is_none() {
        write!(out, "{}", summary.human()).map_err(write_error)?;
    } else {
        writeln!(
            out,
            "stopped after {} of {steps} steps; the summary of those:",
            summary.steps
        )
        .map_err(write_error)?;
        write!(out, "{}", summary.human()).map_err(write_error)?;
    }
    out.flush().map_err(write_error)?;
    if let (Some(plot), Some(path)) = (&plot, &args.plot) {
        let title = format!(
            "{} ({} steps, {} s)",
            args.scene
                .file_name()
                .map_or_else(|| label.clone(), |f| f.to_string_lossy().into_owned()),
            summary.steps,
            summary.sweep_time_s
        );
        plot.write(path, run.walls(), &title)
            .map_err(|e| Failure::BadInput(anyhow::Error::new(e)))?;
        if !args.jsonl {
            println!("plot: {}", path.display());
        }
    }
    match failure {
        None => Ok(()),
        Some(e) => Err(e.into()),
    }
}

fn json(line: &SweepLine) -> Result<String, Failure> {
    serde_json::to_string(line)
        .context("writing a JSON line")
        .map_err(Failure::Breakdown)
}
