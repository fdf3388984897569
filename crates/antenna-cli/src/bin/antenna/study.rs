//! `antenna study STUDY.toml`: a grid of sweeps (or of follow runs), one result row per grid
//! point.

use std::io::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use antenna_cli::study::{Row, RunOptions, Shard, Study, StudyFormat, run_study};
use anyhow::{Context as _, anyhow};
use clap::{Args, ValueEnum};

use crate::Failure;

/// Run a grid of sweeps: a base scene and axes (stiffness profiles, base angles, wall
/// distances, hair layouts, surfaces), one result row per grid point.
///
/// The grid is the product of the study file's axes, the last varying fastest; each row
/// carries its grid index, its axis values and the sweep's metrics (see docs/sweeps.md for the
/// file format and the columns). Sweeps run in parallel; rows come out in grid order.
///
/// On a follow scene (`[robot]`, `[controller]`, `[follow]`) each row is a closed-loop run
/// with the follow summary as columns, over the axes profiles, hairs, surfaces,
/// speeds_m_per_s, kp_n, kd_n_s (kp_rad_per_s_per_m, kd_rad_per_m for a wheeled body) and
/// delays_s; with a `[v_max]` table each row is the highest speed at which the robot follows
/// the wall (v_max_m_per_s, v_max_failure, v_max_monotone, v_max_runs). Collided and lost
/// runs are physical outcomes, not failures.
///
/// Exit status: 0 every sweep ran (some may have jammed: the antenna jammed against a wall,
/// a physical outcome with status `jammed`); 1 some failed (their rows say why; every row
/// is still written); 2 bad input (what and where, nothing on stdout). Rows whose steps the
/// solver relaxed something in (friction dropped, anchors torn out, a residual above the
/// tolerance) count them in `relaxed_steps`.
#[derive(Debug, Args)]
#[command(after_help = "Examples:
  antenna study examples/studies/profiles.toml
  antenna study examples/studies/profiles.toml --format jsonl --jobs 2 -o rows.jsonl
  antenna study examples/studies/profiles.toml --shard 3/8 -o rows-3.csv    # array job 3 of 8")]
pub(crate) struct StudyArgs {
    /// The study file (TOML: `[study]` scene and `[axes]`; see docs/sweeps.md).
    study: PathBuf,
    /// Run only shard I of N (1-based; the grid points whose index is I - 1 modulo N): the N
    /// shards together run the grid, each point once.
    #[arg(long, value_name = "I/N", value_parser = clap::value_parser!(Shard))]
    shard: Option<Shard>,
    /// Sweeps run at once (default: the number of cores).
    #[arg(long, short = 'j', value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    jobs: Option<u64>,
    /// How the rows are written.
    #[arg(long, value_enum, default_value_t = FormatArg::Csv)]
    format: FormatArg,
    /// Write the rows to this file instead of stdout.
    #[arg(long, short = 'o', value_name = "FILE")]
    output: Option<PathBuf>,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum FormatArg {
    /// Comma-separated values with a header line.
    Csv,
    /// One JSON object per line.
    Jsonl,
}

pub(crate) fn run(args: &StudyArgs) -> Result<(), Failure> {
    let study = Study::from_path(&args.study).map_err(anyhow::Error::new)?;
    let shard = args.shard.unwrap_or(Shard::ALL);
    let jobs = match args.jobs {
        Some(j) => usize::try_from(j).unwrap_or(usize::MAX),
        None => std::thread::available_parallelism().map_or(1, std::num::NonZero::get),
    };
    let format = match args.format {
        FormatArg::Csv => StudyFormat::Csv,
        FormatArg::Jsonl => StudyFormat::Jsonl,
    };
    let out: Box<dyn std::io::Write> = match &args.output {
        Some(path) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(path)
                .with_context(|| format!("{}: cannot create the output", path.display()))?,
        )),
        None => Box::new(std::io::BufWriter::new(std::io::stdout().lock())),
    };
    let mut out = match format {
        StudyFormat::Csv => Rows::Csv(Box::new(csv::Writer::from_writer(out))),
        StudyFormat::Jsonl => Rows::Jsonl(out),
    };
    let runs = shard.indices(study.len()).count();
    let what = match (study.is_follow(), &study.v_max) {
        (false, _) => "sweep(s)",
        (true, None) => "follow run(s)",
        (true, Some(_)) => "v_max search(es)",
    };
    eprintln!(
        "{}: {} grid points ({}), shard {shard}: {runs} {what} on {} thread(s)",
        args.study.display(),
        study.len(),
        axis_summary(&study),
        jobs.min(runs.max(1))
    );
    let started = Instant::now();
    let columns = study.columns();
    if let Rows::Csv(csv) = &mut out {
        csv.write_record(columns).context("writing the rows")?;
    }
    let options = RunOptions {
        shard,
        jobs,
        progress: true,
    };
    let counts = run_study(&study, &options, &mut |row: &Row| match &mut out {
        Rows::Csv(csv) => {
            csv.write_record(row.csv_fields(columns))?;
            csv.flush()
        }
        Rows::Jsonl(out) => writeln!(out, "{}", row.json_line(columns)).and_then(|()| out.flush()),
    })
    .context("writing the rows")?;
    match &mut out {
        Rows::Csv(csv) => csv.flush(),
        Rows::Jsonl(out) => out.flush(),
    }
    .context("writing the rows")?;
    if study.is_follow() {
        eprintln!(
            "{} {what} in {:.1} s, {} failed, {} collided, {} lost, {} jammed",
            counts.runs,
            started.elapsed().as_secs_f64(),
            counts.failed,
            counts.collided,
            counts.lost,
            counts.jammed
        );
    } else {
        eprintln!(
            "{} sweep(s) in {:.1} s, {} failed, {} jammed, {} with relaxed steps",
            counts.runs,
            started.elapsed().as_secs_f64(),
            counts.failed,
            counts.jammed,
            counts.relaxed
        );
    }
    if counts.failed > 0 {
        return Err(Failure::NoSuccess(Some(anyhow!(
            "{}: {} of {} {what} failed (their rows say why)",
            args.study.display(),
            counts.failed,
            counts.runs
        ))));
    }
    Ok(())
}

/// Where the rows go: a CSV writer (a header, then a line per row) or JSON lines.
enum Rows {
    Csv(Box<csv::Writer<Box<dyn std::io::Write>>>),
    Jsonl(Box<dyn std::io::Write>),
}

/// `2 profiles x 3 base angles x ...`.
fn axis_summary(study: &Study) -> String {
    let a = &study.axes;
    let parts: Vec<String> = [
        (a.profiles.len(), "profiles"),
        (a.base_angles_deg.len(), "base angles"),
        (a.wall_distances_m.len(), "wall distances"),
        (a.hairs.len(), "hair layouts"),
        (a.surfaces.len(), "surfaces"),
        (a.speeds_m_per_s.len(), "speeds"),
        (a.kp_n.len(), "kp_n"),
        (a.kd_n_s.len(), "kd_n_s"),
        (a.kp_rad_per_s_per_m.len(), "kp_rad_per_s_per_m"),
        (a.kd_rad_per_m.len(), "kd_rad_per_m"),
        (a.delays_s.len(), "delays"),
    ]
    .into_iter()
    .filter(|(n, _)| *n > 0)
    .map(|(n, what)| format!("{n} {what}"))
    .collect();
    if parts.is_empty() {
        "no axes: the base scene once".to_string()
    } else {
        parts.join(" x ")
    }
}
