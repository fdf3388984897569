//! What a sweep did, sampled: the tip's path, the preview and the contacts every
//! [`SAMPLE_EVERY`] steps and at the last, and the joint angles at the end. The CI sample's
//! trajectories are kept in [`GOLDEN_FILE`] so that a change made for speed (issue #14) is
//! seen to leave the results where they were: [`compare`] holds a run against them within
//! [`Tolerance`].
//!
//! Regenerate the file (only when a change of results is intended, and say so in the commit):
//! `ANTENNA_STRESS_WRITE_GOLDEN=1 cargo test -p antenna-tests --release --test stress_contact
//! -- contact_sweeps_finish_with_every_step_certified`.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use nalgebra::Vector2;
use sim_core::Chain;
use sim_core::sweep::SweepStep;

use super::outcome::SweepRecord;

/// Steps between two samples of the trajectory (the placement, step 0, is the first; the last
/// step is always sampled).
pub const SAMPLE_EVERY: usize = 10;

/// The CI sample's trajectories, relative to the `antenna-tests` crate.
pub const GOLDEN_FILE: &str = "golden/stress_ci_trajectories.tsv";

/// One sampled step.
#[derive(Clone, Debug, PartialEq)]
pub struct TrajectorySample {
    /// The step (0: the placement).
    pub step: usize,
    /// The tip, ground frame, metres.
    pub tip_m: Vector2<f64>,
    /// The preview, metres (`None` without a contact ahead of the base link).
    pub preview_m: Option<f64>,
    /// The contacts at the end of the step.
    pub contacts: usize,
}

impl TrajectorySample {
    /// The sample of `step` of a sweep of `chain`.
    pub fn of(chain: &Chain, step: &SweepStep) -> TrajectorySample {
        let tip_m = sim_core::tip_pose(chain, &step.theta_rad)
            .map_or(Vector2::new(f64::NAN, f64::NAN), |pose| pose.position_m)
            + step.base_m;
        TrajectorySample {
            step: step.step,
            tip_m,
            preview_m: step.preview_m,
            contacts: step.contacts.len(),
        }
    }

    /// `step:x:y:preview:contacts`, exactly (`-` for no preview).
    pub fn to_field(&self) -> String {
        let preview = self.preview_m.map_or("-".to_owned(), |p| format!("{p:?}"));
        format!(
            "{}:{:?}:{:?}:{preview}:{}",
            self.step, self.tip_m.x, self.tip_m.y, self.contacts
        )
    }

    /// The inverse of [`Self::to_field`].
    pub fn from_field(field: &str) -> Option<TrajectorySample> {
        let mut parts = field.split(':');
        let step = parts.next()?.parse().ok()?;
        let x = parts.next()?.parse().ok()?;
        let y = parts.next()?.parse().ok()?;
        let preview = parts.next()?;
        let preview_m = if preview == "-" {
            None
        } else {
            Some(preview.parse().ok()?)
        };
        let contacts = parts.next()?.parse().ok()?;
        Some(TrajectorySample {
            step,
            tip_m: Vector2::new(x, y),
            preview_m,
            contacts,
        })
    }
}

/// A sweep's sampled trajectory.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trajectory {
    /// The samples, in step order.
    pub samples: Vec<TrajectorySample>,
    /// The joint angles after the last step solved (the placement's if none was), radians.
    pub final_theta_rad: Vec<f64>,
}

impl Trajectory {
    /// Adds `step` (the placement or a solved step): sampled if it falls on
    /// [`SAMPLE_EVERY`], and kept as the last in any case.
    pub fn record(&mut self, chain: &Chain, step: &SweepStep) {
        let sample = TrajectorySample::of(chain, step);
        if let Some(last) = self.samples.last()
            && last.step % SAMPLE_EVERY != 0
        {
            // The previous step was kept only as the last one.
            self.samples.pop();
        }
        self.samples.push(sample);
        self.final_theta_rad.clone_from(&step.theta_rad);
    }

    /// The trajectory's samples as fields (see [`TrajectorySample::to_field`]).
    pub fn sample_fields(&self) -> Vec<String> {
        self.samples
            .iter()
            .map(TrajectorySample::to_field)
            .collect()
    }

    /// The final joint angles as one comma-separated field, exactly.
    pub fn theta_field(&self) -> String {
        self.final_theta_rad
            .iter()
            .map(|a| format!("{a:?}"))
            .collect::<Vec<_>>()
            .join(",")
    }

    /// The inverse of [`Self::sample_fields`] and [`Self::theta_field`].
    pub fn from_fields(samples: &[String], theta: &str) -> Option<Trajectory> {
        let samples = samples
            .iter()
            .map(|f| TrajectorySample::from_field(f))
            .collect::<Option<Vec<_>>>()?;
        let final_theta_rad = if theta.is_empty() {
            Vec::new()
        } else {
            theta
                .split(',')
                .map(|a| a.parse().ok())
                .collect::<Option<Vec<_>>>()?
        };
        Some(Trajectory {
            samples,
            final_theta_rad,
        })
    }
}

