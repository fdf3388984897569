//! The template's theory: its linearization about the setpoint, the stability boundary in
//! speed, and a simulation of the template under an ideal-preview PD controller (no
//! antenna) whose boundary is found by bisection on the sign of its error envelope's fitted
//! growth rate: the check of the closed loop against theory (issue #47, item 6).
//!
//! # The linearization (Cowan, Lee and Full 2006)
//! With `y` the distance from the point of rotation (POR) to a straight wall, `theta` the
//! body's angle to it and `omega` its turning rate (both positive away from the wall), the
//! template is `dy/dt = v sin(theta)`, `dtheta/dt = omega`, `J domega/dt = -b omega + u`,
//! an ideal antenna of preview `l` measures `d = y / cos(theta) + l tan(theta)` and the PD
//! controller turns the body by `u = -Kp (d - d_set) - Kd dd/dt`. About the setpoint
//! (`d ~ y + l theta`, `dd/dt ~ v theta + l omega`) the closed loop's characteristic
//! polynomial is
//!
//! `J s^3 + (b + Kd l) s^2 + (Kp l + Kd v) s + Kp v = 0`,
//!
//! stable (Routh-Hurwitz, every coefficient positive) if and only if
//! `(b + Kd l)(Kp l + Kd v) > J Kp v`: below the speed
//! `v* = (b + Kd l) Kp l / (J Kp - (b + Kd l) Kd)` when `J Kp > (b + Kd l) Kd` (with P
//! alone, `v* = b l / J`), at every speed otherwise ([`TemplateLinear`]).
//!
//! # The simulation ([`simulate_ideal_preview`])
//! The closed loop itself ([`super::Follow`] without an antenna) runs the template
//! ([`super::body::step_body`], RK4) along a straight wall; each step the
//! ideal preview `d` is measured by a ray cast from the point `l` ahead of the POR along the
//! body's normal toward the wall ([`crate::walls::first_ray_hit`]), `dd/dt` is the backward
//! difference of successive `d`, and `u` is held over the step (a zero-order hold, which
//! acts like a delay of about half a step and moves the boundary: about 1 % at a step of
//! 1 ms). [`envelope_growth_rate_per_s`] fits the growth rate of the error's envelope, and
//! [`simulated_boundary_speed`] bisects any such rate (of this simulation, or of the full
//! loop) on its sign.
//!
//! # The step's shift of the boundary
//! Measured with [`ideal_preview_boundary_speed`] (60 s runs, a 2 mm start offset, the
//! boundary to 0.1 %; 120 s runs give the same figures), against the linearized boundary:
//!
//! | parameters (`J`, `b`, `Kp`, `Kd`, `l`) | `v*`, m/s | 0.5 ms | 1 ms | 2 ms | 5 ms | 10 ms |
//! |---|---|---|---|---|---|---|
//! | 2e-4, 4e-3, 0.05, 0, 0.05 (P only) | 1.000 | -0.5 % | -1.0 % | -2.1 % | -4.9 % | -9.4 % |
//! | 2e-4, 4e-3, 0.05, 0.001, 0.05 | 1.702 | -0.9 % | -1.7 % | -3.5 % | -8.2 % | -15.1 % |
//! | 5e-4, 2e-3, 0.1, 0.002, 0.08 | 0.378 | -0.2 % | -0.4 % | -0.9 % | -2.1 % | -4.3 % |
//!
//! The shift grows in proportion to the step, as a delay of half a step would move it; the
//! derivative term, a backward difference, adds its own half step.

use nalgebra::{Matrix3, Vector2};

use super::{BodyModel, Estimator, Follow, FollowConfig};
use crate::walls::{Line, SolidSide, Wall};

/// The template's closed loop under an ideal-preview PD controller, linearized about the
/// setpoint.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TemplateLinear {
    /// `J`, the body's moment of inertia about the POR, kg m^2.
    pub inertia_kg_m2: f64,
    /// `b`, the rotational damping, N m s/rad.
    pub damping_n_m_s_per_rad: f64,
    /// `Kp`, N m of moment per m of error.
    pub kp_n: f64,
    /// `Kd`, N m per m/s of the error's rate.
    pub kd_n_s: f64,
    /// `l`, the preview distance, m.
    pub preview_m: f64,
}

