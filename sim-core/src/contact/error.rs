//! Errors of the quasi-static contact solver.

use nalgebra::Vector2;

use crate::{ChainError, WallError};

/// Why a quasi-static contact problem could not be set up or advanced.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ContactError {
    /// A list has the wrong length.
    #[error("{argument} has length {actual}, expected {expected}")]
    WrongLength {
        /// Which argument.
        argument: &'static str,
        /// The length needed.
        expected: usize,
        /// The length given.
        actual: usize,
    },
    /// A number is NaN or infinite.
    #[error("{argument}[{index}] is not finite ({value})")]
    NotFinite {
        /// Which argument.
        argument: &'static str,
        /// Its index (0 for a scalar).
        index: usize,
        /// The value.
        value: f64,
    },
    /// A setting is out of its range.
    #[error("setting `{setting}` = {value} is out of range: {expected}")]
    BadSetting {
        /// The setting's field name.
        setting: &'static str,
        /// The value given.
        value: f64,
        /// What is allowed.
        expected: &'static str,
    },
    /// A start angle outside its joint limits.
    #[error("theta[{joint}] = {angle_rad} rad is outside its limits [{cw_rad}, {ccw_rad}]")]
    OutsideLimits {
        /// The joint.
        joint: usize,
        /// The angle given.
        angle_rad: f64,
        /// Its clockwise limit.
        cw_rad: f64,
        /// Its counter-clockwise limit.
        ccw_rad: f64,
    },
    /// The base link (or the base pivot) is inside a wall: nothing the joints do can free it.
    #[error(
        "wall {wall} crosses the base link (by {depth_m:.3e} m) with the base pivot at \
         ({base_x_m:.4}, {base_y_m:.4}) m: nothing the joints do can free it; move the base or \
         the wall"
    )]
    BaseInsideWall {
        /// The wall's index.
        wall: usize,
        /// How deep, metres.
        depth_m: f64,
        /// The base position, x.
        base_x_m: f64,
        /// The base position, y.
        base_y_m: f64,
    },
    /// The start posture puts a link or a hair tip inside a wall.
    #[error(
        "the start posture puts link {link}{hair} inside wall {wall} by {depth_m:.3e} m at \
         ({at_x_m:.4}, {at_y_m:.4}) m; place the antenna against the wall first (see \
         sim_core::sweep::Placement)"
    )]
    StartInsideWall {
        /// The wall's index.
        wall: usize,
        /// The link.
        link: usize,
        /// `" (its hair tip)"` for a hair tip, empty for the link itself.
        hair: &'static str,
        /// How deep, metres.
        depth_m: f64,
        /// Where, x (ground frame, metres): the link's deepest point or the hair tip.
        at_x_m: f64,
        /// Where, y.
        at_y_m: f64,
    },
    /// A step could not be solved, even in the smallest substeps and by following the
    /// downhill path.
    #[error(
        "no equilibrium found moving the base to ({base_x_m}, {base_y_m}) m: {reason} \
         (after {iterations} Newton iterations)"
    )]
    NoConvergence {
        /// The base position aimed for, x.
        base_x_m: f64,
        /// The base position aimed for, y.
        base_y_m: f64,
        /// What went wrong.
        reason: &'static str,
        /// Newton iterations spent on the step.
        iterations: usize,
    },
    /// The state a step reached failed the independent check ([`super::QuasiStatic::check`]):
    /// the step is refused rather than reported.
    #[error(
        "the step to ({base_x_m}, {base_y_m}) m reached a state that fails the independent \
         check: {failures}"
    )]
    Uncertified {
        /// The base position, x.
        base_x_m: f64,
        /// The base position, y.
        base_y_m: f64,
        /// What failed, in words.
        failures: String,
        /// The check.
        check: Box<super::EquilibriumCheck>,
    },
    /// The antenna jammed: no posture within the joints' limits keeps every link out of the
    /// walls with the base where it was to go (see [`super::Jam`]). A physical outcome, not
    /// a failure of the solver: the state is that of the last step solved.
    #[error("{0}")]
    Jammed(Box<super::Jam>),
    /// A chain could not be built.
    #[error(transparent)]
    Chain(#[from] ChainError),
    /// A wall is invalid.
    #[error(transparent)]
    Wall(#[from] WallError),
}

impl ContactError {
    pub(crate) fn no_convergence(
        base_m: Vector2<f64>,
        reason: &'static str,
        iterations: usize,
    ) -> ContactError {
        ContactError::NoConvergence {
            base_x_m: base_m.x,
            base_y_m: base_m.y,
            reason,
            iterations,
        }
    }
}
