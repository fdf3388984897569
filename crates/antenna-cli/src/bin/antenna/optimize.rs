//! `antenna optimize OPT.toml`: the stiffness profile that maximizes a task's metric.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use antenna_cli::optimize::plot::write_plot;
use antenna_cli::optimize::{
    OptimizeError, OptimizeOptions, OptimizeSpec, TABLE_4_1, best_scene_text, run_optimization,
};
use anyhow::{Context as _, anyhow};
use clap::Args;

use crate::{Failure, check_plot_file};

/// Search the joint stiffness profile that maximizes a task's metric over a set of sweeps.
///
/// The file's `[optimize]` table names the base scenes, the objective (`preview-mean`,
/// `mapping-error` or `flip-free-preview`, averaged over the scenes, maximized; on follow
/// scenes `follow-v-max`, the highest speed in m/s with a `[v_max]` table, or `follow-rms`,
/// the RMS distance error in m, minimized, with the scene's robot and gains), the
/// parameters (`per-joint` or `exponential-taper`), the stiffness bounds, the wires (`any`
/// or `available`), the method (argmin's `nelder-mead` or `particle-swarm`), the budget of
/// sweeps and the seed. The seven named profiles of the thesis's Table 4.1 are swept first and
/// the search starts from the best of them, so the result is never worse. Every evaluation
/// is a certified sweep of each scene; a sweep that fails, jams or never touches the wall
/// makes its evaluation infeasible, counted in `failed_evaluations` and listed.
///
/// Ctrl-C (or SIGTERM) stops the search: the sweeps under way finish, and the report covers
/// what was swept. With --log every evaluation is on disk as it completes, and --resume goes
/// on from there (a second Ctrl-C exits at once).
///
/// Exit status: 0 a feasible profile was found; 1 every evaluation was infeasible, or the run
/// was interrupted or could not write its log (the report is still written); 2 bad input
/// (what and where, nothing on stdout; a --log that exists without --resume, or records
/// another optimization).
#[derive(Debug, Args)]
#[command(after_help = "Examples:
  antenna optimize examples/optimize/wall_following.toml
  antenna optimize examples/optimize/wall_following.toml --json -o best.json --plot best.svg
  antenna optimize examples/optimize/wall_following.toml --scene-out best.toml && antenna sweep best.toml
  antenna optimize examples/optimize/wall_following.toml --log run.jsonl            # Ctrl-C, then:
  antenna optimize examples/optimize/wall_following.toml --log run.jsonl --resume
  antenna optimize examples/optimize/follow_rms.toml --scene-out best.toml && antenna follow best.toml")]
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
    /// Write every evaluation to this JSON-lines file as it completes, so that a stopped run
    /// loses nothing (refused if the file exists, unless --resume).
    #[arg(long, value_name = "FILE.jsonl")]
    log: Option<PathBuf>,
    /// Continue the run the --log file records: its evaluations are taken from it instead of
    /// swept again (the same file, seed and scenes; a larger budget goes on past its end).
    #[arg(long, requires = "log")]
    resume: bool,
}

/// The first Ctrl-C (or SIGTERM) sets the flag: no new sweep starts and the report covers
/// what was swept; a second one exits at once.
fn interrupt_flag() -> anyhow::Result<Arc<AtomicBool>> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let flag = Arc::new(AtomicBool::new(false));
    for signal in [SIGINT, SIGTERM] {
        signal_hook::flag::register_conditional_shutdown(signal, 130, Arc::clone(&flag))
            .and_then(|_| signal_hook::flag::register(signal, Arc::clone(&flag)))
            .context("installing the Ctrl-C handler")?;
    }
    Ok(flag)
}

/// An output whose folder does not exist is refused before the search, not after it (a long
/// run's result would be lost).
fn check_output_folder(option: &str, path: Option<&Path>) -> Result<(), Failure> {
    let Some(folder) = path.and_then(Path::parent) else {
        return Ok(());
    };
    if folder.as_os_str().is_empty() || folder.is_dir() {
        return Ok(());
    }
    Err(Failure::BadInput(anyhow!(
        "{option} {}: the folder {} does not exist",
        path.map_or(String::new(), |p| p.display().to_string()),
        folder.display()
    )))
}

pub(crate) fn run(args: &OptimizeArgs) -> Result<(), Failure> {
    check_plot_file(args.plot.as_deref())?;
    check_output_folder("-o", args.output.as_deref())?;
    check_output_folder("--plot", args.plot.as_deref())?;
    check_output_folder("--scene-out", args.scene_out.as_deref())?;
    check_output_folder("--log", args.log.as_deref())?;
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
    let options = OptimizeOptions {
        jobs,
        progress: true,
        log: args.log.clone(),
        resume: args.resume,
        interrupt: Some(interrupt_flag()?),
    };
    let report = run_optimization(&spec, &options).map_err(|e| match e {
        OptimizeError::Log(e) => Failure::BadInput(anyhow::Error::new(e)),
        e => Failure::NoSuccess(Some(anyhow!("{}: {e}", args.file.display()))),
    })?;
    if report.replayed_evaluations > 0 {
        eprintln!(
            "resumed: {} evaluation(s) taken from {}",
            report.replayed_evaluations,
            args.log
                .as_deref()
                .unwrap_or(Path::new("the log"))
                .display()
        );
    }
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
    if report.stopped_by == "interrupted" || report.stopped_by.starts_with("log failed") {
        return Err(Failure::NoSuccess(Some(anyhow!(
            "{}: {}: the report covers the {} evaluation(s) swept{}",
            args.file.display(),
            report.stopped_by,
            report.evaluations,
            if args.log.is_some() {
                "; --resume continues from the log"
            } else {
                ""
            }
        ))));
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
