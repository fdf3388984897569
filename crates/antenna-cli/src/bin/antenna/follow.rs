//! `antenna follow SCENE`: a robot following the scene's walls with the antenna as its only
//! sensor, summarized, as JSON lines, and drawn.

use std::io::Write as _;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use antenna_cli::follow::plot::FollowPlot;
use antenna_cli::follow::{FollowFailure, FollowRun, human};
use antenna_cli::progress;
use antenna_scene::Scene;
use antenna_scene::follow_lines::FollowLine;
use antenna_scene::follow_lines::step_line;
use anyhow::{Context as _, anyhow};
use clap::Args;

use crate::{Failure, bail_input, check_plot_file};

/// How often the JSON lines are flushed while a run goes.
const FLUSH_EVERY: Duration = Duration::from_millis(200);

/// Run a robot along a follow scene's walls, closed loop, the antenna its only sensor.
///
/// The robot (`[robot]`) runs at a constant speed; at every step (`[follow] step_s`) the
/// controller (`[controller]`) estimates the wall's distance from what the antenna's sensors
/// report (`[sensors]`: joint angles and touch bits), and turns the body by PD control on that
/// estimate; the body is integrated by RK4 and the antenna, mounted on it, is solved
/// quasi-statically along the way (sim-core's contact solver: friction, hairs, every wall
/// shape). The summary judges the run against the truth: the error of the true distance to
/// the wall against the setpoint, collisions of the body's footprint with a wall, the
/// estimate's error. See docs/follow.md.
///
/// Exit status: 0 the run went to its end (its status may be "collided" or "lost": the
/// summary says); 1 the antenna's solver found no equilibrium or the antenna jammed (the
/// lines and the summary so far are still written); 2 bad input (what and where, nothing on
/// stdout); 3 a step failed its independent check.
#[derive(Debug, Args)]
#[command(after_help = "Examples:
  antenna follow examples/follow/straight_wall.toml
  antenna follow examples/follow/straight_wall.toml --json
  antenna follow examples/follow/straight_wall.toml --jsonl > run.jsonl
  antenna follow examples/follow/straight_wall.toml --plot run.svg")]
pub(crate) struct FollowArgs {
    /// The follow scene (TOML, with `[robot]`, `[controller]`, `[follow]`; see
    /// docs/scene-format.md).
    scene: PathBuf,
    /// Print the summary as one JSON object.
    #[arg(long, conflicts_with = "jsonl")]
    json: bool,
    /// Print one JSON object per line: a "start" line, a "step" line per step, a "summary"
    /// line (docs/follow.md).
    #[arg(long)]
    jsonl: bool,
    /// Draw the run from above and the error against time to this file (.svg or .png).
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
    /// Steps between the snapshots of the plot (default: about 30 snapshots).
    #[arg(long, value_name = "K", requires = "plot", value_parser = clap::value_parser!(u64).range(1..))]
    plot_every: Option<u64>,
    /// Run this long instead of `[follow] duration_s`, seconds.
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    duration_s: Option<f64>,
    /// Run at this speed instead of `[robot] speed_m_per_s`, m/s.
    #[arg(long, value_name = "V", allow_negative_numbers = true)]
    speed_m_per_s: Option<f64>,
}

