//! Running a study: the grid points of one shard on a rayon pool of `--jobs` threads (each
//! sweep or follow run is independent), the rows handed back in grid order as they become
//! ready.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::Instant;

use indicatif::ProgressBar;

use super::row::profile_label;
use super::{FollowRow, Row, Shard, Study, StudyRow};
use crate::follow::run_summary;
use crate::follow::v_max::v_max;
use crate::progress;
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
    /// Follow rows whose status is `collided` (the body hit a wall: a physical outcome).
    pub collided: usize,
    /// Follow rows whose status is `lost` (no estimate for too long, or too far from the
    /// wall) or `unstable` (the loop unstable at its step): outcomes of the control, not
    /// failures of the solver.
    pub lost: usize,
}

/// Runs the grid points of `options.shard` on a pool of `options.jobs` threads and hands each
/// row to `on_row` in increasing grid order, as soon as it and every row before it are ready.
/// Stops early (and returns the error) if `on_row` fails: the sweeps under way finish, no new
/// one starts.
///
/// # Errors
/// The first error of `on_row` (e.g. the output closed).
pub fn run_study<E>(
    study: &Study,
    options: &RunOptions,
    on_row: &mut dyn FnMut(&Row) -> Result<(), E>,
) -> Result<RunCounts, E> {
    let indices: Vec<usize> = options.shard.indices(study.len()).collect();
    let mut rows = InOrder {
        progress: progress::bar(indices.len(), "runs", options.progress),
        pending: BTreeMap::new(),
        counts: RunCounts::default(),
    };
    let threads = options.jobs.clamp(1, indices.len().max(1));
    let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(threads).build() else {
        // No threads to be had: sweep on this one.
        for (k, &index) in indices.iter().enumerate() {
            rows.deliver(k, run_point(study, index), on_row)?;
        }
        rows.progress.finish_and_clear();
        return Ok(rows.counts);
    };
    let stop = AtomicBool::new(false);
    let (tx, rx) = mpsc::channel::<(usize, Row)>();
    // The points are queued in grid order (first in, first out) and this thread takes the
    // rows as they come back.
    pool.in_place_scope_fifo(|scope| {
        for (k, &index) in indices.iter().enumerate() {
            let (tx, stop) = (tx.clone(), &stop);
            scope.spawn_fifo(move |_| {
                if !stop.load(Ordering::Relaxed) {
                    // The receiver is gone only once a row could not be taken.
                    let _ = tx.send((k, run_point(study, index)));
                }
            });
        }
        drop(tx);
        for (k, row) in rx {
            if let Err(e) = rows.deliver(k, row, on_row) {
                // Nothing takes the rows any more: start no new sweep.
                stop.store(true, Ordering::Relaxed);
                return Err(e);
            }
        }
        Ok(())
    })?;
    rows.progress.finish_and_clear();
    Ok(rows.counts)
}

/// The rows that came back before the ones ahead of them, and what was handed on.
struct InOrder {
    progress: ProgressBar,
    pending: BTreeMap<usize, Row>,
    counts: RunCounts,
}

impl InOrder {
    /// Takes the `k`-th row of the shard and hands on every row now ready, in order.
    fn deliver<E>(
        &mut self,
        k: usize,
        row: Row,
        on_row: &mut dyn FnMut(&Row) -> Result<(), E>,
    ) -> Result<(), E> {
        self.pending.insert(k, row);
        while let Some(row) = self.pending.remove(&self.counts.runs) {
            on_row(&row)?;
            let counts = &mut self.counts;
            counts.runs += 1;
            match row.status() {
                "ok" => {}
                "jammed" => counts.jammed += 1,
                "collided" => counts.collided += 1,
                "lost" | "unstable" => counts.lost += 1,
                _ => counts.failed += 1,
            }
            if row.relaxed_steps().is_some_and(|r| r > 0) {
                counts.relaxed += 1;
            }
            self.progress.set_position(counts.runs as u64);
        }
        Ok(())
    }
}

/// The row of grid point `index`: its sweep, or in a follow study its closed-loop run (or
/// v_max search).
pub fn run_point(study: &Study, index: usize) -> Row {
    if study.is_follow() {
        Row::Follow(run_follow_point(study, index))
    } else {
        Row::Sweep(run_sweep_point(study, index))
    }
}

/// The closed-loop run (or, with `[v_max]`, the v_max search) of grid point `index`.
pub fn run_follow_point(study: &Study, index: usize) -> FollowRow {
    let started = Instant::now();
    let variant = study.variant(index);
    let shown = |scene: &antenna_scene::Scene| {
        let config = scene.follow.as_ref().map(|f| f.config).unwrap_or_default();
        let c = &config.controller;
        let wheeled = matches!(
            config.robot.body,
            sim_core::follow::BodyModel::Wheeled { .. }
        );
        FollowRow {
            index,
            profile: profile_label(&variant, scene),
            hairs: variant
                .hairs
                .as_ref()
                .map_or_else(|| "scene".to_string(), super::HairLayout::label),
            surface: variant
                .surface
                .map_or_else(|| "scene".to_string(), |s| s.label()),
            speed_m_per_s: study.v_max.is_none().then_some(config.robot.speed_m_per_s),
            kp_n: (!wheeled).then_some(c.kp_n),
            kd_n_s: (!wheeled).then_some(c.kd_n_s),
            kp_rad_per_s_per_m: wheeled.then_some(c.kp_rad_per_s_per_m),
            kd_rad_per_m: wheeled.then_some(c.kd_rad_per_m),
            delay_s: c.delay_s,
            status: "failed".to_string(),
            error: None,
            steps: None,
            duration_s: None,
            travel_m: None,
            rms_error_m: None,
            max_error_m: None,
            settling_distance_m: None,
            collisions: None,
            first_collision_s: None,
            contact_share: None,
            estimate_share: None,
            estimate_rms_error_m: None,
            v_max_m_per_s: None,
            v_max_failure: None,
            v_max_monotone: None,
            v_max_runs: None,
            wall_clock_ms: None,
        }
    };
    let scene = match variant.apply(&study.scene, study.bounds) {
        Ok(scene) => scene,
        Err(e) => {
            let mut row = shown(&study.scene);
            row.error = Some(format!("this grid point is not a valid scene: {e}"));
            return row;
        }
    };
    let mut row = shown(&scene);
    let (sweep_scene, config, sensors) = match scene.follow_parts() {
        Ok(parts) => parts,
        Err(e) => {
            row.error = Some(e.to_string());
            return row;
        }
    };
    let located = |e: &sim_core::follow::FollowError| match &scene.follow {
        Some(f) => f.locate(e).to_string(),
        None => e.to_string(),
    };
    match &study.v_max {
        None => match run_summary(&sweep_scene, &sensors, &config) {
            Ok(summary) => row.set_summary(&summary),
            Err(e) => row.error = Some(located(&e)),
        },
        Some(options) => match v_max(&sweep_scene, &sensors, &config, options) {
            Ok(result) => row.set_v_max(&result),
            Err(e) => row.error = Some(located(&e)),
        },
    }
    row.wall_clock_ms = Some(started.elapsed().as_secs_f64() * 1e3);
    row
}

/// The sweep of grid point `index`, as a row.
pub fn run_sweep_point(study: &Study, index: usize) -> StudyRow {
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
