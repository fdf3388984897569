//! The daemon as a service: [`Daemon::start`] wires the bus, the rig, the TCP server and the
//! recorder from a [`Config`] and returns a [`DaemonHandle`]; the `antennad` binary is a thin
//! shell around it, and other crates' tests can run a real antennad in-process.
//!
//! # What runs
//!
//! - **Acquisition and streaming run continuously**, from start to shutdown, on one clock
//!   (`t_ns` in the stream is time since the daemon started): the polling thread reads every
//!   segment on absolute deadlines; the motion thread (`motion.rs`, running the trial script
//!   of `trial_script.rs`) homes the stage against its limit switch before any move, samples
//!   the stage and the base at their own rates and carries out motion commands; the hub
//!   thread publishes every poll to the TCP clients, keeps per-segment health and sends a
//!   `status` line every second and on every change.
//! - **A trial is a recorded window with its script**: `start_trial` (or the first trial, at
//!   start) opens `<data_dir>/<name>.mcap`, runs the trial's base angle and stage moves, and
//!   records every poll, stage and base sample until its duration has passed (duration 0:
//!   until its moves are done), `stop_trial` or `stop_all`, or until its stage loses its home
//!   (a power cycle) or vanishes for 2 s with moves left; then the file is finalized. Only
//!   one trial runs at a time; with hardware none starts by itself ([`first_trial_for`]).
//!
//! # Control rule
//!
//! `move_stage` and `set_base_angle` are carried out when no trial runs, and refused with the
//! reason while one does: the trial's script owns the stage and the base, so a recording
//! always shows the motion its metadata describes. `stop_trial` and `stop_all` always work;
//! `stop_all` needs no token, kills the stage motion at once (the VXM's `K`, written from the
//! client's thread through a second handle on the port, so never behind a query the motion
//! thread waits on) ahead of any command queued before it, and ends any trial. Whatever a trial or a client asks, the stage
//! never goes beyond the soft limits (the move is refused and nothing moves), nor faster than
//! `stage.max_speed_mm_per_s`, and the base angle never leaves the servo's calibrated range.
//!
//! # Recording
//!
//! A trial's file (`antenna_data::record`) takes the `[recording]` options (compression, the
//! sync interval), its messages' log times are Unix-epoch nanoseconds, its metadata keeps the
//! configuration without the token ([`Config::to_recorded_toml`]) and the rig. Free space
//! under the data directory is checked before a trial and every second during one
//! ([`crate::service::free_space`]): below `recording.min_free_mb` a trial is refused, or ends with the
//! reason recorded; polling and streaming go on. Every file ends with `trial ended: <why>`.
//!
//! # Example
//!
//! ```no_run
//! use host_daemon::service::config::Config;
//! use host_daemon::service::daemon::{Daemon, DaemonOptions};
//!
//! let mut config = Config::default();
//! config.server.listen = "127.0.0.1:0".to_owned();
//! let daemon = Daemon::start(config, DaemonOptions::default())?;
//! println!("stream on {:?}", daemon.local_addr());
//! // A generated token (none configured) is for the operator: antennad prints it once.
//! assert!(daemon.token_generated());
//! let summary = daemon.shutdown()?;
//! println!("{} polls", summary.polls);
//! # Ok::<(), anyhow::Error>(())
//! ```

use crate::config::Config;
use crate::hardware::poll::SegmentHealth;
use crate::net::ControlToken;
use crate::service::acquisition::AcquisitionEvent;
use crate::service::clock::TrialClock;
use crate::service::free_space::{FreeSpace, StatvfsFreeSpace};
use crate::service::systemd::Watchdog;
use antenna_data::record::RecordCounts;
use anyhow::{Result, anyhow};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

mod control;
mod hub;
mod log;
mod recording;
mod rig_info;
mod start;
mod trial;

use log::Log;
pub use rig_info::rig_info;

/// How long a control request waits for the daemon's threads to answer.
const CONTROL_TIMEOUT: Duration = Duration::from_secs(5);
/// Log lines kept for [`DaemonHandle::log_lines`].
const LOG_LINES_KEPT: usize = 4000;
/// How long a stopping daemon waits for its polling thread (at least; longer if the
/// watchdog's bound is longer) before leaving it behind in a transfer that does not return.
const POLL_THREAD_STOP_WAIT: Duration = Duration::from_secs(1);

