//! [`Daemon::start`]: the bus and its polling thread, the rig and the motion thread, the TCP
//! server and the hub, wired from a [`Config`].

use super::control::DaemonControl;
use super::hub::Hub;
use super::rig_info::rig_info;
use super::{Daemon, DaemonHandle, DaemonOptions, DaemonSummary, Log, POLL_THREAD_STOP_WAIT};
use crate::config::Config;
use crate::hardware::poll::{Poller, SegmentHealth};
use crate::net::foxglove::{self, FoxgloveError, FoxgloveLive};
use crate::net::{ControlToken, ServerLog, ServerOptions, StreamServer};
use crate::service::acquisition::{
    EventSender, PollSettings, Shared, event_channel, spawn_watched_poller,
};
use crate::service::clock::TrialClock;
use crate::service::estimate::LiveEstimate;
use crate::service::motion::{MotionShared, RigStatus, spawn_motion};
use crate::service::rig::DaemonRig;
use crate::service::trial_script::ScriptEnds;
use crate::service::watchdog::{PollHeartbeat, PollWatchdog, stall_bound};
use crate::sim::rig::{SensedPoses, SimState, sense_keeping_poses, sense_with_faults, sim_bus};
use antenna_data::stream::SegmentStatus;
use anyhow::{Context, Result, anyhow, bail};
use std::collections::{BTreeMap, VecDeque};
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::channel;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// Unix-epoch nanoseconds of `clock`'s origin (the wall clock now, less the time since it).
fn unix_origin_ns(clock: TrialClock) -> u64 {
    let now_ns = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX));
    now_ns.saturating_sub(clock.elapsed_ns())
}

/// What the polling thread reports when it stops: polls, deadlines skipped, the latest
/// wake-up, health per segment.
pub(super) type PollTotals = (u64, u64, Duration, Vec<SegmentHealth>);

/// Waits at most the given time for the polling thread to stop: `None` if it has not (stuck
/// in a bus transfer; it is then left behind, not joined).
pub(super) type PollJoin = Box<dyn FnOnce(Duration) -> Result<Option<PollTotals>> + Send>;

/// A [`PollJoin`] for the polling thread `handle`.
pub(super) fn bounded_join<I: Send + 'static>(
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
        // The live wall estimate (the bend estimator calibrates on the scene here, before
        // anything starts).
        let estimate = LiveEstimate::from_config(&config).map_err(|(key, why)| {
            anyhow!("`{key}` = {:?}: {why}", config.estimate.estimator.name())
        })?;
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
        let sensed_poses = Arc::new(SensedPoses::default());
        let settings = PollSettings {
            period: Duration::from_secs_f64(1.0 / config.bus.poll_hz),
            counter_check_every: config.bus.counter_check_every,
            spin: Duration::from_micros(config.bus.spin_us),
            realtime_priority: config.bus.realtime_priority,
        };
        let heartbeat = Arc::new(PollHeartbeat::new(clock.elapsed_ns()));
        let (poll_join, bus_description) = start_polling(
            &config,
            clock,
            settings,
            sim_state.as_ref().map(|s| (s, &sensed_poses)),
            &events,
            (&stop_threads, &heartbeat),
        )?;
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
        let unix_origin_ns = unix_origin_ns(clock);
        let foxglove = match start_foxglove(&config, &options, unix_origin_ns, &log) {
            Ok(foxglove) => foxglove,
            Err(e) => {
                stop_threads.store(true, Ordering::Relaxed);
                if let Some(server) = server {
                    server.shutdown();
                }
                let _ = motion.join();
                let _ = poll_join(poll_join_bound);
                return Err(e);
            }
        };
        let foxglove_addr = foxglove.as_ref().map(FoxgloveLive::local_addr);
        let local_addr = server.as_ref().map(StreamServer::local_addr);
        log.line(format!(
            "antennad: {bus_description}; {}; {rig_description}",
            polling_summary(&config)
        ));
        if let Some(addr) = local_addr {
            log.line(watch_line(&config, token_generated, addr));
        }
        if let Some(addr) = foxglove_addr {
            log.line(foxglove_line(addr));
        }
        if config.bus.is_sim() {
            log.line(format!(
                "antennad: simulated rig: the scene {} ({} segments, one per flexible joint); \
                 the stage carries the base along its direction of motion, its [start] \
                 placement is applied when a trial starts",
                config.sim.rig.source,
                config.sim.rig.joints()
            ));
        }
        for (warning, text) in config.sim.rig.ignored(config.bus.poll_hz) {
            if warning {
                log.warn(format!("antennad: {text}"));
            } else {
                log.line(format!("antennad: {text}"));
            }
        }

        let stop = Arc::new(AtomicBool::new(false));
        let mut hub = Hub {
            unix_origin_ns,
            token: token.clone(),
            free_check_due: Instant::now(),
            calibrations: config.bus.calibrations(),
            config,
            options: options.clone(),
            clock,
            server,
            foxglove,
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
            sensed_poses: sim_state.is_some().then_some(sensed_poses),
            estimate,
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
                    let motion = motion.join();
                    let polled = poll_join(poll_join_bound)?;
                    // Whatever the threads sent last.
                    hub.drain(&receiver);
                    if polled.is_none() {
                        hub.poll_thread_left_behind(poll_join_bound);
                    }
                    hub.finish();
                    let Ok(motion) = motion else {
                        bail!("the motion thread panicked");
                    };
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
                        moves_started: motion.moves.started,
                        moves_refused: motion.moves.refused,
                        elapsed: clock.elapsed(),
                    })
                })
                .context("starting the hub thread")?
        };
        Ok(DaemonHandle {
            local_addr,
            foxglove_addr,
            token,
            token_generated,
            stop,
            hub: Some(hub_thread),
            log,
            trial: trial_state,
            clock,
        })
    }
}