impl TemplateLinear {
    /// The example: `J = 2e-4`, `b = 4e-3`, `l = 0.05`, `Kp = 0.05`, `Kd = 0` (its
    /// P-only boundary `b l / J` is 1 m/s).
    pub fn example() -> TemplateLinear {
        TemplateLinear {
            inertia_kg_m2: 2.0e-4,
            damping_n_m_s_per_rad: 4.0e-3,
            kp_n: 0.05,
            kd_n_s: 0.0,
            preview_m: 0.05,
        }
    }

    /// The template body these parameters describe.
    pub fn body(&self) -> BodyModel {
        BodyModel::Template {
            inertia_kg_m2: self.inertia_kg_m2,
            damping_n_m_s_per_rad: self.damping_n_m_s_per_rad,
        }
    }

    /// The characteristic polynomial's coefficients at speed `v`, from `s^3` down to `s^0`:
    /// `[J, b + Kd l, Kp l + Kd v, Kp v]`.
    pub fn coefficients(&self, speed_m_per_s: f64) -> [f64; 4] {
        let (j, b, kp, kd, l) = self.parts();
        let v = speed_m_per_s;
        [j, b + kd * l, kp * l + kd * v, kp * v]
    }

    /// Whether the linearized loop is asymptotically stable at speed `v` (Routh-Hurwitz for
    /// a cubic: every coefficient positive and `a2 a1 > a3 a0`). `false` for NaN values.
    pub fn is_stable(&self, speed_m_per_s: f64) -> bool {
        let [a3, a2, a1, a0] = self.coefficients(speed_m_per_s);
        a3 > 0.0 && a2 > 0.0 && a1 > 0.0 && a0 > 0.0 && a2 * a1 > a3 * a0
    }

    /// The speed above which the linearized loop is unstable:
    /// `(b + Kd l) Kp l / (J Kp - (b + Kd l) Kd)` (with P alone `b l / J`); `None` when
    /// `(b + Kd l) Kd >= J Kp`, where no speed makes it unstable (if it is stable at all:
    /// it needs `Kp > 0` and `b + Kd l > 0`), or for NaN values.
    pub fn boundary_speed_m_per_s(&self) -> Option<f64> {
        let (j, b, kp, kd, l) = self.parts();
        let a2 = b + kd * l;
        let denominator = j * kp - a2 * kd;
        if denominator > 0.0 {
            let v = a2 * kp * l / denominator;
            v.is_finite().then_some(v)
        } else {
            None
        }
    }

    /// The largest real part of the characteristic polynomial's roots at speed `v`, 1/s:
    /// the growth rate of the slowest-decaying (or fastest-growing) mode. Computed from the
    /// eigenvalues of the monic cubic's companion matrix, independently of
    /// [`Self::is_stable`]. NaN for `J <= 0` or NaN values.
    pub fn growth_rate_per_s(&self, speed_m_per_s: f64) -> f64 {
        let [a3, a2, a1, a0] = self.coefficients(speed_m_per_s);
        if !(a3 > 0.0 && a2.is_finite() && a1.is_finite() && a0.is_finite()) {
            return f64::NAN;
        }
        let (c2, c1, c0) = (a2 / a3, a1 / a3, a0 / a3);
        let companion = Matrix3::new(-c2, -c1, -c0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0);
        companion
            .complex_eigenvalues()
            .iter()
            .map(|z| z.re)
            .fold(f64::NEG_INFINITY, f64::max)
    }

    fn parts(&self) -> (f64, f64, f64, f64, f64) {
        (
            self.inertia_kg_m2,
            self.damping_n_m_s_per_rad,
            self.kp_n,
            self.kd_n_s,
            self.preview_m,
        )
    }
}

/// A run of the ideal-preview simulation ([`simulate_ideal_preview`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PreviewRun {
    /// The control and integration step, s.
    pub step_s: f64,
    /// How long the body runs, s.
    pub duration_s: f64,
    /// The wanted preview distance `d_set`, m.
    pub setpoint_m: f64,
    /// How much farther from the wall than the setpoint the POR starts, m (the disturbance
    /// whose growth is measured: small, so that the loop stays linear).
    pub start_offset_m: f64,
    /// The start of the run left out of the envelope's fit (the fast real mode's
    /// transient), s.
    pub skip_s: f64,
}

