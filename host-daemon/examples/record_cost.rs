//! What recording costs: the default trial (nine segments at 1 kHz on the simulated rig, the
//! stage carrying the antenna along the wall) recorded as antennad's hub records it, once per
//! way of recording, with the poll timing, the CPU share, the bytes per second written and
//! the time each sync to the disk took. A measurement, not a test:
//!
//! ```text
//! cargo run --release -p host-daemon --example record_cost [-- SECONDS [DIR]]
//! ```
//!
//! Ways (one run each, default 10 s): not recording; uncompressed JSON chunks synced only at
//! the end (what antennad wrote before zstd); zstd chunks synced only at the end; zstd synced
//! every second (the default, `recording.sync_interval_s = 1`); zstd synced at every 100 ms
//! flush (`recording.sync_interval_s = 0.1`). DIR (default: the current directory's
//! `target/record-cost`) should be on the disk the recordings go to. It prints one Markdown
//! table row per way. Jitter = |period - 1000 us| between successive poll starts, as in
//! `poll_jitter`; CPU = utime + stime of the whole process over wall time.

use antenna_data::record::{
    ChunkCompression, RecorderOptions, SegmentsMessage, ServoMessage, StageMessage, TrialMetadata,
    TrialRecorder,
};
use anyhow::{Context, Result};
use host_daemon::service::acquisition::AcquisitionEvent;
use host_daemon::service::config::Config;
use host_daemon::service::daemon::{Daemon, DaemonOptions, EventTap};
use host_daemon::service::samples::record_sample;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

mod support;
use support::{cpu_s, percentile};

