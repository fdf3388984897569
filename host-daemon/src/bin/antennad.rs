//! `antennad`: the antenna host daemon. It runs a trial from its configuration (the built-in
//! default, or `--config FILE`): the segments polled on absolute deadlines, the stage and
//! base servo sampled on the same clock, every sample recorded to `<data_dir>/<trial>.mcap`
//! and published to TCP clients, and a few lines a second printed here.
//!
//! With no configuration it runs the simulated rig: nine segments running the firmware's own
//! logic on a virtual I2C bus, a virtual stage carrying the antenna along a wall, and joint
//! angles from sim-core's equilibrium solver.

use anyhow::{Context, Result, bail};
use clap::Parser;
use host_daemon::PollError;
use host_daemon::acquisition::{AcquisitionEvent, HealthChange};
use host_daemon::config::Config;
use host_daemon::net::{
    ControlCommand, ControlHandler, ControlToken, SegmentSample as NetSample, ServerOptions,
    StreamMessage, StreamServer,
};
use host_daemon::record::{
    SegmentSample, SegmentsMessage, ServoMessage, StageMessage, TrialMetadata, TrialRecorder,
};
use host_daemon::sim_rig::{TrialOptions, run_sim_trial};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

/// The antenna host daemon: runs a trial (by default on the simulated rig), records it to
/// MCAP and streams it over TCP.
#[derive(Debug, Parser)]
#[command(version, about)]
struct Args {
    /// Configuration file (TOML; see host-daemon/config/). Default: the simulated rig.
    #[arg(long)]
    config: Option<PathBuf>,
    /// The trial to run (by name; default: the first in the configuration).
    #[arg(long)]
    trial: Option<String>,
    /// Overrides the trial's duration, seconds (0: until its stage moves are done).
    #[arg(long)]
    duration_s: Option<f64>,
    /// Overrides the data directory.
    #[arg(long)]
    data_dir: Option<PathBuf>,
    /// Overrides the TCP endpoint (address:port).
    #[arg(long)]
    listen: Option<String>,
    /// Do not record the trial.
    #[arg(long)]
    no_record: bool,
    /// Do not start the TCP server.
    #[arg(long)]
    no_server: bool,
    /// Lines printed per second.
    #[arg(long, default_value_t = 4.0)]
    print_hz: f64,
}

/// Control commands from TCP clients during a scripted trial: stopping works; the others are
/// refused with the reason.
struct TrialControl {
    stop: Arc<AtomicBool>,
}

