//! Joint stiffness from a free-oscillation recording (docs/model.md section 9; thesis 6.2).
//!
//! A joint with inertia `J` about its axis, released from a deflection, rings down as an
//! underdamped oscillator `theta(t) = c + A exp(-zeta w_n t) cos(w_d t - psi)`. From the
//! uniformly sampled angle this module estimates
//!
//! 1. the damped frequency `f_d`: a zero-padded FFT of the mean-removed record gives the
//!    spectrum peak, refined to the maximum of the DTFT (golden-section search within one
//!    padded bin). No taper is applied: the ring-down's own decay is its window, and a window
//!    centred on the record (Hann) would suppress its start, where a strongly damped record
//!    has its energy. That peak is what the thesis uses, but for strong damping and few periods
//!    it is biased (the peak of a decaying sinusoid's spectrum is broadened by `zeta w_n` and
//!    pulled by the negative-frequency image and by truncation). So it only seeds a
//!    least-squares fit of `c + exp(-sigma t)(a cos w t + b sin w t)` to the whole record,
//!    which is unbiased for this model (a noiseless record of a few periods gives `f_n` to
//!    ~1e-8) and with noise is limited only by the information in the record. The fit is
//!    separable: variable projection ([`varpro`]'s Levenberg-Marquardt on `(sigma, w)`, the
//!    linear `(a, b, c)` solved for at each step), started at the spectrum peak and the best
//!    of a coarse scan of damping ratios. It replaced a hand-written Levenberg-Marquardt fit of
//!    all five parameters with the same accuracy at about 1.2 times its run time
//!    (`examples/identify_fit_bench.rs`, BENCHMARKS.md).
//!    `f_d = w / 2 pi` from the fit is the default
//!    ([`FrequencySource`]);
//! 2. the damping ratio from the logarithmic decrement averaged over all pairs of peaks
//!    (thesis 6.2.0.13-15; the thesis's average is over every pair `i < j`, not only consecutive
//!    ones). Peaks are located one per period at the times the fit predicts and their heights
//!    are measured from the samples within half a period either side of each (a local least-squares
//!    fit of the damped-cosine shape, so that coarse sampling does not bias them); peaks below
//!    [`IdentifyOptions::min_peak_fraction`] of the first one, or below
//!    [`IdentifyOptions::min_peak_snr`] times their own noise level, are dropped. The fit's
//!    own `sigma / sqrt(sigma^2 + w^2)` is reported too and can be chosen instead
//!    ([`DampingSource`]);
//! 3. `w_n = w_d / sqrt(1 - zeta^2)`, `k_eq = J w_n^2`, `k_wire = k_eq - k_cable`.
//!
//! [`wire_constant`] then gives `C` in `k_wire = C r^4` as the mean of `k_i / r_i^4`
//! (thesis 6.2.0.33).
//!
//! The record should start at or after release (the thesis trimmed each trial to start at its
//! global extremum); a constant offset (the rest angle) is estimated and removed.
//!
//! # Files
//! - `spectrum.rs`: the spectrum peak that seeds the fit;
//! - `fit.rs`: the ring-down model and its variable-projection fit;
//! - `peaks.rs`: the peaks one period apart and their heights;
//! - `physics.rs`: the oscillator's formulas (logarithmic decrement, damping ratio, natural
//!   frequency, stiffness, the wire constant);
//! - `options.rs`: [`IdentifyOptions`] and the answer, [`Identification`];
//! - `error.rs`: [`IdentifyError`];
//! - this file: [`identify_stiffness`], which runs them in order, and the checks of its input.

use std::f64::consts::PI;

mod error;
mod fit;
#[doc(hidden)]
pub mod fit_bench;
mod options;
mod peaks;
mod physics;
mod spectrum;
#[cfg(test)]
mod tests;

pub use crate::design::nitinol::CABLE_STIFFNESS_N_M_PER_RAD;
pub use error::IdentifyError;
pub use options::{DampingSource, FrequencySource, Identification, IdentifyOptions};
pub use physics::{
    SEGMENT_INERTIA_KG_M2, damping_ratio_from_log_decrement, equivalent_stiffness_n_m_per_rad,
    mean_log_decrement, natural_frequency_hz, wire_constant,
};

use fit::{cost_of, fit_damped_sine, scan_seed};
use peaks::measure_peaks;
use spectrum::spectrum_peak_hz;

/// Fewest samples accepted.
pub const MIN_SAMPLES: usize = 16;