impl Default for PreviewRun {
    /// A 1 ms step for 60 s, a setpoint of 0.1 m, a 2 mm start offset, the first 5 s left
    /// out of the fit.
    fn default() -> Self {
        PreviewRun {
            step_s: 0.001,
            duration_s: 60.0,
            setpoint_m: 0.1,
            start_offset_m: 0.002,
            skip_s: 5.0,
        }
    }
}

/// What [`simulate_ideal_preview`] recorded.
#[derive(Clone, Debug, PartialEq)]
pub struct PreviewHistory {
    /// The time of each sample, s.
    pub times_s: Vec<f64>,
    /// The error `d - d_set` at each sample, m.
    pub errors_m: Vec<f64>,
    /// Whether the run ended before its duration because it diverged: the error grew past
    /// half the setpoint, or the ray toward the wall met nothing (the body turned away).
    pub diverged: bool,
}

/// The template at `speed_m_per_s` along a straight wall (the x axis, solid above, on the
/// body's left), starting parallel to it `start_offset_m` farther than the setpoint,
/// under `u = -Kp (d - d_set) - Kd dd/dt` with `d` the ideal preview measured by a ray from
/// the point `l` ahead of the POR along the body's normal, `dd/dt` the backward difference
/// of successive `d` (zero at the first step) and `u` held over each step (module docs).
/// It is the closed loop itself ([`super::Follow::without_antenna`] with the
/// [`Estimator::IdealPreview`]), recording `d - d_set`. A
/// run with a non-positive or non-finite step or duration, or one the loop refuses (a step
/// outside its range), records nothing.
pub fn simulate_ideal_preview(
    linear: &TemplateLinear,
    speed_m_per_s: f64,
    run: &PreviewRun,
) -> PreviewHistory {
    let mut history = PreviewHistory {
        times_s: Vec::new(),
        errors_m: Vec::new(),
        diverged: false,
    };
    let h = run.step_s;
    if !(h > 0.0 && h.is_finite() && run.duration_s > 0.0 && run.duration_s.is_finite()) {
        return history;
    }
    let Ok(line) = Line::new(Vector2::zeros(), 0.0, SolidSide::Left) else {
        return history;
    };
    let mut config = FollowConfig::default();
    config.robot.speed_m_per_s = speed_m_per_s;
    config.robot.body = linear.body();
    // A point-like body: collisions are not what is measured.
    config.robot.footprint_m = [1e-3, 1e-3];
    config.controller.estimator = Estimator::IdealPreview {
        preview_m: linear.preview_m,
    };
    config.controller.setpoint_m = run.setpoint_m;
    config.controller.kp_n = linear.kp_n;
    config.controller.kd_n_s = linear.kd_n_s;
    config.controller.delay_s = 0.0;
    config.settings.step_s = h;
    // One step more than the duration: the sample at `t = duration` is recorded too.
    config.settings.duration_s = run.duration_s + h;
    config.settings.pose_m = Vector2::new(0.0, -(run.setpoint_m + run.start_offset_m));
    config.settings.heading_rad = 0.0;
    config.settings.lost_after_s = run.duration_s + 1.0;
    let Ok(mut follow) = Follow::without_antenna(vec![Wall::smooth(line)], &config) else {
        return history;
    };
    let steps = config.steps();
    history.times_s.reserve(steps);
    history.errors_m.reserve(steps);
    while let Some(Ok(step)) = follow.next_step() {
        let Some(estimate) = step.estimate else {
            history.diverged = true;
            break;
        };
        let error = estimate.distance_m - run.setpoint_m;
        history.times_s.push(step.t_s);
        history.errors_m.push(error);
        if error.abs() > 0.5 * run.setpoint_m {
            history.diverged = true;
            break;
        }
    }
    history
}

/// Errors below this are rounding, not signal: left out of the envelope's fit, m.
const ENVELOPE_FLOOR_M: f64 = 1e-12;

