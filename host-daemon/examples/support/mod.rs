//! What antennad's measurement examples share (`poll_jitter`, `record_cost`, `foxglove_cost`,
//! `estimate_latency`): this process's CPU time and memory from `/proc`, percentiles, a
//! background load of busy processes and the load average. Each example uses part of it.
#![allow(dead_code)]

use anyhow::{Context, Result};

/// utime + stime of this process, seconds (clock ticks of 1/100 s, Linux's USER_HZ).
pub fn cpu_s() -> Result<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").context("/proc/self/stat")?;
    // Fields after the command name (which is in parentheses and may hold spaces).
    let after = stat.rsplit_once(')').context("stat format")?.1;
    let fields: Vec<&str> = after.split_whitespace().collect();
    let ticks: u64 = fields[11].parse::<u64>()? + fields[12].parse::<u64>()?;
    Ok(ticks as f64 / 100.0)
}

/// A `Vm...` line of /proc/self/status, kB.
pub fn status_kb(key: &str) -> Result<u64> {
    let status = std::fs::read_to_string("/proc/self/status").context("/proc/self/status")?;
    let line = status
        .lines()
        .find(|l| l.starts_with(key))
        .with_context(|| format!("{key} in /proc/self/status"))?;
    Ok(line.split_whitespace().nth(1).context("value")?.parse()?)
}

/// The `p` quantile of `sorted` (nearest rank); NaN when it is empty.
pub fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

/// Background load: busy-looping processes, killed when dropped.
pub struct Load(Vec<std::process::Child>);

impl Load {
    /// `n` busy-looping processes (`sh -c 'while :; do :; done'`).
    pub fn start(n: usize) -> Result<Self> {
        let children = (0..n)
            .map(|_| {
                std::process::Command::new("sh")
                    .args(["-c", "while :; do :; done"])
                    .spawn()
                    .context("starting a busy process")
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Self(children))
    }
}

impl Drop for Load {
    fn drop(&mut self) {
        for child in &mut self.0 {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

/// The 1-minute load average.
pub fn load_average() -> Result<f64> {
    let text = std::fs::read_to_string("/proc/loadavg").context("/proc/loadavg")?;
    Ok(text.split_whitespace().next().context("loadavg")?.parse()?)
}
