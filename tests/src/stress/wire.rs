//! A sweep's record as text: a case runs in a child process (which the parent can kill when
//! it overruns its time limit) and prints its record between [`BEGIN`] and [`END`].
//!
//! One field per line, `key<TAB>value<TAB>value...`, every value escaped (`\\`, `\n`, `\t`).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::case::{PlacementKind, Sample};
use super::outcome::{Outcome, SweepRecord};
use super::trajectory::Trajectory;
use super::walls::WallKind;

/// The line before a record.
pub const BEGIN: &str = "<<<stress-record";
/// The line after a record.
pub const END: &str = "stress-record>>>";
/// The start of a progress line a child prints (`stress-progress <step>`: the placement is
/// step 0).
pub const PROGRESS: &str = "stress-progress ";

/// `s` with `\\`, newlines and tabs escaped (one field of a record line).
pub fn escape(s: &str) -> String {
    s.replace('\\', "\\\\")
        .replace('\n', "\\n")
        .replace('\t', "\\t")
}

/// The inverse of [`escape`].
pub fn unescape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut chars = s.chars();
    while let Some(c) = chars.next() {
        if c == '\\' {
            match chars.next() {
                Some('n') => out.push('\n'),
                Some('t') => out.push('\t'),
                Some(other) => out.push(other),
                None => {}
            }
        } else {
            out.push(c);
        }
    }
    out
}

fn step_or_dash(step: Option<usize>) -> String {
    step.map_or("-".to_owned(), |s| s.to_string())
}

impl SweepRecord {
    /// The record as text, [`BEGIN`] to [`END`].
    pub fn to_wire(&self) -> String {
        let mut out = String::new();
        let mut line = |key: &str, values: &[String]| {
            let _ = write!(out, "{key}");
            for v in values {
                let _ = write!(out, "\t{}", escape(v));
            }
            out.push('\n');
        };
        line(BEGIN, &[]);
        line("seed", &[self.seed.to_string()]);
        line("index", &[self.index.to_string()]);
        line("sample", &[self.sample.name().to_owned()]);
        line("links", &[self.links.to_string()]);
        line(
            "wall",
            &[self.wall_kind.map_or("-", WallKind::name).to_owned()],
        );
        line(
            "placement",
            &[self
                .placement_kind
                .map_or("-", PlacementKind::name)
                .to_owned()],
        );
        line("replay", std::slice::from_ref(&self.replay));
        let outcome: Vec<String> = match &self.outcome {
            Outcome::Finished => vec!["finished".into()],
            Outcome::Jammed {
                step,
                description,
                contacts,
                joints_on_stops,
            } => {
                let joints: Vec<String> = joints_on_stops.iter().map(usize::to_string).collect();
                let mut v = vec![
                    "jammed".into(),
                    step.to_string(),
                    description.clone(),
                    joints.join(","),
                ];
                v.extend(contacts.iter().cloned());
                v
            }
            Outcome::PlacementRefused { message } => vec!["refused".into(), message.clone()],
            Outcome::SolverFailure { step, message } => {
                vec!["failure".into(), step_or_dash(*step), message.clone()]
            }
            Outcome::Uncertified { step, failures } => {
                let mut v = vec!["uncertified".into(), step.to_string()];
                v.extend(failures.iter().cloned());
                v
            }
            Outcome::InvalidCase { message } => vec!["invalid".into(), message.clone()],
            Outcome::TimedOut { limit_s, last_step } => vec![
                "timedout".into(),
                format!("{limit_s:?}"),
                step_or_dash(*last_step),
            ],
        };
        line("outcome", &outcome);
        for (key, value) in [
            ("planned_steps", self.planned_steps),
            ("steps", self.steps),
            ("contact_steps", self.contact_steps),
            ("relaxed_steps", self.relaxed_steps),
            ("snaps", self.snaps),
        ] {
            line(key, &[value.to_string()]);
        }
        let relaxations: Vec<String> = self
            .relaxations
            .iter()
            .flat_map(|(k, v)| [k.clone(), v.to_string()])
            .collect();
        line("relaxations", &relaxations);
        let iterations: Vec<String> = self.iterations.iter().map(u32::to_string).collect();
        line("iterations", &[iterations.join(",")]);
        line("placement_note", std::slice::from_ref(&self.placement_note));
        line("wall_clock_s", &[format!("{:?}", self.wall_clock_s)]);
        line("trajectory", &self.trajectory.sample_fields());
        line("final_theta", &[self.trajectory.theta_field()]);
        line(END, &[]);
        out
    }

