//! Nine segments at 1 kHz on the simulated rig: poll period and jitter, wake-up lateness, CPU
//! share and RSS. A measurement, not a test:
//!
//! ```text
//! cargo run --release -p host-daemon --example poll_jitter [-- SECONDS [BUSY...]]
//! ```
//!
//! It runs the default trial (the stage carrying the antenna along the wall, sim-core solving
//! the posture at 50 Hz) once per way of waiting for the poll deadline: a plain sleep on
//! normal scheduling (`bus.realtime_priority = 0`), the same then a 100 us busy wait
//! (`bus.spin_us = 100`), a sleep on `SCHED_FIFO` priority 50 (the default, when permitted),
//! and `SCHED_FIFO` with a 20 us busy wait; and all of that
//! once per background load: each `BUSY` is a number of busy-looping processes (`sh -c 'while
//! :; do :; done'`) started for those runs (default: `0 2`). It prints one Markdown table row
//! per run. It runs antennad itself (`Daemon::start`, no recording, no TCP server); its event
//! tap only keeps the time stamps.

use anyhow::{Context, Result};
use host_daemon::service::acquisition::AcquisitionEvent;
use host_daemon::service::config::Config;
use host_daemon::service::daemon::{Daemon, DaemonOptions, EventTap};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

mod support;
use support::{Load, cpu_s, load_average, percentile, status_kb};

fn main() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let seconds: f64 = args
        .next()
        .map(|s| s.parse())
        .transpose()
        .context("SECONDS")?
        .unwrap_or(10.0);
    let loads: Vec<usize> = args
        .map(|s| s.parse().context("BUSY: a number of busy processes"))
        .collect::<Result<_>>()?;
    let loads = if loads.is_empty() { vec![0, 2] } else { loads };
    let config = Config::default();
    let period_us = 1e6 / config.bus.poll_hz;
    println!(
        "{} segments at {} Hz on the simulated rig, {seconds} s per run, {} cores",
        config.bus.segments.len(),
        config.bus.poll_hz,
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
    println!(
        "| busy processes (load avg) | wait | polls | skipped | period p50 (us) | \
         jitter p50 / p99 / max (us) | late p50 / p99 (us) | CPU (% of a core) | RSS (MB) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let modes: [(&str, u64, u8); 4] = [
        ("normal scheduling, sleep", 0, 0),
        ("normal scheduling, sleep + 100 us spin", 100, 0),
        ("SCHED_FIFO 50, sleep (default)", 0, 50),
        ("SCHED_FIFO 50, sleep + 20 us spin", 20, 50),
    ];
    for &busy in &loads {
        let _load = Load::start(busy)?;
        // Let the load average feel the load.
        std::thread::sleep(Duration::from_secs(if busy > 0 { 5 } else { 0 }));
        for (mode, spin_us, priority) in modes {
            // The event tap keeps the polls' time stamps and a refused real-time request.
            type Seen = (Vec<(u64, u64)>, Option<String>);
            let seen: Arc<Mutex<Seen>> = Arc::new(Mutex::new((
                Vec::with_capacity((seconds * 1200.0) as usize),
                None,
            )));
            let on_event = {
                let seen = Arc::clone(&seen);
                EventTap::new(move |event| {
                    let Ok(mut seen) = seen.lock() else { return };
                    match event {
                        AcquisitionEvent::Poll(p) => seen.0.push((p.t_ns, p.deadline_ns)),
                        AcquisitionEvent::Note { text, .. } if text.contains("refused") => {
                            seen.1 = Some(text.clone());
                        }
                        _ => {}
                    }
                })
            };
            let mut run_config = config.clone();
            run_config.bus.spin_us = spin_us;
            run_config.bus.realtime_priority = priority;
            let cpu_before = cpu_s()?;
            let wall = Instant::now();
            // The daemon itself on the simulated rig, no recording, no TCP server.
            let summary = Daemon::start(
                run_config,
                DaemonOptions::tapped_trial(Duration::from_secs_f64(seconds), on_event),
            )?
            .wait()?;
            let (stamps, refused) = std::mem::take(
                &mut *seen
                    .lock()
                    .map_err(|_| anyhow::anyhow!("the event tap panicked"))?,
            );
            let cpu = (cpu_s()? - cpu_before) / wall.elapsed().as_secs_f64();
            let rss_mb = status_kb("VmRSS:")? as f64 / 1024.0;
            let mut periods: Vec<f64> = stamps
                .windows(2)
                .map(|w| (w[1].0 - w[0].0) as f64 / 1e3)
                .collect();
            let mut jitter: Vec<f64> = periods.iter().map(|p| (p - period_us).abs()).collect();
            let mut late: Vec<f64> = stamps.iter().map(|(t, d)| (t - d) as f64 / 1e3).collect();
            periods.sort_by(f64::total_cmp);
            jitter.sort_by(f64::total_cmp);
            late.sort_by(f64::total_cmp);
            let mode = match &refused {
                Some(_) => format!("{mode} (refused: normal scheduling)"),
                None => mode.to_owned(),
            };
            println!(
                "| {busy} ({:.1}) | {mode} | {} | {} | {:.1} | {:.1} / {:.1} / {:.0} | {:.1} / {:.1} | {:.1} | {:.1} |",
                load_average()?,
                summary.polls,
                summary.skipped,
                percentile(&periods, 0.5),
                percentile(&jitter, 0.5),
                percentile(&jitter, 0.99),
                jitter.last().copied().unwrap_or(0.0),
                percentile(&late, 0.5),
                percentile(&late, 0.99),
                100.0 * cpu,
                rss_mb
            );
            if let Some(text) = refused {
                eprintln!("{text}");
            }
        }
    }
    println!(
        "peak RSS (VmHWM): {:.1} MB",
        status_kb("VmHWM:")? as f64 / 1024.0
    );
    Ok(())
}
