//! The summary of a sweep (docs/model.md 8): steps, time, contacts, snaps, flips, preview
//! distance, the correlations of the point of bend and of the point of contact with the
//! base's distance to the wall, and the mapping error; accumulated step by step
//! ([`SweepStats`]) and reported as a [`SweepSummary`].

use std::fmt::Write as _;

use serde::{Deserialize, Serialize};
use sim_core::sweep::SweepStep;
use sim_core::{
    CoverageAccumulator, CoverageSettings, MappingAccumulator, Sensors, Wall, pearson_correlation,
    spearman_correlation,
};

use super::StepMetrics;

/// What a sweep did, over every recorded step (the placement, step 0, included).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepSummary {
    /// Steps of the sweep proper (the placement, step 0, not counted).
    pub steps: usize,
    /// Simulated time swept, seconds.
    pub sweep_time_s: f64,
    /// Wall-clock time of the placement and all steps, milliseconds.
    pub wall_clock_ms: f64,
    /// Steps (of `steps + 1`, the placement included) with at least one contact.
    pub steps_with_contact: usize,
    /// Mean number of contacts per step.
    pub mean_contacts: f64,
    /// Most contacts in one step.
    pub max_contacts: usize,
    /// Steps in which the posture snapped (left its branch of equilibria).
    pub snaps: usize,
    /// Whether the distal segment had flipped (beyond 90 degrees to the wall) after the
    /// placement.
    pub flipped_at_start: bool,
    /// How many times the distal segment flipped during the sweep (a step flipped after one
    /// that was not).
    pub flips: usize,
    /// The time of the first flip during the sweep, seconds (`null` without one).
    pub first_flip_t_s: Option<f64>,
    /// Whether the distal segment is flipped at the end.
    pub flipped_at_end: bool,
    /// Mean preview distance over the steps with a contact, metres (`null` without one).
    pub preview_mean_m: Option<f64>,
    /// Median preview distance over the steps with a contact, metres.
    pub preview_median_m: Option<f64>,
    /// Pearson correlation of the point of bend (joint number) with the base-to-wall
    /// distance over the steps (`null` where undefined: a constant point of bend, a
    /// distance constant to 1 nm, or fewer than two steps).
    pub bend_distance_pearson: Option<f64>,
    /// Spearman rank correlation of the same.
    pub bend_distance_spearman: Option<f64>,
    /// Pearson correlation of the point of contact (the most proximal contact's point
    /// number) with the base-to-wall distance over the steps with a contact.
    pub contact_distance_pearson: Option<f64>,
    /// Spearman rank correlation of the same.
    pub contact_distance_spearman: Option<f64>,
    /// Contact points estimated from the sensed angles and touch bits, over all steps.
    pub mapping_points: usize,
    /// Their mean distance to the true wall, millimetres (`null` without points).
    pub mapping_mean_error_mm: Option<f64>,
    /// Their largest distance to the true wall, millimetres.
    pub mapping_max_error_mm: Option<f64>,
    /// The wall section the antenna passed (per wall, between its first and last true contact
    /// along the motion), sampled every 0.5 mm of arclength: each sample's mean distance to
    /// the nearest estimated point, millimetres (`null` without points or contacts; see
    /// `sim_core::sensing::coverage`).
    pub mapping_coverage_error_mm: Option<f64>,
    /// The 90th percentile (nearest rank) of that distance, millimetres.
    pub mapping_coverage_p90_mm: Option<f64>,
    /// The fraction of that section within [`COMPLETE_WITHIN_MM`] of an estimated point
    /// (`null` without contacts; `0` without points).
    pub mapping_completeness: Option<f64>,
    /// The scene's `[sensors]` in force and the samples they took; absent (`None`) with
    /// ideal sensors, which sample every step.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensors: Option<SensorsSummary>,
    /// Substeps solved over all steps.
    pub substeps: usize,
    /// Newton iterations over all steps.
    pub iterations: usize,
    /// Newton iterations per step (the placement not counted): the median.
    pub iterations_median: Option<usize>,
    /// Newton iterations per step: the 99th percentile.
    pub iterations_p99: Option<usize>,
    /// Steps in which the solver relaxed something to get through (see each step's
    /// `relaxations`).
    pub relaxed_steps: usize,
    /// Steps in which friction was dropped at every contact (friction locked the antenna).
    pub friction_dropped_steps: usize,
    /// Contacts that jammed and slid without friction, summed over the steps.
    pub jammed_contacts: usize,
    /// Anchored hairs torn out, summed over the steps.
    pub anchors_released: usize,
    /// Steps whose residual was accepted above the tolerance.
    pub residual_above_tolerance_steps: usize,
    /// The largest torque imbalance the independent check found over the steps, N m.
    pub max_torque_residual_nm: f64,
    /// The deepest penetration the independent check found over the steps, m.
    pub max_penetration_m: f64,
    /// `"finished"`, `"jammed"` (the antenna jammed against a wall: a physical outcome) or
    /// `"failed"` (the solver found no equilibrium, or the input could not be swept).
    pub outcome: String,
    /// Why the sweep stopped early (`null` when it finished).
    pub stopped_by: Option<String>,
}

