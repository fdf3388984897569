//! How a closed-loop run went: its status and the figures a robot builder asks for.

use crate::contact::ContactError;

/// How a run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum FollowStatus {
    /// It ran its duration without touching a wall with the body.
    Ok,
    /// The body's footprint overlapped a wall at least once.
    Collided,
    /// No estimate for `[follow] lost_after_s`, or the robot farther than `lost_beyond_m`
    /// from every wall: the run ended there.
    Lost,
    /// The body turned more than [`super::run::MAX_TURN_PER_STEP_RAD`] in one step (or its
    /// state stopped being finite): the loop is unstable at this step (a command held over
    /// a step, a delay, a stiff gain), and the run ended there.
    Unstable,
    /// The antenna's solver refused a step: the run ended there (`kind` is
    /// `"no-convergence"`, `"jammed"`, `"uncertified"` or `"solver-error"`).
    Solver {
        /// The solver's outcome.
        kind: &'static str,
        /// In words.
        message: String,
    },
}

impl FollowStatus {
    /// The status's name (`"ok"`, `"collided"`, `"lost"` or the solver's outcome).
    pub fn name(&self) -> &'static str {
        match self {
            FollowStatus::Ok => "ok",
            FollowStatus::Collided => "collided",
            FollowStatus::Lost => "lost",
            FollowStatus::Unstable => "unstable",
            FollowStatus::Solver { kind, .. } => kind,
        }
    }

    /// The status of a run the solver ended.
    pub fn from_contact_error(e: &ContactError) -> FollowStatus {
        let kind = match e {
            ContactError::NoConvergence { .. } => "no-convergence",
            ContactError::Jammed(_) => "jammed",
            ContactError::Uncertified { .. } => "uncertified",
            _ => "solver-error",
        };
        FollowStatus::Solver {
            kind,
            message: e.to_string(),
        }
    }
}

/// The names a run's status takes.
pub const STATUS_NAMES: &[&str] = &[
    "ok",
    "collided",
    "lost",
    "unstable",
    "no-convergence",
    "jammed",
    "uncertified",
    "solver-error",
];

/// A run's figures.
#[derive(Clone, Debug, PartialEq)]
pub struct FollowSummary {
    /// How it ended.
    pub status: FollowStatus,
    /// Steps run.
    pub steps: usize,
    /// Time run, seconds.
    pub duration_s: f64,
    /// Distance travelled by the point of rotation, m.
    pub travel_m: f64,
    /// The RMS of the true distance's error against the setpoint after the settling
    /// window, m (`None`: the run did not get past it).
    pub rms_error_m: Option<f64>,
    /// The largest such error, m.
    pub max_error_m: Option<f64>,
    /// The travel after which the true error stayed within the settling band, m (`None`:
    /// it never settled).
    pub settling_distance_m: Option<f64>,
    /// How many times the footprint entered a wall.
    pub collisions: usize,
    /// When it first did, seconds.
    pub first_collision_s: Option<f64>,
    /// The share of steps with a contact on the antenna.
    pub contact_share: f64,
    /// The share of steps with an estimate.
    pub estimate_share: f64,
    /// The RMS of the estimate against the true `d` at the estimate's preview, m.
    pub estimate_rms_error_m: Option<f64>,
}

/// The running sums behind a [`FollowSummary`].
#[derive(Clone, Debug, Default)]
pub(super) struct SummaryAccumulator {
    pub steps: usize,
    pub duration_s: f64,
    pub travel_m: f64,
    error_sum_sq: f64,
    error_count: usize,
    max_error_m: f64,
    /// The travel after the last step outside the settling band.
    settled_from_m: Option<f64>,
    pub collisions: usize,
    pub first_collision_s: Option<f64>,
    contact_steps: usize,
    estimate_steps: usize,
    estimate_sum_sq: f64,
    estimate_count: usize,
}

impl SummaryAccumulator {
    /// Adds one step's figures: `error_m` the true distance's error (`None` without a
    /// wall in reach), `estimate_error_m` the estimate's.
    #[allow(clippy::too_many_arguments)]
    pub fn add(
        &mut self,
        travel_m: f64,
        settling_window_m: f64,
        settling_band_m: f64,
        error_m: Option<f64>,
        contact: bool,
        estimate: bool,
        estimate_error_m: Option<f64>,
    ) {
        self.steps += 1;
        self.travel_m = travel_m;
        if let Some(e) = error_m {
            if travel_m >= settling_window_m {
                self.error_sum_sq += e * e;
                self.error_count += 1;
                self.max_error_m = self.max_error_m.max(e.abs());
            }
            if e.abs() > settling_band_m {
                self.settled_from_m = None;
            } else if self.settled_from_m.is_none() {
                self.settled_from_m = Some(travel_m);
            }
        } else {
            self.settled_from_m = None;
        }
        self.contact_steps += usize::from(contact);
        self.estimate_steps += usize::from(estimate);
        if let Some(e) = estimate_error_m {
            self.estimate_sum_sq += e * e;
            self.estimate_count += 1;
        }
    }

    pub fn summary(&self, status: FollowStatus) -> FollowSummary {
        let share = |k: usize| {
            if self.steps == 0 {
                0.0
            } else {
                k as f64 / self.steps as f64
            }
        };
        let rms = |sum: f64, count: usize| (count > 0).then(|| (sum / count as f64).sqrt());
        FollowSummary {
            status,
            steps: self.steps,
            duration_s: self.duration_s,
            travel_m: self.travel_m,
            rms_error_m: rms(self.error_sum_sq, self.error_count),
            max_error_m: (self.error_count > 0).then_some(self.max_error_m),
            settling_distance_m: self.settled_from_m,
            collisions: self.collisions,
            first_collision_s: self.first_collision_s,
            contact_share: share(self.contact_steps),
            estimate_share: share(self.estimate_steps),
            estimate_rms_error_m: rms(self.estimate_sum_sq, self.estimate_count),
        }
    }
}
