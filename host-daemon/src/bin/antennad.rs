//! `antennad`: the antenna host daemon, a thin shell around [`host_daemon::daemon::Daemon`].
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

use anyhow::{Result, bail};
use clap::Parser;
use host_daemon::config::Config;
use host_daemon::daemon::{Daemon, DaemonOptions, first_trial_for};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

/// The antenna host daemon: polls the segments (by default on the simulated rig), streams
/// them over TCP, runs trials and records each to MCAP.
#[derive(Debug, Parser)]
#[command(version, about)]
struct Args {
    /// Configuration file (TOML; see host-daemon/config/). Default: the simulated rig.
    #[arg(long)]
    config: Option<PathBuf>,
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
    /// Overrides the data directory.
    #[arg(long)]
    data_dir: Option<PathBuf>,
    /// Overrides the TCP endpoint (address:port).
    #[arg(long)]
    listen: Option<String>,
    /// Do not record trials.
    #[arg(long)]
    no_record: bool,
    /// Do not start the TCP server.
    #[arg(long)]
    no_server: bool,
    /// Sample lines printed per second during a trial.
    #[arg(long, default_value_t = 4.0)]
    print_hz: f64,
}

fn main() -> ExitCode {
    match run(Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("antennad: {error:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: Args) -> Result<()> {
    let mut config = match &args.config {
        Some(path) => Config::from_file(path)?,
        None => Config::default(),
    };
    if let Some(dir) = &args.data_dir {
        config.data_dir.clone_from(dir);
    }
    if let Some(listen) = &args.listen {
        config.server.listen.clone_from(listen);
    }
    let first_trial_duration = match args.duration_s {
        Some(s) if s.is_finite() && s >= 0.0 => Some(Duration::from_secs_f64(s)),
        Some(s) => bail!("--duration-s must be finite and >= 0, got {s}"),
        None => None,
    };
    let first_trial = first_trial_for(&config, args.trial.clone(), args.idle);
    let waits_idle = first_trial.is_none() && !args.idle;
    let options = DaemonOptions {
        first_trial,
        first_trial_duration,
        exit_after_trial: args.exit_after_trial,
        record: !args.no_record,
        serve: !args.no_server,
        echo: true,
        print_hz: args.print_hz,
        ..DaemonOptions::default()
    };
    let daemon = Daemon::start(config, options)?;
    if daemon.token_generated() && daemon.local_addr().is_some() {
        // The one place a token is shown: generated for this run, printed once, at start.
        println!(
            "antennad: control token for this run (generated; shown only here): {}",
            daemon.token()
        );
    }
    if waits_idle {
        println!(
            "antennad: hardware configured: no trial starts by itself; waiting idle for a \
             client's start_trial (or give --trial NAME)"
        );
    }
    if !args.exit_after_trial {
        println!(
            "antennad: serving until interrupted (Ctrl-C); start another trial with a start_trial command"
        );
    }
    signals::install();
    while !daemon.is_finished() && !signals::received() {
        std::thread::sleep(Duration::from_millis(50));
    }
    let summary = if daemon.is_finished() {
        daemon.wait()?
    } else {
        println!("antennad: interrupted, stopping");
        daemon.shutdown()?
    };
    println!(
        "antennad: {} polls in {:.2} s ({} deadlines skipped, latest wake-up {} us late), \
         {} trials, {} events dropped",
        summary.polls,
        summary.elapsed.as_secs_f64(),
        summary.skipped,
        summary.max_lateness.as_micros(),
        summary.trials.len(),
        summary.dropped
    );
    for (address, health) in summary
        .health
        .iter()
        .enumerate()
        .filter(|(_, h)| !h.all_ok())
    {
        println!("  segment #{address}: {health:?}");
    }
    Ok(())
}

/// SIGINT and SIGTERM end the daemon cleanly (the running trial's file is finalized).
#[cfg(target_os = "linux")]
mod signals {
    use std::sync::atomic::{AtomicBool, Ordering};

    static RECEIVED: AtomicBool = AtomicBool::new(false);

    extern "C" fn on_signal(_: libc::c_int) {
        RECEIVED.store(true, Ordering::Relaxed);
    }

    pub fn install() {
        let handler = on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
        // SAFETY: the handler only stores to an atomic, which is async-signal-safe.
        unsafe {
            libc::signal(libc::SIGINT, handler);
            libc::signal(libc::SIGTERM, handler);
        }
    }

    pub fn received() -> bool {
        RECEIVED.load(Ordering::Relaxed)
    }
}

/// Elsewhere the default signal handling applies.
#[cfg(not(target_os = "linux"))]
mod signals {
    pub fn install() {}
    pub fn received() -> bool {
        false
    }
}
