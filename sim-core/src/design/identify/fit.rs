//! The ring-down model and its fit: `c + exp(-sigma t)(a cos w t + b sin w t)` by variable
//! projection ([`varpro`]'s Levenberg-Marquardt on `(sigma, w)`, the linear `(a, b, c)` solved
//! for at each step), started at the spectrum peak and the best of a coarse scan of damping
//! ratios.

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use varpro::prelude::SeparableNonlinearModel;
use varpro::problem::SeparableProblemBuilder;
use varpro::solvers::levmar::LevMarSolver;

use super::IdentifyError;

/// Least-squares damped sinusoid `c + exp(-sigma t)(a cos w t + b sin w t)`.
#[derive(Debug, Clone, Copy)]
pub(super) struct DampedSineFit {
    pub(super) cos_amplitude_rad: f64,
    pub(super) sin_amplitude_rad: f64,
    pub(super) offset_rad: f64,
    pub(super) sigma_per_s: f64,
    pub(super) omega_rad_s: f64,
    pub(super) rms_residual_rad: f64,
}

/// Linear least squares for (a, b, c) at fixed (sigma, omega); returns params and cost.
fn linear_fit(x: &[f64], fs_hz: f64, sigma: f64, omega: f64) -> Option<(Vector3<f64>, f64)> {
    let mut ata = Matrix3::zeros();
    let mut atb = Vector3::zeros();
    for (i, &v) in x.iter().enumerate() {
        let t = i as f64 / fs_hz;
        let e = (-sigma * t).exp();
        let (s, c) = (omega * t).sin_cos();
        let row = Vector3::new(e * c, e * s, 1.0);
        ata += row * row.transpose();
        atb += row * v;
    }
    let p = ata.cholesky()?.solve(&atb);
    let cost = cost_of(x, fs_hz, &[p[0], p[1], p[2], sigma, omega]);
    cost.is_finite().then_some((p, cost))
}

/// The coarse scan of damping ratios a fit starts from (linear least squares for a, b, c at
/// each): the best `[a, b, c, sigma, omega_start]` and its cost.
pub(super) fn scan_seed(x: &[f64], fs_hz: f64, omega_start: f64) -> Option<([f64; 5], f64)> {
    let mut best: Option<([f64; 5], f64)> = None;
    for zeta in [0.0, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5] {
        let sigma = zeta * omega_start;
        if let Some((p, cost)) = linear_fit(x, fs_hz, sigma, omega_start)
            && best.is_none_or(|(_, c)| cost < c)
        {
            best = Some(([p[0], p[1], p[2], sigma, omega_start], cost));
        }
    }
    best
}

/// The sum of squared residuals of `[a, b, c, sigma, omega]`.
pub(super) fn cost_of(x: &[f64], fs_hz: f64, p: &[f64; 5]) -> f64 {
    x.iter()
        .enumerate()
        .map(|(i, &v)| {
            let t = i as f64 / fs_hz;
            let (s, c) = (p[4] * t).sin_cos();
            let r = v - (p[2] + (-p[3] * t).exp() * (p[0] * c + p[1] * s));
            r * r
        })
        .sum()
}

/// The ring-down as a separable model for varpro: the basis `exp(-sigma t) cos w t`,
/// `exp(-sigma t) sin w t` and 1 at `t = i / fs`, nonlinear in `(sigma, w)`.
struct RingDownModel {
    t: DVector<f64>,
    params: DVector<f64>,
    basis: DMatrix<f64>,
}

impl RingDownModel {
    fn new(samples: usize, fs_hz: f64, sigma: f64, omega: f64) -> Self {
        let mut model = Self {
            t: DVector::from_fn(samples, |i, _| i as f64 / fs_hz),
            params: DVector::zeros(2),
            basis: DMatrix::from_element(samples, 3, 1.0),
        };
        model.update(sigma, omega);
        model
    }

    fn update(&mut self, sigma: f64, omega: f64) {
        self.params = DVector::from_column_slice(&[sigma, omega]);
        for (i, &t) in self.t.iter().enumerate() {
            let e = (-sigma * t).exp();
            let (s, c) = (omega * t).sin_cos();
            self.basis[(i, 0)] = e * c;
            self.basis[(i, 1)] = e * s;
        }
    }
}