/// How far a run may stray from the golden one and still be the same result.
#[derive(Clone, Copy, Debug)]
pub struct Tolerance {
    /// The tip's position and the preview, metres.
    pub position_m: f64,
    /// Each final joint angle, radians.
    pub angle_rad: f64,
}

/// What a run is held to: a step is solved to `ContactSettings::tolerance_m` = 1e-12 m, and
/// certified with gaps within 1e-8 m; a change of arithmetic (a nearest point found from
/// another start, a sum in another order) moves a posture by rounding errors, which a
/// well-posed step keeps at that scale. `1e-8` m and rad: the certification's own bound.
pub const STEP_TOLERANCE: Tolerance = Tolerance {
    position_m: 1e-8,
    angle_rad: 1e-8,
};

/// A record as the golden file keeps it: one line per sweep.
pub fn golden_line(record: &SweepRecord) -> String {
    let mut out = String::new();
    let _ = write!(
        out,
        "{}\t{}\t{}\t{}\t{}\t{}\t{}",
        record.index,
        record.outcome.label(),
        record.steps,
        record.contact_steps,
        record.snaps,
        record.trajectory.theta_field(),
        record.trajectory.sample_fields().join(" "),
    );
    out
}

/// A golden file of `records` (in index order), with a header saying what it is.
pub fn golden_file(seed: u64, records: &[SweepRecord]) -> String {
    let mut sorted: Vec<&SweepRecord> = records.iter().collect();
    sorted.sort_by_key(|r| r.index);
    let mut out = format!(
        "# The CI stress sample's trajectories (seed {seed}): index, outcome, steps, steps in \
         contact, snaps, the final joint angles (rad), and every {SAMPLE_EVERY}th step and the \
         last as step:tip_x_m:tip_y_m:preview_m:contacts. Written by \
         ANTENNA_STRESS_WRITE_GOLDEN=1 (tests/src/stress/trajectory.rs).\n"
    );
    for r in sorted {
        out.push_str(&golden_line(r));
        out.push('\n');
    }
    out
}

/// One sweep of a golden file.
#[derive(Clone, Debug, PartialEq)]
pub struct GoldenSweep {
    /// The outcome's label.
    pub outcome: String,
    /// The steps solved.
    pub steps: usize,
    /// Of those, in contact.
    pub contact_steps: usize,
    /// Snaps.
    pub snaps: usize,
    /// The sampled trajectory.
    pub trajectory: Trajectory,
}

/// The sweeps of a golden file by index; `Err` names the first line that does not parse.
pub fn parse_golden(text: &str) -> Result<BTreeMap<u64, GoldenSweep>, String> {
    let mut out = BTreeMap::new();
    for (number, line) in text.lines().enumerate() {
        if line.starts_with('#') || line.trim().is_empty() {
            continue;
        }
        let bad = || format!("line {} of the golden file does not parse", number + 1);
        let fields: Vec<&str> = line.split('\t').collect();
        let [index, outcome, steps, contact_steps, snaps, theta, samples] = fields[..] else {
            return Err(bad());
        };
        let samples: Vec<String> = samples
            .split(' ')
            .filter(|f| !f.is_empty())
            .map(str::to_owned)
            .collect();
        let trajectory = Trajectory::from_fields(&samples, theta).ok_or_else(bad)?;
        let parse = |s: &str| s.parse::<usize>().map_err(|_| bad());
        out.insert(
            index.parse().map_err(|_| bad())?,
            GoldenSweep {
                outcome: outcome.to_owned(),
                steps: parse(steps)?,
                contact_steps: parse(contact_steps)?,
                snaps: parse(snaps)?,
                trajectory,
            },
        );
    }
    Ok(out)
}

/// `difference <= tolerance`, false for a NaN difference.
fn within(difference: f64, tolerance: f64) -> bool {
    difference <= tolerance
}

/// What the largest differences of a run from the golden one were, over the compared sweeps.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Deviation {
    /// The tip's, metres.
    pub tip_m: f64,
    /// The preview's, metres.
    pub preview_m: f64,
    /// A final joint angle's, radians.
    pub angle_rad: f64,
}

