//! The validated chain description: link lengths, base angle, joint limits, stiffness, rest
//! angles and hairs (thesis 2.2, docs/model.md 1, 3, 4, 7).

use crate::kinematics::error::ChainField;
use crate::kinematics::hair::Hair;
use crate::{ChainError, Frame, KinematicsError};

/// The limits of one joint, `cw_rad <= theta_j <= ccw_rad` (thesis 2.2.4), measured relative to
/// the proximal neighbouring frame `C_{j-1}`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointLimit {
    /// Clockwise (lower) limit in radians.
    pub cw_rad: f64,
    /// Counter-clockwise (upper) limit in radians.
    pub ccw_rad: f64,
}

impl JointLimit {
    /// A limit pair `cw_rad <= theta <= ccw_rad` (checked when the chain is built).
    pub const fn new(cw_rad: f64, ccw_rad: f64) -> JointLimit {
        JointLimit { cw_rad, ccw_rad }
    }

    /// Both limits at `angle_rad`: a rigid joint, as the base joint is (thesis 2.2.4).
    pub const fn fixed(angle_rad: f64) -> JointLimit {
        JointLimit {
            cw_rad: angle_rad,
            ccw_rad: angle_rad,
        }
    }

    /// `(ccw + cw) / 2`, the angle at `q = 0`.
    pub fn mid_rad(&self) -> f64 {
        0.5 * (self.ccw_rad + self.cw_rad)
    }

    /// `(ccw - cw) / 2`, the amplitude of the limit map `g`.
    pub fn half_range_rad(&self) -> f64 {
        0.5 * (self.ccw_rad - self.cw_rad)
    }

    /// Whether `cw <= angle_rad <= ccw`.
    pub fn contains(&self, angle_rad: f64) -> bool {
        self.cw_rad <= angle_rad && angle_rad <= self.ccw_rad
    }
}

/// A planar serial chain of `n + 1` rigid links with joint springs (docs/model.md 1).
///
/// Link 0 is the base link, links `1..=n` the flagellum. Per-joint quantities are indexed
/// `0..=n` like `theta`; joint 0 is the base joint, fixed at the base angle: its limits are
/// both the base angle and its stiffness is 0 (thesis 2.2.4). Build one with [`Chain::builder`].
#[derive(Clone, Debug, PartialEq)]
pub struct Chain {
    link_lengths_m: Vec<f64>,
    base_angle_rad: f64,
    joint_limits: Vec<JointLimit>,
    stiffness_nm_per_rad: Vec<f64>,
    rest_angles_rad: Vec<f64>,
    hairs: Vec<Option<Hair>>,
}

impl Chain {
    /// A builder for a chain with `n` flagellar links (so `n + 1` links with the base).
    ///
    /// Defaults (the thesis's robot, 2.3): every link 0.04 m, base angle 0, joint limits
    /// `[-pi/2, pi/2]`, stiffness 0, rest angles 0, no hairs.
    pub fn builder(n: usize) -> ChainBuilder {
        ChainBuilder::new(n)
    }

    /// `n`, the number of flagellar links; `theta` has `n + 1` entries and the frames are
    /// `-1..=n`.
    pub fn n(&self) -> usize {
        self.link_lengths_m.len() - 1
    }

    /// The number of joint angles, `n + 1`.
    pub fn dof(&self) -> usize {
        self.link_lengths_m.len()
    }

    /// The tip frame `C_n`.
    pub fn tip(&self) -> Frame {
        Frame::link(self.n())
    }

    /// Link lengths in metres, `l_0..=l_n`.
    pub fn link_lengths_m(&self) -> &[f64] {
        &self.link_lengths_m
    }

    /// The sum of all link lengths in metres.
    pub fn total_length_m(&self) -> f64 {
        self.link_lengths_m.iter().sum()
    }

    /// The base angle `theta_0` in radians.
    pub fn base_angle_rad(&self) -> f64 {
        self.base_angle_rad
    }

    /// Joint limits `0..=n`; entry 0 is `JointLimit::fixed(base_angle_rad)`.
    pub fn joint_limits(&self) -> &[JointLimit] {
        &self.joint_limits
    }

    /// Joint stiffness `k_0..=k_n` in N m/rad; `k_0 = 0`.
    pub fn stiffness_nm_per_rad(&self) -> &[f64] {
        &self.stiffness_nm_per_rad
    }

    /// Rest angles `0..=n` in radians; entry 0 is the base angle (it carries no energy).
    pub fn rest_angles_rad(&self) -> &[f64] {
        &self.rest_angles_rad
    }

    /// The hair on each link `0..=n`, if any.
    pub fn hairs(&self) -> &[Option<Hair>] {
        &self.hairs
    }

