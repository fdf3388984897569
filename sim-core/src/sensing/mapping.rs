//! Wall mapping from what the robot senses (thesis 4.2.2, docs/model.md 8): contact points estimated
//! from the joint angles as the segments report them and the touch switches, scored against
//! the true wall as a mean spatial error in millimetres.
//!
//! # What the robot senses (thesis 2.3.1)
//! - **Joint angles**: each segment's Hall sensor gives 12 bits per turn
//!   ([`antenna_protocol::ANGLE_COUNTS_PER_TURN`]):
//!   `theta_q = round(theta / q) q` with `q = 2 pi / 4096` ([`RAD_PER_COUNT`], 0.088 deg;
//!   `f64::round`, halves away from zero). The base angle `theta_0` and the base position are
//!   set by the platform and known exactly: they are not quantized.
//! - **Touch bits**: "four directional detector switches ... uniformly distributed along its
//!   length", actuated by the hairs; bit `k` is switch `k`, bit 0 the most proximal (as
//!   `antenna_protocol::TouchBits`). Switch `k` covers the quarter `[k/4, (k+1)/4)` of its link
//!   ([`switch_for_fraction`]).
//!
//! # The estimate
//! The thesis does not spell out its estimator; this one uses only the sensed data: for every
//! touched switch, the point at the middle of its quarter, `(k + 1/2)/4` of the way along the
//! link from its proximal joint, offset by [`TouchLayout::lateral_offset_m`] along the link's
//! left normal, placed by forward kinematics of the sensed angles from the known base pose.
//! Its error is its distance to the true wall curve (the nearest of the given walls).

use antenna_protocol::{RAD_PER_COUNT, TOUCH_MASK};
use nalgebra::Vector2;

use crate::{Chain, ChainContact, Wall};

/// Touch switches per segment: the bits of the sample word's touch field
/// ([`antenna_protocol::TOUCH_MASK`]).
pub const SWITCHES_PER_SEGMENT: usize = TOUCH_MASK.count_ones() as usize;

/// An argument to the mapping functions that does not fit.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum MappingError {
    /// A per-link list has the wrong length.
    #[error("{argument} has length {actual}, expected {expected}")]
    WrongLength {
        /// Which argument.
        argument: &'static str,
        /// The length needed (`n + 1`).
        expected: usize,
        /// The length given.
        actual: usize,
    },
    /// Touch bits beyond the four switches.
    #[error("touch_bits[{link}] = {bits:#04x} has bits above the four switches")]
    TouchOutOfRange {
        /// The link.
        link: usize,
        /// The offending value.
        bits: u8,
    },
    /// A contact on a link the chain does not have.
    #[error("contact on link {link}, but the chain has links 0..={n}")]
    LinkOutOfRange {
        /// The offending link index.
        link: usize,
        /// The number of flagellar links.
        n: usize,
    },
    /// A sensed angle or the base position is NaN or infinite.
    #[error("{argument}[{index}] is not finite")]
    NotFinite {
        /// Which argument.
        argument: &'static str,
        /// The offending index.
        index: usize,
    },
}

/// The angle a segment reports for `theta_rad`: `round(theta / q) q`, `q = 2 pi / 4096`.
pub fn quantize_angle_rad(theta_rad: f64) -> f64 {
    (theta_rad / RAD_PER_COUNT).round() * RAD_PER_COUNT
}

/// The sensed posture: `theta_0` (the known base angle) copied, `theta_j` (`j >= 1`)
/// quantized. No allocation.
///
/// # Errors
/// [`MappingError::WrongLength`] if `out` is not as long as `theta_rad`.
pub fn sensed_theta_rad(theta_rad: &[f64], out: &mut [f64]) -> Result<(), MappingError> {
    if out.len() != theta_rad.len() {
        return Err(MappingError::WrongLength {
            argument: "out",
            expected: theta_rad.len(),
            actual: out.len(),
        });
    }
    for (j, (o, &theta)) in out.iter_mut().zip(theta_rad).enumerate() {
        *o = if j == 0 {
            theta
        } else {
            quantize_angle_rad(theta)
        };
    }
    Ok(())
}

