//! The errors of the elastica solver and of the closed form.

/// Errors from the elastica solver and the closed form.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ElasticaError {
    /// `length_m` is not finite and positive.
    #[error("length_m = {value_m} m is not finite and positive")]
    InvalidLength {
        /// The offending length, m.
        value_m: f64,
    },
    /// A tip force component is not finite.
    #[error("tip_force_n[{index}] = {value_n} N is not finite")]
    InvalidForce {
        /// 0 for `Fx`, 1 for `Fy`.
        index: usize,
        /// The offending value, N.
        value_n: f64,
    },
    /// `clamp_angle_rad` is not finite.
    #[error("clamp_angle_rad = {value_rad} rad is not finite")]
    InvalidClampAngle {
        /// The offending angle, rad.
        value_rad: f64,
    },
    /// A bending stiffness (a constant, a section value, or a closure's value at `s_m`) is not
    /// finite and positive.
    #[error("bending stiffness at s = {s_m} m is {value_n_m2} N m^2, not finite and positive")]
    InvalidStiffness {
        /// Arc length where it was evaluated (a section's start for piecewise values), m.
        s_m: f64,
        /// The offending value, N m^2.
        value_n_m2: f64,
    },
    /// A breakpoint is not strictly inside (0, L) or not strictly increasing.
    #[error("breakpoints_m[{index}] = {value_m} m is not strictly increasing inside (0, length_m)")]
    InvalidBreakpoint {
        /// Index into the breakpoints.
        index: usize,
        /// The offending value, m.
        value_m: f64,
    },
    /// Piecewise-constant stiffness needs one value more than breakpoints.
    #[error("{values} stiffness value(s) for {breakpoints} breakpoint(s); need breakpoints + 1")]
    SectionCountMismatch {
        /// Number of breakpoints.
        breakpoints: usize,
        /// Number of values.
        values: usize,
    },
    /// A solver option is out of its domain.
    #[error("option {field} = {value} is out of range ({expected})")]
    InvalidOption {
        /// Option name.
        field: &'static str,
        /// The offending value.
        value: f64,
        /// The domain, in words.
        expected: &'static str,
    },
    /// The adaptive integrator's step fell below `1e-14 L`.
    #[error("integration step size underflow at s = {s_m} m")]
    StepSizeUnderflow {
        /// Arc length reached, m.
        s_m: f64,
    },
    /// Newton's method (and load continuation) did not bring `M(L)` to zero.
    #[error(
        "shooting did not converge after {iterations} iterations: |M(L)| = {residual_n_m} N m at M(0) = {base_moment_n_m} N m"
    )]
    NotConverged {
        /// Newton iterations spent.
        iterations: usize,
        /// Best residual `|M(L)|` reached, N m.
        residual_n_m: f64,
        /// The clamp moment at that residual, N m.
        base_moment_n_m: f64,
    },
    /// `alpha` for the closed form is not finite.
    #[error("alpha = {value} is not finite")]
    InvalidAlpha {
        /// The offending value.
        value: f64,
    },
}
