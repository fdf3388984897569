//! Sensors as they are (thesis 2.3.1, 4.2.2): what departs from the ideal reading of the joint
//! angles and the touch switches. [`SensorSettings`] describes it (a scene's `[sensors]`
//! table, the daemon's simulated rig); [`Sensors`] applies it sample by sample, seeded, so
//! that one seed gives one run.
//!
//! # The model
//! - **Joint angles** (`j >= 1`): the reported angle is
//!   `round((theta_j (1 + g_j) + (o_j + e) q) / q) q`, `q` = [`RAD_PER_COUNT`]: `g_j` the
//!   joint's gain error (a fraction), `o_j` its calibration offset in counts, and `e` a fresh
//!   Gaussian draw with standard deviation `angle_noise_counts` for every sample. The base
//!   angle `theta_0` is set by the platform and is copied as it is.
//!   On the robot, the noise is that of one oversampled reading: the firmware sums 16 ten-bit
//!   conversions and shifts right by 2, so a conversion noise of `s` ten-bit counts gives
//!   `s` twelve-bit counts (`sqrt(16) s / 4`); the daemon's simulated rig adds it to each
//!   conversion and lets the firmware's own oversampling do the rest.
//! - **Calibration**: `o_j` and `g_j` are given per joint, or drawn once per joint from a
//!   Gaussian of the given spread with the settings' seed ([`CalibrationError`]; a gain
//!   error's Gaussian is truncated to values above `-1`, where a reading still grows with
//!   the angle).
//! - **Touch switches**: a switch closes when the force at its contact is at least
//!   `touch_threshold_n` (zero: every contact closes its switch, the ideal), and a bit changes
//!   only after `touch_debounce_samples` consecutive raw reads agree (one: no debouncing; the
//!   segment firmware uses three, [`FIRMWARE_DEBOUNCE_SAMPLES`]).
//! - **Sampling**: with `sample_rate_hz`, the robot reads its sensors at `t = k / rate` (a
//!   sweep step is sampled when it is the first at or after the next sample time); without it,
//!   at every step. Moving faster at one rate leaves fewer points per metre of wall (thesis
//!   Figure 4.16).
//!
//! With [`SensorSettings::IDEAL`] every function here returns exactly what the ideal functions
//! of [`crate::sensing::mapping`] return ([`crate::sensed_theta_rad`], [`crate::touch_bits_from_contacts`]).
//!
//! ```
//! use sim_core::{SensorSettings, Sensors, sensed_theta_rad};
//! let theta = [0.3, 0.01, -0.2];
//! // Ideal sensors report the 12-bit angles.
//! let mut ideal = Sensors::new(&SensorSettings::IDEAL, 2)?;
//! let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
//! ideal.sense_angles_rad(&theta, &mut a)?;
//! sensed_theta_rad(&theta, &mut b)?;
//! assert_eq!(a, b);
//! // Noisy ones differ, reproducibly for a seed.
//! let noisy = SensorSettings { angle_noise_counts: 2.0, seed: 7, ..SensorSettings::IDEAL };
//! let mut s = Sensors::new(&noisy, 2)?;
//! s.sense_angles_rad(&theta, &mut a)?;
//! assert_eq!(a[0], theta[0]);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use antenna_protocol::RAD_PER_COUNT;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::contact::Contact;
use crate::sensing::mapping::{
    MappingError, SWITCHES_PER_SEGMENT, quantize_angle_rad, switch_for_fraction,
};

/// The segment firmware's touch debouncing: a bit changes after three agreeing reads.
pub const FIRMWARE_DEBOUNCE_SAMPLES: u32 = 3;

/// A per-joint calibration error: given per joint, or drawn per joint from a spread.
#[derive(Clone, Debug, PartialEq)]
pub enum CalibrationError {
    /// Drawn once per joint from a zero-mean Gaussian with this standard deviation (`>= 0`;
    /// zero: no error).
    Spread(f64),
    /// One value per flagellar joint `1..=n`.
    PerJoint(Vec<f64>),
}

impl CalibrationError {
    /// No error.
    pub const NONE: CalibrationError = CalibrationError::Spread(0.0);

    fn is_none(&self) -> bool {
        match self {
            CalibrationError::Spread(sd) => *sd == 0.0,
            CalibrationError::PerJoint(values) => values.iter().all(|&v| v == 0.0),
        }
    }
}

