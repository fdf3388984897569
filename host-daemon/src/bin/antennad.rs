//! `antennad`: the antenna host daemon, a thin shell around [`host_daemon::service::daemon::Daemon`].
//!
//! It polls the segments continuously, streams every poll to TCP clients and takes control
//! commands (start/stop a trial, move the stage, set the base angle, stop everything). On the
//! simulated rig it starts the configuration's first trial at once, so a first run shows a
//! trial happening, and keeps serving afterwards; `--exit-after-trial` exits when that trial
//! ends. With any hardware configured no trial starts by itself (`--trial NAME` starts one
//! after homing): it waits idle for a client's start_trial.
//!
//! With no configuration it runs the simulated rig: nine segments running the firmware's own
//! logic on a virtual I2C bus, a virtual stage carrying the antenna along a wall, and joint
//! angles from sim-core's equilibrium solver.
//!
//! As a service (`host-daemon/packaging/antennad.service`): the log goes to stderr with
//! timestamps and levels (`RUST_LOG` filters it); the sample lines and the final summary are
//! data, on stdout (`--quiet` drops the sample lines), and a closed or stalled stdout costs
//! lines, never the daemon. SIGTERM or SIGINT stop it cleanly (a running trial's file is
//! finalized); SIGHUP re-reads the configuration file and logs which keys differ from the
//! running configuration, changing nothing until a restart. Under systemd it reports
//! `READY=1`, `STATUS=`, `STOPPING=1` and pings the watchdog (`host_daemon::service::systemd`).

use anyhow::{Result, bail};
use clap::Parser;
use host_daemon::service::config::Config;
use host_daemon::service::config_source::{ConfigSource, changed_keys};
use host_daemon::service::daemon::{Daemon, DaemonHandle, DaemonOptions, first_trial_for};
use host_daemon::service::stdout_lines;
use host_daemon::service::systemd::{self, Watchdog};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;
use tracing::{error, info, warn};

/// The antenna host daemon: polls the segments (by default on the simulated rig), streams
/// them over TCP, runs trials and records each to MCAP.
#[derive(Debug, Parser)]
#[command(version, about)]
struct Args {
    /// Configuration file (TOML; see host-daemon/config/). Default: /etc/antenna/antennad.toml
    /// if it exists, else the simulated rig. A relative data_dir in it is relative to its
    /// directory.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Where to look for a configuration file without --config, colon-separated (tests,
    /// packaging).
    #[arg(long, hide = true, value_delimiter = ':')]
    config_search_path: Option<Vec<PathBuf>>,
    /// The trial to start at once (by name; default: the first in the configuration, on the
    /// simulated rig only: with hardware none starts unless named).
    #[arg(long)]
    trial: Option<String>,
    /// Start no trial; wait for a client's start_trial.
    #[arg(long, conflicts_with_all = ["trial", "exit_after_trial"])]
    idle: bool,
    /// Exit when the first trial has ended (CI, scripts).
    #[arg(long)]
    exit_after_trial: bool,
    /// Overrides the first trial's duration, seconds (0: until its stage moves are done).
    #[arg(long)]
    duration_s: Option<f64>,
    /// Overrides the data directory (relative: to the working directory).
    #[arg(long)]
    data_dir: Option<PathBuf>,
    /// Overrides the TCP endpoint (address:port).
    #[arg(long)]
    listen: Option<String>,
    /// Do not record trials.
    #[arg(long)]
    no_record: bool,
    /// Do not start the TCP server (nor the Foxglove server).
    #[arg(long)]
    no_server: bool,
    /// Overrides the Foxglove WebSocket endpoint (`[foxglove] listen`, address:port; port 0:
    /// any free port, said in the log).
    #[arg(long)]
    foxglove_listen: Option<String>,
    /// Do not start the Foxglove server, whatever `[foxglove]` says.
    #[arg(long)]
    no_foxglove: bool,
    /// Sample lines printed per second during a trial.
    #[arg(long, default_value_t = 4.0)]
    print_hz: f64,
    /// Print no sample lines (the log still goes to stderr, the summary to stdout).
    #[arg(long, short)]
    quiet: bool,
}

