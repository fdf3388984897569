//! Running many cases on every core.

use std::ops::Range;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Instant;

use super::case::{Case, Sample};
use super::outcome::{Outcome, SweepRecord, run_case};

/// Builds and runs case `index` (with the iteration budget if `budgeted`, see
/// [`super::outcome::iteration_budget`]); a generator error or a panic becomes the record's
/// outcome.
pub fn run_index(seed: u64, index: u64, sample: Sample, budgeted: bool) -> SweepRecord {
    let case = match Case::generate(seed, index, sample) {
        Ok(c) => c,
        Err(e) => return SweepRecord::invalid(seed, index, sample, e.to_string()),
    };
    match catch_unwind(AssertUnwindSafe(|| run_case(&case, budgeted))) {
        Ok(rec) => rec,
        Err(panic) => {
            let what = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| (*s).to_owned()))
                .unwrap_or_default();
            let mut rec = SweepRecord::invalid(seed, index, sample, String::new());
            rec.links = case.links;
            rec.wall_kind = Some(case.wall.kind);
            rec.placement_kind = Some(case.placement_kind);
            rec.replay = case.replay_line();
            rec.outcome = Outcome::SolverFailure {
                step: None,
                message: format!("panic: {what}"),
            };
            rec
        }
    }
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

/// Runs cases `indices` of `sample` under `seed` on `threads` threads, each within the
/// iteration budget; the records in index order. With `progress_every > 0` a line goes to stderr every that many sweeps.
pub fn run_cases(
    seed: u64,
    indices: Range<u64>,
    sample: Sample,
    threads: usize,
    progress_every: usize,
) -> Vec<SweepRecord> {
    let next = AtomicU64::new(indices.start);
    let done = AtomicUsize::new(0);
    let total = indices.end.saturating_sub(indices.start);
    let started = Instant::now();
    let (tx, rx) = mpsc::channel();
    std::thread::scope(|scope| {
        for _ in 0..threads.max(1) {
            let tx = tx.clone();
            let (next, done, end) = (&next, &done, indices.end);
            scope.spawn(move || {
                loop {
                    let index = next.fetch_add(1, Ordering::Relaxed);
                    if index >= end {
                        break;
                    }
                    let rec = run_index(seed, index, sample, true);
                    let count = done.fetch_add(1, Ordering::Relaxed) + 1;
                    if progress_every > 0 && count.is_multiple_of(progress_every) {
                        eprintln!(
                            "[stress] {count}/{total} sweeps, {:.0} s",
                            started.elapsed().as_secs_f64()
                        );
                    }
                    if tx.send(rec).is_err() {
                        break;
                    }
                }
            });
        }
    });
    drop(tx);
    let mut out: Vec<SweepRecord> = rx.into_iter().collect();
    out.sort_by_key(|r| r.index);
    out
}
