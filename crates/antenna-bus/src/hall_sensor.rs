//! A simulated segment's Hall sensor and ADC as they are (thesis 2.3.1; issue #18): the
//! conversions the firmware oversamples, with the joint's calibration error and seeded noise.
//!
//! # The model
//! The sensor sees the joint angle turned by the joint's gain error `g` and calibration offset
//! `o` (twelve-bit counts, in the direction of a positive joint angle):
//! `theta (1 + g) + o q`, `q` = [`RAD_PER_COUNT`], so that the host, decoding the word with the
//! segment's [`Calibration`], reads that angle (to a count). Its count is split into the 16
//! ten-bit conversions that oversample to it exactly (the ideal ADC's), and each conversion
//! then gets its own Gaussian noise of standard deviation `s` ten-bit counts, rounded and
//! clamped to the ADC's `0..=1023`. The firmware's oversampling (the sum of the 16, shifted
//! right by 2) then turns that into a twelve-bit reading whose noise has a standard deviation
//! of `s` twelve-bit counts (`sqrt(16) s / 4`), plus the rounding of the conversions and of the
//! shift (about `sqrt(s^2 + 0.16)` in all).
//!
//! What the firmware does with noisy conversions is kept as it is:
//! - the shift truncates, so a noisy reading's mean sits about 3/8 of a count below the
//!   noise-free count (the mean of the two bits dropped); the host's zero calibration, measured
//!   on the same readings, absorbs it;
//! - a noisy conversion that reaches a rail (0 or 1023) sets the firmware's ADC-fault status
//!   bit ([`firmware_segment::adc_fault`]), as it would on the robot near a rail.
//!
//! With no noise the conversions are exactly the ideal ones, and with no gain or offset error
//! the count is exactly [`Calibration::counts_for_angle`] of the angle: [`HallErrors::IDEAL`]
//! is the ideal segment, bit for bit.

use antenna_protocol::{Calibration, RAD_PER_COUNT};
use firmware_segment::{ADC_MASK, OVERSAMPLE_COUNT};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// How a simulated segment's angle sensing departs from the ideal (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HallErrors {
    /// Standard deviation of the noise of each ten-bit conversion, ten-bit counts (`>= 0`):
    /// the oversampled twelve-bit reading's noise has this standard deviation in twelve-bit
    /// counts.
    pub noise_counts: f64,
    /// Calibration offset, twelve-bit counts added to the angle the sensor reports (finite).
    pub offset_counts: f64,
    /// Gain error, a fraction (`> -1`; `0.01`: the angle reads 1 % large).
    pub gain_error: f64,
}

impl HallErrors {
    /// The ideal sensor: no noise, no calibration error.
    pub const IDEAL: HallErrors = HallErrors {
        noise_counts: 0.0,
        offset_counts: 0.0,
        gain_error: 0.0,
    };

    /// Checks the values.
    ///
    /// # Errors
    /// [`HallSensorError`] naming the value out of range.
    pub fn validate(&self) -> Result<(), HallSensorError> {
        if !(self.noise_counts.is_finite() && self.noise_counts >= 0.0) {
            return Err(HallSensorError::Noise(self.noise_counts));
        }
        if !self.offset_counts.is_finite() {
            return Err(HallSensorError::Offset(self.offset_counts));
        }
        if !(self.gain_error.is_finite() && self.gain_error > -1.0) {
            return Err(HallSensorError::Gain(self.gain_error));
        }
        Ok(())
    }
}

impl Default for HallErrors {
    fn default() -> Self {
        Self::IDEAL
    }
}

/// A [`HallErrors`] value out of range.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum HallSensorError {
    /// The noise is negative or not finite.
    #[error("noise_counts = {0}: must be finite and at least 0")]
    Noise(f64),
    /// The offset is not finite.
    #[error("offset_counts = {0}: must be finite")]
    Offset(f64),
    /// The gain error is at or below -1 (the reading would not grow with the angle) or not
    /// finite.
    #[error("gain_error = {0}: must be finite and above -1")]
    Gain(f64),
}

/// One segment's Hall sensor and ADC: its errors and its own seeded noise stream.
#[derive(Debug, Clone)]
pub struct HallSensor {
    errors: HallErrors,
    noise: ChaCha8Rng,
}

impl Default for HallSensor {
    fn default() -> Self {
        Self::ideal()
    }
}

impl HallSensor {
    /// The ideal sensor (draws no noise).
    pub fn ideal() -> Self {
        Self {
            errors: HallErrors::IDEAL,
            noise: ChaCha8Rng::seed_from_u64(0),
        }
    }

    /// A sensor with `errors`, its noise drawn from ChaCha8 seeded with `seed` (as
    /// `SeedableRng::seed_from_u64`) on stream `stream`: give each segment of a bus its own
    /// stream, so that one segment's noise does not depend on the others'.
    ///
    /// # Errors
    /// As [`HallErrors::validate`].
    pub fn new(errors: HallErrors, seed: u64, stream: u64) -> Result<Self, HallSensorError> {
        errors.validate()?;
        let mut noise = ChaCha8Rng::seed_from_u64(seed);
        noise.set_stream(stream);
        Ok(Self { errors, noise })
    }

