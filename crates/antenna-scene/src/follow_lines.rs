//! The lines `antenna follow --jsonl` prints (a closed-loop wall-following run of a follow
//! scene), one JSON object each, told apart by `type`: a `start` line, one `step` line per
//! step, a `summary` line. Every field is documented in `docs/follow.md`. [`step_line`] and
//! [`summary_line`] make them from sim-core's run, for the CLI and the monitor alike; the
//! monitor reads a file of them back through [`read_follow_lines`].
//!
//! Frames: the ground frame is the scene's; `heading_rad` counter-clockwise; `omega_rad_per_s`
//! and `u_n_m` positive turning away from the wall; estimates in the body frame (x ahead, y
//! toward the wall).

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};
use sim_core::follow::{Command, FollowStatus, FollowStep, FollowSummary};

/// One line of `antenna follow --jsonl`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum FollowLine {
    /// The first line: the scene, the robot and what the placement did.
    Start(FollowStart),
    /// One per step.
    Step(FollowStepLine),
    /// The last line.
    Summary(FollowSummaryLine),
}

/// The `start` line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FollowStart {
    /// The scene file as given.
    pub scene: String,
    /// The scene file's text as read (a points file it names is relative to `scene`), so a
    /// reader can redraw the walls.
    pub scene_toml: String,
    /// What the antenna's placement did, in words.
    pub note: String,
    /// The estimator's name.
    pub estimator: String,
    /// `"template"` or `"wheeled"`.
    pub body: String,
    /// `"left"` or `"right"`.
    pub wall_side: String,
    /// Forward speed, m/s.
    pub speed_m_per_s: f64,
    /// The setpoint, m.
    pub setpoint_m: f64,
    /// Steps the run will take at most.
    pub steps: usize,
    /// The step, seconds.
    pub step_s: f64,
    /// The delay in whole steps.
    pub delay_steps: usize,
    /// The footprint `[length, width]`, m.
    pub footprint_m: [f64; 2],
    /// Links `N` (the base link included).
    pub links: usize,
    /// The link lengths, m.
    pub link_lengths_m: Vec<f64>,
}

/// A `step` line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FollowStepLine {
    /// Time, seconds.
    pub t_s: f64,
    /// The point of rotation, ground frame, m.
    pub pose_m: [f64; 2],
    /// Heading, ground frame, counter-clockwise, radians.
    pub heading_rad: f64,
    /// Turning rate, positive away from the wall, rad/s.
    pub omega_rad_per_s: f64,
    /// A template body's moment over the step, N m (null for a wheeled body).
    pub u_n_m: Option<f64>,
    /// A wheeled body's commanded turning rate, rad/s (null for a template body).
    pub turn_command_rad_per_s: Option<f64>,
    /// The antenna's moment about the point of rotation, positive away from the wall, N m.
    pub antenna_moment_n_m: f64,
    /// The smallest distance from the point of rotation to a wall, m.
    pub wall_distance_m: Option<f64>,
    /// `wall_distance_m` minus the setpoint, m.
    pub error_m: Option<f64>,
    /// The estimated `d`, m (null: see `no_estimate`).
    pub estimate_m: Option<f64>,
    /// The estimated angle of the wall to the body axis (positive: the body turned away),
    /// radians.
    pub estimate_angle_rad: Option<f64>,
    /// Where the estimate holds, m ahead of the point of rotation.
    pub estimate_preview_m: Option<f64>,
    /// Why there is no estimate.
    pub no_estimate: Option<String>,
    /// The true `d` at the estimate's preview, m.
    pub true_distance_at_preview_m: Option<f64>,
    /// Contacts on the antenna.
    pub contacts: usize,
    /// The sensed touch bits per link.
    pub touch: Vec<u8>,
    /// Whether the footprint overlaps a wall.
    pub collided: bool,
    /// The antenna's base pivot, ground frame, m.
    pub base_m: Option<[f64; 2]>,
    /// The joint angles, `theta_0` the base angle in the ground frame, radians.
    pub theta_rad: Vec<f64>,
    /// The estimator's points, ground frame, m.
    pub estimated_points_m: Vec<[f64; 2]>,
}

/// The `summary` line (`antenna follow --json` prints it alone).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FollowSummaryLine {
    /// `"ok"`, `"collided"`, `"lost"`, `"unstable"`, or the solver's outcome
    /// (`"no-convergence"`, `"jammed"`, `"uncertified"`, `"solver-error"`).
    pub status: String,
    /// The solver's message where it ended the run.
    pub detail: Option<String>,
    /// Steps run.
    pub steps: usize,
    /// Simulated time, seconds.
    pub duration_s: f64,
    /// Travel of the point of rotation, m.
    pub travel_m: f64,
    /// RMS of the true distance's error after the settling window, m.
    pub rms_error_m: Option<f64>,
    /// Largest such error, m.
    pub max_error_m: Option<f64>,
    /// Travel after which the error stayed within the settling band, m.
    pub settling_distance_m: Option<f64>,
    /// Entries of the footprint into a wall.
    pub collisions: usize,
    /// The first one's time, seconds.
    pub first_collision_s: Option<f64>,
    /// Share of steps with a contact.
    pub contact_share: f64,
    /// Share of steps with an estimate.
    pub estimate_share: f64,
    /// RMS of the estimate against the true `d` at its preview, m.
    pub estimate_rms_error_m: Option<f64>,
    /// Wall-clock time of the run, seconds.
    pub wall_time_s: f64,
}