/// How the robot's sensors depart from the ideal (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct SensorSettings {
    /// Standard deviation of the Hall angle noise of one sample, 12-bit counts (`>= 0`).
    pub angle_noise_counts: f64,
    /// Calibration offset per joint, 12-bit counts.
    pub offset_counts: CalibrationError,
    /// Gain error per joint, a fraction (`0.01`: the angle reads 1 % large).
    pub gain_error: CalibrationError,
    /// Force that closes a touch switch, newtons (`>= 0`; zero: any contact).
    pub touch_threshold_n: f64,
    /// Consecutive agreeing raw reads before a touch bit changes (`>= 1`; one: none).
    pub touch_debounce_samples: u32,
    /// The rate at which the robot samples its sensors, hertz (`> 0`); `None`: every step.
    pub sample_rate_hz: Option<f64>,
    /// The seed of the noise and of drawn calibration errors.
    pub seed: u64,
    /// Whether a touch on the switch under a hair's pivot is estimated at the hair's open
    /// tip instead of on the link ([`crate::TouchLayout::hair_tips`]; `false`: on the link).
    pub hair_tip_points: bool,
}

impl Default for SensorSettings {
    fn default() -> Self {
        Self::IDEAL
    }
}

/// Which setting is out of range.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SensorField {
    /// `angle_noise_counts`.
    AngleNoise,
    /// `offset_counts`.
    Offset,
    /// `gain_error`.
    Gain,
    /// `touch_threshold_n`.
    TouchThreshold,
    /// `touch_debounce_samples`.
    TouchDebounce,
    /// `sample_rate_hz`.
    SampleRate,
}

impl SensorField {
    /// The setting's key, as a scene file names it.
    pub fn key(self) -> &'static str {
        match self {
            Self::AngleNoise => "angle_noise_counts",
            Self::Offset => "offset_counts",
            Self::Gain => "gain_error",
            Self::TouchThreshold => "touch_threshold_n",
            Self::TouchDebounce => "touch_debounce_samples",
            Self::SampleRate => "sample_rate_hz",
        }
    }
}

impl core::fmt::Display for SensorField {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.key())
    }
}

/// Sensor settings that do not fit.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SensorError {
    /// A value out of its range (the message says which).
    #[error("{field} = {value}: {expected}")]
    OutOfRange {
        /// The setting.
        field: SensorField,
        /// Its value (for a per-joint list, the offending entry).
        value: f64,
        /// What it must be.
        expected: &'static str,
    },
    /// A per-joint list of the wrong length.
    #[error("{field} has {actual} entries, one per joint 1..={expected} is needed")]
    WrongLength {
        /// The setting.
        field: SensorField,
        /// The number of flagellar joints `n`.
        expected: usize,
        /// The entries given.
        actual: usize,
    },
}

impl SensorSettings {
    /// Ideal sensors: no noise, no calibration error, any contact closes its switch at once,
    /// a sample at every step.
    pub const IDEAL: SensorSettings = SensorSettings {
        angle_noise_counts: 0.0,
        offset_counts: CalibrationError::NONE,
        gain_error: CalibrationError::NONE,
        touch_threshold_n: 0.0,
        touch_debounce_samples: 1,
        sample_rate_hz: None,
        seed: 0,
        hair_tip_points: false,
    };

    /// Whether every setting is at its ideal value (the seed aside; hair touches placed on
    /// the link, as the ideal estimate always did).
    pub fn is_ideal(&self) -> bool {
        self.angle_noise_counts == 0.0
            && self.offset_counts.is_none()
            && self.gain_error.is_none()
            && self.touch_threshold_n == 0.0
            && self.touch_debounce_samples == 1
            && self.sample_rate_hz.is_none()
            && !self.hair_tip_points
    }

