//! Running one sweep, re-checking every step, and classifying how it ended.
//!
//! sim-core certifies every step itself (`QuasiStatic::step_to` runs an independent check
//! and refuses a state that fails it); the harness checks again after every step, placement
//! included, with `QuasiStatic::check` against `QuasiStatic::certify_tolerances`, and calls
//! a step the solver returned but the check refuses [`Outcome::Uncertified`].

use std::any::Any;
use std::collections::BTreeMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::Instant;

use sim_core::contact::{ContactError, Jam, QuasiStatic};
use sim_core::sweep::{Sweep, SweepError};

use super::case::{Case, PlacementKind, Sample};
use super::step_cost::StepCost;
use super::trajectory::Trajectory;
use super::walls::WallKind;

/// How a sweep ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// Every step returned `Ok` and passed the harness's check.
    Finished,
    /// A step ended with [`ContactError::Jammed`]: the antenna physically cannot go on.
    Jammed {
        /// The step (0: during the placement).
        step: usize,
        /// What pins it, in sim-core's words.
        description: String,
        /// The contacts that pin it.
        contacts: Vec<String>,
        /// The joints on their stops.
        joints_on_stops: Vec<usize>,
    },
    /// The placement could not be done and said why.
    PlacementRefused {
        /// The message.
        message: String,
    },
    /// Anything else: what the suite exists to find.
    SolverFailure {
        /// The step that failed (0: the placement), if known.
        step: Option<usize>,
        /// The message.
        message: String,
    },
    /// A step's state fails the check: sim-core's own (the step refused with
    /// [`ContactError::Uncertified`]) or the harness's (the step returned `Ok`): a bug.
    Uncertified {
        /// The step (0: the placed posture).
        step: usize,
        /// What failed.
        failures: Vec<String>,
    },
    /// The generator could not build the case: a bug of the suite.
    InvalidCase {
        /// The message.
        message: String,
    },
    /// The sweep ran past its time limit (in the placement, or in one step) and its process
    /// was killed: a solver failure too (a sweep that takes minutes).
    TimedOut {
        /// The limit, seconds.
        limit_s: f64,
        /// The last step it had finished (0: the placement), if any.
        last_step: Option<usize>,
    },
}

impl Outcome {
    /// A short label.
    pub fn label(&self) -> &'static str {
        match self {
            Outcome::Finished => "finished",
            Outcome::Jammed { .. } => "jammed",
            Outcome::PlacementRefused { .. } => "placement refused",
            Outcome::SolverFailure { .. } => "solver failure",
            Outcome::Uncertified { .. } => "uncertified",
            Outcome::InvalidCase { .. } => "invalid case",
            Outcome::TimedOut { .. } => "timed out",
        }
    }

    /// Whether this is a failure the suite asserts against (solver failure, uncertified
    /// step, timeout, invalid case).
    pub fn is_failure(&self) -> bool {
        matches!(
            self,
            Outcome::SolverFailure { .. }
                | Outcome::Uncertified { .. }
                | Outcome::InvalidCase { .. }
                | Outcome::TimedOut { .. }
        )
    }

    /// The full message (empty for a finished sweep).
    pub fn message(&self) -> String {
        match self {
            Outcome::Finished => String::new(),
            Outcome::Jammed {
                step,
                description,
                contacts,
                joints_on_stops,
            } => format!(
                "step {step}: jammed: {description}; contacts [{}]; joints on stops {:?}",
                contacts.join("; "),
                joints_on_stops
            ),
            Outcome::PlacementRefused { message } | Outcome::InvalidCase { message } => {
                message.clone()
            }
            Outcome::SolverFailure { message, .. } => message.clone(),
            Outcome::Uncertified { step, failures } => {
                format!("step {step}: uncertified: {}", failures.join(", "))
            }
            Outcome::TimedOut { limit_s, last_step } => format!(
                "still running after {limit_s:.1} s, {}: killed",
                match last_step {
                    None => "in the placement".to_owned(),
                    Some(k) => format!("in step {} (step {k} was done)", k + 1),
                }
            ),
        }
    }

    /// The reason with its numbers replaced by `#`, to count alike reasons together.
    pub fn reason(&self) -> String {
        match self {
            Outcome::Jammed { description, .. } => generalize(description),
            Outcome::Uncertified { failures, .. } => {
                let names: Vec<String> = failures.iter().map(|f| generalize(f)).collect();
                format!("uncertified: {}", names.join(", "))
            }
            other => generalize(&other.message()),
        }
    }
}

