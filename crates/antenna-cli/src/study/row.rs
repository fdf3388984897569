//! One result row per grid point of a study, as CSV (a header, then one line per row, written
//! with the csv crate) or as JSON lines (one object per row). The columns are documented in `docs/sweeps.md` and on
//! [`StudyRow`]'s fields; an empty CSV field is a JSON `null`.

use serde::{Deserialize, Serialize};

use super::{FollowRow, Variant};
use crate::sweep::SweepSummary;
use antenna_scene::{Scene, StiffnessSpec};

/// How rows are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StudyFormat {
    /// Comma-separated values with a header line.
    Csv,
    /// One JSON object per line.
    Jsonl,
}

/// One row of a study: a sweep's ([`StudyRow`]) or a follow run's ([`FollowRow`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Row {
    /// A sweep study's row.
    Sweep(StudyRow),
    /// A follow study's row.
    Follow(FollowRow),
}

impl Row {
    /// The grid point.
    pub fn index(&self) -> usize {
        match self {
            Row::Sweep(r) => r.index,
            Row::Follow(r) => r.index,
        }
    }

    /// The row's status.
    pub fn status(&self) -> &str {
        match self {
            Row::Sweep(r) => &r.status,
            Row::Follow(r) => &r.status,
        }
    }

    /// Steps the solver relaxed something in (sweeps only).
    pub fn relaxed_steps(&self) -> Option<usize> {
        match self {
            Row::Sweep(r) => r.relaxed_steps,
            Row::Follow(_) => None,
        }
    }

    /// The CSV fields of `columns` (the study's [`super::Study::columns`]).
    pub fn csv_fields(&self, columns: &[&str]) -> Vec<String> {
        match self {
            Row::Sweep(r) => r.csv_fields(),
            Row::Follow(r) => r.csv_fields(columns),
        }
    }

    /// The row as one JSON line with `columns`' keys.
    pub fn json_line(&self, columns: &[&str]) -> String {
        match self {
            Row::Sweep(r) => r.json_line(),
            Row::Follow(r) => r.json_line(columns),
        }
    }
}

/// The result of one sweep of a study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StudyRow {
    /// The grid point, `0..` (the last axis varies fastest).
    pub index: usize,
    /// The stiffness profile (`custom` for explicit values).
    pub profile: String,
    /// The base angle, degrees.
    pub base_angle_deg: f64,
    /// The base pivot's start distance from the reference wall (the placement's wall, else
    /// wall 0), metres (`null` without walls).
    pub wall_distance_m: Option<f64>,
    /// The hair layout (`scene` when the axis is absent).
    pub hairs: String,
    /// The walls' surface (`scene` when the axis is absent).
    pub surface: String,
    /// `ok`; `jammed` (the antenna jammed against a wall: a physical outcome, the error
    /// names the contacts and the joints on their stops); or `failed` (the sweep stopped:
    /// the metrics cover the steps done).
    pub status: String,
    /// Why it failed (`null` when it did not).
    pub error: Option<String>,
    /// Steps swept.
    pub steps: Option<usize>,
    /// Simulated time swept, seconds.
    pub sweep_time_s: Option<f64>,
    /// Mean preview distance, metres.
    pub preview_mean_m: Option<f64>,
    /// Median preview distance, metres.
    pub preview_median_m: Option<f64>,
    /// Whether the distal segment flipped during the sweep.
    pub flipped: Option<bool>,
    /// The time of the first flip, seconds.
    pub first_flip_t_s: Option<f64>,
    /// Whether it was flipped after the placement.
    pub flipped_at_start: Option<bool>,
    /// Whether it was flipped at the end.
    pub flipped_at_end: Option<bool>,
    /// Steps that snapped.
    pub snaps: Option<usize>,
    /// Mean number of contacts per step.
    pub mean_contacts: Option<f64>,
    /// Pearson correlation of the point of bend with the base-to-wall distance.
    pub bend_distance_pearson: Option<f64>,
    /// Its Spearman rank correlation.
    pub bend_distance_spearman: Option<f64>,
    /// Pearson correlation of the point of contact with the base-to-wall distance.
    pub contact_distance_pearson: Option<f64>,
    /// Its Spearman rank correlation.
    pub contact_distance_spearman: Option<f64>,
    /// Contact points estimated from the sensed angles and touch bits.
    pub mapping_points: Option<usize>,
    /// Their mean distance to the true wall, millimetres.
    pub mapping_mean_error_mm: Option<f64>,
    /// The wall section passed: each point's mean distance to the nearest estimated point,
    /// millimetres (the sweep summary's `mapping_coverage_error_mm`).
    pub mapping_coverage_error_mm: Option<f64>,
    /// Its 90th percentile, millimetres.
    pub mapping_coverage_p90_mm: Option<f64>,
    /// The fraction of the section within 5 mm of an estimated point.
    pub mapping_completeness: Option<f64>,
    /// Wall-clock time of the sweep, milliseconds.
    pub wall_clock_ms: Option<f64>,
    /// Steps in which the solver relaxed something to get through (friction dropped on a
    /// jam or where friction locked the antenna, anchored hairs torn out, a residual
    /// accepted above the tolerance); `0` when nothing was relaxed.
    pub relaxed_steps: Option<usize>,
    /// Newton iterations per step, median.
    pub iterations_median: Option<usize>,
    /// Newton iterations per step, 99th percentile.
    pub iterations_p99: Option<usize>,
}