/// How [`Daemon::start`] runs the daemon.
#[derive(Debug, Clone)]
pub struct DaemonOptions {
    /// Start a trial at once: `Some(None)` the configuration's first trial, `Some(Some(name))`
    /// the one called `name`, `None` none (wait for `start_trial`); see [`first_trial_for`]
    /// for antennad's rule. Its stage moves wait until the stage is homed.
    pub first_trial: Option<Option<String>>,
    /// Overrides the first trial's duration (zero: until its moves are done).
    pub first_trial_duration: Option<Duration>,
    /// Stop the daemon when the first trial has ended.
    pub exit_after_trial: bool,
    /// Record trials to `<data_dir>/<trial>.mcap`.
    pub record: bool,
    /// Start the TCP server on `server.listen`.
    pub serve: bool,
    /// With [`Self::serve`], start the Foxglove server on `foxglove.listen` when the
    /// configuration turns it on ([`Config::foxglove_enabled`]). `antennad` sets it; off by
    /// default here, so that daemons started in-process (tests, the monitor's) do not all
    /// reach for the same port.
    pub foxglove: bool,
    /// Print sample lines to stdout during a trial ([`crate::service::stdout_lines::stdout`]: a
    /// closed or stalled stdout costs lines, never the daemon). The log goes to `tracing`
    /// either way (target `antennad`), and is kept ([`DaemonHandle::log_lines`]).
    pub echo: bool,
    /// Sample lines printed per second during a trial (with `echo`).
    pub print_hz: f64,
    /// Ping the service manager's watchdog from the hub thread (see [`crate::service::systemd`]).
    pub watchdog: Option<Watchdog>,
    /// Capacity of the acquisition event queue.
    pub queue: usize,
    /// Where free space under the data directory is learnt (the file system's count by
    /// default; tests give a fake one).
    pub free_space: Arc<dyn FreeSpace>,
    /// Sees every acquisition event as the hub takes it, in order (tests and benches watch
    /// a trial through it); `None` by default.
    pub on_event: Option<EventTap>,
}

/// A function handed every acquisition event on the hub thread
/// ([`DaemonOptions::on_event`]); it must be quick, as the hub waits for it.
#[derive(Clone)]
pub struct EventTap(pub Arc<dyn Fn(&AcquisitionEvent) + Send + Sync>);

impl EventTap {
    /// A tap calling `f`.
    pub fn new(f: impl Fn(&AcquisitionEvent) + Send + Sync + 'static) -> Self {
        Self(Arc::new(f))
    }
}

impl std::fmt::Debug for EventTap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("EventTap(..)")
    }
}

impl Default for DaemonOptions {
    /// No trial at start, recording, serving, quiet.
    fn default() -> Self {
        Self {
            first_trial: None,
            first_trial_duration: None,
            exit_after_trial: false,
            record: true,
            serve: true,
            foxglove: false,
            echo: false,
            print_hz: 4.0,
            watchdog: None,
            queue: 16_384,
            free_space: Arc::new(StatvfsFreeSpace),
            on_event: None,
        }
    }
}

impl DaemonOptions {
    /// One run of the configuration's first trial, watched through `on_event` alone: no
    /// recording, no TCP server, exiting when the trial ends (`duration` of zero: when its
    /// stage moves are done). What the tests and the benchmarks (`examples/`) run the daemon
    /// with.
    pub fn tapped_trial(duration: Duration, on_event: EventTap) -> Self {
        Self {
            first_trial: Some(None),
            first_trial_duration: Some(duration),
            exit_after_trial: true,
            record: false,
            serve: false,
            queue: 8192,
            on_event: Some(on_event),
            ..Self::default()
        }
    }
}

/// The trial antennad starts by itself ([`DaemonOptions::first_trial`]): none if `idle`;
/// the one called `named` if given (after homing, with hardware); otherwise the
/// configuration's first trial on the simulated rig only. With any hardware configured
/// ([`Config::has_hardware`]) nothing starts by itself: a restart (systemd's `Restart=`, a
/// crash, a power blip) must not drive the stage from wherever it is; antennad waits idle for
/// a client's `start_trial`.
pub fn first_trial_for(
    config: &Config,
    named: Option<String>,
    idle: bool,
) -> Option<Option<String>> {
    match (idle, named) {
        (true, _) => None,
        (false, Some(name)) => Some(Some(name)),
        (false, None) if config.has_hardware() => None,
        (false, None) => Some(None),
    }
}

