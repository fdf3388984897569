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

use crate::hardware::poll::{PollError, Poller, SegmentHealth};
use crate::hardware::vxm::VxmKill;
use crate::net::{ControlHandler, ControlToken, ServerLog, ServerOptions, StreamServer};
use crate::service::acquisition::{
    AcquisitionEvent, EventSender, FirmwareReading, HealthChange, PollRecord, PollSettings, Shared,
    event_channel, spawn_watched_poller,
};
use crate::service::clock::TrialClock;
use crate::service::config::{Config, SimFaultKind};
use crate::service::free_space::{FreeSpace, StatvfsFreeSpace};
use crate::service::motion::{
    MotionCommand, MotionShared, MoveTarget, Reply, RigStatus, spawn_motion,
};
use crate::service::rig::DaemonRig;
use crate::service::samples::{record_sample, stream_sample};
use crate::service::systemd::Watchdog;
use crate::service::trial_script::ScriptEnds;
use crate::service::watchdog::{PollHeartbeat, PollWatchdog, WatchdogEvent, stall_bound};
use crate::sim::rig::{SimState, sense, sim_bus};
use crate::{SegmentFault, SimBus};
use antenna_data::record::{
    LogMessage, RecordCounts, SegmentsMessage, ServoMessage, StageMessage, TrialMetadata,
    TrialRecorder,
};
use antenna_data::stream::{
    ControlCommand, PollingStatus, RigInfo, RigWall, SegmentStatus, StageTarget, StreamMessage,
};
use antenna_protocol::{Calibration, FIRMWARE_VERSION, StatusFlags};
use anyhow::{Context, Result, anyhow, bail};
use std::collections::{BTreeMap, VecDeque};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel, sync_channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

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
            echo: false,
            print_hz: 4.0,
            watchdog: None,
            queue: 16_384,
            free_space: Arc::new(StatvfsFreeSpace),
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
    token: ControlToken,
    token_generated: bool,
    stop: Arc<AtomicBool>,
    hub: Option<JoinHandle<Result<DaemonSummary>>>,
    log: Log,
    trial: Arc<Mutex<Option<String>>>,
}

impl DaemonHandle {
    /// The TCP endpoint actually bound (`None` without a server).
    pub fn local_addr(&self) -> Option<SocketAddr> {
        self.local_addr
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
    /// and the server.
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

/// Lines for humans: logged through `tracing` (target `antennad`, at the level given) and
/// kept; sample lines go to stdout instead, if asked (`echo`), and are kept too.
#[derive(Debug, Clone)]
struct Log {
    echo: bool,
    lines: Arc<Mutex<VecDeque<String>>>,
}

impl Log {
    /// An informational line.
    fn line(&self, text: String) {
        tracing::info!(target: "antennad", "{}", Self::message(&text));
        self.keep(text);
    }

    /// Something is wrong, and the daemon goes on (a segment gone stale, a disk filling up).
    fn warn(&self, text: String) {
        tracing::warn!(target: "antennad", "{}", Self::message(&text));
        self.keep(text);
    }

    /// Something failed (a recording).
    fn error(&self, text: String) {
        tracing::error!(target: "antennad", "{}", Self::message(&text));
        self.keep(text);
    }

    /// A sample line (or the table's header): data, for stdout.
    fn sample(&self, text: String) {
        if self.echo {
            crate::service::stdout_lines::stdout().line(text.as_str());
        }
        self.keep(text);
    }

    /// `text` as a log message: the logger names the target (`antennad`) itself.
    fn message(text: &str) -> &str {
        let text = text.trim_start();
        text.strip_prefix("antennad: ").unwrap_or(text)
    }

    fn keep(&self, text: String) {
        if let Ok(mut lines) = self.lines.lock() {
            if lines.len() >= LOG_LINES_KEPT {
                lines.pop_front();
            }
            lines.push_back(text);
        }
    }

    fn lines(&self) -> Vec<String> {
        self.lines
            .lock()
            .map(|l| l.iter().cloned().collect())
            .unwrap_or_default()
    }
}

enum HubRequest {
    Start {
        name: String,
        metadata: BTreeMap<String, String>,
        reply: Reply,
    },
    Stop {
        why: &'static str,
        reply: Reply,
    },
}

fn ask<T>(sender: &Sender<T>, make: impl FnOnce(Reply) -> T) -> Result<String, String> {
    let (reply, answer) = sync_channel(1);
    sender
        .send(make(reply))
        .map_err(|_| "the daemon is shutting down".to_owned())?;
    answer
        .recv_timeout(CONTROL_TIMEOUT)
        .map_err(|_| "the daemon did not answer in time".to_owned())?
}

/// The control commands, from any client thread.
struct DaemonControl {
    hub: Mutex<Sender<HubRequest>>,
    motion: Mutex<Sender<MotionCommand>>,
    trial: Arc<Mutex<Option<String>>>,
    max_speed_mm_per_s: f64,
    /// Set by `stop_all` before its command is queued: the motion thread stops before it
    /// carries out anything else, and cancels the moves queued ahead of the stop.
    stop_pending: Arc<AtomicBool>,
    /// The VXM's kill line: `stop_all` sends `K` through it from the client's thread first,
    /// so the kill never waits behind a query the motion thread is waiting on.
    stage_kill: Option<VxmKill>,
}

impl DaemonControl {
    fn hub(&self) -> Result<Sender<HubRequest>, String> {
        self.hub
            .lock()
            .map(|s| s.clone())
            .map_err(|_| "the daemon is shutting down".to_owned())
    }

    fn motion(&self) -> Result<Sender<MotionCommand>, String> {
        self.motion
            .lock()
            .map(|s| s.clone())
            .map_err(|_| "the daemon is shutting down".to_owned())
    }

    fn refuse_during_trial(&self, what: &str) -> Result<(), String> {
        match self.trial.lock().ok().and_then(|t| t.clone()) {
            Some(name) => Err(format!(
                "{what} refused: trial {name:?} is running and its script drives the stage and \
                 the base; send stop_trial (or stop_all) first"
            )),
            None => Ok(()),
        }
    }
}

impl ControlHandler for DaemonControl {
    fn handle(&self, command: ControlCommand) -> Result<String, String> {
        match command {
            ControlCommand::StartTrial { name, metadata } => {
                ask(&self.hub()?, |reply| HubRequest::Start {
                    name,
                    metadata,
                    reply,
                })
            }
            ControlCommand::StopTrial => ask(&self.hub()?, |reply| HubRequest::Stop {
                why: "stop_trial",
                reply,
            }),
            ControlCommand::MoveStage {
                target,
                speed_m_per_s,
            } => {
                self.refuse_during_trial("move_stage")?;
                let speed_mm_per_s =
                    speed_m_per_s.map_or(self.max_speed_mm_per_s / 2.0, |v| v * 1e3);
                if speed_mm_per_s > self.max_speed_mm_per_s {
                    return Err(format!(
                        "move_stage refused: {speed_mm_per_s} mm/s is faster than \
                         stage.max_speed_mm_per_s = {} mm/s",
                        self.max_speed_mm_per_s
                    ));
                }
                let target = match target {
                    StageTarget::Absolute { position_m } => MoveTarget::To(position_m * 1e3),
                    StageTarget::Relative { distance_m } => MoveTarget::By(distance_m * 1e3),
                };
                ask(&self.motion()?, |reply| MotionCommand::Move {
                    target,
                    speed_mm_per_s,
                    reply,
                })
            }
            ControlCommand::SetBaseAngle { angle_deg } => {
                self.refuse_during_trial("set_base_angle")?;
                ask(&self.motion()?, |reply| MotionCommand::SetBase {
                    angle_deg,
                    reply,
                })
            }
            ControlCommand::StopAll => {
                if let Some(kill) = &self.stage_kill {
                    // Best effort: the motion thread kills again through the driver.
                    let _ = kill.kill();
                }
                self.stop_pending.store(true, Ordering::SeqCst);
                let stopped = ask(&self.motion()?, |reply| MotionCommand::StopAll { reply });
                let ended = ask(&self.hub()?, |reply| HubRequest::Stop {
                    why: "stop_all",
                    reply,
                });
                let stopped = stopped?;
                Ok(match ended {
                    Ok(ended) => format!("{stopped}; {ended}"),
                    Err(_) => format!("{stopped}; no trial was running"),
                })
            }
        }
    }
}

/// Unix-epoch nanoseconds of `clock`'s origin (the wall clock now, less the time since it).
fn unix_origin_ns(clock: TrialClock) -> u64 {
    let now_ns = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX));
    now_ns.saturating_sub(clock.elapsed_ns())
}