/// The CSV header, in [`StudyRow`]'s field order.
pub const CSV_COLUMNS: &[&str] = &[
    "index",
    "profile",
    "base_angle_deg",
    "wall_distance_m",
    "hairs",
    "surface",
    "status",
    "error",
    "steps",
    "sweep_time_s",
    "preview_mean_m",
    "preview_median_m",
    "flipped",
    "first_flip_t_s",
    "flipped_at_start",
    "flipped_at_end",
    "snaps",
    "mean_contacts",
    "bend_distance_pearson",
    "bend_distance_spearman",
    "contact_distance_pearson",
    "contact_distance_spearman",
    "mapping_points",
    "mapping_mean_error_mm",
    "mapping_coverage_error_mm",
    "mapping_coverage_p90_mm",
    "mapping_completeness",
    "wall_clock_ms",
    "relaxed_steps",
    "iterations_median",
    "iterations_p99",
];

impl StudyRow {
    /// The row of grid point `index`: its axis values as run (`scene` is the variant's
    /// scene, `None` when the variant could not be built), the summary of its sweep (or of
    /// the steps done) and the error that stopped it.
    pub fn new(
        index: usize,
        variant: &Variant,
        base: &Scene,
        scene: Option<&Scene>,
        summary: Option<&SweepSummary>,
        error: Option<String>,
    ) -> StudyRow {
        let shown = scene.unwrap_or(base);
        let profile = profile_label(variant, shown);
        let wall_distance_m = shown
            .walls
            .get(super::axes::reference_wall(shown))
            .map(|w| w.signed_distance(&shown.base_position_m).gap_m);
        StudyRow {
            index,
            profile,
            base_angle_deg: variant
                .base_angle_deg
                .unwrap_or_else(|| shown.chain.base_angle_rad().to_degrees()),
            wall_distance_m: variant.wall_distance_m.or(wall_distance_m),
            hairs: variant
                .hairs
                .as_ref()
                .map_or_else(|| "scene".to_string(), super::HairLayout::label),
            surface: variant
                .surface
                .map_or_else(|| "scene".to_string(), |s| s.label()),
            status: match (&error, summary) {
                (None, _) => "ok",
                (Some(_), Some(s)) if s.outcome == "jammed" => "jammed",
                (Some(_), _) => "failed",
            }
            .to_string(),
            error,
            steps: summary.map(|s| s.steps),
            sweep_time_s: summary.map(|s| s.sweep_time_s),
            preview_mean_m: summary.and_then(|s| s.preview_mean_m),
            preview_median_m: summary.and_then(|s| s.preview_median_m),
            flipped: summary.map(|s| s.flips > 0),
            first_flip_t_s: summary.and_then(|s| s.first_flip_t_s),
            flipped_at_start: summary.map(|s| s.flipped_at_start),
            flipped_at_end: summary.map(|s| s.flipped_at_end),
            snaps: summary.map(|s| s.snaps),
            mean_contacts: summary.map(|s| s.mean_contacts),
            bend_distance_pearson: summary.and_then(|s| s.bend_distance_pearson),
            bend_distance_spearman: summary.and_then(|s| s.bend_distance_spearman),
            contact_distance_pearson: summary.and_then(|s| s.contact_distance_pearson),
            contact_distance_spearman: summary.and_then(|s| s.contact_distance_spearman),
            mapping_points: summary.map(|s| s.mapping_points),
            mapping_mean_error_mm: summary.and_then(|s| s.mapping_mean_error_mm),
            mapping_coverage_error_mm: summary.and_then(|s| s.mapping_coverage_error_mm),
            mapping_coverage_p90_mm: summary.and_then(|s| s.mapping_coverage_p90_mm),
            mapping_completeness: summary.and_then(|s| s.mapping_completeness),
            wall_clock_ms: summary.map(|s| s.wall_clock_ms),
            relaxed_steps: summary.map(|s| s.relaxed_steps),
            iterations_median: summary.and_then(|s| s.iterations_median),
            iterations_p99: summary.and_then(|s| s.iterations_p99),
        }
    }