/// The sensor settings a sweep used (`[sensors]`, the calibration errors as drawn or given)
/// and the samples taken.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SensorsSummary {
    /// Samples taken (recorded steps the robot read its sensors at, the placement included).
    pub samples: u64,
    /// The sample rate, hertz (`null`: every step).
    pub sample_rate_hz: Option<f64>,
    /// The Hall angle noise of one sample, standard deviation, 12-bit counts.
    pub angle_noise_counts: f64,
    /// The calibration offset of each flexible joint `1..=n` in use, 12-bit counts.
    pub offset_counts: Vec<f64>,
    /// The gain error of each flexible joint `1..=n` in use, a fraction.
    pub gain_error: Vec<f64>,
    /// The force that closes a touch switch, newtons.
    pub touch_threshold_n: f64,
    /// Agreeing raw reads before a touch bit changes.
    pub touch_debounce_samples: u32,
    /// The seed of the noise and of drawn calibration errors.
    pub seed: u64,
    /// Whether a hair's touch is placed at the hair's open tip (`false`: on the link).
    pub hair_tip_points: bool,
}

impl SensorsSummary {
    /// The summary of `sensors` so far; `None` when they are ideal.
    pub fn of(sensors: &Sensors) -> Option<SensorsSummary> {
        let settings = sensors.settings();
        if settings.is_ideal() {
            return None;
        }
        let flexible = |per_link: &[f64]| per_link.get(1..).unwrap_or_default().to_vec();
        Some(SensorsSummary {
            samples: sensors.samples(),
            sample_rate_hz: settings.sample_rate_hz,
            angle_noise_counts: settings.angle_noise_counts,
            offset_counts: flexible(sensors.offset_counts()),
            gain_error: flexible(sensors.gain_error()),
            touch_threshold_n: settings.touch_threshold_n,
            touch_debounce_samples: settings.touch_debounce_samples,
            seed: settings.seed,
            hair_tip_points: settings.hair_tip_points,
        })
    }
}

/// A wall point this close to an estimated point counts as mapped
/// ([`SweepSummary::mapping_completeness`]), millimetres.
pub const COMPLETE_WITHIN_MM: f64 = 5.0;

/// The wall sampling and threshold of the sweep's coverage ([`COMPLETE_WITHIN_MM`]).
pub fn coverage_settings() -> CoverageSettings {
    CoverageSettings {
        complete_within_m: COMPLETE_WITHIN_MM * 1e-3,
        ..CoverageSettings::default()
    }
}