/// `text` with every number replaced by `#`.
pub fn generalize(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let prev_alnum = i > 0 && (chars[i - 1].is_alphanumeric() || chars[i - 1] == '_');
        let starts_number = !prev_alnum
            && (c.is_ascii_digit()
                || (c == '-' && chars.get(i + 1).is_some_and(char::is_ascii_digit)));
        if starts_number {
            i += 1;
            while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
                i += 1;
            }
            // An exponent.
            if i + 1 < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
                let mut j = i + 1;
                if chars[j] == '-' || chars[j] == '+' {
                    j += 1;
                }
                if chars.get(j).is_some_and(char::is_ascii_digit) {
                    i = j;
                    while i < chars.len() && chars[i].is_ascii_digit() {
                        i += 1;
                    }
                }
            }
            out.push('#');
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

/// One sweep's record.
#[derive(Clone, Debug)]
pub struct SweepRecord {
    /// The case's seed.
    pub seed: u64,
    /// The case's index.
    pub index: u64,
    /// The case's sample.
    pub sample: Sample,
    /// `N` (0 for an invalid case).
    pub links: usize,
    /// The wall's kind (`None` for an invalid case).
    pub wall_kind: Option<WallKind>,
    /// The placement's kind (`None` for an invalid case).
    pub placement_kind: Option<PlacementKind>,
    /// The case's replay line.
    pub replay: String,
    /// How it ended.
    pub outcome: Outcome,
    /// The steps it was to take.
    pub planned_steps: usize,
    /// The steps solved after the placement.
    pub steps: usize,
    /// Of those, the steps that ended with a contact.
    pub contact_steps: usize,
    /// Of those, the steps where the solver relaxed something.
    pub relaxed_steps: usize,
    /// What was relaxed (generalized), and in how many steps.
    pub relaxations: BTreeMap<String, usize>,
    /// Newton iterations of each solved step.
    pub iterations: Vec<u32>,
    /// What each solved step cost, and why (kept in this process only: a child's record
    /// read back by its parent has none).
    pub costs: Vec<StepCost>,
    /// Steps that snapped.
    pub snaps: usize,
    /// The placement's note (empty if it failed).
    pub placement_note: String,
    /// Wall-clock time of the placement and the steps, seconds.
    pub wall_clock_s: f64,
    /// The sampled trajectory (the placement and the solved steps).
    pub trajectory: Trajectory,
}

impl SweepRecord {
    /// Newton iterations over the solved steps.
    pub fn total_iterations(&self) -> u64 {
        self.iterations.iter().map(|&i| u64::from(i)).sum()
    }

    /// The outcome with the steps done and the time taken, for reports.
    pub fn outcome_line(&self) -> String {
        format!(
            "{} after {} of {} steps ({} Newton iterations, {:.2} s): {}",
            self.outcome.label(),
            self.steps,
            self.planned_steps,
            self.total_iterations(),
            self.wall_clock_s,
            self.outcome.message()
        )
    }
}

impl SweepRecord {
    /// A record of `case` that has not run yet (outcome [`Outcome::Finished`], nothing
    /// counted).
    pub fn new(case: &Case) -> SweepRecord {
        SweepRecord {
            seed: case.seed,
            index: case.index,
            sample: case.sample,
            links: case.links,
            wall_kind: Some(case.wall.kind),
            placement_kind: Some(case.placement_kind),
            replay: case.replay_line(),
            outcome: Outcome::Finished,
            planned_steps: case.steps(),
            steps: 0,
            contact_steps: 0,
            relaxed_steps: 0,
            relaxations: BTreeMap::new(),
            iterations: Vec::with_capacity(case.steps()),
            costs: Vec::with_capacity(case.steps()),
            snaps: 0,
            placement_note: String::new(),
            wall_clock_s: 0.0,
            trajectory: Trajectory::default(),
        }
    }

