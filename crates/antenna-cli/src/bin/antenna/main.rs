//! `antenna`: solve scene files, sweep them along their walls, run studies of many sweeps,
//! search the stiffness profile that maximizes a task metric,
//! design Nitinol wires for a stiffness profile, identify joint stiffness from a
//! free-oscillation recording, export recorded trials, commission the robot's segments. See
//! the guide's chapters `docs/scenes.md` and `docs/sweeps.md`, and `docs/scene-format.md`.
//!
//! Exit status: 0 success; 1 the solver did not converge (`solve`; the JSON is still printed
//! for a scene without walls), a sweep step failed (`sweep`), a study run failed (`study`;
//! every row is still written), every evaluation was infeasible (`optimize`) or the recording
//! did not yield an identification (`identify`); 2 bad input (a message on stderr that says what and where, nothing on
//! stdout); 3 the solver broke down numerically.

mod follow;
mod optimize;
mod study;
mod sweep;

use std::io::{Read as _, Write as _};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use antenna_cli::design::{design_report, design_table};
use antenna_cli::identify::{DEFAULT_WIRE_CONSTANT, identify_report, identify_summary};
use antenna_cli::recording::Recording;
use antenna_cli::segments::SegmentsFailure;
use antenna_cli::solve::{SolveError, all_minima_of_scene, solve_scene, summary};
use antenna_cli::solve_walls::{solve_wall_scene, wall_summary};
use antenna_scene::SweepFailure;
use antenna_scene::{Scene, Start};
use anyhow::{Context as _, anyhow};
use clap::{Args, Parser, Subcommand, ValueEnum};
use sim_core::{
    DampingSource, EquilibriumError, FrequencySource, IdentifyError, IdentifyOptions, MinimaSearch,
    StiffnessProfile,
};

/// Planar antenna models from the command line: equilibria of scene files, Nitinol wire
/// designs, stiffness identification.
#[derive(Debug, Parser)]
#[command(version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    Solve(SolveArgs),
    Sweep(sweep::SweepArgs),
    Follow(follow::FollowArgs),
    Study(study::StudyArgs),
    Optimize(optimize::OptimizeArgs),
    Design(DesignArgs),
    Identify(IdentifyArgs),
    Export(ExportArgs),
    Segments(antenna_cli::segments::SegmentsArgs),
}

/// Find the static equilibrium of a scene file.
///
/// Exit status: 0 converged; 1 did not converge (the JSON is still printed, with
/// "converged": false); 2 bad input (message on stderr, nothing on stdout); 3 numerical
/// breakdown.
#[derive(Debug, Args)]
#[command(after_help = "Examples:
  antenna solve examples/dead_load.toml
  antenna solve examples/pinned_c.toml --json
  antenna solve examples/pinned_c.toml --all-minima --random-starts 128")]
struct SolveArgs {
    /// The scene file (TOML; see docs/scene-format.md).
    scene: PathBuf,
    /// Print exactly one JSON object (with --all-minima: a JSON array of them).
    #[arg(long)]
    json: bool,
    /// Search for every distinct stable equilibrium, lowest energy first (the potential the
    /// solver minimizes, U - F . p_tip; the scene's initial key is not used: the search has
    /// its own starts).
    #[arg(long)]
    all_minima: bool,
    /// Random starts of the --all-minima search, on top of straight, C, S and the mirrors.
    #[arg(long, default_value_t = MinimaSearch::default().random_starts, requires = "all_minima")]
    random_starts: usize,
    /// Seed of the --all-minima random starts.
    #[arg(long, default_value_t = MinimaSearch::default().seed, requires = "all_minima")]
    seed: u64,
}

/// Map a stiffness profile to the nearest available Nitinol wire per joint.
///
/// The wire law is k = 2.0614e12 r^4 + 0.0016 N m/rad (wire in parallel with the cable);
/// the wires are 0.010-0.022 in and 0.024-0.030 in in steps of 0.001 in. Each joint gets the
/// wire whose k is nearest its target; the range flag says when no wire can reach it.
#[derive(Debug, Args)]
#[command(after_help = "Examples:
  antenna design --profile fast-exponential
  antenna design --profile linear --min-n-m-per-rad 0.004 --max-n-m-per-rad 0.03 --links 12 --link-length-m 0.03 --json
  antenna design --values 0.02,0.01,0.005
  antenna design --scene examples/pinned_c.toml")]