/// Holds `records` against `golden`: every golden sweep must have been run with the same
/// outcome, steps, steps in contact and snaps, its sampled tips, previews and contacts and
/// its final joint angles within `tolerance`. `Err` lists every difference.
pub fn compare(
    golden: &BTreeMap<u64, GoldenSweep>,
    records: &[SweepRecord],
    tolerance: Tolerance,
) -> Result<Deviation, Vec<String>> {
    let mut differences = Vec::new();
    let mut deviation = Deviation::default();
    for (index, want) in golden {
        let Some(got) = records.iter().find(|r| r.index == *index) else {
            differences.push(format!("sweep {index}: not run"));
            continue;
        };
        let mut differ = |what: String| differences.push(format!("sweep {index}: {what}"));
        let counts = [
            ("steps", want.steps, got.steps),
            ("steps in contact", want.contact_steps, got.contact_steps),
            ("snaps", want.snaps, got.snaps),
        ];
        if got.outcome.label() != want.outcome {
            differ(format!(
                "ended {} where it {}",
                got.outcome.label(),
                want.outcome
            ));
        }
        for (what, w, g) in counts {
            if w != g {
                differ(format!("{g} {what} against {w}"));
            }
        }
        let (w, g) = (&want.trajectory, &got.trajectory);
        if w.samples.len() != g.samples.len() {
            differ(format!(
                "{} samples against {}",
                g.samples.len(),
                w.samples.len()
            ));
        }
        for (ws, gs) in w.samples.iter().zip(&g.samples) {
            let tip = (ws.tip_m - gs.tip_m).norm();
            deviation.tip_m = deviation.tip_m.max(tip);
            if !within(tip, tolerance.position_m) || ws.step != gs.step {
                differ(format!(
                    "step {}: the tip at {:?} against {:?} ({tip:.2e} m apart)",
                    gs.step, gs.tip_m, ws.tip_m
                ));
            }
            match (ws.preview_m, gs.preview_m) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    let d = (a - b).abs();
                    deviation.preview_m = deviation.preview_m.max(d);
                    if !within(d, tolerance.position_m) {
                        differ(format!("step {}: preview {b:?} against {a:?}", gs.step));
                    }
                }
                (a, b) => differ(format!("step {}: preview {b:?} against {a:?}", gs.step)),
            }
            if ws.contacts != gs.contacts {
                differ(format!(
                    "step {}: {} contacts against {}",
                    gs.step, gs.contacts, ws.contacts
                ));
            }
        }
        if w.final_theta_rad.len() != g.final_theta_rad.len() {
            differ(format!(
                "{} final joint angles against {}",
                g.final_theta_rad.len(),
                w.final_theta_rad.len()
            ));
        }
        for (joint, (a, b)) in w.final_theta_rad.iter().zip(&g.final_theta_rad).enumerate() {
            let d = (a - b).abs();
            deviation.angle_rad = deviation.angle_rad.max(d);
            if !within(d, tolerance.angle_rad) {
                differ(format!("final angle {joint}: {b:?} against {a:?}"));
            }
        }
    }
    if differences.is_empty() {
        Ok(deviation)
    } else {
        Err(differences)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_round_trip_exactly() {
        let s = TrajectorySample {
            step: 40,
            tip_m: Vector2::new(0.1 + 0.2, -1e-17),
            preview_m: Some(std::f64::consts::PI),
            contacts: 3,
        };
        assert_eq!(TrajectorySample::from_field(&s.to_field()), Some(s.clone()));
        let none = TrajectorySample {
            preview_m: None,
            ..s
        };
        assert_eq!(TrajectorySample::from_field(&none.to_field()), Some(none));
        assert_eq!(TrajectorySample::from_field("1:2:x:-:0"), None);
    }

    #[test]
    fn a_tip_moved_beyond_the_tolerance_is_a_difference() {
        use super::super::case::Sample;
        let mut record = SweepRecord::invalid(1, 7, Sample::Ci, String::new());
        record.steps = 10;
        record.trajectory.samples = vec![
            TrajectorySample {
                step: 0,
                tip_m: Vector2::new(0.3, 0.1),
                preview_m: None,
                contacts: 1,
            },
            TrajectorySample {
                step: 10,
                tip_m: Vector2::new(0.31, 0.1),
                preview_m: Some(0.05),
                contacts: 2,
            },
        ];
        record.trajectory.final_theta_rad = vec![0.5, -0.25];
        let golden = parse_golden(&golden_file(1, std::slice::from_ref(&record))).unwrap();
        assert_eq!(
            compare(&golden, std::slice::from_ref(&record), STEP_TOLERANCE),
            Ok(Deviation::default())
        );
        let mut within = record.clone();
        within.trajectory.samples[1].tip_m.x += 0.5e-8;
        assert!(compare(&golden, &[within], STEP_TOLERANCE).is_ok());
        let mut moved = record.clone();
        moved.trajectory.samples[1].tip_m.x += 2e-8;
        moved.trajectory.final_theta_rad[1] = f64::NAN;
        moved.snaps = 1;
        let differences = compare(&golden, &[moved], STEP_TOLERANCE).unwrap_err();
        assert_eq!(differences.len(), 3, "{differences:?}");
        assert!(compare(&golden, &[], STEP_TOLERANCE).is_err());
    }
}