    /// A record of a case that could not be built.
    pub fn invalid(seed: u64, index: u64, sample: Sample, message: String) -> SweepRecord {
        SweepRecord {
            seed,
            index,
            sample,
            links: 0,
            wall_kind: None,
            placement_kind: None,
            replay: format!(
                "ANTENNA_STRESS_REPLAY={}:{seed}:{index} | (not built)",
                sample.name()
            ),
            outcome: Outcome::InvalidCase { message },
            planned_steps: 0,
            steps: 0,
            contact_steps: 0,
            relaxed_steps: 0,
            relaxations: BTreeMap::new(),
            iterations: Vec::new(),
            costs: Vec::new(),
            snaps: 0,
            placement_note: String::new(),
            wall_clock_s: 0.0,
            trajectory: Trajectory::default(),
        }
    }
}

/// The harness's own check of the current state: the failures, if it fails.
fn recheck(sim: &QuasiStatic) -> Option<Vec<String>> {
    let tolerances = sim.certify_tolerances();
    let check = sim.check();
    if check.holds_within(&tolerances) {
        None
    } else {
        let mut failures = vec!["Ok from the solver but fails the harness's check".to_owned()];
        failures.extend(check.failures(&tolerances));
        Some(failures)
    }
}

/// A jam's outcome. A jam is the walls pinning the antenna: one that names no contact
/// pinning it (sim-core's "pinned by no loaded contact") is the solver failing and calling
/// it a jam, a solver failure.
fn jammed(step: usize, jam: &Jam, message: String) -> Outcome {
    if jam.contacts.is_empty() {
        return Outcome::SolverFailure {
            step: Some(step),
            message: format!("a jam that no contact pins: {message}"),
        };
    }
    Outcome::Jammed {
        step,
        description: jam.description.clone(),
        contacts: jam
            .contacts
            .iter()
            .map(|c| {
                format!(
                    "{:?} on wall {} at ({:.4}, {:.4}) m, N = {:.3e} N",
                    c.feature, c.wall, c.point_m.x, c.point_m.y, c.normal_force_n
                )
            })
            .collect(),
        joints_on_stops: jam.joints_on_stops.clone(),
    }
}

/// The message of a panic's payload.
pub fn panic_message(payload: &(dyn Any + Send)) -> String {
    payload
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| payload.downcast_ref::<&str>().map(|s| (*s).to_owned()))
        .unwrap_or_default()
}

/// A panic in sim-core during step `step` (0: the placement): a solver failure.
fn panicked(step: usize, payload: &(dyn Any + Send)) -> Outcome {
    Outcome::SolverFailure {
        step: Some(step),
        message: format!("step {step}: panic: {}", panic_message(payload)),
    }
}

/// Whether a contact error says the start itself was bad input.
fn bad_start(e: &ContactError) -> bool {
    matches!(
        e,
        ContactError::StartInsideWall { .. }
            | ContactError::BaseInsideWall { .. }
            | ContactError::OutsideLimits { .. }
    )
}

/// What sim-core says in a placement's message when the solver failed under it (the last:
/// a jam that no contact pins, as in [`jammed`]).
const SOLVER_FAILED: [&str; 4] = [
    "no equilibrium found",
    "fails the independent check",
    "did not converge",
    "pinned by no loaded contact",
];

