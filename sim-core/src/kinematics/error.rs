//! Typed errors: invalid chain descriptions ([`ChainError`]) and invalid arguments to the
//! kinematics ([`KinematicsError`]). Every variant names the offending field or argument and
//! its index, so a caller can point at the exact input that was wrong.

use core::fmt;

/// A field of a chain description, named in [`ChainError`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ChainField {
    /// `link_lengths_m[index]`, link `index` (0 is the base link).
    LinkLength,
    /// The base angle `theta_0`.
    BaseAngle,
    /// The clockwise limit of joint `index`.
    JointLimitCw,
    /// The counter-clockwise limit of joint `index`.
    JointLimitCcw,
    /// The stiffness of joint `index`.
    Stiffness,
    /// The rest angle of joint `index`.
    RestAngle,
    /// The length of the hair on link `index`.
    HairLength,
    /// The open angle of the hair on link `index`.
    HairOpenAngle,
    /// The pivot position (distance from the link's distal end) of the hair on link `index`.
    HairPivot,
    /// The lateral offset of the pivot of the hair on link `index`.
    HairLateralOffset,
    /// The spring preload of the hair on link `index`.
    HairPreload,
    /// The spring stiffness of the hair on link `index`.
    HairStiffness,
    /// The root stiffness of the hair on link `index` (a compliant hair).
    HairRootStiffness,
}

impl fmt::Display for ChainField {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::LinkLength => "link_lengths_m",
            Self::BaseAngle => "base_angle_rad",
            Self::JointLimitCw => "joint_limits.cw_rad",
            Self::JointLimitCcw => "joint_limits.ccw_rad",
            Self::Stiffness => "stiffness_nm_per_rad",
            Self::RestAngle => "rest_angles_rad",
            Self::HairLength => "hair.length_m",
            Self::HairOpenAngle => "hair.open_angle_rad",
            Self::HairPivot => "hair.pivot_from_distal_end_m",
            Self::HairLateralOffset => "hair.lateral_offset_m",
            Self::HairPreload => "hair.preload_nm",
            Self::HairStiffness => "hair.stiffness_nm_per_rad",
            Self::HairRootStiffness => "hair.root_stiffness_nm_per_rad",
        })
    }
}

/// An invalid chain description, found by [`crate::kinematics::chain::ChainBuilder::build`].
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum ChainError {
    /// A value is NaN or infinite.
    #[error("{field}[{index}] is not finite ({value})")]
    NotFinite {
        /// Which field.
        field: ChainField,
        /// Link or joint index (0 for the base angle).
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// A link length is zero or negative.
    #[error("link_lengths_m[{index}] must be positive, got {value_m} m")]
    NonPositiveLength {
        /// Link index (0 is the base link).
        index: usize,
        /// The offending length in metres.
        value_m: f64,
    },
    /// The clockwise limit of a joint is greater than its counter-clockwise limit.
    #[error("joint_limits[{index}] reversed: cw {cw_rad} rad > ccw {ccw_rad} rad")]
    LimitsReversed {
        /// Joint index (1..=n).
        index: usize,
        /// The clockwise (lower) limit in radians.
        cw_rad: f64,
        /// The counter-clockwise (upper) limit in radians.
        ccw_rad: f64,
    },
    /// A joint stiffness is negative.
    #[error("stiffness_nm_per_rad[{index}] must be >= 0, got {value_nm_per_rad} N m/rad")]
    NegativeStiffness {
        /// Joint index (1..=n).
        index: usize,
        /// The offending stiffness in N m/rad.
        value_nm_per_rad: f64,
    },
    /// A per-link or per-joint list has the wrong number of entries.
    #[error("{field} has {actual} entries, expected {expected}")]
    WrongCount {
        /// Which list.
        field: ChainField,
        /// The number the chain needs.
        expected: usize,
        /// The number given.
        actual: usize,
    },
    /// An index (of a link carrying a hair, say) is beyond the chain.
    #[error("{field}: link index {index} out of range 0..={n}")]
    IndexOutOfRange {
        /// Which field.
        field: ChainField,
        /// The offending index.
        index: usize,
        /// The number of flagellar links (valid indices are 0..=n).
        n: usize,
    },
    /// A hair parameter is out of its physical range (documented on [`crate::Hair`]).
    #[error("{field}[{index}] out of range: {value}")]
    HairOutOfRange {
        /// Which hair parameter.
        field: ChainField,
        /// The link carrying the hair.
        index: usize,
        /// The offending value.
        value: f64,
    },
}

/// An argument to a kinematics function that does not fit the chain.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum KinematicsError {
    /// A frame index outside `-1..=n`.
    #[error("frame {argument} = {index} out of range -1..={n}")]
    FrameOutOfRange {
        /// Which argument (`"s"`, `"b"`, ...).
        argument: &'static str,
        /// The offending frame index.
        index: isize,
        /// The number of flagellar links.
        n: usize,
    },
    /// A link index outside `0..=n`.
    #[error("link {argument} = {index} out of range 0..={n}")]
    LinkOutOfRange {
        /// Which argument.
        argument: &'static str,
        /// The offending link index.
        index: usize,
        /// The number of flagellar links.
        n: usize,
    },
    /// A vector argument has the wrong length.
    #[error("{argument} has length {actual}, expected {expected}")]
    WrongLength {
        /// Which argument (`"theta"`, `"theta_dot"`, `"q"`, ...).
        argument: &'static str,
        /// The length the chain needs (usually n + 1).
        expected: usize,
        /// The length given.
        actual: usize,
    },
    /// An output buffer has the wrong shape.
    #[error("{argument} is {rows}x{cols}, expected {expected_rows}x{expected_cols}")]
    WrongShape {
        /// Which buffer.
        argument: &'static str,
        /// Rows needed.
        expected_rows: usize,
        /// Columns needed.
        expected_cols: usize,
        /// Rows given.
        rows: usize,
        /// Columns given.
        cols: usize,
    },
    /// A joint angle outside its limits (for the inverse limit map).
    #[error("theta[{index}] = {value_rad} rad outside limits [{cw_rad}, {ccw_rad}]")]
    OutsideLimits {
        /// Joint index.
        index: usize,
        /// The offending angle in radians.
        value_rad: f64,
        /// The clockwise limit.
        cw_rad: f64,
        /// The counter-clockwise limit.
        ccw_rad: f64,
    },
    /// A hair quantity was asked for a link that carries no hair.
    #[error("link {link} carries no hair")]
    NoHair {
        /// The link index.
        link: usize,
    },
}