/// The running statistics of a sweep; [`Self::summary`] reports them.
#[derive(Debug, Clone, Default)]
pub struct SweepStats {
    /// The walls and the coverage gathered against them (`None`: not scored, see
    /// [`Self::with_coverage`]).
    coverage: Option<(Vec<Wall>, CoverageAccumulator)>,
    steps: usize,
    last_t_s: f64,
    contacts_total: usize,
    steps_with_contact: usize,
    max_contacts: usize,
    snaps: usize,
    flipped_at_start: bool,
    last_flipped: bool,
    flips: usize,
    first_flip_t_s: Option<f64>,
    previews_m: Vec<f64>,
    bend: (Vec<f64>, Vec<f64>),
    contact: (Vec<f64>, Vec<f64>),
    mapping: MappingAccumulator,
    substeps: usize,
    iterations: usize,
    step_iterations: Vec<usize>,
    relaxed_steps: usize,
    friction_dropped_steps: usize,
    jammed_contacts: usize,
    anchors_released: usize,
    residual_above_tolerance_steps: usize,
    max_torque_residual_nm: f64,
    max_penetration_m: f64,
    stopped_by: Option<(String, String)>,
}

impl SweepStats {
    /// Statistics that also score the map's coverage of `walls`, passed along
    /// `direction_rad` (the sweep's motion).
    pub fn with_coverage(walls: Vec<Wall>, direction_rad: f64) -> Self {
        let coverage = CoverageAccumulator::new(direction_rad, walls.len());
        Self {
            coverage: Some((walls, coverage)),
            ..Self::default()
        }
    }

    /// Records why the sweep stopped early: `outcome` is `"jammed"` or `"failed"`.
    pub fn stop(&mut self, outcome: &str, why: String) {
        self.stopped_by = Some((outcome.to_string(), why));
    }

    /// Adds a step (the placement, step 0, first).
    pub fn push(&mut self, step: &SweepStep, metrics: &StepMetrics) {
        let flipped = step.flipped();
        if step.step == 0 {
            self.flipped_at_start = flipped;
        } else {
            self.steps += 1;
            if flipped && !self.last_flipped {
                self.flips += 1;
                self.first_flip_t_s.get_or_insert(step.t_s);
            }
        }
        self.last_flipped = flipped;
        self.last_t_s = step.t_s;
        let contacts = step.contacts.len();
        self.contacts_total += contacts;
        self.max_contacts = self.max_contacts.max(contacts);
        if contacts > 0 {
            self.steps_with_contact += 1;
        }
        if step.report.snapped {
            self.snaps += 1;
        }
        if let Some(p) = step.preview_m {
            self.previews_m.push(p);
        }
        if let Some(d) = metrics.wall_distance_m {
            if let Some(j) = step.bend_joint {
                self.bend.0.push(d);
                self.bend.1.push(j as f64);
            }
            if let Some(j) = step.contact_joint {
                self.contact.0.push(d);
                self.contact.1.push(j as f64);
            }
        }
        for &e in &metrics.errors_mm {
            self.mapping.push(e);
        }
        if let Some((_, coverage)) = &mut self.coverage {
            coverage.pass(&step.contacts);
            coverage.estimate(metrics.estimates.iter().map(|e| e.point_m));
        }
        self.substeps += step.report.substeps;
        self.iterations += step.report.iterations;
        let r = &step.report;
        if step.step > 0 {
            self.step_iterations.push(r.iterations);
        }
        if r.relaxed() {
            self.relaxed_steps += 1;
        }
        if r.friction_dropped {
            self.friction_dropped_steps += 1;
        }
        self.jammed_contacts += r.jams;
        self.anchors_released += r.anchors_released;
        if r.residual_above_tolerance {
            self.residual_above_tolerance_steps += 1;
        }
        self.max_torque_residual_nm = self
            .max_torque_residual_nm
            .max(r.certificate.torque_residual_nm);
        self.max_penetration_m = self.max_penetration_m.max(r.certificate.penetration_m);
    }