pub(crate) fn run(args: &FollowArgs) -> Result<(), Failure> {
    let mut scene = Scene::from_path(&args.scene).map_err(anyhow::Error::new)?;
    let Some(follow) = scene.follow.as_mut() else {
        return bail_input(format!(
            "{}: not a follow scene: it has none of [robot], [controller], [follow] (see \
             docs/follow.md)",
            args.scene.display()
        ));
    };
    if let Some(d) = args.duration_s {
        if !(d.is_finite() && d > 0.0) {
            return bail_input(format!("--duration-s {d}: must be positive"));
        }
        follow.config.settings.duration_s = d;
    }
    if let Some(v) = args.speed_m_per_s {
        if !(v.is_finite() && v > 0.0) {
            return bail_input(format!("--speed-m-per-s {v}: must be positive"));
        }
        follow.config.robot.speed_m_per_s = v;
    }
    check_plot_file(args.plot.as_deref())?;
    let mut run = FollowRun::start(&scene).map_err(failure)?;
    let steps = run.steps();
    let config = *run.config();
    let mut plot = args.plot.as_ref().map(|_| {
        let every = args.plot_every.and_then(|k| usize::try_from(k).ok());
        FollowPlot::new(
            steps,
            config.robot.footprint_m,
            scene.chain.link_lengths_m(),
            every,
        )
    });
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    let write_error = |e: std::io::Error| Failure::BadInput(anyhow!("writing to stdout: {e}"));
    let start = run.start_line();
    if args.jsonl {
        writeln!(out, "{}", json(&FollowLine::Start(start))?).map_err(write_error)?;
    } else if !args.json {
        writeln!(
            out,
            "{}: {} body at {} m/s, {} estimator, setpoint {} m, {} steps of {} s",
            start.scene,
            start.body,
            start.speed_m_per_s,
            start.estimator,
            start.setpoint_m,
            start.steps,
            start.step_s
        )
        .map_err(write_error)?;
        if !start.note.is_empty() {
            writeln!(out, "placement: {}", start.note).map_err(write_error)?;
        }
    }
    out.flush().map_err(write_error)?;
    let progress = progress::bar(steps, "steps", true);
    let mut flushed = Instant::now();
    let setpoint_m = config.controller.setpoint_m;
    let mut k = 0u64;
    while let Some(step) = run.next_step() {
        let Ok(step) = step else { break };
        let line = step_line(&step, setpoint_m);
        if args.jsonl {
            writeln!(out, "{}", json(&FollowLine::Step(line.clone()))?).map_err(write_error)?;
            if flushed.elapsed() >= FLUSH_EVERY {
                out.flush().map_err(write_error)?;
                flushed = Instant::now();
            }
        }
        if let Some(plot) = &mut plot {
            plot.push(&line);
        }
        k += 1;
        progress.set_position(k);
    }
    progress.finish_and_clear();
    let summary = run.summary_line();
    if args.jsonl || args.json {
        writeln!(out, "{}", json(&FollowLine::Summary(summary.clone()))?).map_err(write_error)?;
    } else {
        write!(out, "{}", human(&summary)).map_err(write_error)?;
    }
    out.flush().map_err(write_error)?;
    if let (Some(plot), Some(path)) = (&plot, &args.plot) {
        let title = format!(
            "{}: {} at {} m/s, {} ({})",
            args.scene.file_name().map_or_else(
                || start_name(&args.scene),
                |f| f.to_string_lossy().into_owned()
            ),
            run.start_line().body,
            config.robot.speed_m_per_s,
            run.start_line().estimator,
            summary.status
        );
        plot.write(path, run.walls(), &title)
            .map_err(|e| Failure::BadInput(anyhow::Error::new(e)))?;
        if !args.jsonl && !args.json {
            println!("plot: {}", path.display());
        }
    }
    match run.failure() {
        None => Ok(()),
        Some(e) => Err(match e.exit_status() {
            3 => Failure::Breakdown(anyhow!("{e}")),
            _ => Failure::NoSuccess(Some(anyhow!("{e}"))),
        }),
    }
}

fn start_name(path: &std::path::Path) -> String {
    path.display().to_string()
}

fn failure(e: FollowFailure) -> Failure {
    match e.exit_status() {
        2 => Failure::BadInput(anyhow::Error::new(e)),
        3 => Failure::Breakdown(anyhow::Error::new(e)),
        _ => Failure::NoSuccess(Some(anyhow::Error::new(e))),
    }
}

fn json(line: &FollowLine) -> Result<String, Failure> {
    serde_json::to_string(line)
        .context("writing a JSON line")
        .map_err(Failure::Breakdown)
}
