//! Running many cases on every core, each in a child process with a time limit.
//!
//! A sweep the solver cannot finish can spend minutes in its placement or in one step, where
//! nothing can stop it from the outside of sim-core; so each case runs in a child process
//! (the test binary itself, told which case by [`CHILD_ENV`]) that prints its record
//! ([`super::wire`]) and is killed when it overruns its [`TimeLimit`]: the sweep is then
//! [`Outcome::TimedOut`], a failure. A rayon pool of worker threads (one per core unless
//! `ANTENNA_STRESS_THREADS` says otherwise) runs one child at a time on each.

use std::io::Read;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use rayon::prelude::*;

use super::StressError;
use super::case::{Case, Sample};
use super::outcome::{Outcome, SweepRecord, panic_message, run_case};
use super::wire::PROGRESS;

/// The environment variable that makes the test binary a child running one case:
/// `<sample>:<seed>:<index>`.
pub const CHILD_ENV: &str = "ANTENNA_STRESS_CHILD";

/// Builds and runs case `index` in this process (printing progress lines if
/// `echo_progress`); a generator error or a panic becomes the record's outcome.
pub fn run_index(seed: u64, index: u64, sample: Sample, echo_progress: bool) -> SweepRecord {
    let case = match Case::generate(seed, index, sample) {
        Ok(c) => c,
        Err(e) => return SweepRecord::invalid(seed, index, sample, e.to_string()),
    };
    match catch_unwind(AssertUnwindSafe(|| run_case(&case, echo_progress))) {
        Ok(rec) => rec,
        Err(panic) => {
            let what = panic_message(panic.as_ref());
            let mut rec = SweepRecord::new(&case);
            rec.outcome = Outcome::SolverFailure {
                step: None,
                message: format!("panic: {what}"),
            };
            rec
        }
    }
}

/// The child's side: runs the case `spec` (`<sample>:<seed>:<index>`, as in [`CHILD_ENV`])
/// and prints its record.
///
/// # Errors
/// [`StressError::Other`] for a malformed `spec`.
pub fn child_main(spec: &str) -> Result<(), StressError> {
    let bad = || {
        StressError::Other(format!(
            "{CHILD_ENV}={spec}: expected <sample>:<seed>:<index>"
        ))
    };
    let mut parts = spec.trim().split(':');
    let sample = parts.next().and_then(Sample::parse).ok_or_else(bad)?;
    let seed = parts.next().and_then(|s| s.parse().ok()).ok_or_else(bad)?;
    let index = parts.next().and_then(|s| s.parse().ok()).ok_or_else(bad)?;
    let rec = run_index(seed, index, sample, true);
    // On a line of its own (the test harness's "test ... " may precede it).
    print!("\n{}", rec.to_wire());
    Ok(())
}

/// How to start a child that runs one case.
#[derive(Clone, Debug)]
pub struct ChildCommand {
    /// The program (the test binary).
    pub program: PathBuf,
    /// Its arguments (run only the one test).
    pub args: Vec<String>,
}

impl ChildCommand {
    /// This test binary, running only the test `test_name` (which must call [`child_main`]
    /// when [`CHILD_ENV`] is set).
    ///
    /// # Errors
    /// [`StressError::Other`] when the binary's path is unknown.
    pub fn current_test(test_name: &str) -> Result<ChildCommand, StressError> {
        let program = std::env::current_exe()
            .map_err(|e| StressError::Other(format!("the test binary's path: {e}")))?;
        Ok(ChildCommand {
            program,
            args: vec![
                "--exact".into(),
                test_name.into(),
                "--nocapture".into(),
                "--test-threads=1".into(),
            ],
        })
    }
}

/// A sweep's time limit: `base_s + per_link_step_s * N * steps`, at most `max_s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeLimit {
    /// Seconds for any sweep (the process, the placement).
    pub base_s: f64,
    /// Seconds per step and link.
    pub per_link_step_s: f64,
    /// The most any sweep gets, seconds.
    pub max_s: f64,
}

impl TimeLimit {
    /// The limit for `case`, seconds.
    pub fn for_case(&self, case: &Case) -> f64 {
        (self.base_s + self.per_link_step_s * (case.links * case.steps()) as f64).min(self.max_s)
    }
}

/// The last step a child's output says was done.
pub fn last_progress(output: &str) -> Option<usize> {
    output
        .lines()
        .filter_map(|l| l.strip_prefix(PROGRESS))
        .filter_map(|s| s.trim().parse().ok())
        .next_back()
}

/// What a child process left: its output, and whether it was killed past its time limit.
#[derive(Clone, Debug)]
pub struct ChildRun {
    /// Its standard output.
    pub stdout: String,
    /// Its standard error.
    pub stderr: String,
    /// Whether it was killed past its time limit.
    pub killed: bool,
    /// How it exited, in words.
    pub status: String,
}