/// The switch covering fraction `s` of a link: `floor(4 s)`, `s` clamped to `[0, 1]` (the
/// distal end belongs to switch 3; NaN to switch 0).
pub fn switch_for_fraction(s: f64) -> usize {
    let s = if s.is_nan() { 0.0 } else { s.clamp(0.0, 1.0) };
    ((s * SWITCHES_PER_SEGMENT as f64) as usize).min(SWITCHES_PER_SEGMENT - 1)
}

/// The touch bits a posture's contacts set: for each contact, bit
/// [`switch_for_fraction`]`(s)` of its link's entry. `out` has one entry per link
/// (`0..=n`, `n + 1` entries) and is overwritten.
///
/// # Errors
/// [`MappingError::LinkOutOfRange`] for a contact beyond the links of `out`.
pub fn touch_bits_from_contacts(
    contacts: &[ChainContact],
    out: &mut [u8],
) -> Result<(), MappingError> {
    out.fill(0);
    for contact in contacts {
        let n = out.len().saturating_sub(1);
        let bits = out
            .get_mut(contact.link)
            .ok_or(MappingError::LinkOutOfRange {
                link: contact.link,
                n,
            })?;
        *bits |= 1 << switch_for_fraction(contact.s);
    }
    Ok(())
}

/// Where a touched switch puts its estimated contact point.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct TouchLayout {
    /// Offset of the estimated point from the link axis along the link's left (`+y`) normal,
    /// metres (`0`: on the axis, where the simulated links touch; the robot's half-width
    /// toward the wall side otherwise).
    pub lateral_offset_m: f64,
    /// Where a touch on the switch under a hair's pivot is placed: `false` (the default) on
    /// the link like any other switch; `true` at the tip of the hair open against its stop
    /// (the robot knows its hairs' geometry but not their angle, and a hair touching lightly
    /// stays open). A hair's tip touches up to its length away from the link (18 mm on the
    /// thesis's robot), so on an antenna with hairs this places the point where the hair
    /// meets the wall rather than on the link.
    pub hair_tips: bool,
}

impl TouchLayout {
    /// The fraction of its link at which switch `k` is placed: `(k + 1/2) / 4`.
    pub fn switch_fraction(k: usize) -> f64 {
        (k as f64 + 0.5) / SWITCHES_PER_SEGMENT as f64
    }
}

/// One estimated wall contact point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EstimatedContact {
    /// The link whose switch fired.
    pub link: usize,
    /// The switch (`0` most proximal .. `3`).
    pub switch: usize,
    /// The estimated point in the ground frame, metres.
    pub point_m: Vector2<f64>,
}