/// Identifies joint stiffness from a free oscillation sampled at `sample_rate_hz`, for a body
/// of inertia `inertia_kg_m2` about the joint. See the module docs for the method.
///
/// # Errors
/// [`IdentifyError`] for too few samples, a non-finite sample, a bad rate, inertia or
/// option, a constant signal, no oscillation, fewer than two peaks (with
/// [`DampingSource::LogDecrement`]), or a damping ratio not in (-1, 1).
pub fn identify_stiffness(
    angle_rad: &[f64],
    sample_rate_hz: f64,
    inertia_kg_m2: f64,
    options: &IdentifyOptions,
) -> Result<Identification, IdentifyError> {
    validate(angle_rad, sample_rate_hz, inertia_kg_m2, options)?;
    let n = angle_rad.len();
    let duration_s = n as f64 / sample_rate_hz;
    let (lo, hi) = angle_rad
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    let scale = lo.abs().max(hi.abs());
    if hi - lo <= 1e-12 * scale || hi == lo {
        return Err(IdentifyError::ConstantSignal {
            peak_to_peak_rad: hi - lo,
        });
    }

    let spectrum_hz = spectrum_peak_hz(angle_rad, sample_rate_hz)?;
    if spectrum_hz * duration_s < 1.5 {
        return Err(IdentifyError::NoOscillation {
            reason: "record holds fewer than 1.5 periods of the spectrum peak",
            frequency_hz: spectrum_hz,
        });
    }
    let fit = fit_damped_sine(angle_rad, sample_rate_hz, 2.0 * PI * spectrum_hz)?;
    let fit_hz = fit.omega_rad_s / (2.0 * PI);
    if !(fit_hz > 0.0 && fit_hz < 0.5 * sample_rate_hz && fit_hz * duration_s >= 1.5) {
        return Err(IdentifyError::NoOscillation {
            reason: "fitted frequency outside (1.5 / duration, Nyquist)",
            frequency_hz: fit_hz,
        });
    }
    let signal_rms = rms_about_mean(angle_rad);
    if fit.rms_residual_rad > 0.5 * signal_rms {
        return Err(IdentifyError::NoOscillation {
            reason: "a damped sinusoid explains less than 75 % of the signal variance",
            frequency_hz: fit_hz,
        });
    }
    let zeta_fit = fit.sigma_per_s / fit.sigma_per_s.hypot(fit.omega_rad_s);

    let (peak_times_s, peak_heights_rad) = measure_peaks(
        angle_rad,
        sample_rate_hz,
        &fit,
        options.min_peak_fraction,
        options.min_peak_snr,
    );
    let (log_decrement, zeta_log) = if peak_heights_rad.len() >= 2 {
        let delta = mean_log_decrement(&peak_heights_rad)?;
        (delta, damping_ratio_from_log_decrement(delta))
    } else {
        (f64::NAN, f64::NAN)
    };
    let damping_ratio = match options.damping {
        DampingSource::LogDecrement => {
            if peak_heights_rad.len() < 2 {
                return Err(IdentifyError::TooFewPeaks {
                    found: peak_heights_rad.len(),
                    required: 2,
                });
            }
            zeta_log
        }
        DampingSource::DampedSineFit => zeta_fit,
    };
    let damped_frequency_hz = match options.frequency {
        FrequencySource::DampedSineFit => fit_hz,
        FrequencySource::SpectrumPeak => spectrum_hz,
    };
    let natural_frequency_hz = natural_frequency_hz(damped_frequency_hz, damping_ratio)?;
    let k_eq = equivalent_stiffness_n_m_per_rad(natural_frequency_hz, inertia_kg_m2)?;
    Ok(Identification {
        spectrum_peak_frequency_hz: spectrum_hz,
        fit_damped_frequency_hz: fit_hz,
        damped_frequency_hz,
        peak_heights_rad,
        peak_times_s,
        log_decrement,
        damping_ratio_log_decrement: zeta_log,
        damping_ratio_fit: zeta_fit,
        damping_ratio,
        natural_frequency_hz,
        equivalent_stiffness_n_m_per_rad: k_eq,
        wire_stiffness_n_m_per_rad: k_eq - options.cable_stiffness_n_m_per_rad,
        offset_rad: fit.offset_rad,
        fit_rms_residual_rad: fit.rms_residual_rad,
    })
}

fn positive(field: &'static str, value: f64) -> Result<(), IdentifyError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(IdentifyError::InvalidArgument {
            field,
            value,
            expected: "finite and positive",
        })
    }
}

fn validate(
    angle_rad: &[f64],
    sample_rate_hz: f64,
    inertia_kg_m2: f64,
    options: &IdentifyOptions,
) -> Result<(), IdentifyError> {
    if angle_rad.len() < MIN_SAMPLES {
        return Err(IdentifyError::TooShort {
            samples: angle_rad.len(),
            minimum: MIN_SAMPLES,
        });
    }
    if let Some((index, &value)) = angle_rad.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(IdentifyError::NonFiniteSample { index, value });
    }
    positive("sample_rate_hz", sample_rate_hz)?;
    positive("inertia_kg_m2", inertia_kg_m2)?;
    let k_cable = options.cable_stiffness_n_m_per_rad;
    if !(k_cable.is_finite() && k_cable >= 0.0) {
        return Err(IdentifyError::InvalidArgument {
            field: "cable_stiffness_n_m_per_rad",
            value: k_cable,
            expected: "finite and non-negative",
        });
    }
    let frac = options.min_peak_fraction;
    if !(frac.is_finite() && (0.0..1.0).contains(&frac)) {
        return Err(IdentifyError::InvalidArgument {
            field: "min_peak_fraction",
            value: frac,
            expected: "in [0, 1)",
        });
    }
    let snr = options.min_peak_snr;
    if !(snr.is_finite() && snr >= 0.0) {
        return Err(IdentifyError::InvalidArgument {
            field: "min_peak_snr",
            value: snr,
            expected: "finite and non-negative",
        });
    }
    Ok(())
}

fn rms_about_mean(x: &[f64]) -> f64 {
    let mean = x.iter().sum::<f64>() / x.len() as f64;
    (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / x.len() as f64).sqrt()
}