/// One trial the daemon ran.
#[derive(Debug, Clone, PartialEq)]
pub struct TrialOutcome {
    /// Its name.
    pub name: String,
    /// Its recording, if recorded.
    pub path: Option<PathBuf>,
    /// Messages recorded.
    pub recorded: RecordCounts,
    /// Why it ended.
    pub ended: String,
}

/// What the daemon did, from start to shutdown.
#[derive(Debug, Clone, PartialEq)]
pub struct DaemonSummary {
    /// Polls made.
    pub polls: u64,
    /// Poll deadlines skipped.
    pub skipped: u64,
    /// The latest poll wake-up after its deadline.
    pub max_lateness: Duration,
    /// Health per segment.
    pub health: Vec<SegmentHealth>,
    /// Acquisition events dropped because the hub fell behind (should be 0).
    pub dropped: u64,
    /// The polling thread was still stuck (in a bus transfer that did not return) when the
    /// daemon stopped: it was left behind, the recording finalized without it, and the
    /// counts above are what the hub had seen.
    pub poll_thread_stuck: bool,
    /// The trials, in order.
    pub trials: Vec<TrialOutcome>,
    /// Stage moves started, over every trial's script.
    pub moves_started: usize,
    /// Stage moves refused (beyond the soft limits, not homed...), over every trial's script.
    pub moves_refused: usize,
    /// How long the daemon ran.
    pub elapsed: Duration,
}

/// The daemon (see the module documentation).
#[derive(Debug, Clone, Copy, Default)]
pub struct Daemon;

/// A running daemon. Dropping it shuts it down (finalizing a running trial's file).
#[derive(Debug)]
pub struct DaemonHandle {
    local_addr: Option<SocketAddr>,
    foxglove_addr: Option<SocketAddr>,
    token: ControlToken,
    token_generated: bool,
    stop: Arc<AtomicBool>,
    hub: Option<JoinHandle<Result<DaemonSummary>>>,
    log: Log,
    trial: Arc<Mutex<Option<String>>>,
    clock: TrialClock,
}

impl DaemonHandle {
    /// The daemon's clock: every `t_ns` it streams and records (a poll's, an estimate's
    /// `estimated_ns`) is [`TrialClock::elapsed_ns`] of it, so an in-process client reads
    /// latencies on the same clock.
    pub fn clock(&self) -> TrialClock {
        self.clock
    }

    /// The TCP endpoint actually bound (`None` without a server).
    pub fn local_addr(&self) -> Option<SocketAddr> {
        self.local_addr
    }

    /// The Foxglove WebSocket endpoint actually bound (`None` when no Foxglove server runs).
    pub fn foxglove_addr(&self) -> Option<SocketAddr> {
        self.foxglove_addr
    }

    /// The control token (the configured one, or the one generated at start).
    pub fn token(&self) -> &str {
        self.token.expose()
    }

    /// Whether the token was generated at start (none was configured): `antennad` then
    /// prints it once.
    pub fn token_generated(&self) -> bool {
        self.token_generated
    }

    /// The trial running now, if any.
    pub fn trial(&self) -> Option<String> {
        self.trial.lock().ok().and_then(|t| t.clone())
    }

    /// Whether the daemon has stopped on its own (after its trial with `exit_after_trial`, or
    /// a fatal error).
    pub fn is_finished(&self) -> bool {
        self.hub.as_ref().is_none_or(JoinHandle::is_finished)
    }

    /// The log so far (the last few thousand lines), oldest first.
    pub fn log_lines(&self) -> Vec<String> {
        self.log.lines()
    }

    /// Waits until the daemon stops on its own (see [`DaemonHandle::is_finished`]).
    pub fn wait(mut self) -> Result<DaemonSummary> {
        self.join()
    }

    /// Stops the daemon: ends any trial (its file finalized), stops the stage, the threads
    /// and the servers.
    pub fn shutdown(mut self) -> Result<DaemonSummary> {
        self.stop.store(true, Ordering::Relaxed);
        self.join()
    }

    fn join(&mut self) -> Result<DaemonSummary> {
        let hub = self
            .hub
            .take()
            .ok_or_else(|| anyhow!("the daemon was already joined"))?;
        hub.join()
            .map_err(|_| anyhow!("the daemon's hub thread panicked"))?
    }
}

impl Drop for DaemonHandle {
    fn drop(&mut self) {
        if self.hub.is_some() {
            self.stop.store(true, Ordering::Relaxed);
            let _ = self.join();
        }
    }
}