    /// The summary so far; `wall_clock_ms` is the caller's measure.
    pub fn summary(&self, wall_clock_ms: f64) -> SweepSummary {
        let recorded = self.steps + 1;
        let mapping = self.mapping.score();
        // The walls, directions and points are checked where they are made (a scene, a
        // sweep's steps), so the coverage cannot fail on them; if it ever did, it is
        // reported as not scored (null), never as a number.
        let coverage = self
            .coverage
            .as_ref()
            .and_then(|(walls, c)| c.coverage(walls, &coverage_settings()).ok());
        SweepSummary {
            steps: self.steps,
            sweep_time_s: self.last_t_s,
            wall_clock_ms,
            steps_with_contact: self.steps_with_contact,
            mean_contacts: self.contacts_total as f64 / recorded as f64,
            max_contacts: self.max_contacts,
            snaps: self.snaps,
            flipped_at_start: self.flipped_at_start,
            flips: self.flips,
            first_flip_t_s: self.first_flip_t_s,
            flipped_at_end: self.last_flipped,
            preview_mean_m: mean(&self.previews_m),
            preview_median_m: median(&self.previews_m),
            bend_distance_pearson: correlation(&self.bend, pearson_correlation),
            bend_distance_spearman: correlation(&self.bend, spearman_correlation),
            contact_distance_pearson: correlation(&self.contact, pearson_correlation),
            contact_distance_spearman: correlation(&self.contact, spearman_correlation),
            mapping_points: mapping.count,
            mapping_mean_error_mm: mapping.mean_error_mm,
            mapping_max_error_mm: mapping.max_error_mm,
            mapping_coverage_error_mm: coverage.as_ref().and_then(|c| c.mean_error_mm),
            mapping_coverage_p90_mm: coverage.as_ref().and_then(|c| c.p90_error_mm),
            mapping_completeness: coverage.as_ref().and_then(|c| c.completeness),
            sensors: None,
            substeps: self.substeps,
            iterations: self.iterations,
            iterations_median: percentile(&self.step_iterations, 0.5),
            iterations_p99: percentile(&self.step_iterations, 0.99),
            relaxed_steps: self.relaxed_steps,
            friction_dropped_steps: self.friction_dropped_steps,
            jammed_contacts: self.jammed_contacts,
            anchors_released: self.anchors_released,
            residual_above_tolerance_steps: self.residual_above_tolerance_steps,
            max_torque_residual_nm: self.max_torque_residual_nm,
            max_penetration_m: self.max_penetration_m,
            outcome: self
                .stopped_by
                .as_ref()
                .map_or_else(|| "finished".to_string(), |(o, _)| o.clone()),
            stopped_by: self.stopped_by.as_ref().map(|(_, why)| why.clone()),
        }
    }
}

/// The `q`-quantile of `values` (nearest rank), `None` without values.
fn percentile(values: &[usize], q: f64) -> Option<usize> {
    if values.is_empty() {
        return None;
    }
    let mut sorted = values.to_vec();
    sorted.sort_unstable();
    let rank = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
    Some(sorted[rank - 1])
}

/// A distance that varies by less than this over a sweep is constant (a base moving along a
/// parallel wall): its correlations are undefined, not the noise of rounding, metres.
pub const CONSTANT_DISTANCE_M: f64 = 1e-9;

/// The correlation of a point number with the base-to-wall distance (`pairs.0`), `None`
/// where undefined: fewer than two steps, a constant point number, or a distance that
/// varies by less than [`CONSTANT_DISTANCE_M`].
fn correlation(
    pairs: &(Vec<f64>, Vec<f64>),
    how: fn(&[f64], &[f64]) -> Option<f64>,
) -> Option<f64> {
    let lo = pairs.0.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = pairs.0.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let range_m = hi - lo;
    if range_m.is_nan() || range_m < CONSTANT_DISTANCE_M {
        return None;
    }
    how(&pairs.0, &pairs.1)
}

fn mean(values: &[f64]) -> Option<f64> {
    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
}

