//! The summary: a markdown table by `N`, by wall kind and by placement (and all sweeps),
//! the distinct reasons of placement refusals, jams and relaxations with their counts, and
//! every failure with its replay line.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::case::{PlacementKind, WIDE_LINK_COUNTS};
use super::outcome::{Outcome, SweepRecord};
use super::walls::WallKind;

/// The `q`-quantile (nearest rank) of sorted `values`.
fn quantile(sorted: &[u32], q: f64) -> Option<u32> {
    if sorted.is_empty() {
        return None;
    }
    let rank = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
    Some(sorted[rank - 1])
}

/// One row of the table.
fn row(label: &str, records: &[&SweepRecord]) -> String {
    let count = |f: fn(&Outcome) -> bool| records.iter().filter(|r| f(&r.outcome)).count();
    let mut iterations: Vec<u32> = records
        .iter()
        .flat_map(|r| r.iterations.iter().copied())
        .collect();
    iterations.sort_unstable();
    let show = |v: Option<u32>| v.map_or("-".to_owned(), |v| v.to_string());
    let wall_clock: f64 = records.iter().map(|r| r.wall_clock_s).sum();
    let slowest = records
        .iter()
        .map(|r| r.wall_clock_s)
        .fold(0.0_f64, f64::max);
    format!(
        "| {label} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} / {} | {:.1} s ({:.2} s) |",
        records.len(),
        count(|o| matches!(o, Outcome::Finished)),
        count(|o| matches!(o, Outcome::Jammed { .. })),
        count(|o| matches!(o, Outcome::PlacementRefused { .. })),
        count(|o| matches!(
            o,
            Outcome::SolverFailure { .. } | Outcome::InvalidCase { .. }
        )),
        count(|o| matches!(o, Outcome::TimedOut { .. })),
        count(|o| matches!(o, Outcome::Uncertified { .. })),
        records.iter().map(|r| r.steps).sum::<usize>(),
        records.iter().map(|r| r.contact_steps).sum::<usize>(),
        records.iter().map(|r| r.relaxed_steps).sum::<usize>(),
        show(quantile(&iterations, 0.5)),
        show(quantile(&iterations, 0.99)),
        wall_clock,
        slowest,
    )
}

/// Counts of generalized reasons, most frequent first.
fn reasons<'a>(items: impl Iterator<Item = (String, usize)> + 'a) -> Vec<(String, usize)> {
    let mut map: BTreeMap<String, usize> = BTreeMap::new();
    for (reason, count) in items {
        *map.entry(reason).or_default() += count;
    }
    let mut v: Vec<(String, usize)> = map.into_iter().collect();
    v.sort_by(|a, b| b.1.cmp(&a.1).then_with(|| a.0.cmp(&b.0)));
    v
}

fn reason_list(out: &mut String, title: &str, list: &[(String, usize)]) {
    let _ = writeln!(out, "\n{title}:");
    if list.is_empty() {
        let _ = writeln!(out, "- none");
    }
    for (reason, count) in list {
        let _ = writeln!(out, "- {count} x {reason}");
    }
}

/// The summary of `records` in markdown.
pub fn summary_markdown(records: &[SweepRecord]) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "| sweeps of | sweeps | finished | jammed | placement refused | solver failures | \
         timed out | uncertified | steps | steps in contact | relaxed steps | Newton iterations per step \
         median / p99 | wall clock (slowest sweep) |"
    );
    let _ = writeln!(
        out,
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    let all: Vec<&SweepRecord> = records.iter().collect();
    let _ = writeln!(out, "{}", row("all", &all));
    for n in WIDE_LINK_COUNTS {
        let group: Vec<&SweepRecord> = records.iter().filter(|r| r.links == n).collect();
        if !group.is_empty() {
            let _ = writeln!(out, "{}", row(&format!("N = {n}"), &group));
        }
    }
    for kind in WallKind::ALL {
        let group: Vec<&SweepRecord> = records
            .iter()
            .filter(|r| r.wall_kind == Some(kind))
            .collect();
        if !group.is_empty() {
            let _ = writeln!(out, "{}", row(&format!("{} walls", kind.name()), &group));
        }
    }
    for kind in PlacementKind::ALL {
        let group: Vec<&SweepRecord> = records
            .iter()
            .filter(|r| r.placement_kind == Some(kind))
            .collect();
        if !group.is_empty() {
            let _ = writeln!(out, "{}", row(&format!("placed {}", kind.name()), &group));
        }
    }
    let invalid: Vec<&SweepRecord> = records
        .iter()
        .filter(|r| matches!(r.outcome, Outcome::InvalidCase { .. }))
        .collect();
    if !invalid.is_empty() {
        let _ = writeln!(
            out,
            "\n{} case(s) could not be built by the generator (counted as solver failures \
             above).",
            invalid.len()
        );
    }
    let of = |f: fn(&Outcome) -> bool| {
        reasons(
            records
                .iter()
                .filter(move |r| f(&r.outcome))
                .map(|r| (r.outcome.reason(), 1)),
        )
    };
    reason_list(
        &mut out,
        "Placement refusals, by reason",
        &of(|o| matches!(o, Outcome::PlacementRefused { .. })),
    );
    reason_list(
        &mut out,
        "Jams, by reason",
        &of(|o| matches!(o, Outcome::Jammed { .. })),
    );
    reason_list(
        &mut out,
        "Relaxed steps, by what was relaxed",
        &reasons(
            records
                .iter()
                .flat_map(|r| r.relaxations.iter().map(|(k, v)| (k.clone(), *v))),
        ),
    );
    reason_list(
        &mut out,
        "Solver failures and uncertified steps, by reason",
        &of(Outcome::is_failure),
    );
    let mut slowest: Vec<&SweepRecord> = records.iter().collect();
    slowest.sort_by(|a, b| b.wall_clock_s.total_cmp(&a.wall_clock_s));
    let _ = writeln!(out, "\nSlowest sweeps:");
    for r in slowest.iter().take(5) {
        let _ = writeln!(out, "- {}\n  -> {}", r.replay, r.outcome_line());
    }
    out
}

/// Every sweep that did not finish, grouped by generalized reason: the replay line and the
/// exact message (failures first, then jams, then refusals).
pub fn unfinished_report(records: &[SweepRecord]) -> String {
    let mut out = String::new();
    type Class = (&'static str, fn(&Outcome) -> bool);
    let classes: [Class; 3] = [
        ("solver failures and uncertified steps", Outcome::is_failure),
        ("jams", |o| matches!(o, Outcome::Jammed { .. })),
        ("placement refusals", |o| {
            matches!(o, Outcome::PlacementRefused { .. })
        }),
    ];
    for (title, f) in classes {
        let mut groups: BTreeMap<String, Vec<&SweepRecord>> = BTreeMap::new();
        for r in records.iter().filter(|r| f(&r.outcome)) {
            groups.entry(r.outcome.reason()).or_default().push(r);
        }
        if groups.is_empty() {
            continue;
        }
        let _ = writeln!(out, "\n## {title}");
        for (reason, group) in groups {
            let _ = writeln!(out, "\n### {} x {reason}", group.len());
            for r in group {
                let _ = writeln!(out, "- {}", r.replay);
                let _ = writeln!(out, "  -> {}", r.outcome_line());
            }
        }
    }
    out
}