struct DesignArgs {
    /// Take the stiffness (and link lengths) from this scene file.
    #[arg(long, conflicts_with_all = ["profile", "values", "links", "link_length_m", "min_n_m_per_rad", "max_n_m_per_rad"])]
    scene: Option<PathBuf>,
    /// A profile name (docs/model.md 5): constant, linear, slow-exponential, fast-exponential,
    /// logarithmic, slow-reciprocal, fast-reciprocal, cockroach.
    #[arg(long, conflicts_with = "values")]
    profile: Option<String>,
    /// Explicit targets, N m/rad, comma-separated, one per joint.
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    values: Option<Vec<f64>>,
    /// Softest joint of the profile, N m/rad.
    #[arg(long, default_value_t = 0.004)]
    min_n_m_per_rad: f64,
    /// Stiffest joint of the profile, N m/rad.
    #[arg(long, default_value_t = 0.082)]
    max_n_m_per_rad: f64,
    /// Links N, base link included (N - 1 joints).
    #[arg(long, default_value_t = 9)]
    links: usize,
    /// Length of every link, m.
    #[arg(long, default_value_t = 0.04)]
    link_length_m: f64,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
}

/// Identify a joint's stiffness from a free-oscillation recording (thesis 6.2).
///
/// RECORDING is a CSV file ("-" reads stdin): an optional header naming `t_s` and
/// `angle_rad` or `angle_deg` (other columns are ignored); without a header one column is
/// angle_rad and two are t_s,angle_rad. `#` starts a comment line. With a time column the
/// sample rate comes from it (uniform steps required); otherwise give --sample-rate-hz.
/// Reports f_d, zeta, f_n, k_eq = J (2 pi f_n)^2 and k_wire = k_eq - k_cable.
#[derive(Debug, Args)]
#[command(after_help = "Examples:
  antenna identify ringdown.csv --inertia-kg-m2 3.25e-6
  antenna identify angles.txt --sample-rate-hz 500 --inertia-kg-m2 3.25e-6 --wire-radius --json")]
struct IdentifyArgs {
    /// The recording (CSV; "-" for stdin).
    recording: PathBuf,
    /// Inertia of the oscillating body about the joint, kg m^2 (the thesis's segment: 3.25e-6).
    #[arg(long)]
    inertia_kg_m2: f64,
    /// Sample rate, Hz (required without a time column; must agree with one within 0.1 %).
    #[arg(long)]
    sample_rate_hz: Option<f64>,
    /// Cable stiffness subtracted from k_eq, N m/rad.
    #[arg(long, default_value_t = IdentifyOptions::default().cable_stiffness_n_m_per_rad)]
    cable_n_m_per_rad: f64,
    /// Which damped-frequency estimate to use.
    #[arg(long, value_enum, default_value_t = FrequencyArg::Fit)]
    frequency: FrequencyArg,
    /// Which damping-ratio estimate to use.
    #[arg(long, value_enum, default_value_t = DampingArg::LogDecrement)]
    damping: DampingArg,
    /// Also report the wire radius r = (k_wire / C)^(1/4).
    #[arg(long)]
    wire_radius: bool,
    /// The constant C of k_wire = C r^4, N m/rad per m^4 (implies --wire-radius).
    #[arg(long)]
    wire_constant: Option<f64>,
    /// Print JSON instead of a summary.
    #[arg(long)]
    json: bool,
}

/// Export a trial recorded by antennad (MCAP) to a MAT-file (v5, scipy.io.loadmat reads it)
/// and/or a CSV file.
///
/// A trial cut short by a crash exports up to its last flush (with a warning on stderr).
/// Variables and columns: see the `antenna_cli::export` docs. Exit status: 0 written; 2 bad
/// input or a failed write (a message naming the file; a failed write leaves no partial
/// file).
#[derive(Debug, Args)]
#[command(after_help = "Examples:
  antenna export data/trial-001.mcap --mat trial-001.mat
  antenna export data/trial-001.mcap --csv trial-001.csv")]