/// Runs `command` with [`CHILD_ENV`] set to `spec`, killed after `limit_s` seconds.
///
/// # Errors
/// The error of starting the process.
pub fn run_child(command: &ChildCommand, spec: &str, limit_s: f64) -> std::io::Result<ChildRun> {
    let started = Instant::now();
    let mut child = Command::new(&command.program)
        .args(&command.args)
        .env(CHILD_ENV, spec)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    let reader = |pipe: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut text = String::new();
            if let Some(mut p) = pipe {
                let _ = p.read_to_string(&mut text);
            }
            text
        })
    };
    let out = reader(
        child
            .stdout
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let err = reader(
        child
            .stderr
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let killed = loop {
        if !matches!(child.try_wait(), Ok(None)) {
            break false;
        }
        if started.elapsed().as_secs_f64() > limit_s {
            let _ = child.kill();
            break true;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let status = child.wait();
    Ok(ChildRun {
        stdout: out.join().unwrap_or_default(),
        stderr: err.join().unwrap_or_default(),
        killed,
        status: status.map_or_else(|e| e.to_string(), |s| s.to_string()),
    })
}

/// Runs case `index` in a child process, killed after its time limit.
pub fn run_in_child(
    command: &ChildCommand,
    limit: &TimeLimit,
    seed: u64,
    index: u64,
    sample: Sample,
) -> SweepRecord {
    let case = match Case::generate(seed, index, sample) {
        Ok(c) => c,
        Err(e) => return SweepRecord::invalid(seed, index, sample, e.to_string()),
    };
    let limit_s = limit.for_case(&case);
    let started = Instant::now();
    let mut rec = SweepRecord::new(&case);
    let spec = format!("{}:{seed}:{index}", sample.name());
    let child = match run_child(command, &spec, limit_s) {
        Ok(c) => c,
        Err(e) => {
            rec.outcome = Outcome::InvalidCase {
                message: format!("could not start a child process: {e}"),
            };
            return rec;
        }
    };
    if !child.killed
        && let Some(r) = SweepRecord::from_wire(&child.stdout)
    {
        return r;
    }
    rec.wall_clock_s = started.elapsed().as_secs_f64();
    rec.outcome = if child.killed {
        Outcome::TimedOut {
            limit_s,
            last_step: last_progress(&child.stdout),
        }
    } else {
        Outcome::SolverFailure {
            step: last_progress(&child.stdout).map(|s| s + 1),
            message: format!(
                "the child process ended ({}) without a record; its stderr ends: {}",
                child.status,
                stderr_tail(&child.stderr)
            ),
        }
    };
    rec
}

/// The last lines of a child's standard error, joined by ` / `.
pub fn stderr_tail(err: &str) -> String {
    let tail: Vec<&str> = err.lines().rev().take(6).collect();
    let tail: Vec<&str> = tail.into_iter().rev().collect();
    tail.join(" / ")
}

/// How [`run_cases`] runs.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Worker threads.
    pub threads: usize,
    /// A line to stderr every that many sweeps (0: none).
    pub progress_every: usize,
    /// How to start the child process that runs a case.
    pub command: ChildCommand,
    /// Its time limit.
    pub limit: TimeLimit,
}

/// The number of worker threads: `ANTENNA_STRESS_THREADS` or the machine's parallelism.
pub fn default_threads() -> usize {
    std::env::var("ANTENNA_STRESS_THREADS")
        .ok()
        .and_then(|v| v.parse().ok())
        .or_else(|| std::thread::available_parallelism().ok().map(|n| n.get()))
        .unwrap_or(2)
        .max(1)
}

/// Runs cases `indices` of `sample` under `seed`, each in a child process within its time
/// limit, on a pool of [`RunOptions::threads`] worker threads (rayon's, one case at a time
/// each); the records in index order.
pub fn run_cases(
    seed: u64,
    indices: &[u64],
    sample: Sample,
    options: &RunOptions,
) -> Vec<SweepRecord> {
    let mut out = on_workers(
        indices,
        options.threads,
        options.progress_every,
        "sweeps",
        |index| run_in_child(&options.command, &options.limit, seed, index, sample),
    );
    out.sort_by_key(|r| r.index);
    out
}

/// Runs `run` on every index of `indices` on a pool of `threads` worker threads (rayon's,
/// one index at a time each), with a line to stderr every `progress_every` (0: none)
/// naming them `noun`; the results in the order of `indices`.
pub fn on_workers<T: Send>(
    indices: &[u64],
    threads: usize,
    progress_every: usize,
    noun: &str,
    run: impl Fn(u64) -> T + Sync + Send,
) -> Vec<T> {
    let done = AtomicUsize::new(0);
    let total = indices.len();
    let started = Instant::now();
    let run_all = || -> Vec<T> {
        indices
            .par_iter()
            .with_max_len(1)
            .map(|&index| {
                let result = run(index);
                let count = done.fetch_add(1, Ordering::Relaxed) + 1;
                if progress_every > 0 && count.is_multiple_of(progress_every) {
                    eprintln!(
                        "[stress] {count}/{total} {noun}, {:.0} s",
                        started.elapsed().as_secs_f64()
                    );
                }
                result
            })
            .collect()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.max(1))
        .build();
    // A pool that cannot start its threads leaves the work to rayon's global pool.
    match pool {
        Ok(pool) => pool.install(run_all),
        Err(_) => run_all(),
    }
}
