//! Nine segments at 1 kHz on the simulated rig: poll period and jitter, wake-up lateness, CPU
//! share and RSS. A measurement, not a test:
//!
//! ```text
//! cargo run --release -p host-daemon --example poll_jitter [-- SECONDS]
//! ```
//!
//! It runs the default trial (the stage carrying the antenna along the wall, sim-core solving
//! the posture at 50 Hz) twice, without and with a 100 us busy wait before each deadline,
//! and prints one Markdown table row per run. The event consumer only keeps the time
//! stamps (no recording, no TCP server).

use anyhow::{Context, Result};
use host_daemon::acquisition::AcquisitionEvent;
use host_daemon::config::Config;
use host_daemon::sim_rig::{TrialOptions, run_sim_trial};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

/// utime + stime of this process, seconds (clock ticks of 1/100 s, Linux's USER_HZ).
fn cpu_s() -> Result<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").context("/proc/self/stat")?;
    // Fields after the command name (which is in parentheses and may hold spaces).
    let after = stat.rsplit_once(')').context("stat format")?.1;
    let fields: Vec<&str> = after.split_whitespace().collect();
    let ticks: u64 = fields[11].parse::<u64>()? + fields[12].parse::<u64>()?;
    Ok(ticks as f64 / 100.0)
}

/// A `Vm...` line of /proc/self/status, kB.
fn status_kb(key: &str) -> Result<u64> {
    let status = std::fs::read_to_string("/proc/self/status").context("/proc/self/status")?;
    let line = status
        .lines()
        .find(|l| l.starts_with(key))
        .with_context(|| format!("{key} in /proc/self/status"))?;
    Ok(line.split_whitespace().nth(1).context("value")?.parse()?)
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

fn main() -> Result<()> {
    let seconds: f64 = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()
        .context("SECONDS")?
        .unwrap_or(10.0);
    let config = Config::default();
    let period_us = 1e6 / config.bus.poll_hz;
    println!(
        "{} segments at {} Hz on the simulated rig, {seconds} s per run",
        config.bus.segments.len(),
        config.bus.poll_hz
    );
    println!(
        "| busy wait | polls | skipped | period p50 (us) | jitter p50 / p99 / max (us) | \
         late p50 / p99 (us) | CPU (% of a core) | RSS (MB) |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for spin_us in [0u64, 100] {
        let mut stamps: Vec<(u64, u64)> = Vec::with_capacity((seconds * 1200.0) as usize);
        let options = TrialOptions {
            duration: Some(Duration::from_secs_f64(seconds)),
            spin: Some(Duration::from_micros(spin_us)),
            ..TrialOptions::default()
        };
        let cpu_before = cpu_s()?;
        let wall = Instant::now();
        let summary = run_sim_trial(
            &config,
            &config.trials[0],
            options,
            Arc::new(AtomicBool::new(false)),
            |event| {
                if let AcquisitionEvent::Poll(p) = event {
                    stamps.push((p.t_ns, p.deadline_ns));
                }
            },
        )?;
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
        println!(
            "| {spin_us} us | {} | {} | {:.1} | {:.1} / {:.1} / {:.0} | {:.1} / {:.1} | {:.1} | {:.1} |",
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
    }
    println!(
        "peak RSS (VmHWM): {:.1} MB",
        status_kb("VmHWM:")? as f64 / 1024.0
    );
    Ok(())
}