    /// Checks every setting for a chain of `n` flagellar joints.
    ///
    /// # Errors
    /// [`SensorError::OutOfRange`] for a negative or non-finite noise, spread or threshold, a
    /// non-finite per-joint value, a gain error at or below `-1` (the reading would not grow
    /// with the angle), a debounce of zero, or a sample rate that is not positive and finite;
    /// [`SensorError::WrongLength`] for a per-joint list without `n` entries.
    pub fn validate(&self, n: usize) -> Result<(), SensorError> {
        let out = |field, value, expected| {
            Err(SensorError::OutOfRange {
                field,
                value,
                expected,
            })
        };
        let non_negative = |field, value: f64| {
            if value.is_finite() && value >= 0.0 {
                Ok(())
            } else {
                out(field, value, "must be finite and at least 0")
            }
        };
        non_negative(SensorField::AngleNoise, self.angle_noise_counts)?;
        non_negative(SensorField::TouchThreshold, self.touch_threshold_n)?;
        for (field, error) in [
            (SensorField::Offset, &self.offset_counts),
            (SensorField::Gain, &self.gain_error),
        ] {
            match error {
                CalibrationError::Spread(sd) => non_negative(field, *sd)?,
                CalibrationError::PerJoint(values) => {
                    if values.len() != n {
                        return Err(SensorError::WrongLength {
                            field,
                            expected: n,
                            actual: values.len(),
                        });
                    }
                    for &v in values {
                        if !v.is_finite() {
                            return out(field, v, "every entry must be finite");
                        }
                        if field == SensorField::Gain && v <= -1.0 {
                            return out(field, v, "every entry must be above -1");
                        }
                    }
                }
            }
        }
        if self.touch_debounce_samples == 0 {
            return out(SensorField::TouchDebounce, 0.0, "must be at least 1");
        }
        if let Some(rate) = self.sample_rate_hz
            && !(rate.is_finite() && rate > 0.0)
        {
            return out(SensorField::SampleRate, rate, "must be finite and above 0");
        }
        Ok(())
    }
}

/// Whether `contact` closes the touch switch under it for a switch that needs
/// `touch_threshold_n`: always at zero (the ideal switch), otherwise when the magnitude of the
/// wall's force there is at least the threshold.
pub fn closes_switch(contact: &Contact, touch_threshold_n: f64) -> bool {
    touch_threshold_n == 0.0 || contact.force_n().norm() >= touch_threshold_n
}

/// Sensors in use: the settings, the calibration drawn from them, the noise generator, the
/// debouncers' history and the sampling clock.
#[derive(Clone, Debug)]
pub struct Sensors {
    settings: SensorSettings,
    /// Per link `0..=n` (entry 0 unused, zero).
    offset_counts: Vec<f64>,
    /// Per link `0..=n` (entry 0 unused, zero).
    gain_error: Vec<f64>,
    noise: ChaCha8Rng,
    /// Per link: the debounced bits, and per switch the run of agreeing raw reads that
    /// differ from it.
    stable: Vec<u8>,
    runs: Vec<[u32; SWITCHES_PER_SEGMENT]>,
    raw: Vec<u8>,
    next_sample_s: f64,
    samples: u64,
}

impl Sensors {
    /// Sensors for a chain of `n` flagellar joints: checks `settings` and draws the
    /// calibration errors given as spreads (offsets first, then gains, joint by joint, from
    /// the seed).
    ///
    /// # Errors
    /// As [`SensorSettings::validate`].
    pub fn new(settings: &SensorSettings, n: usize) -> Result<Sensors, SensorError> {
        settings.validate(n)?;
        let mut calibration = ChaCha8Rng::seed_from_u64(settings.seed);
        // `above`: the draw is repeated until it exceeds this (a gain error at or below -1
        // would make a reading that does not grow with the angle); at least half of a
        // zero-mean Gaussian's draws pass, so this ends.
        let mut draw = |error: &CalibrationError, above: f64| -> Vec<f64> {
            let mut per_link = vec![0.0; n + 1];
            match error {
                CalibrationError::Spread(sd) if *sd > 0.0 => {
                    for v in &mut per_link[1..] {
                        *v = loop {
                            let z: f64 = StandardNormal.sample(&mut calibration);
                            if sd * z > above {
                                break sd * z;
                            }
                        };
                    }
                }
                CalibrationError::Spread(_) => {}
                CalibrationError::PerJoint(values) => per_link[1..].copy_from_slice(values),
            }
            per_link
        };
        let offset_counts = draw(&settings.offset_counts, f64::NEG_INFINITY);
        let gain_error = draw(&settings.gain_error, -1.0);
        // The noise has its own stream, so the calibration does not depend on the noise level.
        let noise = ChaCha8Rng::seed_from_u64(settings.seed ^ 0x9E37_79B9_7F4A_7C15);
        Ok(Sensors {
            settings: settings.clone(),
            offset_counts,
            gain_error,
            noise,
            stable: vec![0; n + 1],
            runs: vec![[0; SWITCHES_PER_SEGMENT]; n + 1],
            raw: vec![0; n + 1],
            next_sample_s: 0.0,
            samples: 0,
        })
    }

    /// The settings.
    pub fn settings(&self) -> &SensorSettings {
        &self.settings
    }

    /// Where the robot places the point of each touched switch ([`crate::estimate_contacts`]).
    pub fn touch_layout(&self) -> crate::TouchLayout {
        crate::TouchLayout {
            hair_tips: self.settings.hair_tip_points,
            ..crate::TouchLayout::default()
        }
    }