/// How a sweep error ends the sweep.
pub fn classify(e: &SweepError) -> Outcome {
    let message = e.to_string();
    match e {
        // A placement that failed because the solver did: a solver failure (sim-core words
        // it into the placement's message; these are its words for `NoConvergence` and
        // `Uncertified`, and for a pinned equilibrium that did not converge).
        SweepError::Placement(m) if SOLVER_FAILED.iter().any(|w| m.contains(w)) => {
            Outcome::SolverFailure {
                step: Some(0),
                message,
            }
        }
        SweepError::Placement(_) | SweepError::PlacementSolve(_) => {
            Outcome::PlacementRefused { message }
        }
        SweepError::Step {
            step,
            source: ContactError::Jammed(jam),
            ..
        } => jammed(*step, jam, message),
        SweepError::Contact(ContactError::Jammed(jam)) => jammed(0, jam, message),
        // sim-core's own check refused the state the solver reached.
        SweepError::Step {
            step,
            source: ContactError::Uncertified { failures, .. },
            ..
        } => Outcome::Uncertified {
            step: *step,
            failures: vec![format!("refused by sim-core's own check: {failures}")],
        },
        SweepError::Contact(ContactError::Uncertified { failures, .. }) => Outcome::Uncertified {
            step: 0,
            failures: vec![format!("refused by sim-core's own check: {failures}")],
        },
        SweepError::Step {
            step: 0, source, ..
        } if bad_start(source) => Outcome::PlacementRefused { message },
        SweepError::Contact(source) if bad_start(source) => Outcome::PlacementRefused { message },
        SweepError::Step { step, .. } => Outcome::SolverFailure {
            step: Some(*step),
            message,
        },
        _ => Outcome::SolverFailure {
            step: None,
            message,
        },
    }
}

/// Runs `case`'s sweep to its end (or its first error), checking every step. With
/// `echo_progress`, prints a progress line ([`super::wire::PROGRESS`]) after the placement
/// and after every step (for a parent process to see where a killed sweep was).
pub fn run_case(case: &Case, echo_progress: bool) -> SweepRecord {
    let started = Instant::now();
    let mut rec = SweepRecord::new(case);
    rec.outcome = sweep(case, &mut rec, echo_progress);
    rec.wall_clock_s = started.elapsed().as_secs_f64();
    rec
}

fn sweep(case: &Case, rec: &mut SweepRecord, echo: bool) -> Outcome {
    let progress = |step: usize| {
        if echo {
            println!("{}{step}", super::wire::PROGRESS);
        }
    };
    let mut sweep = match catch_unwind(AssertUnwindSafe(|| Sweep::new(case.scene.clone()))) {
        Ok(Ok(s)) => s,
        Ok(Err(e)) => return classify(&e),
        Err(payload) => return panicked(0, payload.as_ref()),
    };
    rec.placement_note = sweep.placement_note().to_owned();
    if let Some(placed) = sweep.placed() {
        rec.trajectory.record(&case.scene.chain, placed);
    }
    if let Some(failures) = recheck(sweep.sim()) {
        return Outcome::Uncertified { step: 0, failures };
    }
    progress(0);
    loop {
        let next = match catch_unwind(AssertUnwindSafe(|| sweep.next_step())) {
            Ok(next) => next,
            Err(payload) => return panicked(rec.steps + 1, payload.as_ref()),
        };
        let Some(result) = next else {
            break;
        };
        let step = match result {
            Ok(step) => step,
            Err(e) => return classify(&e),
        };
        rec.steps += 1;
        rec.trajectory.record(&case.scene.chain, &step);
        rec.iterations
            .push(u32::try_from(step.report.iterations).unwrap_or(u32::MAX));
        rec.costs
            .push(StepCost::new(step.step, &step.report, step.contacts.len()));
        rec.contact_steps += usize::from(!step.contacts.is_empty());
        rec.snaps += usize::from(step.report.snapped);
        if step.report.relaxed() {
            rec.relaxed_steps += 1;
            for r in step.report.relaxations() {
                *rec.relaxations.entry(generalize(&r)).or_default() += 1;
            }
        }
        if let Some(failures) = recheck(sweep.sim()) {
            return Outcome::Uncertified {
                step: step.step,
                failures,
            };
        }
        progress(step.step);
    }
    Outcome::Finished
}
