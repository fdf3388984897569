//! Shooting on the clamp moment: [`solve`] integrates the beam's equations and their
//! variational equations from the clamp (the crate's `numerics::gbs` steps under an adaptive
//! step-size control that lands on every section end and sample point) and drives the tip
//! moment `M(L)` to zero by a safeguarded Newton method, with load continuation as a fallback.

use crate::numerics::gbs::{GBS_COLUMNS, gbs_step};

use super::problem::{section_knots, validate};
use super::{
    BendingStiffness, ElasticaError, ElasticaOptions, ElasticaProblem, ElasticaSolution, ShapePoint,
};

/// State: x, y, theta, M, d theta / d M0, d M / d M0.
type State = [f64; 6];

/// Solves the elastica by shooting on the clamp moment.
///
/// # Errors
/// [`ElasticaError`] for invalid geometry, load, stiffness or options; a non-positive or
/// non-finite `EI` met during integration; step-size underflow; or
/// [`ElasticaError::NotConverged`] with the best residual when shooting fails.
pub fn solve(
    problem: &ElasticaProblem,
    options: &ElasticaOptions,
) -> Result<ElasticaSolution, ElasticaError> {
    validate(problem, options)?;
    let length_m = problem.length_m;
    let [fx, fy] = problem.tip_force_n;
    let force_n = fx.hypot(fy);
    let moment_scale_n_m = force_n * length_m;
    let mut shooter = Shooter {
        problem,
        tolerance: options.integration_tolerance,
        moment_scale_n_m,
        step_hint_m: length_m / 4.0,
        knots: section_knots(problem),
    };
    let (theta0, l) = (problem.clamp_angle_rad, length_m);
    let straight_m0 = l * (theta0.cos() * fy - theta0.sin() * fx);
    let start_m0 = options.initial_base_moment_n_m.unwrap_or(straight_m0);
    let threshold = options.residual_tolerance * moment_scale_n_m;

    let (base_moment_n_m, newton_iterations) = if force_n == 0.0 {
        (0.0, 0)
    } else {
        match newton(&mut shooter, 1.0, start_m0, threshold, options) {
            Ok(found) => found,
            Err(NewtonFailure::Hard(e)) => return Err(e),
            Err(NewtonFailure::Soft(its, residual, at)) => continuation(
                &mut shooter,
                start_m0,
                threshold,
                options,
                (its, residual, at),
            )?,
        }
    };

    // Final pass at the full load, hitting the sample points exactly.
    let samples = options.shape_samples;
    let sample_s: Vec<f64> = (0..samples)
        .map(|i| length_m * i as f64 / (samples - 1) as f64)
        .collect();
    let mut shape = Vec::with_capacity(samples);
    if samples > 0 {
        shape.push(ShapePoint {
            arc_length_m: 0.0,
            position_m: [0.0, 0.0],
            angle_rad: theta0,
            moment_n_m: base_moment_n_m,
        });
    }
    let end = shooter.integrate(1.0, base_moment_n_m, &sample_s, |s, y| {
        if s > 0.0 {
            shape.push(ShapePoint {
                arc_length_m: s,
                position_m: [y[0], y[1]],
                angle_rad: y[2],
                moment_n_m: y[3],
            });
        }
    })?;
    let residual = end[3].abs();
    if force_n != 0.0 && (residual.is_nan() || residual > 10.0 * threshold) {
        return Err(ElasticaError::NotConverged {
            iterations: newton_iterations,
            residual_n_m: residual,
            base_moment_n_m,
        });
    }
    Ok(ElasticaSolution {
        tip_position_m: [end[0], end[1]],
        tip_angle_rad: end[2],
        base_moment_n_m,
        moment_residual_n_m: residual,
        newton_iterations,
        shape,
    })
}

/// Why Newton stopped short.
enum NewtonFailure {
    /// A problem error (e.g. `EI` invalid where it was met): give up at once.
    Hard(ElasticaError),
    /// No convergence: (iterations, best residual, its M0).
    Soft(usize, f64, f64),
}

/// Integrates, sorting errors into hard (bad problem) and soft (step-size underflow).
fn shoot(shooter: &mut Shooter<'_>, lambda: f64, m0: f64) -> Result<Option<State>, ElasticaError> {
    match shooter.integrate(lambda, m0, &[], |_, _| {}) {
        Ok(end) => Ok(Some(end)),
        Err(ElasticaError::StepSizeUnderflow { .. }) => Ok(None),
        Err(e) => Err(e),
    }
}

