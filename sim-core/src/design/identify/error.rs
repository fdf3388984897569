//! The errors of stiffness identification.

/// Errors from stiffness identification.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IdentifyError {
    /// Fewer samples than [`MIN_SAMPLES`](super::MIN_SAMPLES).
    #[error("angle_rad has {samples} samples; at least {minimum} are needed")]
    TooShort {
        /// Samples given.
        samples: usize,
        /// Samples needed.
        minimum: usize,
    },
    /// A sample is NaN or infinite.
    #[error("angle_rad[{index}] = {value} is not finite")]
    NonFiniteSample {
        /// Index of the sample.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// A scalar argument or option is out of its domain.
    #[error("{field} = {value} is out of range ({expected})")]
    InvalidArgument {
        /// Argument or option name (`"sample_rate_hz"`, `"inertia_kg_m2"`, ...).
        field: &'static str,
        /// The offending value.
        value: f64,
        /// The domain, in words.
        expected: &'static str,
    },
    /// The signal does not vary (peak-to-peak at rounding level).
    #[error("angle_rad is constant (peak-to-peak {peak_to_peak_rad} rad)")]
    ConstantSignal {
        /// Peak-to-peak of the record, rad.
        peak_to_peak_rad: f64,
    },
    /// No oscillation found: the spectrum has no interior peak, the record holds fewer than
    /// 1.5 periods of it, or a damped sinusoid explains too little of the signal.
    #[error("no oscillation found: {reason}")]
    NoOscillation {
        /// What failed.
        reason: &'static str,
        /// The frequency involved (spectrum peak or fitted), Hz; NaN when none.
        frequency_hz: f64,
    },
    /// Fewer than two usable peaks for the logarithmic decrement.
    #[error("found {found} usable peak(s); the logarithmic decrement needs at least {required}")]
    TooFewPeaks {
        /// Peaks found above the threshold.
        found: usize,
        /// Peaks needed (2).
        required: usize,
    },
    /// A peak value handed to [`mean_log_decrement`](super::mean_log_decrement) is not finite and positive.
    #[error("peaks[{index}] = {value} is not finite and positive")]
    InvalidPeak {
        /// Index of the peak.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// The damping ratio is not below 1 (not underdamped).
    #[error("damping ratio {damping_ratio} is not in (-1, 1)")]
    NotUnderdamped {
        /// The estimated damping ratio.
        damping_ratio: f64,
    },
    /// The least-squares fit produced no finite result.
    #[error(
        "damped-sinusoid fit failed after {iterations} model evaluations (rms residual {rms_residual_rad} rad)"
    )]
    FitFailed {
        /// Model evaluations of the Levenberg-Marquardt search (0 when it did not start).
        iterations: usize,
        /// Root-mean-square residual of the last iterate, rad (NaN when there is none).
        rms_residual_rad: f64,
    },
    /// [`wire_constant`](super::wire_constant) was given no rows.
    #[error("no rows to average")]
    NoRows,
    /// A row of [`wire_constant`](super::wire_constant) has a bad radius or stiffness.
    #[error("row {index}: {field} = {value} is not finite and positive")]
    InvalidRow {
        /// Row index.
        index: usize,
        /// `"radius_m"` or `"wire_stiffness_n_m_per_rad"`.
        field: &'static str,
        /// The offending value.
        value: f64,
    },
}
