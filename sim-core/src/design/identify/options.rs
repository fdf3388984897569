//! What [`identify_stiffness`](super::identify_stiffness) is asked ([`IdentifyOptions`]: the
//! estimates it uses, the peaks it keeps) and what it answers ([`Identification`]).

use super::CABLE_STIFFNESS_N_M_PER_RAD;

/// Which damped-frequency estimate feeds `w_n`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FrequencySource {
    /// Least-squares fit of a damped sinusoid, seeded by the spectrum peak (default).
    #[default]
    DampedSineFit,
    /// The windowed spectrum peak alone (the thesis's method; biased for strong damping).
    SpectrumPeak,
}

/// Which damping-ratio estimate feeds `w_n`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DampingSource {
    /// Logarithmic decrement averaged over all peak pairs, thesis 6.2.0.13-15 (default).
    #[default]
    LogDecrement,
    /// The decay rate of the least-squares fit.
    DampedSineFit,
}

/// Options for [`identify_stiffness`](super::identify_stiffness).
#[derive(Debug, Clone, PartialEq)]
pub struct IdentifyOptions {
    /// Cable stiffness subtracted from `k_eq`, N m/rad (default 0.0016).
    pub cable_stiffness_n_m_per_rad: f64,
    /// Peaks below this fraction of the first peak are treated as noise (default 0.05).
    pub min_peak_fraction: f64,
    /// Peaks below this multiple of their own noise level (the fit's rms residual times
    /// `sqrt(2 / samples in the peak's window)`) are treated as noise (default 10).
    pub min_peak_snr: f64,
    /// Source of `f_d` (default: fit).
    pub frequency: FrequencySource,
    /// Source of `zeta` (default: logarithmic decrement).
    pub damping: DampingSource,
}

impl Default for IdentifyOptions {
    fn default() -> Self {
        Self {
            cable_stiffness_n_m_per_rad: CABLE_STIFFNESS_N_M_PER_RAD,
            min_peak_fraction: 0.05,
            min_peak_snr: 10.0,
            frequency: FrequencySource::default(),
            damping: DampingSource::default(),
        }
    }
}

/// The result of [`identify_stiffness`](super::identify_stiffness).
#[derive(Debug, Clone, PartialEq)]
pub struct Identification {
    /// Damped frequency at the windowed spectrum peak, Hz.
    pub spectrum_peak_frequency_hz: f64,
    /// Damped frequency of the least-squares fit, Hz.
    pub fit_damped_frequency_hz: f64,
    /// Damped frequency used (per [`IdentifyOptions::frequency`]), Hz.
    pub damped_frequency_hz: f64,
    /// Peak heights above the fitted offset, rad, in time order.
    pub peak_heights_rad: Vec<f64>,
    /// Peak times, s from the first sample.
    pub peak_times_s: Vec<f64>,
    /// Mean logarithmic decrement over all peak pairs (thesis 6.2.0.15); NaN with < 2 peaks.
    pub log_decrement: f64,
    /// Damping ratio from the logarithmic decrement (thesis 6.2.0.14); NaN with < 2 peaks.
    pub damping_ratio_log_decrement: f64,
    /// Damping ratio of the least-squares fit.
    pub damping_ratio_fit: f64,
    /// Damping ratio used (per [`IdentifyOptions::damping`]).
    pub damping_ratio: f64,
    /// Undamped natural frequency `f_d / sqrt(1 - zeta^2)`, Hz.
    pub natural_frequency_hz: f64,
    /// `J w_n^2`, N m/rad.
    pub equivalent_stiffness_n_m_per_rad: f64,
    /// `k_eq - k_cable`, N m/rad (negative when the joint is softer than the cable alone).
    pub wire_stiffness_n_m_per_rad: f64,
    /// Fitted rest angle (offset), rad.
    pub offset_rad: f64,
    /// Root-mean-square residual of the fit, rad.
    pub fit_rms_residual_rad: f64,
}