/// The Foxglove server of `[foxglove]`, if it runs: only with the TCP server
/// ([`DaemonOptions::serve`]) and [`DaemonOptions::foxglove`], when
/// [`Config::foxglove_enabled`]. A port that cannot be bound is an error naming
/// `foxglove.listen`, or with `foxglove.required = false` a warning and no Foxglove; an
/// antennad built without the server refuses `foxglove.enabled = true` and otherwise says it
/// has none.
fn start_foxglove(
    config: &Config,
    options: &DaemonOptions,
    unix_origin_ns: u64,
    log: &Log,
) -> Result<Option<FoxgloveLive>> {
    if !foxglove::BUILT {
        if config.foxglove.enabled == Some(true) {
            bail!("`foxglove.enabled` = true: {}", FoxgloveError::NotBuilt);
        }
        if options.serve && options.foxglove && config.foxglove_enabled() {
            log.line(
                "antennad: no Foxglove server: this antennad was built without it (cargo \
                 feature `foxglove`)"
                    .to_owned(),
            );
        }
        return Ok(None);
    }
    if !(options.serve && options.foxglove && config.foxglove_enabled()) {
        return Ok(None);
    }
    let listen = &config.foxglove.listen;
    match FoxgloveLive::start(config, unix_origin_ns) {
        Ok(live) => Ok(Some(live)),
        Err(e) if !config.foxglove.required => {
            log.warn(format!(
                "antennad: `foxglove.listen` = {listen:?}: {e}; running without Foxglove \
                 (foxglove.required = false)"
            ));
            Ok(None)
        }
        Err(e) => Err(anyhow!(e)).context(format!(
            "`foxglove.listen` = {listen:?}: starting the Foxglove server (another antennad or \
             program on the port? set [foxglove] listen, or required = false to start without it)"
        )),
    }
}

/// Where Foxglove connects, for the log at start.
fn foxglove_line(addr: SocketAddr) -> String {
    format!(
        "  see it in Foxglove: open a connection, Foxglove WebSocket, ws://{addr} (view-only; \
         the layout docs/foxglove/antenna-layout.json, docs/foxglove.md)"
    )
}

/// The polling thread: on the simulated bus (its segments sensing `sim_state`, with
/// `sim.faults`) or the hardware one; what to join it with, and the bus for the start line.
fn start_polling(
    config: &Config,
    clock: TrialClock,
    settings: PollSettings,
    sim_state: Option<(&Shared<SimState>, &Arc<SensedPoses>)>,
    events: &EventSender,
    (stop, heartbeat): (&Arc<AtomicBool>, &Arc<PollHeartbeat>),
) -> Result<(PollJoin, String)> {
    let addresses = config.bus.addresses();
    let Some((state, poses)) = sim_state else {
        return hardware_poller(
            config,
            &addresses,
            clock,
            settings,
            events,
            (stop, heartbeat),
        );
    };
    let handle = spawn_watched_poller(
        Poller::new(sim_bus(config)?, &addresses),
        clock,
        settings,
        sense_with_faults(
            sense_keeping_poses(Arc::clone(state), Arc::clone(poses)),
            config,
        ),
        events.clone(),
        Arc::clone(stop),
        Arc::clone(heartbeat),
    )
    .context("starting the polling thread")?;
    Ok((
        bounded_join(handle),
        "simulated rig (virtual I2C bus)".to_owned(),
    ))
}