    /// A builder holding this chain's description, to change some of it.
    ///
    /// ```
    /// # fn main() -> Result<(), sim_core::ChainError> {
    /// let chain = sim_core::Chain::builder(3).stiffness_nm_per_rad(0.01).build()?;
    /// assert_eq!(chain.to_builder().build()?, chain);
    /// let stiffer = chain.to_builder().stiffness_nm_per_rad(0.02).build()?;
    /// assert_eq!(stiffer.stiffness_nm_per_rad()[1..], [0.02; 3]);
    /// # Ok(())
    /// # }
    /// ```
    pub fn to_builder(&self) -> ChainBuilder {
        ChainBuilder {
            n: self.n(),
            link_lengths_m: self.link_lengths_m.clone(),
            base_angle_rad: self.base_angle_rad,
            joint_limits: self.joint_limits[1..].to_vec(),
            stiffness_nm_per_rad: self.stiffness_nm_per_rad[1..].to_vec(),
            rest_angles_rad: self.rest_angles_rad[1..].to_vec(),
            hairs: self
                .hairs
                .iter()
                .enumerate()
                .filter_map(|(link, hair)| hair.map(|h| (link, h)))
                .collect(),
        }
    }

    /// A copy of this chain with another base angle (joint 0's limits follow it).
    ///
    /// # Errors
    /// [`ChainError::NotFinite`] if `base_angle_rad` is NaN or infinite.
    pub fn with_base_angle_rad(&self, base_angle_rad: f64) -> Result<Chain, ChainError> {
        if !base_angle_rad.is_finite() {
            return Err(ChainError::NotFinite {
                field: ChainField::BaseAngle,
                index: 0,
                value: base_angle_rad,
            });
        }
        let mut chain = self.clone();
        chain.base_angle_rad = base_angle_rad;
        chain.joint_limits[0] = JointLimit::fixed(base_angle_rad);
        chain.rest_angles_rad[0] = base_angle_rad;
        Ok(chain)
    }

    /// `theta` for the chain at rest in its limits: the base angle, then each joint's rest
    /// angle clamped into its limits.
    pub fn rest_theta(&self) -> Vec<f64> {
        self.rest_angles_rad
            .iter()
            .zip(&self.joint_limits)
            .map(|(&r, lim)| r.clamp(lim.cw_rad, lim.ccw_rad))
            .collect()
    }

    /// Checks that a joint-space vector has `n + 1` entries.
    pub(crate) fn check_len(
        &self,
        argument: &'static str,
        len: usize,
    ) -> Result<(), KinematicsError> {
        if len == self.dof() {
            Ok(())
        } else {
            Err(KinematicsError::WrongLength {
                argument,
                expected: self.dof(),
                actual: len,
            })
        }
    }
}

/// Builds a validated [`Chain`]; see [`Chain::builder`] for the defaults.
#[derive(Clone, Debug)]
pub struct ChainBuilder {
    n: usize,
    link_lengths_m: Vec<f64>,
    base_angle_rad: f64,
    joint_limits: Vec<JointLimit>,
    stiffness_nm_per_rad: Vec<f64>,
    rest_angles_rad: Vec<f64>,
    hairs: Vec<(usize, Hair)>,
}

/// Spreads one value over `count` entries.
fn uniform<T: Clone>(value: T, count: usize) -> Vec<T> {
    vec![value; count]
}

impl ChainBuilder {
    /// See [`Chain::builder`].
    pub fn new(n: usize) -> ChainBuilder {
        let half_pi = core::f64::consts::FRAC_PI_2;
        ChainBuilder {
            n,
            link_lengths_m: uniform(0.04, n + 1),
            base_angle_rad: 0.0,
            joint_limits: uniform(JointLimit::new(-half_pi, half_pi), n),
            stiffness_nm_per_rad: uniform(0.0, n),
            rest_angles_rad: uniform(0.0, n),
            hairs: Vec::new(),
        }
    }

    /// Every link, the base link included, `length_m` long (the thesis's uniform `l`).
    pub fn link_length_m(mut self, length_m: f64) -> Self {
        self.link_lengths_m = uniform(length_m, self.n + 1);
        self
    }

    /// One length per link `0..=n` (`n + 1` entries).
    pub fn link_lengths_m(mut self, lengths_m: impl Into<Vec<f64>>) -> Self {
        self.link_lengths_m = lengths_m.into();
        self
    }

    /// The base angle `theta_0` (radians, from the ground x-axis, the direction of base
    /// motion). Joint 0's limits are set to it.
    pub fn base_angle_rad(mut self, angle_rad: f64) -> Self {
        self.base_angle_rad = angle_rad;
        self
    }

    /// The same limits for every flagellar joint `1..=n`.
    pub fn joint_limit(mut self, limit: JointLimit) -> Self {
        self.joint_limits = uniform(limit, self.n);
        self
    }

    /// One limit pair per flagellar joint `1..=n` (`n` entries; joint 0 is the base).
    pub fn joint_limits(mut self, limits: impl Into<Vec<JointLimit>>) -> Self {
        self.joint_limits = limits.into();
        self
    }

    /// The same stiffness (N m/rad) for every flagellar joint `1..=n`.
    pub fn stiffness_nm_per_rad(mut self, k: f64) -> Self {
        self.stiffness_nm_per_rad = uniform(k, self.n);
        self
    }