/// The contact points the robot would estimate: forward kinematics of `sensed_theta_rad`
/// (`n + 1` entries, see [`sensed_theta_rad`]) from the base pivot at `base_m`, one point per
/// set bit of `touch_bits` (`n + 1` entries, entry `i` for link `i`), appended to `out` in
/// link then switch order. Allocates only if `out` must grow.
///
/// # Errors
/// [`MappingError::WrongLength`], [`MappingError::TouchOutOfRange`] (bits above the four
/// switches), [`MappingError::NotFinite`].
pub fn estimate_contacts(
    chain: &Chain,
    base_m: &Vector2<f64>,
    sensed_theta_rad: &[f64],
    touch_bits: &[u8],
    layout: &TouchLayout,
    out: &mut Vec<EstimatedContact>,
) -> Result<(), MappingError> {
    let links = chain.n() + 1;
    for (argument, actual) in [
        ("sensed_theta_rad", sensed_theta_rad.len()),
        ("touch_bits", touch_bits.len()),
    ] {
        if actual != links {
            return Err(MappingError::WrongLength {
                argument,
                expected: links,
                actual,
            });
        }
    }
    for (index, value) in [base_m.x, base_m.y].into_iter().enumerate() {
        if !value.is_finite() {
            return Err(MappingError::NotFinite {
                argument: "base_m",
                index,
            });
        }
    }
    if let Some(index) = sensed_theta_rad.iter().position(|t| !t.is_finite()) {
        return Err(MappingError::NotFinite {
            argument: "sensed_theta_rad",
            index,
        });
    }
    if let Some(link) = touch_bits
        .iter()
        .position(|&b| b >> SWITCHES_PER_SEGMENT != 0)
    {
        return Err(MappingError::TouchOutOfRange {
            link,
            bits: touch_bits[link],
        });
    }
    let mut joint_m = *base_m;
    let mut phi_rad = 0.0;
    for (link, ((&theta, &length_m), &bits)) in sensed_theta_rad
        .iter()
        .zip(chain.link_lengths_m())
        .zip(touch_bits)
        .enumerate()
    {
        phi_rad += theta;
        let (sin, cos) = phi_rad.sin_cos();
        let along = Vector2::new(cos, sin);
        let left = Vector2::new(-sin, cos);
        // The hair whose pivot's switch is estimated at the hair's open tip, if any.
        let hair = if layout.hair_tips && length_m > 0.0 {
            chain.hairs().get(link).copied().flatten().map(|h| {
                let pivot_switch = switch_for_fraction(1.0 - h.pivot_from_distal_end_m / length_m);
                let tip = h.tip_in_link_m(h.open_angle_rad);
                // The link frame's origin is the distal end.
                let tip_m = joint_m + along * (length_m + tip.x) + left * tip.y;
                (pivot_switch, tip_m)
            })
        } else {
            None
        };
        for switch in (0..SWITCHES_PER_SEGMENT).filter(|k| bits & (1 << k) != 0) {
            let point_m = match hair {
                Some((pivot_switch, tip_m)) if pivot_switch == switch => tip_m,
                _ => {
                    joint_m
                        + along * (TouchLayout::switch_fraction(switch) * length_m)
                        + left * layout.lateral_offset_m
                }
            };
            out.push(EstimatedContact {
                link,
                switch,
                point_m,
            });
        }
        joint_m += along * length_m;
    }
    Ok(())
}

/// The distance from `point_m` to the nearest of `walls` (the absolute signed distance),
/// millimetres; `None` without walls.
pub fn point_error_mm(walls: &[Wall], point_m: &Vector2<f64>) -> Option<f64> {
    walls
        .iter()
        .map(|w| w.signed_distance(point_m).gap_m.abs() * 1e3)
        .reduce(f64::min)
}

/// A mapping score: how many points, their mean and largest distance to the true wall.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MappingScore {
    /// The number of estimated points scored.
    pub count: usize,
    /// Their mean distance to the true wall, millimetres (`None` without points).
    pub mean_error_mm: Option<f64>,
    /// Their largest distance to the true wall, millimetres (`None` without points).
    pub max_error_mm: Option<f64>,
}

/// A running mapping score over many steps of a sweep; no allocation.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct MappingAccumulator {
    count: usize,
    sum_mm: f64,
    max_mm: f64,
}

impl MappingAccumulator {
    /// Adds one point's error, millimetres.
    pub fn push(&mut self, error_mm: f64) {
        self.count += 1;
        self.sum_mm += error_mm;
        self.max_mm = self.max_mm.max(error_mm);
    }

    /// Adds every estimate's error against `walls` (nothing if there are no walls).
    pub fn add(&mut self, walls: &[Wall], estimates: &[EstimatedContact]) {
        for estimate in estimates {
            if let Some(error_mm) = point_error_mm(walls, &estimate.point_m) {
                self.push(error_mm);
            }
        }
    }

    /// The score so far.
    pub fn score(&self) -> MappingScore {
        let any = self.count > 0;
        MappingScore {
            count: self.count,
            mean_error_mm: any.then(|| self.sum_mm / self.count as f64),
            max_error_mm: any.then_some(self.max_mm),
        }
    }
}

/// The score of one set of estimates against `walls` (see [`MappingAccumulator`] to score a
/// whole sweep).
pub fn mapping_score(walls: &[Wall], estimates: &[EstimatedContact]) -> MappingScore {
    let mut accumulator = MappingAccumulator::default();
    accumulator.add(walls, estimates);
    accumulator.score()
}
