//! The oscillator's physics (thesis 6.2): the logarithmic decrement of a peak sequence and the
//! damping ratio it gives, the natural frequency from the damped one, the rotational stiffness
//! from the natural frequency and the inertia, and the wire constant `C` of `k_wire = C r^4`.

use std::f64::consts::PI;

use super::{IdentifyError, positive};

/// Inertia of one robot segment about its joint (thesis Table 6.1), kg m^2.
pub const SEGMENT_INERTIA_KG_M2: f64 = 3.25e-6;
/// Mean logarithmic decrement over all peak pairs `i < j` (thesis 6.2.0.15):
/// `sum_{i<j} ln(p_i / p_j) / (j - i)` divided by the number of pairs `n(n-1)/2`.
///
/// # Errors
/// [`IdentifyError::TooFewPeaks`] for fewer than 2 peaks, [`IdentifyError::InvalidPeak`] for a
/// non-finite or non-positive one.
pub fn mean_log_decrement(peaks: &[f64]) -> Result<f64, IdentifyError> {
    if peaks.len() < 2 {
        return Err(IdentifyError::TooFewPeaks {
            found: peaks.len(),
            required: 2,
        });
    }
    for (index, &value) in peaks.iter().enumerate() {
        if !(value.is_finite() && value > 0.0) {
            return Err(IdentifyError::InvalidPeak { index, value });
        }
    }
    let n = peaks.len();
    let mut sum = 0.0;
    for i in 0..n - 1 {
        for j in i + 1..n {
            sum += (peaks[i] / peaks[j]).ln() / (j - i) as f64;
        }
    }
    Ok(sum / (n * (n - 1) / 2) as f64)
}

/// Damping ratio from a logarithmic decrement (thesis 6.2.0.14):
/// `zeta = (D / 2 pi) / sqrt(1 + (D / 2 pi)^2)`.
pub fn damping_ratio_from_log_decrement(log_decrement: f64) -> f64 {
    let q = log_decrement / (2.0 * PI);
    q / (1.0 + q * q).sqrt()
}

/// Undamped natural frequency `f_d / sqrt(1 - zeta^2)` (thesis 6.2.0.11), Hz.
///
/// # Errors
/// [`IdentifyError::InvalidArgument`] for a non-finite or non-positive `f_d`,
/// [`IdentifyError::NotUnderdamped`] unless `-1 < zeta < 1`.
pub fn natural_frequency_hz(
    damped_frequency_hz: f64,
    damping_ratio: f64,
) -> Result<f64, IdentifyError> {
    positive("damped_frequency_hz", damped_frequency_hz)?;
    if !(damping_ratio.is_finite() && damping_ratio.abs() < 1.0) {
        return Err(IdentifyError::NotUnderdamped { damping_ratio });
    }
    Ok(damped_frequency_hz / (1.0 - damping_ratio * damping_ratio).sqrt())
}

/// Rotational stiffness `J (2 pi f_n)^2` (thesis 6.2.0.10), N m/rad.
///
/// # Errors
/// [`IdentifyError::InvalidArgument`] for a non-finite or non-positive argument.
pub fn equivalent_stiffness_n_m_per_rad(
    natural_frequency_hz: f64,
    inertia_kg_m2: f64,
) -> Result<f64, IdentifyError> {
    positive("natural_frequency_hz", natural_frequency_hz)?;
    positive("inertia_kg_m2", inertia_kg_m2)?;
    let w = 2.0 * PI * natural_frequency_hz;
    Ok(inertia_kg_m2 * w * w)
}

/// `C` in `k_wire = C r^4` as the mean of `k_i / r_i^4` over rows
/// `(radius_m, wire_stiffness_n_m_per_rad)` (thesis 6.2.0.33), N m/rad per m^4.
///
/// # Errors
/// [`IdentifyError::NoRows`] for no rows, [`IdentifyError::InvalidRow`] for a non-finite or
/// non-positive radius or stiffness.
pub fn wire_constant(rows: &[(f64, f64)]) -> Result<f64, IdentifyError> {
    if rows.is_empty() {
        return Err(IdentifyError::NoRows);
    }
    let mut sum = 0.0;
    for (index, &(radius_m, k)) in rows.iter().enumerate() {
        for (field, value) in [("radius_m", radius_m), ("wire_stiffness_n_m_per_rad", k)] {
            if !(value.is_finite() && value > 0.0) {
                return Err(IdentifyError::InvalidRow {
                    index,
                    field,
                    value,
                });
            }
        }
        sum += k / radius_m.powi(4);
    }
    Ok(sum / rows.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_log_decrement_matches_seed_formula() {
        // Exact exponential decay: every pair gives the same per-period decrement.
        let peaks: Vec<f64> = (0..6).map(|i| (-0.3 * i as f64).exp()).collect();
        assert!((mean_log_decrement(&peaks).unwrap() - 0.3).abs() < 1e-14);
        // Three peaks: pairs (1,2) ln 2, (1,3) ln(4)/2 = ln 2... use uneven ones.
        let p = [1.0, 0.5, 0.4];
        let want = ((2.0f64).ln() + (2.5f64).ln() / 2.0 + (1.25f64).ln()) / 3.0;
        assert!((mean_log_decrement(&p).unwrap() - want).abs() < 1e-15);
        // 6.2.0.14 inverts delta = 2 pi zeta / sqrt(1 - zeta^2).
        let zeta: f64 = 0.137;
        let delta = 2.0 * PI * zeta / (1.0 - zeta * zeta).sqrt();
        assert!((damping_ratio_from_log_decrement(delta) - zeta).abs() < 1e-15);
    }
}