    /// The record in `text` (the first one between [`BEGIN`] and [`END`]), if there is a
    /// whole one.
    pub fn from_wire(text: &str) -> Option<SweepRecord> {
        let mut fields: BTreeMap<&str, Vec<String>> = BTreeMap::new();
        let mut inside = false;
        let mut complete = false;
        for line in text.lines() {
            if line.ends_with(BEGIN) {
                inside = true;
                continue;
            }
            if !inside {
                continue;
            }
            if line == END {
                complete = true;
                break;
            }
            let mut parts = line.split('\t');
            let key = parts.next()?;
            fields.insert(key, parts.map(unescape).collect());
        }
        if !complete {
            return None;
        }
        let one = |key: &str| fields.get(key).and_then(|v| v.first()).cloned();
        let number = |key: &str| one(key).and_then(|v| v.parse::<usize>().ok());
        let outcome_fields = fields.get("outcome")?;
        let at = |i: usize| outcome_fields.get(i).cloned().unwrap_or_default();
        let step_at = |i: usize| at(i).parse::<usize>().ok();
        let outcome = match at(0).as_str() {
            "finished" => Outcome::Finished,
            "jammed" => Outcome::Jammed {
                step: step_at(1)?,
                description: at(2),
                joints_on_stops: at(3).split(',').filter_map(|j| j.parse().ok()).collect(),
                contacts: outcome_fields.iter().skip(4).cloned().collect(),
            },
            "refused" => Outcome::PlacementRefused { message: at(1) },
            "failure" => Outcome::SolverFailure {
                step: step_at(1),
                message: at(2),
            },
            "uncertified" => Outcome::Uncertified {
                step: step_at(1)?,
                failures: outcome_fields.iter().skip(2).cloned().collect(),
            },
            "invalid" => Outcome::InvalidCase { message: at(1) },
            "timedout" => Outcome::TimedOut {
                limit_s: at(1).parse().ok()?,
                last_step: step_at(2),
            },
            _ => return None,
        };
        let relaxations = fields
            .get("relaxations")
            .map(|v| {
                v.chunks(2)
                    .filter_map(|c| Some((c.first()?.clone(), c.get(1)?.parse().ok()?)))
                    .collect()
            })
            .unwrap_or_default();
        let iterations = one("iterations")
            .map(|v| v.split(',').filter_map(|i| i.parse().ok()).collect())
            .unwrap_or_default();
        let wall = one("wall")?;
        let placement = one("placement")?;
        Some(SweepRecord {
            seed: one("seed")?.parse().ok()?,
            index: one("index")?.parse().ok()?,
            sample: Sample::parse(&one("sample")?)?,
            links: number("links")?,
            wall_kind: WallKind::ALL.into_iter().find(|k| k.name() == wall),
            placement_kind: PlacementKind::ALL
                .into_iter()
                .find(|k| k.name() == placement),
            replay: one("replay")?,
            outcome,
            planned_steps: number("planned_steps")?,
            steps: number("steps")?,
            contact_steps: number("contact_steps")?,
            relaxed_steps: number("relaxed_steps")?,
            relaxations,
            iterations,
            costs: Vec::new(),
            snaps: number("snaps")?,
            placement_note: one("placement_note").unwrap_or_default(),
            wall_clock_s: one("wall_clock_s")?.parse().ok()?,
            trajectory: Trajectory::from_fields(
                fields.get("trajectory").map_or(&[][..], Vec::as_slice),
                &one("final_theta").unwrap_or_default(),
            )?,
        })
    }
}