/// The growth rate of the envelope of `errors_m` (sampled at `times_s`), 1/s: the
/// least-squares slope of `ln |e|` at the local maxima of `|e|` from `skip_s` on (at least
/// 3 of them, above `1e-12` m), or where `|e|` has fewer such peaks (no oscillation), of
/// `ln |e|` at every sample from `skip_s` on above that floor (at least 2). `None` when
/// there is not enough to fit, or the lengths differ.
pub fn envelope_growth_rate_per_s(times_s: &[f64], errors_m: &[f64], skip_s: f64) -> Option<f64> {
    if times_s.len() != errors_m.len() {
        return None;
    }
    let mut peaks = LeastSquares::default();
    for i in 1..errors_m.len().saturating_sub(1) {
        let (before, here, after) = (
            errors_m[i - 1].abs(),
            errors_m[i].abs(),
            errors_m[i + 1].abs(),
        );
        if times_s[i] >= skip_s && here > ENVELOPE_FLOOR_M && here >= before && here > after {
            peaks.add(times_s[i], here.ln());
        }
    }
    if peaks.count >= 3 {
        return peaks.slope();
    }
    let mut samples = LeastSquares::default();
    for (t, e) in times_s.iter().zip(errors_m) {
        if *t >= skip_s && e.abs() > ENVELOPE_FLOOR_M {
            samples.add(*t, e.abs().ln());
        }
    }
    if samples.count >= 2 {
        samples.slope()
    } else {
        None
    }
}

/// Sums for a least-squares line.
#[derive(Default)]
struct LeastSquares {
    count: usize,
    sx: f64,
    sy: f64,
    sxx: f64,
    sxy: f64,
}

impl LeastSquares {
    fn add(&mut self, x: f64, y: f64) {
        self.count += 1;
        self.sx += x;
        self.sy += y;
        self.sxx += x * x;
        self.sxy += x * y;
    }

    fn slope(&self) -> Option<f64> {
        let n = self.count as f64;
        let denominator = n * self.sxx - self.sx * self.sx;
        let slope = (n * self.sxy - self.sx * self.sy) / denominator;
        (denominator > 0.0 && slope.is_finite()).then_some(slope)
    }
}

/// The fitted envelope growth rate of [`simulate_ideal_preview`] at `speed_m_per_s`, 1/s
/// ([`envelope_growth_rate_per_s`] from `run.skip_s` on); `+inf` for a run that diverged,
/// `None` when there is not enough to fit.
pub fn ideal_preview_growth_rate_per_s(
    linear: &TemplateLinear,
    speed_m_per_s: f64,
    run: &PreviewRun,
) -> Option<f64> {
    let history = simulate_ideal_preview(linear, speed_m_per_s, run);
    if history.diverged {
        return Some(f64::INFINITY);
    }
    envelope_growth_rate_per_s(&history.times_s, &history.errors_m, run.skip_s)
}

/// The speed where `growth_rate_per_s` (any fitted growth rate of a run at a speed: of
/// [`ideal_preview_growth_rate_per_s`], or of the full loop) changes sign, by bisection
/// within `bracket_m_per_s = [stable, unstable]` until the bracket is narrower than
/// `relative_tolerance` of its middle (at most 100 halvings); the middle of the last
/// bracket. `None` when the bracket's ends do not have a negative and a positive rate
/// (or are not finite), or a rate cannot be fitted.
pub fn simulated_boundary_speed(
    mut growth_rate_per_s: impl FnMut(f64) -> Option<f64>,
    bracket_m_per_s: [f64; 2],
    relative_tolerance: f64,
) -> Option<f64> {
    let [mut stable, mut unstable] = bracket_m_per_s;
    if !(stable.is_finite() && unstable.is_finite()) {
        return None;
    }
    if !(growth_rate_per_s(stable)? < 0.0 && growth_rate_per_s(unstable)? > 0.0) {
        return None;
    }
    for _ in 0..100 {
        let middle = 0.5 * (stable + unstable);
        if (unstable - stable).abs() <= relative_tolerance * middle.abs() {
            break;
        }
        if growth_rate_per_s(middle)? < 0.0 {
            stable = middle;
        } else {
            unstable = middle;
        }
    }
    Some(0.5 * (stable + unstable))
}