    /// The errors in force.
    pub fn errors(&self) -> HallErrors {
        self.errors
    }

    /// The count of the angle the sensor sees for the joint angle `angle_rad` (see the module
    /// docs), through `calibration`.
    pub fn counts(&self, calibration: Calibration, angle_rad: f64) -> u16 {
        let HallErrors {
            gain_error,
            offset_counts,
            ..
        } = self.errors;
        // The ideal count is that of the angle itself, untouched (not even by `+ 0.0`).
        let sensed_rad = if gain_error == 0.0 && offset_counts == 0.0 {
            angle_rad
        } else {
            angle_rad * (1.0 + gain_error) + offset_counts * RAD_PER_COUNT
        };
        calibration.counts_for_angle(sensed_rad)
    }

    /// One sampling period's 16 ten-bit conversions for the joint angle `angle_rad`: the
    /// ideal ones for its count, each with its own noise (one draw per conversion when there
    /// is noise, none otherwise).
    pub fn conversions(
        &mut self,
        calibration: Calibration,
        angle_rad: f64,
    ) -> [u16; OVERSAMPLE_COUNT] {
        let ideal = conversions_for_counts(self.counts(calibration, angle_rad));
        let sd = self.errors.noise_counts;
        if sd == 0.0 {
            return ideal;
        }
        ideal.map(|conversion| {
            let z: f64 = StandardNormal.sample(&mut self.noise);
            let noisy = (f64::from(conversion) + sd * z).round();
            // In range after the clamp: the cast is exact.
            noisy.clamp(0.0, f64::from(ADC_MASK)) as u16
        })
    }
}

/// Sixteen 10-bit conversions whose oversampled value, `(sum) >> 2`, is `counts` (clamped to
/// 4092, the largest count 16 ten-bit conversions can make).
pub(crate) fn conversions_for_counts(counts: u16) -> [u16; OVERSAMPLE_COUNT] {
    let sum = u32::from(counts.min(4092)) << 2;
    let base = sum / OVERSAMPLE_COUNT as u32;
    let extra = (sum % OVERSAMPLE_COUNT as u32) as usize;
    let mut conversions = [base as u16; OVERSAMPLE_COUNT];
    for conversion in conversions.iter_mut().take(extra) {
        *conversion += 1;
    }
    conversions
}

#[cfg(test)]
mod tests {
    use super::*;
    use antenna_protocol::Direction;
    use firmware_segment::{adc_fault, oversample};

    #[test]
    fn conversions_oversample_to_the_requested_count() {
        for counts in 0..=4092u16 {
            assert_eq!(oversample(&conversions_for_counts(counts)), counts);
        }
        assert_eq!(oversample(&conversions_for_counts(4095)), 4092);
    }

    #[test]
    fn the_ideal_sensor_is_the_ideal_count_and_conversions() {
        let calibration = Calibration::new(1500, Direction::Clockwise);
        let mut sensor = HallSensor::ideal();
        for k in -300..300 {
            let angle_rad = f64::from(k) * 0.0037;
            let counts = calibration.counts_for_angle(angle_rad);
            assert_eq!(sensor.counts(calibration, angle_rad), counts);
            assert_eq!(
                sensor.conversions(calibration, angle_rad),
                conversions_for_counts(counts)
            );
        }
    }

    #[test]
    fn out_of_range_errors_are_refused() {
        let with = |noise_counts, offset_counts, gain_error| {
            HallSensor::new(
                HallErrors {
                    noise_counts,
                    offset_counts,
                    gain_error,
                },
                1,
                0,
            )
            .err()
        };
        assert_eq!(with(-0.1, 0.0, 0.0), Some(HallSensorError::Noise(-0.1)));
        assert!(matches!(
            with(f64::NAN, 0.0, 0.0),
            Some(HallSensorError::Noise(_))
        ));
        assert!(matches!(
            with(0.0, f64::INFINITY, 0.0),
            Some(HallSensorError::Offset(_))
        ));
        assert_eq!(with(0.0, 0.0, -1.0), Some(HallSensorError::Gain(-1.0)));
        assert_eq!(with(2.0, -3.0, -0.5), None);
    }

    /// A noisy conversion on a rail is the firmware's ADC fault, as on the robot.
    #[test]
    fn noise_near_a_rail_reaches_it_and_is_an_adc_fault() {
        let calibration = Calibration::new(0, Direction::CounterClockwise);
        let errors = HallErrors {
            noise_counts: 2.0,
            ..HallErrors::IDEAL
        };
        let mut sensor = HallSensor::new(errors, 3, 0).unwrap_or_default();
        // Count 8: conversions of 0 and 1, so noise puts some of them on the 0 rail.
        let angle_rad = 8.0 * RAD_PER_COUNT;
        let faults = (0..100)
            .filter(|_| adc_fault(&sensor.conversions(calibration, angle_rad)))
            .count();
        assert!(faults > 90, "{faults}");
    }
}