/// varpro asked for a parameter the model does not have (a bug, not bad input).
const MODEL_MISUSE: IdentifyError = IdentifyError::FitFailed {
    iterations: 0,
    rms_residual_rad: f64::NAN,
};

impl SeparableNonlinearModel for RingDownModel {
    type ScalarType = f64;
    type Error = IdentifyError;

    fn parameter_count(&self) -> usize {
        2
    }

    fn base_function_count(&self) -> usize {
        3
    }

    fn output_len(&self) -> usize {
        self.t.len()
    }

    fn set_params(&mut self, parameters: DVector<f64>) -> Result<(), IdentifyError> {
        match *parameters.as_slice() {
            [sigma, omega] => {
                self.update(sigma, omega);
                Ok(())
            }
            _ => Err(MODEL_MISUSE),
        }
    }

    fn params(&self) -> DVector<f64> {
        self.params.clone()
    }

    fn eval(&self) -> Result<DMatrix<f64>, IdentifyError> {
        Ok(self.basis.clone())
    }

    fn eval_partial_deriv(&self, index: usize) -> Result<DMatrix<f64>, IdentifyError> {
        if index > 1 {
            return Err(MODEL_MISUSE);
        }
        // d/dsigma (e c, e s) = -t (e c, e s); d/dw (e c, e s) = t (-e s, e c); the
        // constant has none.
        let mut d = DMatrix::zeros(self.t.len(), 3);
        for (i, &t) in self.t.iter().enumerate() {
            let (ec, es) = (self.basis[(i, 0)], self.basis[(i, 1)]);
            (d[(i, 0)], d[(i, 1)]) = if index == 0 {
                (-t * ec, -t * es)
            } else {
                (-t * es, t * ec)
            };
        }
        Ok(d)
    }
}

/// Least-squares fit of `c + exp(-sigma t)(a cos w t + b sin w t)` by variable projection
/// (varpro: Levenberg-Marquardt on `(sigma, w)`, `(a, b, c)` solved for at each step), from
/// `w = omega_start` and the best `sigma` of a coarse scan of damping ratios.
pub(super) fn fit_damped_sine(
    x: &[f64],
    fs_hz: f64,
    omega_start: f64,
) -> Result<DampedSineFit, IdentifyError> {
    let failed = |iterations, rms_residual_rad| IdentifyError::FitFailed {
        iterations,
        rms_residual_rad,
    };
    let (seed, _) = scan_seed(x, fs_hz, omega_start).ok_or(failed(0, f64::NAN))?;
    let sigma_start = seed[3];
    let model = RingDownModel::new(x.len(), fs_hz, sigma_start, omega_start);
    let problem = SeparableProblemBuilder::new(model)
        .observations(DVector::from_column_slice(x))
        .build()
        .map_err(|_| failed(0, f64::NAN))?;
    // A search that stops short of its tolerances (out of patience, no improvement possible)
    // keeps its last iterate: like any fit it must be finite here and pass the frequency and
    // residual checks of `identify_stiffness`.
    let (Ok(result) | Err(result)) = LevMarSolver::default().solve(problem);
    let evaluations = result.minimization_report.number_of_evaluations;
    let nonlinear = result.nonlinear_parameters();
    let linear: Vec<f64> = result
        .linear_coefficients()
        .map(|c| c.iter().copied().collect())
        .unwrap_or_default();
    let (&[sigma, omega], &[a, b, c]) = (nonlinear.as_slice(), linear.as_slice()) else {
        return Err(failed(evaluations, f64::NAN));
    };
    let p = [a, b, c, sigma, omega];
    let rms = (cost_of(x, fs_hz, &p) / x.len() as f64).sqrt();
    if !(p.iter().all(|v| v.is_finite()) && rms.is_finite()) {
        return Err(failed(evaluations, rms));
    }
    // Keep the frequency positive: (a, b, w) and (a, -b, -w) are the same signal.
    let (b, omega) = if omega < 0.0 {
        (-b, -omega)
    } else {
        (b, omega)
    };
    Ok(DampedSineFit {
        cos_amplitude_rad: a,
        sin_amplitude_rad: b,
        offset_rad: c,
        sigma_per_s: sigma,
        omega_rad_s: omega,
        rms_residual_rad: rms,
    })
}