/// Safeguarded Newton on `M(L)` at load factor `lambda`.
///
/// Every equilibrium has `|M(0)| = |p_L x F| <= |F| L = B`, so iterates stay in `[-B, B]`.
/// Points where `M(L) < 0` and `> 0` are remembered; once both exist they bracket a root and
/// a Newton step leaving the bracket, or one that fails to halve `|M(L)|`, is replaced by
/// bisection. The first time a step fails to halve `|M(L)|`, `M(L)` is probed at `+-B` to
/// find a bracket. Without a bracket, steps are backtracked until `|M(L)|` decreases.
fn newton(
    shooter: &mut Shooter<'_>,
    lambda: f64,
    start_m0: f64,
    threshold: f64,
    options: &ElasticaOptions,
) -> Result<(f64, usize), NewtonFailure> {
    let threshold = threshold * lambda;
    let bound = lambda * shooter.moment_scale_n_m;
    let mut m0 = start_m0.clamp(-bound, bound);
    let Some(mut end) = shoot(shooter, lambda, m0).map_err(NewtonFailure::Hard)? else {
        return Err(NewtonFailure::Soft(0, f64::INFINITY, m0));
    };
    let (mut negative, mut positive): (Option<f64>, Option<f64>) = (None, None);
    let record = |m: f64, r: f64, neg: &mut Option<f64>, pos: &mut Option<f64>| {
        if r < 0.0 {
            *neg = Some(m);
        } else if r > 0.0 {
            *pos = Some(m);
        }
    };
    record(m0, end[3], &mut negative, &mut positive);
    let mut probed = false;
    let mut slow = false;
    for it in 1..=options.max_newton_iterations {
        let residual = end[3];
        if residual.abs() <= threshold {
            return Ok((m0, it - 1));
        }
        let slope = end[5];
        let newton_m0 = if slope.is_finite() && slope != 0.0 {
            (m0 - residual / slope).clamp(-bound, bound)
        } else {
            f64::NAN
        };
        if let (Some(a), Some(b)) = (negative, positive) {
            let (lo, hi) = (a.min(b), a.max(b));
            let candidate = if !slow && newton_m0 > lo && newton_m0 < hi {
                newton_m0
            } else {
                0.5 * (lo + hi)
            };
            let Some(trial) = shoot(shooter, lambda, candidate).map_err(NewtonFailure::Hard)?
            else {
                return Err(NewtonFailure::Soft(it, residual.abs(), m0));
            };
            record(candidate, trial[3], &mut negative, &mut positive);
            slow = trial[3].abs() > 0.5 * residual.abs();
            if hi - lo <= 4.0 * f64::EPSILON * bound.max(hi.abs()) {
                // The bracket has collapsed to rounding level.
                return if trial[3].abs().min(residual.abs()) <= 10.0 * threshold {
                    Ok((candidate, it))
                } else {
                    Err(NewtonFailure::Soft(it, trial[3].abs(), candidate))
                };
            }
            m0 = candidate;
            end = trial;
            continue;
        }
        if !newton_m0.is_finite() {
            return Err(NewtonFailure::Soft(it, residual.abs(), m0));
        }
        let mut accepted = false;
        let mut t = 1.0;
        for _ in 0..40 {
            let trial_m0 = m0 + t * (newton_m0 - m0);
            if let Some(trial) = shoot(shooter, lambda, trial_m0).map_err(NewtonFailure::Hard)? {
                record(trial_m0, trial[3], &mut negative, &mut positive);
                if trial[3].abs() < residual.abs() {
                    let halved = trial[3].abs() <= 0.5 * residual.abs();
                    m0 = trial_m0;
                    end = trial;
                    accepted = true;
                    if !halved && !probed {
                        probed = true;
                        for edge in [-bound, bound] {
                            if let Some(e) =
                                shoot(shooter, lambda, edge).map_err(NewtonFailure::Hard)?
                            {
                                record(edge, e[3], &mut negative, &mut positive);
                            }
                        }
                    }
                    break;
                }
                if negative.is_some() && positive.is_some() {
                    // A bracket appeared: let the bracketed branch take over.
                    accepted = true;
                    break;
                }
            }
            t *= 0.5;
        }
        if !accepted {
            // No decrease: either converged to rounding level or stuck.
            return if residual.abs() <= 10.0 * threshold {
                Ok((m0, it))
            } else {
                Err(NewtonFailure::Soft(it, residual.abs(), m0))
            };
        }
    }
    if end[3].abs() <= threshold {
        Ok((m0, options.max_newton_iterations))
    } else {
        Err(NewtonFailure::Soft(
            options.max_newton_iterations,
            end[3].abs(),
            m0,
        ))
    }
}