fn main() -> ExitCode {
    init_logging();
    let result = run(Args::parse());
    // The last lines out, but a stdout nobody reads cannot hold the exit.
    stdout_lines::stdout().flush(Duration::from_secs(1));
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            error!(target: "antennad", "{e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Leveled, timestamped log lines to stderr, filtered by `RUST_LOG` (default `info`); colours
/// only on a terminal. A failed write to stderr is dropped silently.
fn init_logging() {
    use tracing_subscriber::EnvFilter;
    let (filter, bad) = match std::env::var("RUST_LOG") {
        Ok(spec) => match EnvFilter::try_new(&spec) {
            Ok(filter) => (filter, None),
            Err(e) => (
                EnvFilter::new("info"),
                Some(format!("RUST_LOG={spec:?}: {e}")),
            ),
        },
        Err(_) => (EnvFilter::new("info"), None),
    };
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal())
        .log_internal_errors(false)
        .init();
    if let Some(bad) = bad {
        warn!(target: "antennad", "{bad}; logging at info");
    }
}

/// The command line's overrides of the configuration (applied again on a reload, so they do
/// not count as changes).
fn apply_overrides(config: &mut Config, args: &Args) {
    if let Some(dir) = &args.data_dir {
        config.data_dir.clone_from(dir);
    }
    if let Some(listen) = &args.listen {
        config.server.listen.clone_from(listen);
    }
    if let Some(listen) = &args.foxglove_listen {
        config.foxglove.listen.clone_from(listen);
    }
}

fn run(args: Args) -> Result<()> {
    let search = args
        .config_search_path
        .clone()
        .unwrap_or_else(ConfigSource::system_search_path);
    let source = ConfigSource::find(args.config.as_deref(), &search);
    let mut config = source.load()?;
    apply_overrides(&mut config, &args);
    info!(target: "antennad", "configuration: {source}; recordings under {}", config.data_dir.display());
    let first_trial_duration = match args.duration_s {
        Some(s) if s.is_finite() && s >= 0.0 => Some(Duration::from_secs_f64(s)),
        Some(s) => bail!("--duration-s must be finite and >= 0, got {s}"),
        None => None,
    };
    let first_trial = first_trial_for(&config, args.trial.clone(), args.idle);
    let waits_idle = first_trial.is_none() && !args.idle;
    let watchdog = Watchdog::from_env();
    if let Some(watchdog) = watchdog {
        info!(target: "antennad", "systemd watchdog: pinging every {} ms", watchdog.ping_every().as_millis());
    }
    let options = DaemonOptions {
        first_trial,
        first_trial_duration,
        exit_after_trial: args.exit_after_trial,
        record: !args.no_record,
        serve: !args.no_server,
        // As `[foxglove]` says: on for the simulated rig, off with hardware.
        foxglove: !args.no_foxglove,
        echo: !args.quiet,
        print_hz: args.print_hz,
        watchdog,
        ..DaemonOptions::default()
    };
    let running = config.clone();
    // Before the threads start, so no signal finds the default action (death) in place.
    let signals = signals::Flags::install()?;
    let daemon = Daemon::start(config, options)?;
    let out = stdout_lines::stdout();
    if daemon.token_generated() && daemon.local_addr().is_some() {
        // The one place a token is shown: generated for this run, printed once, at start.
        out.line(format!(
            "antennad: control token for this run (generated; shown only here): {}",
            daemon.token()
        ));
    }
    if waits_idle {
        info!(
            target: "antennad",
            "hardware configured: no trial starts by itself; waiting idle for a client's \
             start_trial (or give --trial NAME)"
        );
    }
    let mut status = service_status(&daemon);
    notify("READY=1", systemd::notify_ready(&status));
    if !args.exit_after_trial {
        info!(
            target: "antennad",
            "serving until SIGTERM or Ctrl-C (SIGHUP re-reads the configuration); start another \
             trial with a start_trial command"
        );
    }
    let mut stdout_error_logged = false;
    let stopped_by = loop {
        if daemon.is_finished() {
            break None;
        }
        if let Some(signal) = signals.stop() {
            break Some(signal);
        }
        if signals.take_hangup() {
            reload(&source, &args, &running, &daemon);
        }
        let now = service_status(&daemon);
        if now != status {
            status = now;
            notify("STATUS=", systemd::notify_status(&status));
        }
        if !stdout_error_logged && let Some(e) = out.error() {
            stdout_error_logged = true;
            warn!(target: "antennad", "stdout: {e}; sample lines are dropped from now on, the daemon goes on");
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let summary = match stopped_by {
        None => {
            notify(
                "STOPPING=1",
                systemd::notify_stopping("stopping: the trial ended"),
            );
            daemon.wait()?
        }
        Some(signal) => {
            info!(target: "antennad", "{signal} received, stopping");
            notify(
                "STOPPING=1",
                systemd::notify_stopping(&format!("stopping on {signal}")),
            );
            daemon.shutdown()?
        }
    };
    // The summary is the run's result: stdout, with the sample lines.
    out.line(format!(
        "antennad: {} polls in {:.2} s ({} deadlines skipped, latest wake-up {} us late), \
         {} trials, {} events dropped",
        summary.polls,
        summary.elapsed.as_secs_f64(),
        summary.skipped,
        summary.max_lateness.as_micros(),
        summary.trials.len(),
        summary.dropped
    ));
    for (address, health) in summary
        .health
        .iter()
        .enumerate()
        .filter(|(_, h)| !h.all_ok())
    {
        out.line(format!("  segment #{address}: {health:?}"));
    }
    Ok(())
}

/// What `systemctl status` shows.
fn service_status(daemon: &DaemonHandle) -> String {
    match daemon.trial() {
        Some(trial) => format!("polling; trial {trial:?} running"),
        None => "polling; no trial running".to_owned(),
    }
}

/// Logs a failed notification (only under a service manager: elsewhere they are no-ops).
fn notify(what: &str, result: std::io::Result<()>) {
    if let Err(e) = result {
        warn!(target: "antennad", "telling systemd {what} failed: {e}");
    }
}

/// SIGHUP: re-reads the configuration and logs what differs from the running one. Nothing
/// is applied: the bus, the devices, the server and the trials stay as they started.
fn reload(source: &ConfigSource, args: &Args, running: &Config, daemon: &DaemonHandle) {
    let trial = daemon.trial().map_or_else(
        || "no trial running".to_owned(),
        |t| format!("trial {t:?} running"),
    );
    if source.path().is_none() {
        info!(target: "antennad", "SIGHUP: {source}: nothing to re-read ({trial})");
        return;
    }
    match source.load() {
        Err(e) => warn!(
            target: "antennad",
            "SIGHUP: {e}; the running configuration stays ({trial})"
        ),
        Ok(mut reread) => {
            apply_overrides(&mut reread, args);
            let keys = changed_keys(running, &reread);
            if keys.is_empty() {
                info!(target: "antennad", "SIGHUP: {source} re-read: unchanged ({trial})");
            } else {
                warn!(
                    target: "antennad",
                    "SIGHUP: {source} re-read: {} key(s) differ from the running configuration: \
                     {}; they take effect at the next start (systemctl restart antennad), \
                     nothing was changed now ({trial})",
                    keys.len(),
                    keys.join(", ")
                );
            }
        }
    }
}

/// SIGTERM and SIGINT stop the daemon cleanly (the running trial's file is finalized); SIGHUP
/// asks for a reload. Each only raises a flag (`signal-hook`).
#[cfg(target_os = "linux")]
mod signals {
    use anyhow::{Context, Result};
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};

    pub struct Flags {
        term: Arc<AtomicBool>,
        int: Arc<AtomicBool>,
        hup: Arc<AtomicBool>,
    }

    impl Flags {
        pub fn install() -> Result<Self> {
            let flags = Self {
                term: Arc::new(AtomicBool::new(false)),
                int: Arc::new(AtomicBool::new(false)),
                hup: Arc::new(AtomicBool::new(false)),
            };
            for (signal, flag) in [
                (SIGTERM, &flags.term),
                (SIGINT, &flags.int),
                (SIGHUP, &flags.hup),
            ] {
                signal_hook::flag::register(signal, Arc::clone(flag))
                    .with_context(|| format!("installing the handler of signal {signal}"))?;
            }
            Ok(flags)
        }

        /// The stop signal received, if one was.
        pub fn stop(&self) -> Option<&'static str> {
            if self.term.load(Ordering::Relaxed) {
                Some("SIGTERM")
            } else if self.int.load(Ordering::Relaxed) {
                Some("SIGINT")
            } else {
                None
            }
        }

        /// Whether a SIGHUP came since the last call.
        pub fn take_hangup(&self) -> bool {
            self.hup.swap(false, Ordering::Relaxed)
        }
    }
}

/// Elsewhere the default signal handling applies.
#[cfg(not(target_os = "linux"))]
mod signals {
    pub struct Flags;

    impl Flags {
        pub fn install() -> anyhow::Result<Self> {
            Ok(Self)
        }
        pub fn stop(&self) -> Option<&'static str> {
            None
        }
        pub fn take_hangup(&self) -> bool {
            false
        }
    }
}