fn median(values: &[f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let mid = sorted.len() / 2;
    Some(if sorted.len().is_multiple_of(2) {
        0.5 * (sorted[mid - 1] + sorted[mid])
    } else {
        sorted[mid]
    })
}

fn optional(value: Option<f64>, scale: f64, unit: &str) -> String {
    value.map_or_else(
        || "undefined".to_string(),
        |v| format!("{:.4}{unit}", v * scale),
    )
}

impl SweepSummary {
    /// A few lines for people.
    pub fn human(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(
            out,
            "{} steps, {:.3} s swept in {:.0} ms wall clock ({} substeps, {} Newton iterations)",
            self.steps, self.sweep_time_s, self.wall_clock_ms, self.substeps, self.iterations
        );
        let _ = writeln!(
            out,
            "contacts: {} of {} steps touch a wall; {:.2} contacts per step, at most {}",
            self.steps_with_contact,
            self.steps + 1,
            self.mean_contacts,
            self.max_contacts
        );
        let flip_time = self
            .first_flip_t_s
            .map_or_else(String::new, |t| format!(", first at t = {t:.3} s"));
        let _ = writeln!(
            out,
            "snaps: {}; flips: {}{flip_time} (flipped after placement: {}, at the end: {})",
            self.snaps,
            self.flips,
            yes_no(self.flipped_at_start),
            yes_no(self.flipped_at_end)
        );
        let _ = writeln!(
            out,
            "preview distance: mean {}, median {}",
            optional(self.preview_mean_m, 1e3, " mm"),
            optional(self.preview_median_m, 1e3, " mm")
        );
        let _ = writeln!(
            out,
            "correlation with the base-to-wall distance: point of bend {} (Spearman {}), point of contact {} (Spearman {})",
            optional(self.bend_distance_pearson, 1.0, ""),
            optional(self.bend_distance_spearman, 1.0, ""),
            optional(self.contact_distance_pearson, 1.0, ""),
            optional(self.contact_distance_spearman, 1.0, "")
        );
        let _ = writeln!(
            out,
            "mapping from sensed angles and touch bits: {} points, mean error {}, max {}",
            self.mapping_points,
            optional(self.mapping_mean_error_mm, 1.0, " mm"),
            optional(self.mapping_max_error_mm, 1.0, " mm")
        );
        let _ = writeln!(
            out,
            "wall coverage of the section passed: mean {}, p90 {}, {} within {COMPLETE_WITHIN_MM} mm",
            optional(self.mapping_coverage_error_mm, 1.0, " mm"),
            optional(self.mapping_coverage_p90_mm, 1.0, " mm"),
            self.mapping_completeness
                .map_or_else(|| "-".to_string(), |c| format!("{:.1} %", 100.0 * c)),
        );
        if let Some(sensors) = &self.sensors {
            let rate = sensors
                .sample_rate_hz
                .map_or_else(|| "every step".to_string(), |r| format!("{r} Hz"));
            let largest = |values: &[f64]| values.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            let _ = writeln!(
                out,
                "sensors: {} samples ({rate}); angle noise {} counts, calibration offsets up to \
                 {:.2} counts and gain errors up to {:.2} %, touch threshold {} N, debounce {} \
                 sample(s), seed {}",
                sensors.samples,
                sensors.angle_noise_counts,
                largest(&sensors.offset_counts),
                100.0 * largest(&sensors.gain_error),
                sensors.touch_threshold_n,
                sensors.touch_debounce_samples,
                sensors.seed
            );
        }
        let _ = writeln!(
            out,
            "solver: Newton iterations per step median {}, p99 {}; every step certified (largest \
             torque imbalance {:.1e} N m, deepest penetration {:.1e} m)",
            self.iterations_median
                .map_or_else(|| "-".to_string(), |v| v.to_string()),
            self.iterations_p99
                .map_or_else(|| "-".to_string(), |v| v.to_string()),
            self.max_torque_residual_nm,
            self.max_penetration_m
        );
        if self.relaxed_steps > 0 {
            let _ = writeln!(
                out,
                "RELAXED in {} step(s): friction dropped at every contact in {}, {} jammed \
                 contact(s) slid without friction, {} anchored hair(s) torn out, {} residual(s) \
                 accepted above the tolerance",
                self.relaxed_steps,
                self.friction_dropped_steps,
                self.jammed_contacts,
                self.anchors_released,
                self.residual_above_tolerance_steps
            );
        }
        if let Some(why) = &self.stopped_by {
            let _ = writeln!(out, "{}: {why}", self.outcome.to_uppercase());
        }
        out
    }
}

fn yes_no(b: bool) -> &'static str {
    if b { "yes" } else { "no" }
}
