//! `antenna optimize OPT.toml`: the stiffness profile that maximizes a task's metric.

use std::io::Write as _;
use std::path::PathBuf;

use antenna_cli::optimize::plot::write_plot;
use antenna_cli::optimize::{
    OptimizeOptions, OptimizeSpec, TABLE_4_1, best_scene_text, run_optimization,
};
use anyhow::{Context as _, anyhow};
use clap::Args;

use crate::{Failure, check_plot_file};

/// Search the joint stiffness profile that maximizes a task's metric over a set of sweeps.
///
/// The file's `[optimize]` table names the base scenes, the objective (`preview-mean`,
/// `mapping-error` or `flip-free-preview`, averaged over the scenes, maximized), the
/// parameters (`per-joint` or `exponential-taper`), the stiffness bounds, the wires (`any`
/// or `available`), the method (argmin's `nelder-mead` or `particle-swarm`), the budget of
/// sweeps and the seed. The seven named profiles of the seed's Table 4.1 are swept first and
/// the search starts from the best of them, so the result is never worse. Every evaluation
/// is a certified sweep of each scene; a sweep that fails, jams or never touches the wall
/// makes its evaluation infeasible, counted in `failed_evaluations` and listed.
///
/// Exit status: 0 a feasible profile was found; 1 every evaluation was infeasible (the
/// report is still written); 2 bad input (what and where, nothing on stdout).
#[derive(Debug, Args)]
#[command(after_help = "Examples:
  antenna optimize examples/optimize/wall_following.toml
  antenna optimize examples/optimize/wall_following.toml --json -o best.json --plot best.svg
  antenna optimize examples/optimize/wall_following.toml --scene-out best.toml && antenna sweep best.toml")]
pub(crate) struct OptimizeArgs {
    /// The optimization file (TOML: `[optimize]`; see docs/optimize.md).
    file: PathBuf,
    /// Print one JSON object (values_n_m_per_rad, objective_value, best_named_profile,
    /// evaluations, failed_evaluations, history, ...) instead of a table.
    #[arg(long)]
    json: bool,
    /// Sweeps run at once (default: the number of cores).
    #[arg(long, short = 'j', value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    jobs: Option<u64>,
    /// Write the report (the table, or the JSON with --json) to this file instead of stdout.
    #[arg(long, short = 'o', value_name = "FILE")]
    output: Option<PathBuf>,
    /// Draw the convergence and the profile found beside the named ones (.svg or .png).
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
    /// Write the first scene with the stiffnesses found (`values_n_m_per_rad`) to this
    /// file, ready for `antenna sweep`.
    #[arg(long, value_name = "FILE")]
    scene_out: Option<PathBuf>,
}

pub(crate) fn run(args: &OptimizeArgs) -> Result<(), Failure> {
    check_plot_file(args.plot.as_deref())?;
    let spec = OptimizeSpec::from_path(&args.file).map_err(anyhow::Error::new)?;
    let jobs = match args.jobs {
        Some(j) => usize::try_from(j).unwrap_or(usize::MAX),
        None => std::thread::available_parallelism().map_or(1, std::num::NonZero::get),
    };
    eprintln!(
        "{}: maximize {} over {} scene(s), {} ({} coordinate(s)), wires {}, {}: the {} named \
         profiles, then the search, at most {} sweeps on {jobs} thread(s)",
        args.file.display(),
        spec.objective.name(),
        spec.scenes.len(),
        spec.space.family.name(),
        spec.space.dim(),
        spec.space.wires.name(),
        spec.method.name(),
        TABLE_4_1.len(),
        spec.budget,
    );
    let report = run_optimization(
        &spec,
        &OptimizeOptions {
            jobs,
            progress: true,
        },
    )
    .map_err(|e| Failure::NoSuccess(Some(anyhow!("{}: {e}", args.file.display()))))?;
    let text = if args.json {
        let mut json = serde_json::to_string(&report).context("writing the report as JSON")?;
        json.push('\n');
        json
    } else {
        report.table()
    };
    match &args.output {
        Some(path) => std::fs::write(path, &text)
            .with_context(|| format!("{}: cannot write the report", path.display()))?,
        None => {
            let mut out = std::io::stdout().lock();
            out.write_all(text.as_bytes())
                .and_then(|()| out.flush())
                .context("writing the report")?;
        }
    }
    if let Some(path) = &args.plot {
        write_plot(&report, path).map_err(|e| Failure::BadInput(anyhow::Error::new(e)))?;
        eprintln!("plot: {}", path.display());
    }
    if let Some(path) = &args.scene_out {
        let scene = best_scene_text(&spec, &report).map_err(|e| anyhow!(e))?;
        std::fs::write(path, scene)
            .with_context(|| format!("{}: cannot write the scene", path.display()))?;
    }
    if report.objective_value.is_none() {
        return Err(Failure::NoSuccess(Some(anyhow!(
            "{}: every one of {} evaluation(s) was infeasible (the report says why)",
            args.file.display(),
            report.evaluations
        ))));
    }
    Ok(())
}
