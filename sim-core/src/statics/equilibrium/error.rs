//! Typed errors of the equilibrium solvers.

/// Why an equilibrium solve could not produce an answer.
///
/// A solve that runs out of iterations is not an error: it returns an
/// [`Equilibrium`](super::Equilibrium) with `converged: false`.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum EquilibriumError {
    /// A vector argument has the wrong number of entries.
    #[error("{argument} has {actual} entries, expected {expected}")]
    WrongLength {
        /// Which argument (`"initial angles"`, ...).
        argument: &'static str,
        /// The number the chain needs.
        expected: usize,
        /// The number given.
        actual: usize,
    },
    /// An input is NaN or infinite.
    #[error("{argument}[{index}] is not finite ({value})")]
    NotFinite {
        /// Which argument (`"tip_force_n"`, `"tip_pin_m"`, `"initial angles"`).
        argument: &'static str,
        /// The entry (joint index `1..=n` for angles, 0/1 for x/y).
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// A start angle given explicitly lies outside its joint's limits.
    #[error("start angle of joint {index} = {value_rad} rad outside limits [{cw_rad}, {ccw_rad}]")]
    StartOutsideLimits {
        /// Joint index `1..=n`.
        index: usize,
        /// The offending angle in radians.
        value_rad: f64,
        /// The clockwise limit.
        cw_rad: f64,
        /// The counter-clockwise limit.
        ccw_rad: f64,
    },
    /// An option is out of range.
    #[error("invalid solver option {option} = {value}")]
    InvalidOption {
        /// Which option (`"tolerance"`, `"max_iterations"`).
        option: &'static str,
        /// The offending value.
        value: f64,
    },
    /// The pin target lies where the tip cannot be: farther from the first flexible joint
    /// than the flexible links reach, or nearer than the folded chain can come.
    #[error(
        "pin target unreachable: {distance_m} m from the first flexible joint, reachable {min_reach_m}..={reach_m} m"
    )]
    Unreachable {
        /// Distance from the first flexible joint (frame `C_0`) to the target, metres.
        distance_m: f64,
        /// The largest distance the tip can be from `C_0` (the flexible length), metres.
        reach_m: f64,
        /// The smallest distance the tip can be from `C_0` without limits, metres.
        min_reach_m: f64,
    },
    /// The search found no posture within the joint limits that meets the pin: from the
    /// given start and from every standard restart, the augmented-Lagrangian penalty reached
    /// its cap while the gap stopped shrinking (the chain jammed against its limits). This
    /// is what a local search can say: the limits keep the target out of reach of the
    /// postures it tried, not a proof that no posture reaches it.
    #[error(
        "pin not reached within the joint limits: the search from {starts} start(s) jammed \
         against the limits, closest gap {gap_m} m, after {iterations} iterations"
    )]
    PinInfeasible {
        /// The smallest remaining distance from the tip to the target over the starts
        /// tried, metres.
        gap_m: f64,
        /// How many starts were tried (the given one and the restarts).
        starts: usize,
        /// Newton iterations spent.
        iterations: usize,
    },
    /// The iteration broke down (no descent possible although not converged, or a
    /// non-finite value appeared).
    #[error("numerical breakdown at iteration {iteration}: {reason}")]
    NumericalBreakdown {
        /// The Newton iteration at which it happened.
        iteration: usize,
        /// What happened.
        reason: &'static str,
    },
}