    /// The calibration offsets in use per link `0..=n` (entry 0 is zero), counts.
    pub fn offset_counts(&self) -> &[f64] {
        &self.offset_counts
    }

    /// The gain errors in use per link `0..=n` (entry 0 is zero).
    pub fn gain_error(&self) -> &[f64] {
        &self.gain_error
    }

    /// The samples taken so far ([`Self::is_sample_due`] answers that returned `true`).
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// Whether the robot samples at time `t_s` (non-decreasing from call to call): always
    /// without a sample rate; otherwise when `t_s` has reached the next sample time, which
    /// then moves on by whole periods past `t_s`.
    pub fn is_sample_due(&mut self, t_s: f64) -> bool {
        let due = match self.settings.sample_rate_hz {
            None => true,
            Some(rate) => {
                // A relative tolerance so that t = k dt reaches k / rate despite rounding.
                if t_s + 1e-9 * t_s.abs().max(1.0) >= self.next_sample_s {
                    let period_s = 1.0 / rate;
                    let periods = ((t_s - self.next_sample_s) / period_s).floor().max(0.0) + 1.0;
                    self.next_sample_s += periods * period_s;
                    true
                } else {
                    false
                }
            }
        };
        if due {
            self.samples += 1;
        }
        due
    }

    /// The reported joint angles for the true `theta_rad` (`n + 1` entries; see the module
    /// docs). Draws one noise value per joint when there is noise.
    ///
    /// # Errors
    /// [`MappingError::WrongLength`] if `theta_rad` or `out` has not `n + 1` entries.
    pub fn sense_angles_rad(
        &mut self,
        theta_rad: &[f64],
        out: &mut [f64],
    ) -> Result<(), MappingError> {
        let links = self.offset_counts.len();
        for (argument, actual) in [("theta_rad", theta_rad.len()), ("out", out.len())] {
            if actual != links {
                return Err(MappingError::WrongLength {
                    argument,
                    expected: links,
                    actual,
                });
            }
        }
        let sd = self.settings.angle_noise_counts;
        for (j, (o, &theta)) in out.iter_mut().zip(theta_rad).enumerate() {
            if j == 0 {
                *o = theta;
                continue;
            }
            let (g, offset) = (self.gain_error[j], self.offset_counts[j]);
            let e = if sd > 0.0 {
                let z: f64 = StandardNormal.sample(&mut self.noise);
                sd * z
            } else {
                0.0
            };
            // The ideal reading is the true angle itself, untouched (not even by `+ 0.0`).
            let reading = if g == 0.0 && offset == 0.0 && e == 0.0 {
                theta
            } else {
                theta * (1.0 + g) + (offset + e) * RAD_PER_COUNT
            };
            *o = quantize_angle_rad(reading);
        }
        Ok(())
    }

    /// The debounced touch bits for `contacts` (one entry per link `0..=n` in `out`): a
    /// contact whose force is at least the threshold closes the switch under it.
    ///
    /// # Errors
    /// [`MappingError::WrongLength`] if `out` has not `n + 1` entries;
    /// [`MappingError::LinkOutOfRange`] for a contact beyond them.
    pub fn sense_touch(
        &mut self,
        contacts: &[Contact],
        out: &mut [u8],
    ) -> Result<(), MappingError> {
        let links = self.stable.len();
        if out.len() != links {
            return Err(MappingError::WrongLength {
                argument: "out",
                expected: links,
                actual: out.len(),
            });
        }
        self.raw.fill(0);
        let threshold = self.settings.touch_threshold_n;
        for contact in contacts {
            let link = contact.feature.link();
            let bits = self
                .raw
                .get_mut(link)
                .ok_or(MappingError::LinkOutOfRange { link, n: links - 1 })?;
            if closes_switch(contact, threshold) {
                *bits |= 1 << switch_for_fraction(contact.s);
            }
        }
        let needed = self.settings.touch_debounce_samples;
        for (link, o) in out.iter_mut().enumerate() {
            let (raw, stable) = (self.raw[link], &mut self.stable[link]);
            for (k, run) in self.runs[link].iter_mut().enumerate() {
                let bit = 1u8 << k;
                if raw & bit == *stable & bit {
                    *run = 0;
                    continue;
                }
                *run += 1;
                if *run >= needed {
                    *stable ^= bit;
                    *run = 0;
                }
            }
            *o = *stable;
        }
        Ok(())
    }
}