impl ControlHandler for TrialControl {
    fn handle(&self, command: ControlCommand) -> Result<String, String> {
        match command {
            ControlCommand::StopTrial | ControlCommand::StopAll => {
                self.stop.store(true, Ordering::Relaxed);
                Ok("stopping the trial and the stage".to_owned())
            }
            ControlCommand::StartTrial { .. } => {
                Err("a trial is already running (this antennad runs one trial per start)".into())
            }
            ControlCommand::MoveStage { .. } | ControlCommand::SetBaseAngle { .. } => {
                Err("the stage and base follow the trial's script while it runs".into())
            }
        }
    }
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
    let (mut config, config_text) = match &args.config {
        Some(path) => {
            let config = Config::from_file(path)?;
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("reading {}", path.display()))?;
            (config, text)
        }
        None => (
            Config::default(),
            "# the built-in default: the simulated rig\n".to_owned(),
        ),
    };
    if let Some(dir) = &args.data_dir {
        config.data_dir.clone_from(dir);
    }
    if let Some(listen) = &args.listen {
        config.server.listen.clone_from(listen);
    }
    if !(args.print_hz.is_finite() && args.print_hz > 0.0) {
        bail!("--print-hz must be positive, got {}", args.print_hz);
    }
    let Some(trial) = config.trial(args.trial.as_deref()).cloned() else {
        let names: Vec<&str> = config.trials.iter().map(|t| t.name.as_str()).collect();
        bail!(
            "no trial {:?} in the configuration (trials: {})",
            args.trial.as_deref().unwrap_or("(first)"),
            names.join(", ")
        );
    };
    let duration = match args.duration_s {
        Some(s) if s.is_finite() && s >= 0.0 => Some(Duration::from_secs_f64(s)),
        Some(s) => bail!("--duration-s must be finite and >= 0, got {s}"),
        None => None,
    };
    if !config.bus.is_sim() {
        bail!(
            "bus.device = {:?}: this build of antennad drives only the simulated rig \
             (bus.device = \"sim\"); the hardware I2C, VXM and Maestro path is not wired in yet",
            config.bus.device
        );
    }

    let stop = Arc::new(AtomicBool::new(false));
    let addresses = config.bus.addresses();
    let calibrations = config.bus.calibrations();

    let server = if args.no_server {
        None
    } else {
        let (token, shown) = match &config.server.token {
            Some(token) => (token.clone(), "(the configured server.token)".to_owned()),
            None => {
                let token = generated_token();
                (token.clone(), token)
            }
        };
        let token = ControlToken::new(token).context("server.token must not be empty")?;
        let options = ServerOptions {
            segment_addresses: addresses.clone(),
            ..ServerOptions::default()
        };
        let handler = Arc::new(TrialControl {
            stop: Arc::clone(&stop),
        });
        let server =
            StreamServer::bind_with(config.server.listen.as_str(), token, handler, options)
                .with_context(|| format!("starting the TCP server on {}", config.server.listen))?;
        Some((server, shown))
    };

    let mut recorder = if args.no_record {
        None
    } else {
        std::fs::create_dir_all(&config.data_dir).with_context(|| {
            format!("creating the data directory {}", config.data_dir.display())
        })?;
        let path = free_path(&config.data_dir, &trial.name);
        let metadata = TrialMetadata {
            trial: trial.name.clone(),
            started_unix_s: SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .map_or(0.0, |d| d.as_secs_f64()),
            config: config_text,
            notes: trial.metadata.clone(),
        };
        Some(
            TrialRecorder::create(&path, &metadata)
                .with_context(|| format!("creating the recording {}", path.display()))?,
        )
    };

    let shown_duration = duration.unwrap_or(Duration::from_secs_f64(trial.duration_s));
    println!(
        "antennad: simulated rig, {} segments at {:#04x}..={:#04x}, polling at {} Hz; trial {:?} {}",
        addresses.len(),
        addresses[0],
        addresses[addresses.len() - 1],
        config.bus.poll_hz,
        trial.name,
        if shown_duration.is_zero() {
            "until its moves are done".to_owned()
        } else {
            format!("for {} s", shown_duration.as_secs_f64())
        }
    );
    println!(
        "  wall {} m from the track at {} deg; antenna of {} x {} m links ({} stiffness); \
         stage moves: {}",
        config.sim.wall.distance_m,
        config.sim.wall.angle_deg,
        config.sim.antenna.links,
        config.sim.antenna.link_length_m,
        config.sim.antenna.stiffness_profile,
        trial
            .moves
            .iter()
            .map(|m| format!("{:+} mm at {} mm/s", m.distance_mm, m.speed_mm_per_s))
            .collect::<Vec<_>>()
            .join(", then ")
    );
    if let Some(recorder) = &recorder {
        println!("  recording to {}", recorder.path().display());
    }
    if let Some((server, token)) = &server {
        let addr = server.local_addr();
        println!(
            "  watch it with: nc {ip} {port}   (or, without nc: cat </dev/tcp/{ip}/{port}; \
             newline-delimited JSON, docs/stream-protocol.md; control token: {token})",
            ip = addr.ip(),
            port = addr.port()
        );
    }
    println!(
        "{:>7} {:>8}  joint angles, deg (base to tip)                      touch",
        "t_s", "stage_mm"
    );

    let print_every = ((config.bus.poll_hz / args.print_hz).round() as u64).max(1);
    let mut stage_mm: Option<f64> = None;
    let mut base_rad: Option<f64> = None;
    let mut record_error: Option<anyhow::Error> = None;
    let options = TrialOptions {
        duration,
        ..TrialOptions::default()
    };
    let summary = run_sim_trial(&config, &trial, options, Arc::clone(&stop), |event| {
        let t_s = event_t_ns(event) as f64 * 1e-9;
        if let Some(rec) = recorder.as_mut().filter(|_| record_error.is_none()) {
            let result = match event {
                AcquisitionEvent::Poll(poll) => rec.record_segments(&SegmentsMessage {
                    t_s,
                    segments: poll
                        .readings
                        .iter()
                        .zip(&calibrations)
                        .enumerate()
                        .map(|(k, (r, &c))| SegmentSample::from_reading(r, c, poll.is_stale(k)))
                        .collect(),
                }),
                AcquisitionEvent::Stage { position_mm, .. } => rec.record_stage(&StageMessage {
                    t_s,
                    position_m: position_mm * 1e-3,
                }),
                AcquisitionEvent::Base { angle_rad, .. } => rec.record_servo(&ServoMessage {
                    t_s,
                    base_angle_rad: *angle_rad,
                }),
                _ => Ok(()),
            }
            .and_then(|()| rec.flush_if_due(t_s));
            if let Err(e) = result {
                eprintln!("antennad: recording failed, stopping the trial: {e}");
                record_error = Some(e.into());
                stop.store(true, Ordering::Relaxed);
            }
        }
        match event {
            AcquisitionEvent::Stage { position_mm, .. } => stage_mm = Some(*position_mm),
            AcquisitionEvent::Base { angle_rad, .. } => base_rad = Some(*angle_rad),
            AcquisitionEvent::Note { text, .. } => println!("{t_s:7.2}   -- {text}"),
            AcquisitionEvent::Health {
                address, change, ..
            } => match change {
                HealthChange::Stale => {
                    println!("{t_s:7.2}   -- segment {address:#04x}: counter stopped (stale)")
                }
                HealthChange::Recovered => {
                    println!("{t_s:7.2}   -- segment {address:#04x}: counter moving again")
                }
            },
            AcquisitionEvent::Poll(poll) => {
                if let Some((server, _)) = &server {
                    server.publish(&StreamMessage::Samples {
                        seq: poll.seq,
                        t_ns: poll.t_ns,
                        segments: poll
                            .readings
                            .iter()
                            .zip(&calibrations)
                            .map(|(r, c)| match r.result {
                                Ok(word) => NetSample {
                                    address: r.address,
                                    angle_rad: Some(c.angle_rad(word.angle_counts())),
                                    contact: Some(word.touch().any()),
                                    counter: None,
                                    error: None,
                                },
                                Err(e) => NetSample {
                                    address: r.address,
                                    angle_rad: None,
                                    contact: None,
                                    counter: None,
                                    error: Some(
                                        match e {
                                            PollError::Nack { .. } => "nack",
                                            PollError::Corrupted { .. } => "pec",
                                            PollError::Bus { .. } => "bus",
                                        }
                                        .to_owned(),
                                    ),
                                },
                            })
                            .collect(),
                        stage_position_m: stage_mm.map(|mm| mm * 1e-3),
                        base_angle_deg: base_rad.map(f64::to_degrees),
                    });
                }
                if poll.seq.is_multiple_of(print_every) {
                    print_line(t_s, stage_mm, poll, &calibrations);
                }
            }
        }
    })?;

    if let Some((server, _)) = server {
        server.shutdown();
    }
    if let Some(rec) = recorder {
        let written = rec.written();
        if let Some(e) = record_error {
            return Err(e.context("the recording failed"));
        }
        let path = rec.finish().context("closing the recording")?;
        println!(
            "antennad: recorded {} polls, {} stage and {} servo samples to {}",
            written.segments,
            written.stage,
            written.servo,
            path.display()
        );
    }
    println!(
        "antennad: {} polls in {:.2} s ({} deadlines skipped, latest wake-up {} us late), \
         {} moves ({} refused), {} events dropped",
        summary.polls,
        summary.elapsed.as_secs_f64(),
        summary.skipped,
        summary.max_lateness.as_micros(),
        summary.moves_started,
        summary.moves_refused,
        summary.dropped
    );
    for (address, health) in addresses.iter().zip(&summary.health) {
        if !health.all_ok() {
            println!("  segment {address:#04x}: {health:?}");
        }
    }
    Ok(())
}

fn event_t_ns(event: &AcquisitionEvent) -> u64 {
    match event {
        AcquisitionEvent::Poll(poll) => poll.t_ns,
        AcquisitionEvent::Stage { t_ns, .. }
        | AcquisitionEvent::Base { t_ns, .. }
        | AcquisitionEvent::Health { t_ns, .. }
        | AcquisitionEvent::Note { t_ns, .. } => *t_ns,
    }
}

fn print_line(
    t_s: f64,
    stage_mm: Option<f64>,
    poll: &host_daemon::acquisition::PollRecord,
    calibrations: &[antenna_protocol::Calibration],
) {
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
    println!("{t_s:7.2} {stage} {angles}   {touches}");
}

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

/// A control token for this run when none is configured: not guessable from outside.
fn generated_token() -> String {
    use std::hash::{BuildHasher, Hasher};
    let mut hasher = std::collections::hash_map::RandomState::new().build_hasher();
    hasher.write_u128(
        SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos()),
    );
    hasher.write_u32(std::process::id());
    format!("{:016x}", hasher.finish())
}
