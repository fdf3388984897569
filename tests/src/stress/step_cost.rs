//! What each solved step of a sweep cost, and why (`ANTENNA_STRESS_TRACE=1` with
//! `ANTENNA_STRESS_REPLAY`): the Newton iterations and what the solver did to spend them.
//! Where a sweep's Newton p99 comes from is read here, one step at a time.

use sim_core::contact::StepReport;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// The Newton iterations above which a step counts as expensive (issue #13's p99 goal).
pub const EXPENSIVE_ITERATIONS: usize = 40;

/// What one solved step cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepCost {
    /// The step's number (1 for the first after the placement).
    pub step: usize,
    /// Newton iterations over all its solves.
    pub iterations: usize,
    /// Substeps it was refined into (1 when solved whole).
    pub substeps: usize,
    /// Whether it was followed downhill as a snap.
    pub snapped: bool,
    /// Pseudo-time steps of its snap.
    pub snap_steps: usize,
    /// Solves repeated because the pairs changed.
    pub resolves: usize,
    /// Solves that needed the fixed point on the normal forces.
    pub fixed_point_solves: usize,
    /// Contacts that jammed (slid without friction).
    pub jams: usize,
    /// Whether friction was dropped at every contact.
    pub friction_dropped: bool,
    /// Contacts at its end.
    pub contacts: usize,
}

impl StepCost {
    /// The cost of step `step` from its report, with `contacts` contacts at its end.
    pub fn new(step: usize, report: &StepReport, contacts: usize) -> StepCost {
        StepCost {
            step,
            iterations: report.iterations,
            substeps: report.substeps,
            snapped: report.snapped,
            snap_steps: report.snap_steps,
            resolves: report.resolves,
            fixed_point_solves: report.fixed_point_solves,
            jams: report.jams,
            friction_dropped: report.friction_dropped,
            contacts,
        }
    }

    /// What most likely spent its iterations, the first that applies: a snap, friction
    /// dropped, a jam, the fixed point, substeps, pairs that changed, else one solve (a
    /// stall and its repair).
    pub fn kind(&self) -> &'static str {
        if self.snapped {
            "snap"
        } else if self.friction_dropped {
            "friction dropped"
        } else if self.jams > 0 {
            "jam"
        } else if self.fixed_point_solves > 0 {
            "fixed point"
        } else if self.substeps > 1 {
            "substeps"
        } else if self.resolves > 0 {
            "pairs changed"
        } else {
            "one solve"
        }
    }

    /// One line for a trace.
    pub fn line(&self) -> String {
        format!(
            "step {}: {} Newton iterations ({}), {} substep(s), {} snap step(s), {} resolve(s), \
             {} fixed-point solve(s), {} jam(s){}, {} contact(s)",
            self.step,
            self.iterations,
            self.kind(),
            self.substeps,
            self.snap_steps,
            self.resolves,
            self.fixed_point_solves,
            self.jams,
            if self.friction_dropped {
                ", friction dropped"
            } else {
                ""
            },
            self.contacts
        )
    }
}

/// The steps of `costs` over [`EXPENSIVE_ITERATIONS`], counted by [`StepCost::kind`] with
/// their iterations, one line per kind (the most steps first).
pub fn expensive_by_kind(costs: &[StepCost]) -> String {
    let mut by_kind: BTreeMap<&str, (usize, usize)> = BTreeMap::new();
    for c in costs.iter().filter(|c| c.iterations > EXPENSIVE_ITERATIONS) {
        let e = by_kind.entry(c.kind()).or_default();
        e.0 += 1;
        e.1 += c.iterations;
    }
    let mut rows: Vec<_> = by_kind.into_iter().collect();
    rows.sort_by(|a, b| b.1.0.cmp(&a.1.0).then(a.0.cmp(b.0)));
    let mut out = String::new();
    for (kind, (steps, iterations)) in rows {
        let _ = writeln!(
            out,
            "- {steps} step(s) over {EXPENSIVE_ITERATIONS} Newton iterations by {kind}: \
             {iterations} iterations"
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cost(iterations: usize) -> StepCost {
        StepCost {
            step: 1,
            iterations,
            substeps: 1,
            ..StepCost::default()
        }
    }

    #[test]
    fn a_snap_counts_as_a_snap_before_anything_it_also_did() {
        let c = StepCost {
            snapped: true,
            jams: 2,
            substeps: 4,
            ..cost(500)
        };
        assert_eq!(c.kind(), "snap");
        assert_eq!(
            StepCost {
                jams: 1,
                ..cost(50)
            }
            .kind(),
            "jam"
        );
        assert_eq!(
            StepCost {
                substeps: 3,
                ..cost(50)
            }
            .kind(),
            "substeps"
        );
        assert_eq!(cost(50).kind(), "one solve");
    }

    #[test]
    fn only_steps_over_the_goal_are_counted_most_first() {
        let costs = [
            cost(40),
            cost(41),
            StepCost {
                substeps: 2,
                ..cost(100)
            },
            StepCost {
                substeps: 2,
                ..cost(60)
            },
        ];
        let text = expensive_by_kind(&costs);
        assert_eq!(
            text,
            "- 2 step(s) over 40 Newton iterations by substeps: 160 iterations\n\
             - 1 step(s) over 40 Newton iterations by one solve: 41 iterations\n"
        );
    }
}