struct ExportArgs {
    /// The trial file (MCAP, written by antennad).
    trial: PathBuf,
    /// Write a MAT-file here.
    #[arg(long, required_unless_present = "csv")]
    mat: Option<PathBuf>,
    /// Write a CSV file here.
    #[arg(long)]
    csv: Option<PathBuf>,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum FrequencyArg {
    /// Least-squares damped-sinusoid fit seeded by the spectrum peak.
    Fit,
    /// The spectrum peak alone (the thesis's method; biased for strong damping).
    SpectrumPeak,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum DampingArg {
    /// Logarithmic decrement averaged over all peak pairs (the thesis's method).
    LogDecrement,
    /// The decay rate of the damped-sinusoid fit.
    Fit,
}

/// How a command failed, which decides the exit status.
pub(crate) enum Failure {
    /// 1: an answer exists but is not a success (already printed when there is one).
    NoSuccess(Option<anyhow::Error>),
    /// 2: bad input.
    BadInput(anyhow::Error),
    /// 3: the solver broke down.
    Breakdown(anyhow::Error),
}

impl From<SweepFailure> for Failure {
    fn from(e: SweepFailure) -> Self {
        match e {
            SweepFailure::BadInput(_) => Failure::BadInput(anyhow::Error::new(e)),
            SweepFailure::NoConvergence(_) | SweepFailure::Jammed(_) => {
                Failure::NoSuccess(Some(anyhow::Error::new(e)))
            }
            SweepFailure::Breakdown(_) => Failure::Breakdown(anyhow::Error::new(e)),
        }
    }
}

impl From<SegmentsFailure> for Failure {
    fn from(e: SegmentsFailure) -> Self {
        match e {
            SegmentsFailure::NoSuccess(e) => Failure::NoSuccess(e),
            SegmentsFailure::BadInput(e) => Failure::BadInput(e),
        }
    }
}

impl From<anyhow::Error> for Failure {
    fn from(e: anyhow::Error) -> Self {
        Failure::BadInput(e)
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Solve(args) => run_solve(&args),
        Command::Sweep(args) => sweep::run(&args),
        Command::Follow(args) => follow::run(&args),
        Command::Study(args) => study::run(&args),
        Command::Optimize(args) => optimize::run(&args),
        Command::Design(args) => run_design(&args),
        Command::Identify(args) => run_identify(&args),
        Command::Export(args) => run_export(&args),
        Command::Segments(args) => {
            antenna_cli::segments::run(&args, &mut std::io::stdout()).map_err(Failure::from)
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::NoSuccess(e)) => {
            if let Some(e) = e {
                eprintln!("error: {e:#}");
            }
            ExitCode::from(1)
        }
        Err(Failure::BadInput(e)) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
        Err(Failure::Breakdown(e)) => {
            eprintln!("error: {e:#}");
            ExitCode::from(3)
        }
    }
}

pub(crate) fn print_json<T: serde::Serialize>(value: &T) -> Result<(), Failure> {
    let text = serde_json::to_string_pretty(value).context("writing JSON")?;
    // An error (a closed pipe: `antenna solve --json | head`), not a panic.
    let mut out = std::io::stdout().lock();
    writeln!(out, "{text}")
        .and_then(|()| out.flush())
        .context("writing the JSON to stdout")?;
    Ok(())
}

/// A solver error with the scene key it concerns, and its exit status.
fn solve_failure(scene: &Scene, path: &Path, e: SolveError) -> Failure {
    let place = |loc: Option<antenna_scene::Location>, key: &str| match loc {
        Some(l) => format!("{}:{l}: {key}", path.display()),
        None => format!("{}: {key}", path.display()),
    };
    match e {
        SolveError::Input(
            inner @ (EquilibriumError::Unreachable { .. } | EquilibriumError::PinInfeasible { .. }),
        ) => Failure::BadInput(anyhow!(
            "{}: {inner}",
            place(
                scene.locations.tip_pin_position_m,
                "`position_m` in [tip_pin]"
            )
        )),
        SolveError::Input(inner @ EquilibriumError::StartOutsideLimits { .. }) => {
            Failure::BadInput(anyhow!(
                "{}: {inner}",
                place(scene.locations.solver_initial, "`initial` in [solver]")
            ))
        }
        SolveError::Input(inner) => Failure::BadInput(anyhow!(
            "{}: the solver refused the scene: {inner}",
            path.display()
        )),
        SolveError::Breakdown(inner) => Failure::Breakdown(anyhow!(
            "{}: the solver broke down: {inner}",
            path.display()
        )),
        SolveError::Kinematics(inner) => Failure::Breakdown(anyhow!(
            "{}: positions of the equilibrium: {inner}",
            path.display()
        )),
    }
}

fn run_solve(args: &SolveArgs) -> Result<(), Failure> {
    let scene = Scene::from_path(&args.scene).map_err(anyhow::Error::new)?;
    if scene.has_walls() {
        return run_solve_walls(args, &scene);
    }
    if args.all_minima {
        let search = MinimaSearch {
            random_starts: args.random_starts,
            seed: args.seed,
        };
        let minima = all_minima_of_scene(&scene, &search)
            .map_err(|e| solve_failure(&scene, &args.scene, e))?;
        if args.json {
            let reports: Vec<_> = minima.iter().map(|(_, r)| r).collect();
            print_json(&reports)?;
        } else {
            println!(
                "{}: {} stable equilibri{} found ({} random starts, seed {}), lowest energy first",
                args.scene.display(),
                minima.len(),
                if minima.len() == 1 { "um" } else { "a" },
                search.random_starts,
                search.seed
            );
            for (i, (eq, r)) in minima.iter().enumerate() {
                println!("\n#{}:", i + 1);
                print!("{}", summary(&scene, eq, r));
            }
        }
        if minima.is_empty() {
            return Err(Failure::NoSuccess(Some(anyhow!(
                "{}: the search found no stable equilibrium",
                args.scene.display()
            ))));
        }
        return Ok(());
    }

    let (eq, report) = solve_scene(&scene).map_err(|e| solve_failure(&scene, &args.scene, e))?;
    if args.json {
        print_json(&report)?;
    } else {
        let start = match &scene.solver.initial {
            Start::Straight => "straight".to_string(),
            Start::C => "C".to_string(),
            Start::S => "S".to_string(),
            Start::MirrorC => "mirror-C".to_string(),
            Start::MirrorS => "mirror-S".to_string(),
            Start::AnglesRad(_) => "given angles".to_string(),
        };
        println!(
            "{}: {} links ({} flexible joints), start {start}",
            args.scene.display(),
            scene.n() + 1,
            scene.n()
        );
        print!("{}", summary(&scene, &eq, &report));
    }
    if report.converged {
        Ok(())
    } else {
        Err(Failure::NoSuccess(Some(anyhow!(
            "{}: did not converge in {} iterations (KKT residual {:e})",
            args.scene.display(),
            report.iterations,
            report.residual
        ))))
    }
}

/// `antenna solve` on a scene with walls: the placed and settled posture.
fn run_solve_walls(args: &SolveArgs, scene: &Scene) -> Result<(), Failure> {
    if args.all_minima {
        return bail_input(format!(
            "{}: --all-minima searches the equilibria of scenes without walls; this scene has \
             [[walls]] (its equilibrium is the posture [start] places and settles)",
            args.scene.display()
        ));
    }
    let eq = solve_wall_scene(scene)?;
    if args.json {
        print_json(&eq.report)?;
    } else {
        println!(
            "{}: {} links ({} flexible joints) against {} wall(s)",
            args.scene.display(),
            scene.n() + 1,
            scene.n(),
            scene.walls.len()
        );
        print!("{}", wall_summary(scene, &eq));
    }
    if eq.report.converged {
        Ok(())
    } else {
        Err(Failure::NoSuccess(Some(anyhow!(
            "{}: the settled posture's residual {:e} m exceeds [contact] tolerance_m = {:e}",
            args.scene.display(),
            eq.report.residual,
            scene.contact.tolerance_m
        ))))
    }
}

fn run_design(args: &DesignArgs) -> Result<(), Failure> {
    let targets: Vec<f64> = if let Some(path) = &args.scene {
        let scene = Scene::from_path(path).map_err(anyhow::Error::new)?;
        scene.chain.stiffness_nm_per_rad()[1..].to_vec()
    } else if let Some(values) = &args.values {
        values.clone()
    } else {
        let name = args.profile.as_deref().unwrap_or("fast-exponential");
        let profile: StiffnessProfile = name.parse().with_context(|| {
            let names: Vec<&str> = StiffnessProfile::NAMED.iter().map(|p| p.name()).collect();
            format!("--profile {name:?}: known profiles: {}", names.join(", "))
        })?;
        if args.links < 2 {
            return Err(Failure::BadInput(anyhow!(
                "--links {}: a chain needs at least 2 links (the base link and one joint)",
                args.links
            )));
        }
        let lengths = vec![args.link_length_m; args.links];
        profile
            .stiffness_n_m_per_rad(&lengths, args.min_n_m_per_rad, args.max_n_m_per_rad)
            .context("stiffness profile")?
    };
    let report = design_report(&targets).context("wire design")?;
    if args.json {
        print_json(&report)
    } else {
        print!("{}", design_table(&report));
        Ok(())
    }
}

fn read_recording(path: &Path) -> anyhow::Result<Recording> {
    let text = if path.as_os_str() == "-" {
        let mut s = String::new();
        std::io::stdin()
            .read_to_string(&mut s)
            .context("reading the recording from stdin")?;
        s
    } else {
        std::fs::read_to_string(path)
            .with_context(|| format!("{}: cannot read the recording", path.display()))?
    };
    Recording::parse(&text).with_context(|| format!("{}", path.display()))
}

fn run_identify(args: &IdentifyArgs) -> Result<(), Failure> {
    let recording = read_recording(&args.recording)?;
    let sample_rate_hz = match (recording.sample_rate_hz, args.sample_rate_hz) {
        (Some(from_file), Some(given)) => {
            if (from_file - given).abs() > 1e-3 * given.abs() {
                return Err(Failure::BadInput(anyhow!(
                    "{}: the time column gives {from_file} Hz but --sample-rate-hz is {given}",
                    args.recording.display()
                )));
            }
            from_file
        }
        (Some(r), None) | (None, Some(r)) => r,
        (None, None) => {
            return Err(Failure::BadInput(anyhow!(
                "{}: no time column (t_s); give --sample-rate-hz",
                args.recording.display()
            )));
        }
    };
    let options = IdentifyOptions {
        cable_stiffness_n_m_per_rad: args.cable_n_m_per_rad,
        frequency: match args.frequency {
            FrequencyArg::Fit => FrequencySource::DampedSineFit,
            FrequencyArg::SpectrumPeak => FrequencySource::SpectrumPeak,
        },
        damping: match args.damping {
            DampingArg::LogDecrement => DampingSource::LogDecrement,
            DampingArg::Fit => DampingSource::DampedSineFit,
        },
        ..IdentifyOptions::default()
    };
    let wire_constant = match (args.wire_radius, args.wire_constant) {
        (_, Some(c)) if !(c.is_finite() && c > 0.0) => {
            bail_input(format!("--wire-constant {c} must be finite and positive"))?
        }
        (_, Some(c)) => Some(c),
        (true, None) => Some(DEFAULT_WIRE_CONSTANT),
        (false, None) => None,
    };
    let report = identify_report(
        &recording.angle_rad,
        sample_rate_hz,
        args.inertia_kg_m2,
        &options,
        wire_constant,
    )
    .map_err(|e| {
        let no_result = matches!(
            e,
            IdentifyError::NoOscillation { .. }
                | IdentifyError::TooFewPeaks { .. }
                | IdentifyError::NotUnderdamped { .. }
                | IdentifyError::FitFailed { .. }
        );
        let e =
            anyhow::Error::new(e).context(format!("{}: identification", args.recording.display()));
        if no_result {
            Failure::NoSuccess(Some(e))
        } else {
            Failure::BadInput(e)
        }
    })?;
    if args.json {
        print_json(&report)
    } else {
        print!("{}", identify_summary(&report));
        Ok(())
    }
}

fn run_export(args: &ExportArgs) -> Result<(), Failure> {
    let path = &args.trial;
    let trial = antenna_data::record::TrialReader::read(path)
        .map_err(|e| anyhow!("cannot export the trial: {e}"))?;
    if let Some(why) = &trial.truncated {
        eprintln!(
            "warning: {}: the trial file ends early (a crash?); exporting {} polls up to its last flush ({why})",
            path.display(),
            trial.segments.len()
        );
    }
    if let Some(out) = &args.mat {
        antenna_cli::export::write_mat(&trial, out)
            .with_context(|| format!("{}: exporting to {}", path.display(), out.display()))?;
    }
    if let Some(out) = &args.csv {
        antenna_cli::export::write_csv(&trial, out)
            .with_context(|| format!("{}: exporting to {}", path.display(), out.display()))?;
    }
    Ok(())
}

/// `--plot FILE`: an SVG or a PNG, by its extension (checked before any work is done).
pub(crate) fn check_plot_file(plot: Option<&Path>) -> Result<(), Failure> {
    let Some(plot) = plot else {
        return Ok(());
    };
    let ext = plot
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    if matches!(ext.as_deref(), Some("svg" | "png")) {
        Ok(())
    } else {
        bail_input(format!(
            "--plot {}: the file name must end in .svg or .png",
            plot.display()
        ))
    }
}

pub(crate) fn bail_input<T>(message: String) -> Result<T, Failure> {
    Err(Failure::BadInput(anyhow!(message)))
}
