//! Counts to radians, with a per-segment calibration: each magnet is press-fit at an arbitrary
//! angle (zero offset) and a segment may be mounted either way up (direction).

use crate::{ANGLE_COUNTS_PER_TURN, MAX_ANGLE_COUNT};
use core::f64::consts::PI;

/// Radians per angle count: one turn over 4096 counts (0.088 deg).
pub const RAD_PER_COUNT: f64 = 2.0 * PI / ANGLE_COUNTS_PER_TURN as f64;

/// Which way the count grows with the joint angle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Direction {
    /// Counts grow with counter-clockwise joint rotation (the model's positive sense).
    #[default]
    CounterClockwise,
    /// Counts grow with clockwise joint rotation.
    Clockwise,
}

/// A segment's calibration: the count that reads at joint angle zero, and the direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Calibration {
    zero_counts: u16,
    direction: Direction,
}

impl Calibration {
    /// A calibration with the count read at zero joint angle (taken modulo 4096).
    pub const fn new(zero_counts: u16, direction: Direction) -> Self {
        Self {
            zero_counts: zero_counts & MAX_ANGLE_COUNT,
            direction,
        }
    }

    /// The count read at zero joint angle.
    pub const fn zero_counts(self) -> u16 {
        self.zero_counts
    }

    /// The direction.
    pub const fn direction(self) -> Direction {
        self.direction
    }

    /// The signed count offset from zero, wrapped to -2048..=2047.
    pub const fn signed_counts(self, counts: u16) -> i16 {
        let delta = (counts & MAX_ANGLE_COUNT).wrapping_sub(self.zero_counts) & MAX_ANGLE_COUNT;
        let signed = if delta >= ANGLE_COUNTS_PER_TURN / 2 {
            delta as i16 - ANGLE_COUNTS_PER_TURN as i16
        } else {
            delta as i16
        };
        match self.direction {
            Direction::CounterClockwise => signed,
            Direction::Clockwise => -signed,
        }
    }

    /// The joint angle in radians, in [-pi, pi), for a raw count.
    pub fn angle_rad(self, counts: u16) -> f64 {
        f64::from(self.signed_counts(counts)) * RAD_PER_COUNT
    }

    /// The count a segment with this calibration reads at `angle_rad` (nearest count; the
    /// simulated rig uses it to quantize joint angles as the Hall sensor does).
    pub fn counts_for_angle(self, angle_rad: f64) -> u16 {
        let signed = angle_rad / RAD_PER_COUNT;
        let signed = match self.direction {
            Direction::CounterClockwise => signed,
            Direction::Clockwise => -signed,
        };
        let turn = f64::from(ANGLE_COUNTS_PER_TURN);
        // rem_euclid keeps the value in [0, 4096); NaN maps to the zero count.
        let wrapped = libm_round(signed).rem_euclid_f64(turn);
        let counts = if wrapped.is_finite() {
            wrapped as u16
        } else {
            0
        };
        (counts.wrapping_add(self.zero_counts)) & MAX_ANGLE_COUNT
    }
}

/// `f64::round` is not in `core`; round half away from zero by hand.
fn libm_round(x: f64) -> f64 {
    let truncated = x as i64 as f64;
    if !x.is_finite() || x.abs() >= 4.5e15 {
        return x;
    }
    let fraction = x - truncated;
    if fraction >= 0.5 {
        truncated + 1.0
    } else if fraction <= -0.5 {
        truncated - 1.0
    } else {
        truncated
    }
}

trait RemEuclidF64 {
    fn rem_euclid_f64(self, modulus: f64) -> f64;
}

impl RemEuclidF64 for f64 {
    fn rem_euclid_f64(self, modulus: f64) -> f64 {
        let r = self % modulus;
        if r < 0.0 { r + modulus } else { r }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn zero_offset_reads_zero_and_half_turn_wraps_negative() {
        let cal = Calibration::new(1000, Direction::CounterClockwise);
        assert_eq!(cal.angle_rad(1000), 0.0);
        assert_eq!(cal.signed_counts(1001), 1);
        assert_eq!(cal.signed_counts(999), -1);
        assert_eq!(cal.signed_counts(1000 + 2048), -2048);
        assert!((cal.angle_rad(1000 + 1024) - PI / 2.0).abs() < 1e-12);
        let flipped = Calibration::new(1000, Direction::Clockwise);
        assert!((flipped.angle_rad(1000 + 1024) + PI / 2.0).abs() < 1e-12);
    }

    #[test]
    fn every_count_round_trips_through_radians() {
        for direction in [Direction::CounterClockwise, Direction::Clockwise] {
            for zero in [0u16, 1, 2047, 2048, 4095] {
                let cal = Calibration::new(zero, direction);
                for counts in 0..=MAX_ANGLE_COUNT {
                    assert_eq!(cal.counts_for_angle(cal.angle_rad(counts)), counts);
                }
            }
        }
    }

    proptest! {
        #[test]
        fn quantization_error_is_at_most_half_a_count(
            angle in -3.1f64..3.1, zero in 0u16..4096, clockwise in any::<bool>()
        ) {
            let direction = if clockwise { Direction::Clockwise } else { Direction::CounterClockwise };
            let cal = Calibration::new(zero, direction);
            let back = cal.angle_rad(cal.counts_for_angle(angle));
            prop_assert!((back - angle).abs() <= RAD_PER_COUNT / 2.0 + 1e-12);
        }
    }

    #[test]
    fn non_finite_angles_map_to_the_zero_count() {
        let cal = Calibration::new(77, Direction::CounterClockwise);
        assert_eq!(cal.counts_for_angle(f64::NAN), 77);
    }
}