/// One way of recording: a name and the recorder's options (`None`: no recording).
type Way = (&'static str, Option<RecorderOptions>);

/// What one run measured.
struct Run {
    polls: u64,
    skipped: u64,
    jitter_us: Vec<f64>,
    cpu_percent: f64,
    bytes: u64,
    seconds: f64,
    sync_ms: Vec<f64>,
}

/// What the event tap keeps of a run: the recorder, the polls' time stamps, the syncs' times.
struct Tap {
    recorder: Option<TrialRecorder>,
    stamps: Vec<u64>,
    sync_ms: Vec<f64>,
    failed: Option<anyhow::Error>,
}

impl Tap {
    /// Records `event` as antennad's hub does (when recording).
    fn take(&mut self, event: &AcquisitionEvent, calibrations: &[antenna_protocol::Calibration]) {
        let Some(recorder) = self.recorder.as_mut() else {
            if let AcquisitionEvent::Poll(p) = event {
                self.stamps.push(p.t_ns);
            }
            return;
        };
        let synced = recorder.synced();
        let started = Instant::now();
        let result = match event {
            AcquisitionEvent::Poll(p) => {
                self.stamps.push(p.t_ns);
                recorder.record_segments(&SegmentsMessage {
                    seq: Some(p.seq),
                    t_s: p.t_ns as f64 * 1e-9,
                    segments: p
                        .readings
                        .iter()
                        .zip(calibrations)
                        .enumerate()
                        .map(|(k, (r, &c))| record_sample(r, c, p.is_stale(k)))
                        .collect(),
                })
            }
            AcquisitionEvent::Stage { t_ns, position_mm } => recorder.record_stage(&StageMessage {
                t_s: *t_ns as f64 * 1e-9,
                position_m: position_mm * 1e-3,
            }),
            AcquisitionEvent::Base { t_ns, angle_rad } => recorder.record_servo(&ServoMessage {
                t_s: *t_ns as f64 * 1e-9,
                base_angle_rad: *angle_rad,
            }),
            _ => Ok(()),
        };
        if recorder.synced() != synced {
            self.sync_ms.push(started.elapsed().as_secs_f64() * 1e3);
        }
        if let Err(e) = result {
            self.failed.get_or_insert(e.into());
        }
    }
}

fn run(
    config: &Config,
    seconds: f64,
    options: Option<RecorderOptions>,
    path: &Path,
) -> Result<Run> {
    let metadata = TrialMetadata {
        trial: "record-cost".to_owned(),
        started_unix_s: 0.0,
        started_unix_ns: Some(0),
        config: config.to_recorded_toml(),
        notes: Default::default(),
        rig: Some(host_daemon::service::daemon::rig_info(config)),
    };
    let _ = std::fs::remove_file(path);
    let recorder = options
        .map(|o| TrialRecorder::create_with(path, &metadata, o))
        .transpose()?;
    let tap = Arc::new(Mutex::new(Tap {
        recorder,
        stamps: Vec::with_capacity((seconds * 1200.0) as usize),
        sync_ms: Vec::new(),
        failed: None,
    }));
    let on_event = {
        let tap = Arc::clone(&tap);
        let calibrations = config.bus.calibrations();
        EventTap::new(move |event| {
            if let Ok(mut tap) = tap.lock() {
                tap.take(event, &calibrations);
            }
        })
    };
    let cpu_before = cpu_s()?;
    let wall = Instant::now();
    // The daemon itself on the simulated rig, its own recording off: this one records.
    let summary = Daemon::start(
        config.clone(),
        DaemonOptions::tapped_trial(Duration::from_secs_f64(seconds), on_event),
    )?
    .wait()?;
    let elapsed = wall.elapsed().as_secs_f64();
    let Tap {
        recorder,
        stamps,
        mut sync_ms,
        failed,
    } = Arc::try_unwrap(tap)
        .map_err(|_| anyhow::anyhow!("the daemon still holds the event tap"))?
        .into_inner()
        .map_err(|_| anyhow::anyhow!("the event tap panicked"))?;
    if let Some(recorder) = recorder {
        recorder.finish()?;
    }
    let cpu_percent = 100.0 * (cpu_s()? - cpu_before) / elapsed;
    if let Some(e) = failed {
        return Err(e);
    }
    let period_ns = 1e9 / config.bus.poll_hz;
    let jitter_us = stamps
        .windows(2)
        .map(|w| ((w[1] - w[0]) as f64 - period_ns).abs() / 1e3)
        .collect();
    let bytes = std::fs::metadata(path).map_or(0, |m| m.len());
    sync_ms.sort_by(f64::total_cmp);
    Ok(Run {
        polls: summary.polls,
        skipped: summary.skipped,
        jitter_us,
        cpu_percent,
        bytes,
        seconds: summary.elapsed.as_secs_f64(),
        sync_ms,
    })
}

fn main() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let seconds: f64 = args
        .next()
        .map(|s| s.parse())
        .transpose()
        .context("SECONDS")?
        .unwrap_or(10.0);
    let dir: PathBuf = args
        .next()
        .map_or_else(|| PathBuf::from("target/record-cost"), PathBuf::from);
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let config = Config::default();
    let zstd = |sync_interval_s| RecorderOptions {
        compression: ChunkCompression::Zstd,
        sync_interval_s,
    };
    let ways: [Way; 5] = [
        ("not recording", None),
        (
            "uncompressed, synced at the end (before)",
            Some(RecorderOptions {
                compression: ChunkCompression::None,
                sync_interval_s: 0.0,
            }),
        ),
        ("zstd, synced at the end", Some(zstd(0.0))),
        ("**zstd, synced every 1 s (default)**", Some(zstd(1.0))),
        ("zstd, synced every 100 ms flush", Some(zstd(0.1))),
    ];
    println!(
        "{seconds} s per run, {} cores, files in {}",
        std::thread::available_parallelism().map_or(0, |n| n.get()),
        dir.display()
    );
    println!(
        "| recording | polls | skipped | jitter p50 / p99 / max (us) | CPU (% of a core) | \
         bytes/s | syncs | sync p50 / max (ms) |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for (name, options) in ways {
        let path = dir.join("record-cost.mcap");
        let mut r = run(&config, seconds, options, &path)?;
        r.jitter_us.sort_by(f64::total_cmp);
        let bytes_per_s = if options.is_some() {
            format!("{:.0}", r.bytes as f64 / r.seconds)
        } else {
            "-".to_owned()
        };
        println!(
            "| {name} | {} | {} | {:.1} / {:.1} / {:.0} | {:.1} | {bytes_per_s} | {} | {:.2} / {:.2} |",
            r.polls,
            r.skipped,
            percentile(&r.jitter_us, 0.5),
            percentile(&r.jitter_us, 0.99),
            r.jitter_us.last().copied().unwrap_or(f64::NAN),
            r.cpu_percent,
            r.sync_ms.len(),
            percentile(&r.sync_ms, 0.5),
            r.sync_ms.last().copied().unwrap_or(f64::NAN),
        );
        let _ = std::fs::remove_file(&path);
    }
    Ok(())
}
