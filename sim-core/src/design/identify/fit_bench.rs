//! Hooks for `examples/identify_fit_bench.rs`, which measures the ring-down fit against a
//! hand-written Levenberg-Marquardt baseline, and the ring-down records it shares with this
//! module's tests. Not part of the API.

use super::{IdentifyError, PI, fit_damped_sine, spectrum_peak_hz};

/// The coarse scan of damping ratios every fit starts from: the best
/// `[a, b, c, sigma, omega_start]` and its cost.
pub fn scan_seed(x: &[f64], fs_hz: f64, omega_start: f64) -> Option<([f64; 5], f64)> {
    super::scan_seed(x, fs_hz, omega_start)
}

/// The sum of squared residuals of `[a, b, c, sigma, omega]`.
pub fn cost_of(x: &[f64], fs_hz: f64, p: &[f64; 5]) -> f64 {
    super::cost_of(x, fs_hz, p)
}

/// xorshift64* with Box-Muller: deterministic noise without a rand dependency.
pub struct Noise(pub u64);
impl Noise {
    /// Uniform in (0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    /// Standard normal.
    pub fn gaussian(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
    }
}

/// A sampled ring-down `offset + A exp(-zeta w_n t) cos(w_d t + phase)` plus Gaussian
/// noise of `noise_rad` (seeded): the records of identify's tests and of
/// `examples/identify_fit_bench.rs`.
#[allow(clippy::too_many_arguments)]
pub fn ring_down(
    f_n_hz: f64,
    zeta: f64,
    fs_hz: f64,
    duration_s: f64,
    amplitude_rad: f64,
    phase_rad: f64,
    offset_rad: f64,
    noise_rad: f64,
    seed: u64,
) -> Vec<f64> {
    let wn = 2.0 * PI * f_n_hz;
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    let mut noise = Noise(seed.max(1));
    (0..(duration_s * fs_hz).round() as usize)
        .map(|i| {
            let t = i as f64 / fs_hz;
            offset_rad
                + amplitude_rad * (-zeta * wn * t).exp() * (wd * t + phase_rad).cos()
                + noise_rad * noise.gaussian()
        })
        .collect()
}

/// The fit's starting angular frequency, rad/s: the spectrum peak
/// [`super::identify_stiffness`] seeds it with.
///
/// # Errors
/// [`IdentifyError`] for fewer than [`super::MIN_SAMPLES`] samples, a non-finite
/// sample or rate, or no spectrum peak.
pub fn seed_rad_s(angle_rad: &[f64], sample_rate_hz: f64) -> Result<f64, IdentifyError> {
    super::validate(
        angle_rad,
        sample_rate_hz,
        1.0,
        &super::IdentifyOptions::default(),
    )?;
    Ok(2.0 * PI * spectrum_peak_hz(angle_rad, sample_rate_hz)?)
}

/// The ring-down fit of [`super::identify_stiffness`] from `omega_start_rad_s`: its
/// decay rate, 1/s, and angular frequency, rad/s.
///
/// # Errors
/// [`IdentifyError`] for fewer than [`super::MIN_SAMPLES`] samples, a non-finite
/// sample, rate or start, or a failed fit.
pub fn fit(
    angle_rad: &[f64],
    sample_rate_hz: f64,
    omega_start_rad_s: f64,
) -> Result<(f64, f64), IdentifyError> {
    super::validate(
        angle_rad,
        sample_rate_hz,
        1.0,
        &super::IdentifyOptions::default(),
    )?;
    super::positive("omega_start_rad_s", omega_start_rad_s)?;
    let fit = fit_damped_sine(angle_rad, sample_rate_hz, omega_start_rad_s)?;
    Ok((fit.sigma_per_s, fit.omega_rad_s))
}