    /// The row's CSV fields, in [`CSV_COLUMNS`]' order: an absent value is empty, a number
    /// as JSON writes it (`30.0`), text as it is (the csv writer quotes it where needed).
    pub fn csv_fields(&self) -> Vec<String> {
        let value = serde_json::to_value(self).unwrap_or_default();
        CSV_COLUMNS
            .iter()
            .map(|c| match &value[*c] {
                serde_json::Value::Null => String::new(),
                serde_json::Value::String(s) => s.clone(),
                other => other.to_string(),
            })
            .collect()
    }

    /// The row as one JSON line.
    pub fn json_line(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }
}

/// The profile of a grid point as written in rows (`custom` for explicit values).
pub fn profile_label(variant: &Variant, scene: &Scene) -> String {
    match (&variant.profile, &scene.stiffness) {
        (Some(p), _) => p.name().to_string(),
        (None, StiffnessSpec::Profile { profile, .. }) => profile.name().to_string(),
        (None, StiffnessSpec::Values) => "custom".to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_columns_are_the_fields_in_order() {
        let row = StudyRow {
            index: 3,
            profile: "linear".into(),
            base_angle_deg: 30.0,
            wall_distance_m: Some(0.2),
            hairs: "distal".into(),
            surface: "smooth mu=0.3".into(),
            status: "failed".into(),
            error: Some("step 4 (t = 0.04 s) failed: \"why\", and more".into()),
            steps: Some(3),
            sweep_time_s: Some(0.03),
            preview_mean_m: None,
            preview_median_m: None,
            flipped: Some(false),
            first_flip_t_s: None,
            flipped_at_start: Some(true),
            flipped_at_end: Some(true),
            snaps: Some(0),
            mean_contacts: Some(1.5),
            bend_distance_pearson: None,
            bend_distance_spearman: None,
            contact_distance_pearson: None,
            contact_distance_spearman: None,
            mapping_points: Some(4),
            mapping_mean_error_mm: Some(1.25),
            mapping_coverage_error_mm: Some(2.5),
            mapping_coverage_p90_mm: Some(7.0),
            mapping_completeness: Some(0.75),
            wall_clock_ms: Some(12.0),
            relaxed_steps: Some(0),
            iterations_median: Some(1),
            iterations_p99: Some(3),
        };
        let value = serde_json::to_value(&row).unwrap_or_default();
        let keys: Vec<&String> = value
            .as_object()
            .map(|o| o.keys().collect())
            .unwrap_or_default();
        assert_eq!(keys.len(), CSV_COLUMNS.len());
        for c in CSV_COLUMNS {
            assert!(value.get(*c).is_some(), "{c}");
        }
        let mut csv = csv::Writer::from_writer(Vec::new());
        csv.write_record(row.csv_fields()).unwrap();
        let line = String::from_utf8(csv.into_inner().unwrap()).unwrap();
        assert!(line.starts_with("3,linear,30.0,0.2,distal,smooth mu=0.3,failed,\"step 4 (t = 0.04 s) failed: \"\"why\"\", and more\",3,0.03,,,false,"), "{line}");
        assert!(
            line.ends_with(",4,1.25,2.5,7.0,0.75,12.0,0,1,3\n"),
            "{line}"
        );
    }
}
