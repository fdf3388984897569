//! Running a study: the grid points of one shard on a pool of threads (each sweep is
//! independent), the rows handed back in grid order as they become ready.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;

use super::{Shard, Study, StudyRow};
use crate::progress::Progress;
use crate::sweep::SweepRun;

/// How to run a study.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunOptions {
    /// Which grid points.
    pub shard: Shard,
    /// Threads (at least 1).
    pub jobs: usize,
    /// Whether to draw a progress bar on stderr (when it is a terminal).
    pub progress: bool,
}

/// How many sweeps ran and how many of them failed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RunCounts {
    /// Rows written.
    pub runs: usize,
    /// Rows whose status is `failed`.
    pub failed: usize,
    /// Rows whose status is `jammed` (the antenna jammed: a physical outcome).
    pub jammed: usize,
    /// Rows with steps the solver relaxed something in.
    pub relaxed: usize,
}

/// Runs the grid points of `options.shard` on `options.jobs` threads and hands each row to
/// `on_row` in increasing grid order. Stops early (and returns the error) if `on_row` fails.
///
/// # Errors
/// The first error of `on_row` (e.g. the output closed).
pub fn run_study<E>(
    study: &Study,
    options: &RunOptions,
    on_row: &mut dyn FnMut(&StudyRow) -> Result<(), E>,
) -> Result<RunCounts, E> {
    let indices: Vec<usize> = options.shard.indices(study.len()).collect();
    let next = AtomicUsize::new(0);
    let mut progress = Progress::new(indices.len(), "runs");
    if !options.progress {
        progress.finish();
    }
    let mut counts = RunCounts::default();
    std::thread::scope(|scope| {
        let (tx, rx) = mpsc::channel::<(usize, StudyRow)>();
        let workers = options.jobs.clamp(1, indices.len().max(1));
        for _ in 0..workers {
            let tx = tx.clone();
            let (indices, next) = (&indices, &next);
            scope.spawn(move || {
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&index) = indices.get(k) else {
                        break;
                    };
                    if tx.send((k, run_point(study, index))).is_err() {
                        break;
                    }
                }
            });
        }
        drop(tx);
        let mut pending = BTreeMap::new();
        for (k, row) in rx {
            pending.insert(k, row);
            while let Some(row) = pending.remove(&counts.runs) {
                if let Err(e) = on_row(&row) {
                    // Stop the workers: nothing takes their rows any more.
                    next.store(indices.len(), Ordering::Relaxed);
                    return Err(e);
                }
                counts.runs += 1;
                match row.status.as_str() {
                    "ok" => {}
                    "jammed" => counts.jammed += 1,
                    _ => counts.failed += 1,
                }
                if row.relaxed_steps.is_some_and(|r| r > 0) {
                    counts.relaxed += 1;
                }
                progress.set(counts.runs);
            }
        }
        Ok(())
    })?;
    progress.finish();
    Ok(counts)
}

/// The sweep of grid point `index`, as a row.
pub fn run_point(study: &Study, index: usize) -> StudyRow {
    let variant = study.variant(index);
    let scene = match variant.apply(&study.scene, study.bounds) {
        Ok(scene) => scene,
        Err(e) => {
            return StudyRow::new(
                index,
                &variant,
                &study.scene,
                None,
                None,
                Some(format!("this grid point is not a valid scene: {e}")),
            );
        }
    };
    let mut run = match SweepRun::start(&scene) {
        Ok(run) => run,
        Err(e) => {
            return StudyRow::new(
                index,
                &variant,
                &study.scene,
                Some(&scene),
                None,
                Some(e.to_string()),
            );
        }
    };
    let mut error = None;
    while let Some(state) = run.next_state() {
        if let Err(e) = state {
            error = Some(e.to_string());
            break;
        }
    }
    StudyRow::new(
        index,
        &variant,
        &study.scene,
        Some(&scene),
        Some(&run.summary()),
        error,
    )
}