/// Load continuation from the unloaded beam in 4, then 16, then 64 equal steps.
fn continuation(
    shooter: &mut Shooter<'_>,
    start_m0: f64,
    threshold: f64,
    options: &ElasticaOptions,
    direct: (usize, f64, f64),
) -> Result<(f64, usize), ElasticaError> {
    let (mut total, mut best_residual, mut best_m0) = direct;
    'levels: for levels in [4usize, 16, 64] {
        let mut m0 = 0.0;
        let mut previous_lambda = 0.0;
        for i in 1..=levels {
            let lambda = i as f64 / levels as f64;
            // M(0) scales with the load to first order.
            let guess = if i == 1 {
                start_m0 * lambda
            } else {
                m0 * lambda / previous_lambda
            };
            match newton(shooter, lambda, guess, threshold, options) {
                Ok((found, its)) => {
                    total += its;
                    m0 = found;
                    previous_lambda = lambda;
                }
                Err(NewtonFailure::Hard(e)) => return Err(e),
                Err(NewtonFailure::Soft(its, residual, at)) => {
                    total += its;
                    if lambda == 1.0 && residual < best_residual {
                        best_residual = residual;
                        best_m0 = at;
                    }
                    continue 'levels;
                }
            }
        }
        return Ok((m0, total));
    }
    Err(ElasticaError::NotConverged {
        iterations: total,
        residual_n_m: best_residual,
        base_moment_n_m: best_m0,
    })
}

struct Shooter<'a> {
    problem: &'a ElasticaProblem,
    tolerance: f64,
    moment_scale_n_m: f64,
    step_hint_m: f64,
    /// Section ends: breakpoints then `L`.
    knots: Vec<f64>,
}

impl Shooter<'_> {
    /// Integrates from the clamp with `M(0) = m0` under `lambda` times the load to `L`,
    /// calling `on_sample` at each of `samples` (sorted, in [0, L]) and returning the tip
    /// state.
    fn integrate(
        &mut self,
        lambda: f64,
        m0: f64,
        samples: &[f64],
        mut on_sample: impl FnMut(f64, &State),
    ) -> Result<State, ElasticaError> {
        let p = self.problem;
        let (fx, fy) = (lambda * p.tip_force_n[0], lambda * p.tip_force_n[1]);
        let l = p.length_m;
        let mut y: State = [0.0, 0.0, p.clamp_angle_rad, m0, 0.0, 1.0];
        let scale: [f64; 4] = [
            self.tolerance * l,
            self.tolerance * l,
            self.tolerance,
            self.tolerance * self.moment_scale_n_m.max(f64::MIN_POSITIVE),
        ];
        let mut s = 0.0;
        let mut sample_iter = samples.iter().copied().filter(|&v| v > 0.0).peekable();
        for section in 0..self.knots.len() {
            let section_end = self.knots[section];
            while s < section_end {
                let target = match sample_iter.peek() {
                    Some(&v) if v < section_end => v,
                    _ => section_end,
                };
                let rhs = Rhs {
                    fx,
                    fy,
                    stiffness: &p.bending_stiffness,
                    section,
                };
                y = self.advance(&rhs, s, target, y, &scale)?;
                s = target;
                if sample_iter.peek().is_some_and(|&v| v <= target) {
                    sample_iter.next();
                    on_sample(s, &y);
                }
            }
        }
        Ok(y)
    }

    /// Adaptive GBS steps from `s0` to exactly `s1`.
    fn advance(
        &mut self,
        rhs: &Rhs<'_>,
        s0: f64,
        s1: f64,
        mut y: State,
        scale: &[f64; 4],
    ) -> Result<State, ElasticaError> {
        let l = self.problem.length_m;
        let mut s = s0;
        let mut h = self.step_hint_m.min(s1 - s0);
        let mut steps = 0usize;
        while s < s1 {
            let remaining = s1 - s;
            let capped = h >= remaining;
            if capped {
                h = remaining;
            }
            let (y_new, err) = gbs_step(|s, y| rhs.eval(s, y), s, h, &y, scale, scale[2])?;
            let exponent = 1.0 / (2 * GBS_COLUMNS - 1) as f64;
            let fac = if err > 0.0 {
                (0.94 * (0.65 / err).powf(exponent)).clamp(0.2, 4.0)
            } else {
                4.0
            };
            if err <= 1.0 {
                s = if capped { s1 } else { s + h };
                y = y_new;
                // A step cut short to land on s1 says nothing about a longer one failing.
                self.step_hint_m = if capped {
                    self.step_hint_m.max(h * fac)
                } else {
                    h * fac
                };
                h = self.step_hint_m;
            } else {
                h *= fac;
                self.step_hint_m = h;
            }
            steps += 1;
            if h < 1e-14 * l || steps > 1_000_000 {
                return Err(ElasticaError::StepSizeUnderflow { s_m: s });
            }
        }
        Ok(y)
    }
}

struct Rhs<'a> {
    fx: f64,
    fy: f64,
    stiffness: &'a BendingStiffness,
    section: usize,
}

impl Rhs<'_> {
    fn eval(&self, s: f64, y: &State) -> Result<State, ElasticaError> {
        let ei = self.stiffness.at(s, self.section)?;
        let (sin_t, cos_t) = y[2].sin_cos();
        Ok([
            cos_t,
            sin_t,
            y[3] / ei,
            self.fx * sin_t - self.fy * cos_t,
            y[5] / ei,
            (self.fx * cos_t + self.fy * sin_t) * y[4],
        ])
    }
}
