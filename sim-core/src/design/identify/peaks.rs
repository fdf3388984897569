//! The peaks of the ring-down: one per period at the times the fit predicts, each height
//! measured by a local least-squares fit of the damped-cosine shape to the samples within half a
//! period either side (so that coarse sampling does not bias it).

use std::f64::consts::PI;

use super::fit::DampedSineFit;

/// Peak times and heights above the fitted offset, one per period at the times the fit
/// predicts, each measured from the samples within half a period either side by a local
/// least-squares fit of the damped-cosine shape. Stops at the first peak below `min_fraction`
/// of the first one or below `min_snr` times its own noise level, or with fewer than 3
/// samples in its window (such a window at the record's start is skipped).
pub(super) fn measure_peaks(
    x: &[f64],
    fs_hz: f64,
    fit: &DampedSineFit,
    min_fraction: f64,
    min_snr: f64,
) -> (Vec<f64>, Vec<f64>) {
    let (sigma, omega) = (fit.sigma_per_s, fit.omega_rad_s);
    let period_s = 2.0 * PI / omega;
    let psi = fit.sin_amplitude_rad.atan2(fit.cos_amplitude_rad);
    let lag = (sigma / omega).atan();
    let duration_s = (x.len() - 1) as f64 / fs_hz;
    // Maxima of exp(-sigma t) cos(w t - psi) sit at w t - psi = -atan(sigma / w) + 2 pi m.
    let t0 = (psi - lag) / omega;
    let m0 = (-t0 / period_s).ceil();
    let mut times = Vec::new();
    let mut heights = Vec::new();
    let mut m = m0;
    loop {
        let tm = t0 + m * period_s;
        if tm > duration_s {
            break;
        }
        // Half a period either side (half-open, so neighbouring windows share no sample), cut
        // to the record: the local model is the damped-cosine shape, so no symmetry is needed.
        let first = ((tm - period_s / 2.0) * fs_hz).ceil().max(0.0) as usize;
        let end = (((tm + period_s / 2.0) * fs_hz).ceil().max(0.0) as usize).min(x.len());
        let measured = if end >= first + 3 {
            local_peak_height(x, fs_hz, first, end - 1, tm, fit)
        } else {
            None
        };
        let Some(h) = measured else {
            if heights.is_empty() {
                m += 1.0;
                continue;
            }
            break;
        };
        // Standard error of a height measured from `count` samples with the fit's residual.
        let count = end.saturating_sub(first) as f64;
        let height_noise = fit.rms_residual_rad * (2.0 / count).sqrt();
        if h.is_nan()
            || h <= 0.0
            || h < min_snr * height_noise
            || heights
                .first()
                .is_some_and(|&h0: &f64| h < min_fraction * h0)
        {
            break;
        }
        times.push(tm);
        heights.push(h);
        m += 1.0;
    }
    (times, heights)
}

/// Height of the local damped-cosine model `exp(-sigma u)(p cos w u + q sin w u)`, `u = t - tm`,
/// fitted to samples `first..=last` (offset removed), at its maximum.
fn local_peak_height(
    x: &[f64],
    fs_hz: f64,
    first: usize,
    last: usize,
    tm: f64,
    fit: &DampedSineFit,
) -> Option<f64> {
    if last < first + 1 {
        return None;
    }
    let (sigma, omega) = (fit.sigma_per_s, fit.omega_rad_s);
    let (mut scc, mut scs, mut sss, mut sxc, mut sxs) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (i, &v) in x.iter().enumerate().take(last + 1).skip(first) {
        let u = i as f64 / fs_hz - tm;
        let e = (-sigma * u).exp();
        let (s, c) = (omega * u).sin_cos();
        let (bc, bs) = (e * c, e * s);
        let y = v - fit.offset_rad;
        scc += bc * bc;
        scs += bc * bs;
        sss += bs * bs;
        sxc += y * bc;
        sxs += y * bs;
    }
    let det = scc * sss - scs * scs;
    if det.is_nan() || det.abs() <= 1e-12 * scc * sss {
        return None;
    }
    let p = (sxc * sss - sxs * scs) / det;
    let q = (sxs * scc - sxc * scs) / det;
    let amp = p.hypot(q);
    let phase = q.atan2(p);
    // Maximum at w u - phase = -atan(sigma / w); take the one nearest u = 0.
    let lag = (sigma / omega).atan();
    let mut u_star = (phase - lag) / omega;
    let period_s = 2.0 * PI / omega;
    u_star -= (u_star / period_s).round() * period_s;
    Some(amp * (-sigma * u_star).exp() * lag.cos())
}