    /// One stiffness (N m/rad) per flagellar joint `1..=n` (`n` entries).
    pub fn stiffnesses_nm_per_rad(mut self, k: impl Into<Vec<f64>>) -> Self {
        self.stiffness_nm_per_rad = k.into();
        self
    }

    /// One rest angle (radians) per flagellar joint `1..=n` (`n` entries); a pre-bent
    /// antenna has non-zero rest angles (docs/model.md 4). A rest angle may lie outside the
    /// joint's limits (a preloaded spring, thesis 2.2.4).
    pub fn rest_angles_rad(mut self, rest_rad: impl Into<Vec<f64>>) -> Self {
        self.rest_angles_rad = rest_rad.into();
        self
    }

    /// A hair on link `link` (`0..=n`; docs/model.md puts hairs on flagellar links `1..=n`).
    pub fn hair(mut self, link: usize, hair: Hair) -> Self {
        self.hairs.push((link, hair));
        self
    }

    /// Removes every hair given so far.
    pub fn without_hairs(mut self) -> Self {
        self.hairs.clear();
        self
    }

    /// The same hair on every flagellar link `1..=n`.
    pub fn hair_on_every_flagellar_link(mut self, hair: Hair) -> Self {
        self.hairs.extend((1..=self.n).map(|i| (i, hair)));
        self
    }

    /// Validates and builds the chain.
    ///
    /// # Errors
    /// A [`ChainError`] naming the first invalid field and its index: a NaN or infinite
    /// value, a link length `<= 0`, limits with `cw > ccw`, a negative stiffness, a list of
    /// the wrong length, or a hair parameter out of range.
    pub fn build(self) -> Result<Chain, ChainError> {
        let n = self.n;
        check_count(ChainField::LinkLength, n + 1, self.link_lengths_m.len())?;
        check_count(ChainField::JointLimitCw, n, self.joint_limits.len())?;
        check_count(ChainField::Stiffness, n, self.stiffness_nm_per_rad.len())?;
        check_count(ChainField::RestAngle, n, self.rest_angles_rad.len())?;

        for (index, &value_m) in self.link_lengths_m.iter().enumerate() {
            finite(ChainField::LinkLength, index, value_m)?;
            if value_m <= 0.0 {
                return Err(ChainError::NonPositiveLength { index, value_m });
            }
        }
        finite(ChainField::BaseAngle, 0, self.base_angle_rad)?;
        for (i, lim) in self.joint_limits.iter().enumerate() {
            let index = i + 1;
            finite(ChainField::JointLimitCw, index, lim.cw_rad)?;
            finite(ChainField::JointLimitCcw, index, lim.ccw_rad)?;
            if lim.cw_rad > lim.ccw_rad {
                return Err(ChainError::LimitsReversed {
                    index,
                    cw_rad: lim.cw_rad,
                    ccw_rad: lim.ccw_rad,
                });
            }
        }
        for (i, &k) in self.stiffness_nm_per_rad.iter().enumerate() {
            let index = i + 1;
            finite(ChainField::Stiffness, index, k)?;
            if k < 0.0 {
                return Err(ChainError::NegativeStiffness {
                    index,
                    value_nm_per_rad: k,
                });
            }
        }
        for (i, &r) in self.rest_angles_rad.iter().enumerate() {
            finite(ChainField::RestAngle, i + 1, r)?;
        }
        let mut hairs = vec![None; n + 1];
        for &(link, hair) in &self.hairs {
            if link > n {
                return Err(ChainError::IndexOutOfRange {
                    field: ChainField::HairLength,
                    index: link,
                    n,
                });
            }
            hair.validate(link, self.link_lengths_m[link])?;
            hairs[link] = Some(hair);
        }

        let mut joint_limits = Vec::with_capacity(n + 1);
        joint_limits.push(JointLimit::fixed(self.base_angle_rad));
        joint_limits.extend_from_slice(&self.joint_limits);
        let mut stiffness = Vec::with_capacity(n + 1);
        stiffness.push(0.0);
        stiffness.extend_from_slice(&self.stiffness_nm_per_rad);
        let mut rest = Vec::with_capacity(n + 1);
        rest.push(self.base_angle_rad);
        rest.extend_from_slice(&self.rest_angles_rad);
        Ok(Chain {
            link_lengths_m: self.link_lengths_m,
            base_angle_rad: self.base_angle_rad,
            joint_limits,
            stiffness_nm_per_rad: stiffness,
            rest_angles_rad: rest,
            hairs,
        })
    }
}

fn check_count(field: ChainField, expected: usize, actual: usize) -> Result<(), ChainError> {
    if expected == actual {
        Ok(())
    } else {
        Err(ChainError::WrongCount {
            field,
            expected,
            actual,
        })
    }
}

pub(crate) fn finite(field: ChainField, index: usize, value: f64) -> Result<(), ChainError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(ChainError::NotFinite {
            field,
            index,
            value,
        })
    }
}