/// The start line's account of the polling: `"9 segments at 0x20..=0x28, polling at 1000 Hz
/// (virtual bus: no bit-time limit)"`.
fn polling_summary(config: &Config) -> String {
    let addresses = config.bus.addresses();
    let (first, last) = (
        addresses.first().copied().unwrap_or_default(),
        addresses.last().copied().unwrap_or_default(),
    );
    format!(
        "{} segments at {first:#04x}..={last:#04x}, polling at {} Hz ({})",
        addresses.len(),
        config.bus.poll_hz,
        bus_load(config),
    )
}

/// How to watch the stream at `addr`, and where the control token came from (never the token).
fn watch_line(config: &Config, token_generated: bool, addr: SocketAddr) -> String {
    let token_source = if token_generated {
        "generated at start (antennad prints it once)"
    } else if config.server.token_file.is_some() {
        "from server.token_file"
    } else if config.server.token_env.is_some() {
        "from server.token_env"
    } else {
        "the configured server.token"
    };
    format!(
        "  watch it with: nc {ip} {port}   (or, without nc: cat </dev/tcp/{ip}/{port}; \
         newline-delimited JSON, docs/stream-protocol.md; control token: \
         {token_source}; stop_all needs none)",
        ip = addr.ip(),
        port = addr.port()
    )
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

pub(super) fn trial_names(config: &Config) -> String {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_start_line_gives_the_segments_the_rate_and_the_bus_load() {
        let mut config = Config::default();
        assert_eq!(
            polling_summary(&config),
            "8 segments at 0x20..=0x27, polling at 1000 Hz (virtual bus: no bit-time limit)"
        );
        config.bus.device = "/dev/i2c-1".to_owned();
        config.bus.speed_hz = Some(1_000_000);
        assert_eq!(
            bus_load(&config),
            "361 bit times a poll, 36 % of the period at bus.speed_hz = 1000000"
        );
    }

    #[test]
    fn the_watch_line_says_where_the_token_came_from_never_what_it_is() {
        let mut config = Config::default();
        let addr: SocketAddr = "127.0.0.1:7878".parse().unwrap();
        let line = watch_line(&config, true, addr);
        assert!(line.contains("nc 127.0.0.1 7878"), "{line}");
        assert!(line.contains("generated at start"), "{line}");
        config.server.token_env = Some("ANTENNAD_TOKEN".to_owned());
        assert!(watch_line(&config, false, addr).contains("from server.token_env"));
        config.server.token_env = None;
        config.server.token = Some(ControlToken::new("s3cret-s3cret-s3cret").unwrap());
        let line = watch_line(&config, false, addr);
        assert!(line.contains("the configured server.token"), "{line}");
        assert!(!line.contains("s3cret"), "{line}");
    }

    #[test]
    fn the_foxglove_line_gives_the_websocket_url() {
        let line = foxglove_line("127.0.0.1:8765".parse().unwrap());
        assert!(line.contains("ws://127.0.0.1:8765"), "{line}");
        assert!(line.contains("view-only"), "{line}");
    }

    /// Built without the server: `foxglove.enabled = true` is refused naming the key; left
    /// out on the simulated rig (on by default), antennad starts and says it has none.
    #[cfg(not(feature = "foxglove"))]
    #[test]
    fn without_the_feature_enabled_is_refused_and_the_default_is_said() {
        let mut config = Config::default();
        config.server.listen = "127.0.0.1:0".to_owned();
        config.data_dir =
            std::env::temp_dir().join(format!("antennad-nofox-{}", std::process::id()));
        config.foxglove.enabled = Some(true);
        let options = DaemonOptions {
            foxglove: true,
            record: false,
            ..DaemonOptions::default()
        };
        let error = Daemon::start(config.clone(), options.clone()).unwrap_err();
        let text = format!("{error:#}");
        assert!(text.contains("`foxglove.enabled` = true"), "{text}");
        assert!(text.contains("built without"), "{text}");
        config.foxglove.enabled = None;
        let daemon = Daemon::start(config, options).unwrap();
        assert_eq!(daemon.foxglove_addr(), None);
        assert!(
            daemon
                .log_lines()
                .iter()
                .any(|l| l.contains("no Foxglove server")),
            "{:?}",
            daemon.log_lines()
        );
        daemon.shutdown().unwrap();
    }

    #[test]
    fn an_unknown_first_trial_is_refused_naming_the_trials() {
        let options = DaemonOptions {
            first_trial: Some(Some("nope".to_owned())),
            serve: false,
            record: false,
            ..DaemonOptions::default()
        };
        let error = Daemon::start(Config::default(), options).unwrap_err();
        assert_eq!(
            error.to_string(),
            format!(
                "no trial \"nope\" in the configuration (trials: {})",
                trial_names(&Config::default())
            )
        );
    }
}
