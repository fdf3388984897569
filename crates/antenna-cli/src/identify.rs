//! `antenna identify`: joint stiffness from a free-oscillation recording (thesis 6.2, docs/model.md
//! 9), as a summary or JSON. The method is sim-core's [`identify_stiffness`].

use std::fmt::Write as _;

use serde::{Deserialize, Serialize};
use sim_core::design::nitinol::{M_PER_INCH, WIRE_CONSTANT_N_M_PER_RAD_PER_M4};
use sim_core::{Identification, IdentifyError, IdentifyOptions, identify_stiffness};

/// What `antenna identify` reports. Symbols as in the seed: `f_d` damped frequency, `zeta`
/// damping ratio, `f_n` natural frequency, `k_eq = J (2 pi f_n)^2`, `k_wire = k_eq - k_cable`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IdentifyReport {
    /// Samples in the recording.
    pub samples: usize,
    /// Sample rate used, Hz.
    pub sample_rate_hz: f64,
    /// Inertia about the joint, kg m^2.
    pub inertia_kg_m2: f64,
    /// Damped frequency used, Hz.
    pub f_d_hz: f64,
    /// Damped frequency at the spectrum peak, Hz (the thesis's estimate).
    pub f_d_spectrum_peak_hz: f64,
    /// Damping ratio used.
    pub zeta: f64,
    /// Damping ratio from the logarithmic decrement (NaN, printed as null, with < 2 peaks).
    pub zeta_log_decrement: Option<f64>,
    /// Damping ratio of the damped-sinusoid fit.
    pub zeta_fit: f64,
    /// Peaks used for the logarithmic decrement.
    pub peaks: usize,
    /// Natural frequency `f_d / sqrt(1 - zeta^2)`, Hz.
    pub f_n_hz: f64,
    /// Equivalent joint stiffness `J (2 pi f_n)^2`, N m/rad.
    pub k_eq_n_m_per_rad: f64,
    /// Wire stiffness `k_eq - k_cable`, N m/rad.
    pub k_wire_n_m_per_rad: f64,
    /// Cable stiffness subtracted, N m/rad.
    pub k_cable_n_m_per_rad: f64,
    /// Rest angle (the fitted offset), rad.
    pub offset_rad: f64,
    /// Root-mean-square residual of the fit, rad.
    pub fit_rms_residual_rad: f64,
    /// Wire radius `(k_wire / C)^(1/4)`, m, when asked for (`None` also when `k_wire <= 0`).
    pub wire_radius_m: Option<f64>,
    /// Wire diameter, inches, alongside `wire_radius_m`.
    pub wire_diameter_in: Option<f64>,
    /// The constant `C` used for the radius, N m/rad per m^4, when asked for.
    pub wire_constant_n_m_per_rad_per_m4: Option<f64>,
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// Identifies the joint and builds the report. With `wire_constant` (`C` in
/// `k_wire = C r^4`) the report includes the wire radius that gives `k_wire`.
///
/// # Errors
/// [`IdentifyError`] from the identification (too few samples, no oscillation, ...).
pub fn identify_report(
    angle_rad: &[f64],
    sample_rate_hz: f64,
    inertia_kg_m2: f64,
    options: &IdentifyOptions,
    wire_constant: Option<f64>,
) -> Result<IdentifyReport, IdentifyError> {
    let id: Identification = identify_stiffness(angle_rad, sample_rate_hz, inertia_kg_m2, options)?;
    let radius = wire_constant.and_then(|c| {
        (id.wire_stiffness_n_m_per_rad > 0.0 && c > 0.0)
            .then(|| (id.wire_stiffness_n_m_per_rad / c).powf(0.25))
    });
    Ok(IdentifyReport {
        samples: angle_rad.len(),
        sample_rate_hz,
        inertia_kg_m2,
        f_d_hz: id.damped_frequency_hz,
        f_d_spectrum_peak_hz: id.spectrum_peak_frequency_hz,
        zeta: id.damping_ratio,
        zeta_log_decrement: finite(id.damping_ratio_log_decrement),
        zeta_fit: id.damping_ratio_fit,
        peaks: id.peak_heights_rad.len(),
        f_n_hz: id.natural_frequency_hz,
        k_eq_n_m_per_rad: id.equivalent_stiffness_n_m_per_rad,
        k_wire_n_m_per_rad: id.wire_stiffness_n_m_per_rad,
        k_cable_n_m_per_rad: options.cable_stiffness_n_m_per_rad,
        offset_rad: id.offset_rad,
        fit_rms_residual_rad: id.fit_rms_residual_rad,
        wire_radius_m: radius,
        wire_diameter_in: radius.map(|r| 2.0 * r / M_PER_INCH),
        wire_constant_n_m_per_rad_per_m4: wire_constant,
    })
}

/// The default `C` for `--wire-radius` (thesis 6.2.0.33).
pub const DEFAULT_WIRE_CONSTANT: f64 = WIRE_CONSTANT_N_M_PER_RAD_PER_M4;

/// A short human summary of the report.
pub fn identify_summary(r: &IdentifyReport) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{} samples at {} Hz ({:.3} s), J = {:e} kg m^2",
        r.samples,
        r.sample_rate_hz,
        r.samples as f64 / r.sample_rate_hz,
        r.inertia_kg_m2
    );
    let _ = writeln!(
        out,
        "f_d    = {:.6} Hz (spectrum peak {:.6} Hz)",
        r.f_d_hz, r.f_d_spectrum_peak_hz
    );
    let zeta_ld = r
        .zeta_log_decrement
        .map_or_else(|| "n/a".to_string(), |z| format!("{z:.6}"));
    let _ = writeln!(
        out,
        "zeta   = {:.6} (log decrement over {} peaks: {zeta_ld}; fit: {:.6})",
        r.zeta, r.peaks, r.zeta_fit
    );
    let _ = writeln!(out, "f_n    = {:.6} Hz", r.f_n_hz);
    let _ = writeln!(out, "k_eq   = {:.6e} N m/rad", r.k_eq_n_m_per_rad);
    let _ = writeln!(
        out,
        "k_wire = {:.6e} N m/rad (k_eq - cable {} N m/rad)",
        r.k_wire_n_m_per_rad, r.k_cable_n_m_per_rad
    );
    if let Some(c) = r.wire_constant_n_m_per_rad_per_m4 {
        match (r.wire_radius_m, r.wire_diameter_in) {
            (Some(radius), Some(d)) => {
                let _ = writeln!(
                    out,
                    "wire   r = {radius:.6e} m (diameter {d:.4} in) from k_wire = C r^4, C = {c:e}"
                );
            }
            _ => {
                let _ = writeln!(out, "wire   none: k_wire <= 0 (the cable alone is stiffer)");
            }
        }
    }
    out
}