/// `text` with every occurrence of the token replaced: what a client asks to record never
/// carries it into a file.
fn scrub(text: &str, token: &ControlToken) -> String {
    text.replace(token.expose(), "<redacted>")
}

/// How often the free space under the data directory is looked at during a trial.
const FREE_SPACE_CHECK: Duration = Duration::from_secs(1);

/// `<dir>/<name>.mcap`, or `<dir>/<name>-2.mcap` and so on if it exists.
fn free_path(dir: &Path, name: &str) -> PathBuf {
    let first = dir.join(format!("{name}.mcap"));
    if !first.exists() {
        return first;
    }
    (2u32..)
        .map(|k| dir.join(format!("{name}-{k}.mcap")))
        .find(|p| !p.exists())
        .unwrap_or(first)
}

/// What the polling thread reports when it stops: polls, deadlines skipped, the latest
/// wake-up, health per segment.
type PollTotals = (u64, u64, Duration, Vec<SegmentHealth>);

/// Waits at most the given time for the polling thread to stop: `None` if it has not (stuck
/// in a bus transfer; it is then left behind, not joined).
type PollJoin = Box<dyn FnOnce(Duration) -> Result<Option<PollTotals>> + Send>;

/// A [`PollJoin`] for the polling thread `handle`.
fn bounded_join<I: Send + 'static>(
    handle: JoinHandle<crate::service::acquisition::PollReport<I>>,
) -> PollJoin {
    Box::new(move |bound: Duration| {
        let deadline = Instant::now() + bound;
        while !handle.is_finished() {
            if Instant::now() >= deadline {
                // Dropping the handle detaches the thread: it stays in its transfer.
                return Ok(None);
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        let r = handle
            .join()
            .map_err(|_| anyhow!("the polling thread panicked"))?;
        Ok(Some((r.polls, r.skipped, r.max_lateness, r.health)))
    })
}

impl Daemon {
    /// Starts the daemon of `config`: opens the bus (`bus.device`), the stage and the servo,
    /// binds the TCP server, starts the threads and, if asked, the first trial. Every error
    /// names the configuration key or the file at fault.
    pub fn start(config: Config, options: DaemonOptions) -> Result<DaemonHandle> {
        if !(options.print_hz.is_finite() && options.print_hz > 0.0) {
            bail!("the print rate must be positive, got {}", options.print_hz);
        }
        if let Some(name) = &options.first_trial
            && config.trial(name.as_deref()).is_none()
        {
            bail!(
                "no trial {:?} in the configuration (trials: {})",
                name.as_deref().unwrap_or("(first)"),
                trial_names(&config)
            );
        }
        let log = Log {
            echo: options.echo,
            lines: Arc::new(Mutex::new(VecDeque::new())),
        };
        let token_generated = config.server.token.is_none();
        let token = match config.server.token.clone() {
            Some(token) => token,
            None => ControlToken::generate().context("generating the control token")?,
        };
        let addresses = config.bus.addresses();
        let clock = TrialClock::start();
        let stop_threads = Arc::new(AtomicBool::new(false));
        let (events, receiver) = event_channel(options.queue);

        // The bus first (polling starts), then the stage and servo: a missing device fails
        // before anything is sent to the others.
        let sim_state: Option<Shared<SimState>> = config
            .bus
            .is_sim()
            .then(|| Arc::new(Mutex::new(SimState::default())));
        let settings = PollSettings {
            period: Duration::from_secs_f64(1.0 / config.bus.poll_hz),
            counter_check_every: config.bus.counter_check_every,
            spin: Duration::from_micros(config.bus.spin_us),
            realtime_priority: config.bus.realtime_priority,
        };
        let heartbeat = Arc::new(PollHeartbeat::new(clock.elapsed_ns()));
        let (poll_join, bus_description) = match &sim_state {
            Some(state) => {
                let handle = spawn_watched_poller(
                    Poller::new(sim_bus(&config)?, &addresses),
                    clock,
                    settings,
                    sense_with_faults(sense(Arc::clone(state)), &config),
                    events.clone(),
                    Arc::clone(&stop_threads),
                    Arc::clone(&heartbeat),
                )
                .context("starting the polling thread")?;
                (
                    bounded_join(handle),
                    "simulated rig (virtual I2C bus)".to_owned(),
                )
            }
            None => hardware_poller(
                &config,
                &addresses,
                clock,
                settings,
                &events,
                (&stop_threads, &heartbeat),
            )?,
        };
        // However the daemon stops, it waits this long for the polling thread, not forever.
        let poll_join_bound = stall_bound(settings.period).max(POLL_THREAD_STOP_WAIT);
        let rig = match DaemonRig::open(&config, sim_state.clone()) {
            Ok(rig) => rig,
            Err(e) => {
                stop_threads.store(true, Ordering::Relaxed);
                let _ = poll_join(poll_join_bound);
                return Err(e);
            }
        };
        let rig_description = format!("{}, {}", rig.stage_description(), rig.servo_description());
        let rig_status = Arc::new(RigStatus::default());
        let stage_kill = rig.stage_kill();

        let (motion_tx, motion_rx) = channel();
        let (hub_tx, hub_rx) = channel();
        let trial_state = Arc::new(Mutex::new(None));
        let script_ends = Arc::new(ScriptEnds::default());
        let stop_pending = Arc::new(AtomicBool::new(false));
        let motion = spawn_motion(
            rig,
            clock,
            (
                Duration::from_secs_f64(1.0 / config.stage.sample_hz),
                Duration::from_secs_f64(1.0 / config.servo.sample_hz),
            ),
            events.clone(),
            MotionShared {
                commands: motion_rx,
                stop_pending: Arc::clone(&stop_pending),
                stop: Arc::clone(&stop_threads),
                status: Arc::clone(&rig_status),
                script_ends: Arc::clone(&script_ends),
            },
        )
        .context("starting the motion thread")?;

        let server = if options.serve {
            let handler = Arc::new(DaemonControl {
                hub: Mutex::new(hub_tx),
                motion: Mutex::new(motion_tx.clone()),
                trial: Arc::clone(&trial_state),
                max_speed_mm_per_s: config.stage.max_speed_mm_per_s,
                stop_pending: Arc::clone(&stop_pending),
                stage_kill,
            });
            let server_log = log.clone();
            let server_options = ServerOptions {
                segment_addresses: addresses.clone(),
                rig: Some(rig_info(&config)),
                max_clients: config.server.max_clients,
                max_clients_per_peer: config.server.max_clients_per_peer,
                log: ServerLog::new(move |line| server_log.line(format!("antennad: {line}"))),
                ..ServerOptions::default()
            };
            match StreamServer::bind_with(
                config.server.listen.as_str(),
                token.clone(),
                handler,
                server_options,
            ) {
                Ok(server) => Some(server),
                Err(e) => {
                    stop_threads.store(true, Ordering::Relaxed);
                    let _ = motion.join();
                    let _ = poll_join(poll_join_bound);
                    return Err(anyhow!(e)).context(format!(
                        "`server.listen` = {:?}: starting the TCP server",
                        config.server.listen
                    ));
                }
            }
        } else {
            None
        };
        let local_addr = server.as_ref().map(StreamServer::local_addr);
        let first = &addresses[0];
        let last = &addresses[addresses.len() - 1];
        log.line(format!(
            "antennad: {bus_description}; {} segments at {first:#04x}..={last:#04x}, polling at \
             {} Hz ({}); {rig_description}",
            addresses.len(),
            config.bus.poll_hz,
            bus_load(&config),
        ));
        if let Some(addr) = local_addr {
            let token_source = if token_generated {
                "generated at start (antennad prints it once)"
            } else if config.server.token_file.is_some() {
                "from server.token_file"
            } else if config.server.token_env.is_some() {
                "from server.token_env"
            } else {
                "the configured server.token"
            };
            log.line(format!(
                "  watch it with: nc {ip} {port}   (or, without nc: cat </dev/tcp/{ip}/{port}; \
                 newline-delimited JSON, docs/stream-protocol.md; control token: \
                 {token_source}; stop_all needs none)",
                ip = addr.ip(),
                port = addr.port()
            ));
        }

        let stop = Arc::new(AtomicBool::new(false));
        let mut hub = Hub {
            unix_origin_ns: unix_origin_ns(clock),
            token: token.clone(),
            free_check_due: Instant::now(),
            calibrations: config.bus.calibrations(),
            config,
            options: options.clone(),
            clock,
            server,
            log: log.clone(),
            trial: None,
            trial_state: Arc::clone(&trial_state),
            next_trial_id: 1,
            motion: motion_tx,
            script_ends,
            rig_status,
            stage_mm: None,
            base_rad: None,
            health: addresses
                .iter()
                .map(|&address| SegmentStatus {
                    address,
                    ok: 0,
                    nack: 0,
                    pec_error: 0,
                    stale: 0,
                    bus_error: 0,
                    status_flags: None,
                    firmware_version: None,
                })
                .collect(),
            watchdog: PollWatchdog::new(heartbeat, stall_bound(settings.period)),
            note: None,
            status_due: Instant::now(),
            outcomes: Vec::new(),
            finished: false,
            sim_state: sim_state.clone(),
            sim_relaxed_logged: 0,
            max_lateness_seen: Duration::ZERO,
        };
        if let Some(name) = &options.first_trial {
            let name = hub
                .config
                .trial(name.as_deref())
                .map(|t| t.name.clone())
                .unwrap_or_default();
            if let Err(e) = hub.start_trial(&name, BTreeMap::new(), options.first_trial_duration) {
                stop_threads.store(true, Ordering::Relaxed);
                let _ = motion.join();
                let _ = poll_join(poll_join_bound);
                bail!("starting trial {name:?}: {e}");
            }
        }
        let hub_thread = {
            let stop = Arc::clone(&stop);
            std::thread::Builder::new()
                .name("antennad-hub".to_owned())
                .spawn(move || {
                    hub.run(&receiver, &hub_rx, &stop);
                    stop_threads.store(true, Ordering::Relaxed);
                    let motion_ok = motion.join().is_ok();
                    let polled = poll_join(poll_join_bound)?;
                    // Whatever the threads sent last.
                    hub.drain(&receiver);
                    if polled.is_none() {
                        hub.poll_thread_left_behind(poll_join_bound);
                    }
                    hub.finish();
                    if !motion_ok {
                        bail!("the motion thread panicked");
                    }
                    let poll_thread_stuck = polled.is_none();
                    let (polls, skipped, max_lateness, health) =
                        polled.unwrap_or_else(|| hub.totals_seen());
                    Ok(DaemonSummary {
                        polls,
                        skipped,
                        max_lateness,
                        health,
                        dropped: events.dropped(),
                        poll_thread_stuck,
                        trials: hub.outcomes,
                        elapsed: clock.elapsed(),
                    })
                })
                .context("starting the hub thread")?
        };
        Ok(DaemonHandle {
            local_addr,
            token,
            token_generated,
            stop,
            hub: Some(hub_thread),
            log,
            trial: trial_state,
        })
    }
}

/// The rig's geometry for the stream's `hello` (docs/stream-protocol.md): the antenna and
/// wall of `[sim.antenna]` and `[sim.wall]`, the stage's soft limits and the poll rate.
pub fn rig_info(config: &Config) -> RigInfo {
    let antenna = &config.sim.antenna;
    let link_lengths_m = vec![antenna.link_length_m; antenna.links + 1];
    let stiffness_n_m_per_rad = antenna
        .profile()
        .and_then(|p| {
            p.stiffness_n_m_per_rad(
                &link_lengths_m,
                antenna.k_min_n_m_per_rad,
                antenna.k_max_n_m_per_rad,
            )
            .ok()
        })
        .unwrap_or_default();
    RigInfo {
        poll_hz: config.bus.poll_hz,
        link_lengths_m,
        base_mount_angle_deg: antenna.base_angle_deg,
        stiffness_profile: antenna.stiffness_profile.clone(),
        k_min_n_m_per_rad: antenna.k_min_n_m_per_rad,
        k_max_n_m_per_rad: antenna.k_max_n_m_per_rad,
        stiffness_n_m_per_rad,
        wall: RigWall {
            distance_m: config.sim.wall.distance_m,
            angle_deg: config.sim.wall.angle_deg,
            stiffness_n_per_m: config.sim.wall.stiffness_n_per_m,
        },
        stage_min_m: config.stage.min_mm * 1e-3,
        stage_max_m: config.stage.max_mm * 1e-3,
    }
}

/// The simulated segments' hook, with `sim.faults` applied by the time since the start.
fn sense_with_faults(
    mut sense: impl FnMut(&mut SimBus, Duration) + Send + 'static,
    config: &Config,
) -> impl FnMut(&mut SimBus, Duration) + Send + 'static {
    let faults: Vec<(usize, SegmentFault, Duration, Duration)> = config
        .sim
        .faults
        .iter()
        .filter_map(|f| {
            let index = config
                .bus
                .segments
                .iter()
                .position(|s| s.address == f.address)?;
            let kind = match f.kind {
                SimFaultKind::Nack => SegmentFault::Nack,
                SimFaultKind::Pec => SegmentFault::CorruptPec,
                SimFaultKind::Stuck => SegmentFault::StuckCounter,
                SimFaultKind::Hang => SegmentFault::Hang,
            };
            Some((
                index,
                kind,
                Duration::from_secs_f64(f.from_s),
                Duration::from_secs_f64(f.until_s),
            ))
        })
        .collect();
    let segments = config.bus.segments.len();
    move |bus, now| {
        if !faults.is_empty() {
            for k in 0..segments {
                let fault = faults
                    .iter()
                    .find(|(index, _, from, until)| *index == k && *from <= now && now < *until)
                    .map_or(SegmentFault::None, |f| f.1);
                if let Some(segment) = bus.segment_mut(k) {
                    segment.set_fault(fault);
                }
            }
        }
        sense(bus, now);
    }
}

/// What a poll costs the bus, for the start line: `"399 bit times a poll, 40 % of the period
/// at bus.speed_hz = 1000000"` or the simulated bus's `"virtual bus: no bit-time limit"`.
fn bus_load(config: &Config) -> String {
    let bus = &config.bus;
    match bus.checked_speed_hz() {
        Some(speed_hz) => {
            let budget = crate::hardware::bus_budget::BusBudget::new(
                bus.segments.len(),
                bus.poll_hz,
                speed_hz,
            );
            format!(
                "{} bit times a poll, {:.0} % of the period at bus.speed_hz = {speed_hz}",
                budget.bit_times_per_poll(),
                budget.share() * 100.0
            )
        }
        None => "virtual bus: no bit-time limit".to_owned(),
    }
}

/// The names of the status register's flags that are set, e.g. `["ADC fault"]`.
fn flag_names(flags: StatusFlags) -> Vec<String> {
    let mut names = Vec::new();
    if flags.adc_fault() {
        names.push("ADC fault (angle sensor on a rail)".to_owned());
    }
    if flags.touch_stuck() {
        names.push("touch switch stuck closed".to_owned());
    }
    if flags.address_not_set() {
        names.push("address not assigned".to_owned());
    }
    let unknown = flags.bits() & !StatusFlags::DEFINED;
    if unknown != 0 {
        names.push(format!("unknown flags {unknown:#04x}"));
    }
    names
}

fn trial_names(config: &Config) -> String {
    config
        .trials
        .iter()
        .map(|t| t.name.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The polling thread on the Linux I2C bus of `bus.device`.
#[cfg(target_os = "linux")]
fn hardware_poller(
    config: &Config,
    addresses: &[u8],
    clock: TrialClock,
    settings: PollSettings,
    events: &EventSender,
    (stop, heartbeat): (&Arc<AtomicBool>, &Arc<PollHeartbeat>),
) -> Result<(PollJoin, String)> {
    let bus = crate::hardware::i2c_bus::LinuxI2cBus::open(&config.bus.device, addresses)?;
    let handle = spawn_watched_poller(
        Poller::new(bus, addresses),
        clock,
        settings,
        |_: &mut crate::hardware::i2c_bus::LinuxI2cBus, _| {},
        events.clone(),
        Arc::clone(stop),
        Arc::clone(heartbeat),
    )
    .context("starting the polling thread")?;
    Ok((
        bounded_join(handle),
        format!("I2C bus {}", config.bus.device),
    ))
}

/// The polling thread on a hardware bus: Linux only.
#[cfg(not(target_os = "linux"))]
fn hardware_poller(
    config: &Config,
    _addresses: &[u8],
    _clock: TrialClock,
    _settings: PollSettings,
    _events: &EventSender,
    _stop: (&Arc<AtomicBool>, &Arc<PollHeartbeat>),
) -> Result<(PollJoin, String)> {
    bail!(
        "`bus.device` = {:?}: hardware I2C needs Linux; use \"sim\"",
        config.bus.device
    )
}

/// A trial being recorded.
struct ActiveTrial {
    id: u64,
    name: String,
    start_ns: u64,
    /// Zero: until the script is done.
    duration: Duration,
    recorder: Option<TrialRecorder>,
    print_every: u64,
}

struct Hub {
    /// Unix-epoch nanoseconds of the clock's origin: a poll's `t_ns` plus this is its
    /// wall-clock time (the recordings' log times).
    unix_origin_ns: u64,
    /// Never recorded: anything a client asks to record is scrubbed of it.
    token: ControlToken,
    /// When the free space under the data directory is looked at next during a trial.
    free_check_due: Instant,
    config: Config,
    options: DaemonOptions,
    clock: TrialClock,
    calibrations: Vec<Calibration>,
    server: Option<StreamServer>,
    log: Log,
    trial: Option<ActiveTrial>,
    trial_state: Arc<Mutex<Option<String>>>,
    next_trial_id: u64,
    motion: Sender<MotionCommand>,
    script_ends: Arc<ScriptEnds>,
    rig_status: Arc<RigStatus>,
    stage_mm: Option<f64>,
    base_rad: Option<f64>,
    health: Vec<SegmentStatus>,
    note: Option<String>,
    status_due: Instant,
    outcomes: Vec<TrialOutcome>,
    finished: bool,
    /// The simulated rig's physics (its contact solver's relaxations are logged).
    sim_state: Option<Shared<SimState>>,
    /// Relaxed steps of the simulation already logged.
    sim_relaxed_logged: u64,
    /// Watches the polling thread's heartbeat.
    watchdog: PollWatchdog,
    /// The latest poll wake-up after its deadline, as the hub saw the polls.
    max_lateness_seen: Duration,
}

impl Hub {
    fn run(
        &mut self,
        receiver: &Receiver<AcquisitionEvent>,
        requests: &Receiver<HubRequest>,
        stop: &AtomicBool,
    ) {
        let mut watchdog_due = Instant::now();
        while !stop.load(Ordering::Relaxed) && !self.finished {
            // The hub proves the daemon alive: wedged, it stops the pings.
            if let Some(watchdog) = &self.options.watchdog
                && Instant::now() >= watchdog_due
            {
                watchdog_due = Instant::now() + watchdog.ping_every();
                if let Err(e) = watchdog.ping() {
                    tracing::warn!(target: "antennad", "watchdog ping failed: {e}");
                }
            }
            if let Ok(event) = receiver.recv_timeout(Duration::from_millis(10)) {
                self.on_event(&event);
                self.drain(receiver);
            }
            while let Ok(request) = requests.try_recv() {
                self.on_request(request);
            }
            self.check_watchdog();
            self.check_trial_end();
            if Instant::now() >= self.status_due {
                self.publish_status();
            }
        }
    }

    /// Looks at the polling thread's heartbeat: a stall starting or ending is logged,
    /// recorded in the trial and sent in a status line.
    fn check_watchdog(&mut self) {
        let now_ns = self.clock.elapsed_ns();
        let Some(event) = self.watchdog.check(now_ns) else {
            return;
        };
        let text = match event {
            WatchdogEvent::Stalled {
                last_poll_ns,
                silent,
            } => format!(
                "polling stalled: no poll since t = {:.3} s, {} ms ago (bound {} ms); the \
                 polling thread is stuck, most likely in an I2C transfer that does not return; \
                 no samples until it does",
                self.t_s(last_poll_ns),
                silent.as_millis(),
                self.watchdog.status(now_ns).bound.as_millis()
            ),
            WatchdogEvent::Resumed {
                stalled_for,
                missed_deadlines,
            } => format!(
                "polling resumed after {} ms without a poll; {missed_deadlines} poll deadlines \
                 missed",
                stalled_for.as_millis()
            ),
        };
        self.log
            .line(format!("{:7.2}   -- {text}", self.t_s(now_ns)));
        self.record_log(now_ns, &text);
        self.note = Some(text);
        self.publish_status();
    }

    /// The polling thread did not stop within `waited` (stuck in a transfer): said in the
    /// log and, before it is finalized, in the running trial's recording.
    fn poll_thread_left_behind(&mut self, waited: Duration) {
        let now_ns = self.clock.elapsed_ns();
        let text = format!(
            "the polling thread did not stop within {} ms (last poll at t = {:.3} s; stuck in a \
             bus transfer): left behind, the recording is finalized without it",
            waited.as_millis(),
            self.t_s(self.watchdog.heartbeat().last_poll_ns())
        );
        self.log.line(format!("antennad: {text}"));
        self.record_log(now_ns, &text);
    }

    /// Polls, deadlines skipped, the latest wake-up and the health per segment as the hub
    /// counted them (for a polling thread that never reported; `stale` counts polls made
    /// while the segment was stale).
    fn totals_seen(&self) -> PollTotals {
        let heartbeat = self.watchdog.heartbeat();
        let health = self
            .health
            .iter()
            .map(|s| SegmentHealth {
                ok: s.ok,
                nacks: s.nack,
                pec_errors: s.pec_error,
                bus_errors: s.bus_error,
                stale: s.stale,
            })
            .collect();
        (
            heartbeat.polls(),
            heartbeat.missed_deadlines(),
            self.max_lateness_seen,
            health,
        )
    }

    fn drain(&mut self, receiver: &Receiver<AcquisitionEvent>) {
        while let Ok(event) = receiver.try_recv() {
            self.on_event(&event);
        }
    }

    fn finish(&mut self) {
        if self.trial.is_some() {
            self.end_trial("the daemon stopped");
        }
        if let Some(server) = self.server.take() {
            server.shutdown();
        }
    }

    fn t_s(&self, t_ns: u64) -> f64 {
        t_ns as f64 * 1e-9
    }

    fn on_request(&mut self, request: HubRequest) {
        match request {
            HubRequest::Start {
                name,
                metadata,
                reply,
            } => {
                let _ = reply.send(self.start_trial(&name, metadata, None));
            }
            HubRequest::Stop { why, reply } => {
                let answer = if self.trial.is_some() {
                    Ok(self.end_trial(why))
                } else {
                    Err("no trial is running".to_owned())
                };
                let _ = reply.send(answer);
            }
        }
    }

    fn start_trial(
        &mut self,
        name: &str,
        metadata: BTreeMap<String, String>,
        duration: Option<Duration>,
    ) -> Result<String, String> {
        if let Some(trial) = &self.trial {
            return Err(format!(
                "trial {:?} is already running; send stop_trial first",
                trial.name
            ));
        }
        let Some(config) = self.config.trial(Some(name)).cloned() else {
            return Err(format!(
                "no trial {name:?} in the configuration (trials: {})",
                trial_names(&self.config)
            ));
        };
        let mut notes = config.metadata.clone();
        notes.extend(metadata);
        let notes = notes
            .into_iter()
            .map(|(k, v)| (scrub(&k, &self.token), scrub(&v, &self.token)))
            .collect();
        let start_ns = self.clock.elapsed_ns();
        let recorder = if self.options.record {
            let dir = &self.config.data_dir;
            std::fs::create_dir_all(dir)
                .map_err(|e| format!("creating the data directory {}: {e}", dir.display()))?;
            if let Some(short) = self.free_space_short() {
                return Err(format!("trial {:?} refused: {short}", config.name));
            }
            let path = free_path(dir, &config.name);
            let started_unix_ns = self.unix_origin_ns.saturating_add(start_ns);
            let metadata = TrialMetadata {
                trial: config.name.clone(),
                started_unix_s: started_unix_ns as f64 * 1e-9,
                started_unix_ns: Some(started_unix_ns),
                config: scrub(&self.config.to_recorded_toml(), &self.token),
                notes,
                rig: Some(rig_info(&self.config)),
            };
            let options = self.config.recording.recorder_options();
            Some(
                TrialRecorder::create_with(&path, &metadata, options)
                    .map_err(|e| format!("creating the recording {}: {e}", path.display()))?,
            )
        } else {
            None
        };
        self.free_check_due = Instant::now() + FREE_SPACE_CHECK;
        let id = self.next_trial_id;
        self.next_trial_id += 1;
        let duration = duration.unwrap_or(Duration::from_secs_f64(config.duration_s));
        let moves = config
            .moves
            .iter()
            .map(|m| format!("{:+} mm at {} mm/s", m.distance_mm, m.speed_mm_per_s))
            .collect::<Vec<_>>()
            .join(", then ");
        let mut message = format!(
            "trial {:?} started: base angle {} deg, stage moves {}, {}",
            config.name,
            config.base_angle_deg,
            if moves.is_empty() { "none" } else { &moves },
            if duration.is_zero() {
                "until its moves are done".to_owned()
            } else {
                format!("for {} s", duration.as_secs_f64())
            }
        );
        if let Some(recorder) = &recorder {
            message.push_str(&format!("; recording to {}", recorder.path().display()));
        }
        self.log.line(format!("antennad: {message}"));
        if self.options.echo {
            self.log.sample(format!(
                "{:>7} {:>8}  joint angles, deg (base to tip)                      touch",
                "t_s", "stage_mm"
            ));
        }
        let print_every = ((self.config.bus.poll_hz / self.options.print_hz).round() as u64).max(1);
        self.trial = Some(ActiveTrial {
            id,
            name: config.name.clone(),
            start_ns,
            duration,
            recorder,
            print_every,
        });
        if let Ok(mut state) = self.trial_state.lock() {
            *state = Some(config.name.clone());
        }
        let _ = self.motion.send(MotionCommand::RunScript {
            id,
            trial: Box::new(config),
        });
        self.note = Some(message.clone());
        self.publish_status();
        Ok(message)
    }

    /// Ends the running trial (there must be one): stops its script and the stage, finalizes
    /// the file. Returns what happened.
    fn end_trial(&mut self, why: &str) -> String {
        let Some(trial) = self.trial.take() else {
            return "no trial was running".to_owned();
        };
        if let Ok(mut state) = self.trial_state.lock() {
            *state = None;
        }
        let _ = self.motion.send(MotionCommand::EndScript);
        let (path, recorded, result) = match trial.recorder {
            Some(mut recorder) => {
                // The reason is the file's last word (a full disk may refuse even that).
                let t_s = self.clock.elapsed_ns().saturating_sub(trial.start_ns) as f64 * 1e-9;
                let _ = recorder.record_log(&LogMessage {
                    t_s,
                    text: format!("trial ended: {why}"),
                });
                let written = recorder.written();
                let path = recorder.path().to_path_buf();
                let result = recorder.finish().map(|_| ());
                (Some(path), written, result)
            }
            None => (None, RecordCounts::default(), Ok(())),
        };
        let mut message = format!("trial {:?} ended ({why})", trial.name);
        if let Some(path) = &path {
            match result {
                Ok(()) => message.push_str(&format!(
                    "; recorded {} polls, {} stage and {} servo samples to {}",
                    recorded.segments,
                    recorded.stage,
                    recorded.servo,
                    path.display()
                )),
                Err(e) => message.push_str(&format!("; closing {} failed: {e}", path.display())),
            }
        }
        self.log.line(format!("antennad: {message}"));
        self.outcomes.push(TrialOutcome {
            name: trial.name,
            path,
            recorded,
            ended: why.to_owned(),
        });
        if self.options.exit_after_trial {
            self.finished = true;
        }
        self.note = Some(message.clone());
        self.publish_status();
        message
    }

    /// Why the data directory has too little room for a recording, if it has.
    fn free_space_short(&self) -> Option<String> {
        let dir = &self.config.data_dir;
        let min_bytes = self.config.recording.min_free_bytes();
        match self.options.free_space.free_bytes(dir) {
            Ok(free) if free < min_bytes => Some(format!(
                "the disk holding {} is nearly full: {:.1} MB free, below recording.min_free_mb \
                 = {} MB",
                dir.display(),
                free as f64 * 1e-6,
                self.config.recording.min_free_mb
            )),
            Ok(_) => None,
            Err(e) => Some(format!(
                "the free space under {} cannot be read: {e}",
                dir.display()
            )),
        }
    }

    fn check_trial_end(&mut self) {
        if self.trial.as_ref().is_some_and(|t| t.recorder.is_some())
            && Instant::now() >= self.free_check_due
        {
            self.free_check_due = Instant::now() + FREE_SPACE_CHECK;
            if let Some(short) = self.free_space_short() {
                self.log
                    .warn(format!("antennad: {short}; ending the trial"));
                let why: &'static str = "the disk is nearly full";
                self.record_log(self.clock.elapsed_ns(), &short);
                self.end_trial(why);
                return;
            }
        }
        let Some(trial) = &self.trial else { return };
        if let Some(why) = self.script_ends.failure(trial.id) {
            self.end_trial(&why);
            return;
        }
        let elapsed_ns = self.clock.elapsed_ns().saturating_sub(trial.start_ns);
        let why = if trial.duration.is_zero() {
            self.script_ends
                .is_done(trial.id)
                .then_some("its moves are done")
        } else {
            (u128::from(elapsed_ns) >= trial.duration.as_nanos()).then_some("its duration passed")
        };
        if let Some(why) = why {
            self.end_trial(why);
        }
    }

    /// Records `f`'s message if a trial runs and `t_ns` is inside it; a failing recorder ends
    /// the trial.
    fn record(
        &mut self,
        t_ns: u64,
        f: impl FnOnce(&mut TrialRecorder, f64) -> Result<(), antenna_data::record::RecordError>,
    ) {
        let Some(trial) = &mut self.trial else { return };
        if t_ns < trial.start_ns {
            return;
        }
        let t_s = (t_ns - trial.start_ns) as f64 * 1e-9;
        let Some(recorder) = &mut trial.recorder else {
            return;
        };
        if let Err(e) = f(recorder, t_s).and_then(|()| recorder.flush_if_due(t_s)) {
            self.log
                .error(format!("antennad: recording failed, ending the trial: {e}"));
            self.end_trial("the recording failed");
        }
    }

    fn on_event(&mut self, event: &AcquisitionEvent) {
        match event {
            AcquisitionEvent::Poll(poll) => self.on_poll(poll),
            AcquisitionEvent::Stage { t_ns, position_mm } => {
                self.stage_mm = Some(*position_mm);
                let position_m = position_mm * 1e-3;
                self.record(*t_ns, |r, t_s| {
                    r.record_stage(&StageMessage { t_s, position_m })
                });
            }
            AcquisitionEvent::Base { t_ns, angle_rad } => {
                self.base_rad = Some(*angle_rad);
                let base_angle_rad = *angle_rad;
                self.record(*t_ns, |r, t_s| {
                    r.record_servo(&ServoMessage {
                        t_s,
                        base_angle_rad,
                    })
                });
            }
            AcquisitionEvent::Health {
                t_ns,
                address,
                change,
            } => {
                let text = match change {
                    HealthChange::Stale => {
                        format!("segment {address:#04x}: counter stopped (stale)")
                    }
                    HealthChange::Recovered => {
                        format!("segment {address:#04x}: counter moving again")
                    }
                };
                let line = format!("{:7.2}   -- {text}", self.t_s(*t_ns));
                match change {
                    HealthChange::Stale => self.log.warn(line),
                    HealthChange::Recovered => self.log.line(line),
                }
                self.record_log(*t_ns, &text);
                self.note = Some(text);
                self.publish_status();
            }
            AcquisitionEvent::Note { t_ns, text } => {
                self.log
                    .line(format!("{:7.2}   -- {text}", self.t_s(*t_ns)));
                self.record_log(*t_ns, text);
                self.note = Some(text.clone());
                self.publish_status();
            }
            AcquisitionEvent::Firmware {
                t_ns,
                address,
                reading,
            } => self.on_firmware(*t_ns, *address, *reading),
        }
    }

    /// A firmware register read: kept in the segment's status; a change of its flags, or a
    /// version other than the one this antennad speaks, is logged and recorded.
    fn on_firmware(&mut self, t_ns: u64, address: u8, reading: FirmwareReading) {
        let Some(status) = self.health.iter_mut().find(|s| s.address == address) else {
            return;
        };
        let text = match reading {
            FirmwareReading::Status(flags) => {
                let previous = status.status_flags.replace(flags.bits());
                if previous.unwrap_or(0) == flags.bits() {
                    return;
                }
                let names = flag_names(flags);
                if names.is_empty() {
                    format!("segment {address:#04x}: firmware status clear again")
                } else {
                    format!("segment {address:#04x} reports {}", names.join(", "))
                }
            }
            FirmwareReading::Version(major, minor) => {
                let version = format!("{major}.{minor}");
                let previous = status.firmware_version.replace(version.clone());
                if previous.as_ref() == Some(&version) || (major, minor) == FIRMWARE_VERSION {
                    return;
                }
                format!(
                    "segment {address:#04x} runs firmware {version}; this antennad speaks \
                     protocol {}.{}",
                    FIRMWARE_VERSION.0, FIRMWARE_VERSION.1
                )
            }
            FirmwareReading::Unread(_) => return,
        };
        self.log.line(format!("{:7.2}   -- {text}", self.t_s(t_ns)));
        self.record_log(t_ns, &text);
        self.note = Some(text);
        self.publish_status();
    }

    fn record_log(&mut self, t_ns: u64, text: &str) {
        self.record(t_ns, |r, t_s| {
            r.record_log(&LogMessage {
                t_s,
                text: text.to_owned(),
            })
        });
    }

    /// Logs what the simulation's contact solver relaxed since the last poll (a line per
    /// relaxed step, with the stage position).
    fn log_sim_relaxations(&mut self) {
        let Some(state) = &self.sim_state else {
            return;
        };
        let (relaxed, said) = match state.lock() {
            Ok(s) => (s.relaxed_steps, s.relaxations.join(", ")),
            Err(_) => return,
        };
        if relaxed > self.sim_relaxed_logged {
            self.sim_relaxed_logged = relaxed;
            let at = self
                .stage_mm
                .map_or_else(String::new, |mm| format!(" at stage {mm:.1} mm"));
            self.log.line(format!(
                "antennad: simulation{at}: the contact solver relaxed a step ({said}); \
                 {relaxed} relaxed step(s) so far"
            ));
        }
    }

    fn on_poll(&mut self, poll: &PollRecord) {
        self.log_sim_relaxations();
        self.max_lateness_seen = self.max_lateness_seen.max(Duration::from_nanos(
            poll.t_ns.saturating_sub(poll.deadline_ns),
        ));
        for (k, (reading, status)) in poll.readings.iter().zip(&mut self.health).enumerate() {
            match reading.result {
                Ok(_) => status.ok += 1,
                Err(PollError::Nack { .. }) => status.nack += 1,
                Err(PollError::Corrupted { .. }) => status.pec_error += 1,
                Err(PollError::Bus { .. }) => status.bus_error += 1,
            }
            if poll.is_stale(k) {
                status.stale += 1;
            }
        }
        if !self.rig_status.stage.load(Ordering::Relaxed) {
            self.stage_mm = None;
        }
        if !self.rig_status.servo.load(Ordering::Relaxed) {
            self.base_rad = None;
        }
        if let Some(server) = &self.server {
            server.publish(&StreamMessage::Samples {
                seq: poll.seq,
                t_ns: poll.t_ns,
                segments: poll
                    .readings
                    .iter()
                    .zip(&self.calibrations)
                    .enumerate()
                    .map(|(k, (r, c))| stream_sample(r, *c, poll.is_stale(k)))
                    .collect(),
                stage_position_m: self.stage_mm.map(|mm| mm * 1e-3),
                base_angle_deg: self.base_rad.map(f64::to_degrees),
            });
        }
        let calibrations = self.calibrations.clone();
        let seq = poll.seq;
        self.record(poll.t_ns, |r, t_s| {
            r.record_segments(&SegmentsMessage {
                seq: Some(seq),
                t_s,
                segments: poll
                    .readings
                    .iter()
                    .zip(&calibrations)
                    .enumerate()
                    .map(|(k, (r, &c))| record_sample(r, c, poll.is_stale(k)))
                    .collect(),
            })
        });
        if self.options.echo
            && let Some(trial) = &self.trial
            && poll.t_ns >= trial.start_ns
            && poll.seq.is_multiple_of(trial.print_every)
        {
            let t_s = (poll.t_ns - trial.start_ns) as f64 * 1e-9;
            self.log
                .sample(sample_line(t_s, self.stage_mm, poll, &self.calibrations));
        }
    }

    fn publish_status(&mut self) {
        self.status_due = Instant::now() + Duration::from_secs(1);
        let Some(server) = &self.server else { return };
        let mut notes = Vec::new();
        if !self.rig_status.stage.load(Ordering::Relaxed) {
            notes.push("stage unavailable".to_owned());
        }
        if !self.rig_status.servo.load(Ordering::Relaxed) {
            notes.push("servo unavailable".to_owned());
        }
        let now_ns = self.clock.elapsed_ns();
        let polling = self.watchdog.status(now_ns);
        if polling.stalled {
            notes.push(format!(
                "polling stalled for {} ms",
                polling.since_last_poll.as_millis()
            ));
        }
        for segment in &self.health {
            let names = flag_names(StatusFlags::from_bits(segment.status_flags.unwrap_or(0)));
            if !names.is_empty() {
                notes.push(format!(
                    "segment {:#04x}: {}",
                    segment.address,
                    names.join(", ")
                ));
            }
        }
        if let Some(note) = self.note.take() {
            notes.push(note);
        }
        server.publish(&StreamMessage::Status {
            t_ns: now_ns,
            trial: self.trial.as_ref().map(|t| t.name.clone()),
            segments: self.health.clone(),
            note: (!notes.is_empty()).then(|| notes.join("; ")),
            polling: Some(PollingStatus {
                stalled: polling.stalled,
                since_last_poll_ms: u64::try_from(polling.since_last_poll.as_millis())
                    .unwrap_or(u64::MAX),
                stall_after_ms: u64::try_from(polling.bound.as_millis()).unwrap_or(u64::MAX),
                polls: polling.polls,
                missed_deadlines: polling.missed_deadlines,
                stalls: polling.stalls,
            }),
        });
    }
}

/// `   1.25    37.5   -3.1  -2.9 ...   ....#` : trial time, stage, angles, touch marks.
fn sample_line(
    t_s: f64,
    stage_mm: Option<f64>,
    poll: &PollRecord,
    calibrations: &[Calibration],
) -> String {
    let mut angles = String::new();
    let mut touches = String::new();
    for (k, (reading, calibration)) in poll.readings.iter().zip(calibrations).enumerate() {
        match reading.result {
            Ok(word) => {
                let deg = calibration.angle_rad(word.angle_counts()).to_degrees();
                angles.push_str(&format!("{deg:6.1}"));
                touches.push(if poll.is_stale(k) {
                    's'
                } else if word.touch().any() {
                    '#'
                } else {
                    '.'
                });
            }
            Err(_) => {
                angles.push_str("   ---");
                touches.push('?');
            }
        }
    }
    let stage = stage_mm.map_or("     ---".to_owned(), |mm| format!("{mm:8.1}"));
    format!("{t_s:7.2} {stage} {angles}   {touches}")
}