/// [`simulated_boundary_speed`] of [`ideal_preview_growth_rate_per_s`], to `0.1 %`.
pub fn ideal_preview_boundary_speed(
    linear: &TemplateLinear,
    run: &PreviewRun,
    bracket_m_per_s: [f64; 2],
) -> Option<f64> {
    simulated_boundary_speed(
        |v| ideal_preview_growth_rate_per_s(linear, v, run),
        bracket_m_per_s,
        1e-3,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn the_p_only_boundary_is_b_l_over_j() {
        let linear = TemplateLinear::example();
        let v = linear.boundary_speed_m_per_s();
        assert!(v.is_some_and(|v| (v - 1.0).abs() < 1e-12), "{v:?}");
        let other = TemplateLinear {
            inertia_kg_m2: 3.0e-4,
            damping_n_m_s_per_rad: 2.0e-3,
            kp_n: 0.2,
            kd_n_s: 0.0,
            preview_m: 0.08,
        };
        let v = other.boundary_speed_m_per_s();
        let expected = 2.0e-3 * 0.08 / 3.0e-4;
        assert!(v.is_some_and(|v| (v - expected).abs() < 1e-12), "{v:?}");
    }

    #[test]
    fn the_boundary_grows_nothing_and_splits_stable_from_unstable() {
        for linear in [
            TemplateLinear::example(),
            TemplateLinear {
                kd_n_s: 0.001,
                ..TemplateLinear::example()
            },
            TemplateLinear {
                inertia_kg_m2: 5.0e-4,
                damping_n_m_s_per_rad: 2.0e-3,
                kp_n: 0.1,
                kd_n_s: 0.002,
                preview_m: 0.08,
            },
        ] {
            let v = linear.boundary_speed_m_per_s().unwrap_or(f64::NAN);
            assert!(v > 0.0, "{linear:?}");
            let rate = linear.growth_rate_per_s(v);
            assert!(rate.abs() < 1e-9, "{linear:?}: {rate}");
            assert!(linear.growth_rate_per_s(0.99 * v) < 0.0 && linear.is_stable(0.99 * v));
            assert!(linear.growth_rate_per_s(1.01 * v) > 0.0 && !linear.is_stable(1.01 * v));
        }
    }

    #[test]
    fn enough_derivative_gain_has_no_speed_limit() {
        // (b + Kd l) Kd >= J Kp: stable at every speed.
        let linear = TemplateLinear {
            kd_n_s: 0.01,
            ..TemplateLinear::example()
        };
        assert_eq!(linear.boundary_speed_m_per_s(), None);
        for v in [0.01, 0.3, 1.0, 10.0, 100.0] {
            assert!(linear.is_stable(v), "{v}");
            assert!(linear.growth_rate_per_s(v) < 0.0, "{v}");
        }
        // No proportional gain: a root at zero, never asymptotically stable.
        let none = TemplateLinear {
            kp_n: 0.0,
            ..TemplateLinear::example()
        };
        assert_eq!(none.boundary_speed_m_per_s(), None);
        assert!(!none.is_stable(0.5));
        assert!(none.growth_rate_per_s(0.5).abs() < 1e-12);
        // NaN in, no panic out.
        let nan = TemplateLinear {
            kp_n: f64::NAN,
            ..TemplateLinear::example()
        };
        assert_eq!(nan.boundary_speed_m_per_s(), None);
        assert!(!nan.is_stable(0.5));
        assert!(nan.growth_rate_per_s(0.5).is_nan());
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        /// Routh-Hurwitz agrees with the sign of the roots' largest real part, and the
        /// boundary (where there is one) with both.
        #[test]
        fn routh_hurwitz_agrees_with_the_roots(
            log_j in -5.0f64..-2.0,
            log_b in -4.0f64..-1.0,
            log_kp in -3.0f64..0.0,
            kd_fraction in 0.0f64..2.0,
            preview in 0.001f64..0.2,
            log_v in -2.0f64..1.0,
        ) {
            let j = 10f64.powf(log_j);
            let b = 10f64.powf(log_b);
            let kp = 10f64.powf(log_kp);
            // Kd around the value where the speed limit goes away.
            let kd = kd_fraction * j * kp / (b + 1e-3);
            let linear = TemplateLinear {
                inertia_kg_m2: j,
                damping_n_m_s_per_rad: b,
                kp_n: kp,
                kd_n_s: kd,
                preview_m: preview,
            };
            let v = 10f64.powf(log_v);
            let rate = linear.growth_rate_per_s(v);
            // (Too close to the boundary to tell the sign of the rate apart from rounding.)
            let scale = linear.coefficients(v)[1] / j;
            if rate.abs() > 1e-9 * scale {
                prop_assert_eq!(linear.is_stable(v), rate < 0.0, "{:?} at {}: {}", linear, v, rate);
            }
            match linear.boundary_speed_m_per_s() {
                Some(boundary) => {
                    prop_assert!(linear.is_stable(0.999 * boundary));
                    prop_assert!(!linear.is_stable(1.001 * boundary));
                }
                None => prop_assert!(linear.is_stable(v)),
            }
        }
    }

    #[test]
    fn the_envelope_fit_finds_a_damped_sinusoids_rate() {
        for sigma in [-0.3, -0.01, 0.0, 0.02, 0.5] {
            let times: Vec<f64> = (0..20_000).map(|k| k as f64 * 1e-3).collect();
            let errors: Vec<f64> = times
                .iter()
                .map(|t| 1e-3 * (sigma * t).exp() * (3.0 * t + 0.4).sin())
                .collect();
            let fitted = envelope_growth_rate_per_s(&times, &errors, 1.0).unwrap();
            assert!((fitted - sigma).abs() < 1e-4, "{sigma}: {fitted}");
        }
        // Monotone decay: the samples themselves.
        let times: Vec<f64> = (0..1000).map(|k| k as f64 * 1e-2).collect();
        let errors: Vec<f64> = times.iter().map(|t| 2e-3 * (-0.7 * t).exp()).collect();
        let fitted = envelope_growth_rate_per_s(&times, &errors, 0.0).unwrap();
        assert!((fitted + 0.7).abs() < 1e-9, "{fitted}");
        assert_eq!(envelope_growth_rate_per_s(&[0.0], &[1.0], 0.0), None);
        assert_eq!(envelope_growth_rate_per_s(&[0.0, 1.0], &[1.0], 0.0), None);
    }

    #[test]
    fn the_bisection_finds_a_sign_change_and_refuses_a_bad_bracket() {
        let v = simulated_boundary_speed(|v| Some(v - 0.7), [0.1, 2.0], 1e-6).unwrap();
        assert!((v - 0.7).abs() < 1e-6, "{v}");
        assert_eq!(
            simulated_boundary_speed(|v| Some(v - 0.7), [0.8, 2.0], 1e-6),
            None
        );
        assert_eq!(simulated_boundary_speed(|_| None, [0.1, 2.0], 1e-6), None);
        let mut calls = 0;
        let v = simulated_boundary_speed(
            |v| {
                calls += 1;
                Some(v - 0.7)
            },
            [0.0, 2.0],
            1e-3,
        );
        assert!(v.is_some() && calls < 20, "{calls}");
    }

    #[test]
    fn the_simulation_settles_below_the_boundary_and_diverges_above() {
        let linear = TemplateLinear::example();
        let run = PreviewRun {
            duration_s: 20.0,
            ..PreviewRun::default()
        };
        let below = simulate_ideal_preview(&linear, 0.5, &run);
        assert!(!below.diverged);
        assert_eq!(below.times_s.len(), 20_001);
        assert!((below.errors_m[0] - 0.002).abs() < 1e-15);
        assert!(below.errors_m.last().is_some_and(|e| e.abs() < 1e-4));
        let above = ideal_preview_growth_rate_per_s(&linear, 3.0, &run);
        assert!(above.is_some_and(|r| r > 0.0), "{above:?}");
        let fitted = ideal_preview_growth_rate_per_s(&linear, 0.5, &run).unwrap_or(f64::NAN);
        let theory = linear.growth_rate_per_s(0.5);
        assert!(
            (fitted - theory).abs() < 0.02 * theory.abs(),
            "{fitted} vs {theory}"
        );
    }
}