/// Why a follow file could not be read.
#[derive(Debug, thiserror::Error)]
#[error("line {line}: {message}")]
pub struct FollowReadError {
    /// The line (1-based).
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

/// Reads the lines of `antenna follow --jsonl` (blank lines skipped).
///
/// # Errors
/// [`FollowReadError`] naming the first line that is not a follow line.
pub fn read_follow_lines(text: &str) -> Result<Vec<FollowLine>, FollowReadError> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            serde_json::from_str(l).map_err(|e| FollowReadError {
                line: i + 1,
                message: e.to_string(),
            })
        })
        .collect()
}

/// A step of sim-core's loop as its line: `error_m` is the true distance minus `setpoint_m`.
pub fn step_line(step: &FollowStep, setpoint_m: f64) -> FollowStepLine {
    let pair = |v: Vector2<f64>| [v.x, v.y];
    let (u_n_m, turn_command_rad_per_s) = match step.command {
        Command::Moment(u) => (Some(u), None),
        Command::TurnRate(w) => (None, Some(w)),
    };
    FollowStepLine {
        t_s: step.t_s,
        pose_m: pair(step.pose_m),
        heading_rad: step.heading_rad,
        omega_rad_per_s: step.omega_rad_per_s,
        u_n_m,
        turn_command_rad_per_s,
        antenna_moment_n_m: step.antenna_moment_n_m,
        wall_distance_m: step.wall_distance_m,
        error_m: step.wall_distance_m.map(|d| d - setpoint_m),
        estimate_m: step.estimate.map(|e| e.distance_m),
        estimate_angle_rad: step.estimate.and_then(|e| e.angle_rad),
        estimate_preview_m: step.estimate.map(|e| e.preview_m),
        no_estimate: step.no_estimate.map(|n| n.reason().to_string()),
        true_distance_at_preview_m: step.true_distance_at_preview_m,
        contacts: step.contacts,
        touch: step.touch.clone(),
        collided: step.collided,
        base_m: step.base_m.map(pair),
        theta_rad: step.theta_rad.clone(),
        estimated_points_m: step.estimated_points_m.iter().map(|p| pair(*p)).collect(),
    }
}

/// A run's summary as its line, with the run's wall-clock time.
pub fn summary_line(summary: &FollowSummary, wall_time_s: f64) -> FollowSummaryLine {
    FollowSummaryLine {
        status: summary.status.name().to_string(),
        detail: match &summary.status {
            FollowStatus::Solver { message, .. } => Some(message.clone()),
            _ => None,
        },
        steps: summary.steps,
        duration_s: summary.duration_s,
        travel_m: summary.travel_m,
        rms_error_m: summary.rms_error_m,
        max_error_m: summary.max_error_m,
        settling_distance_m: summary.settling_distance_m,
        collisions: summary.collisions,
        first_collision_s: summary.first_collision_s,
        contact_share: summary.contact_share,
        estimate_share: summary.estimate_share,
        estimate_rms_error_m: summary.estimate_rms_error_m,
        wall_time_s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_step_line_reads_back_and_a_bad_line_is_located() {
        let step = FollowLine::Step(FollowStepLine {
            t_s: 0.01,
            pose_m: [0.003, 0.12],
            heading_rad: 0.0,
            omega_rad_per_s: 0.1,
            u_n_m: Some(-1e-3),
            turn_command_rad_per_s: None,
            antenna_moment_n_m: 0.0,
            wall_distance_m: Some(0.08),
            error_m: Some(-0.02),
            estimate_m: None,
            estimate_angle_rad: None,
            estimate_preview_m: None,
            no_estimate: Some("no contact in the window".into()),
            true_distance_at_preview_m: None,
            contacts: 0,
            touch: vec![0, 0],
            collided: false,
            base_m: Some([0.04, 0.14]),
            theta_rad: vec![0.5, 0.0],
            estimated_points_m: vec![],
        });
        let text = serde_json::to_string(&step).unwrap();
        assert!(text.starts_with("{\"type\":\"step\""));
        let read = read_follow_lines(&format!("{text}\n\n")).unwrap();
        assert_eq!(read, vec![step]);
        let e = read_follow_lines(&format!("{text}\n{{\"type\":\"nope\"}}\n")).unwrap_err();
        assert_eq!(e.line, 2);
    }
}
