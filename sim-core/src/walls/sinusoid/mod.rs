//! A sinusoidal wall (thesis 4.2.2): `c(t) = o + t u + A sin(2 pi f t + phase) v` about a
//! straight baseline through `o` with direction `u = (cos a, sin a)`, `v = (-sin a, cos a)`.
//!
//! **Frequency unit.** `frequency_per_m` counts **cycles per metre** (wavelength `1 / f`).
//! The thesis writes only "1/m" for its walls (2.8 to 14.2 1/m); cycles per metre puts the
//! finest at a 70 mm wavelength, under two 40 mm segments, which fits its mapping errors
//! growing to 25 mm there; radians per metre would make even the finest wall 0.44 m per cycle.
//!
//! **Nearest point.** The true Euclidean one: in the baseline frame the query point is
//! `(x, y)`; the nearest parameter lies within `|t - x| <= |y - g(x)|` (the vertical gap is an
//! upper bound on the distance). That bracket is sampled at no more than a 32nd of a wavelength
//! (and a quarter of the bracket), scanning outward from `x` and stopping once the lower bound
//! `(t - x)^2 + max(|y| - A, 0)^2` exceeds the best squared distance found; every sampled local
//! minimum is refined by Newton's method on `D'(t)`, safeguarded by bisection. Where `D` may
//! not be convex over the bracket (a point farther from the curve than about half its smallest
//! radius of curvature `1 / (A k^2)`: past the centre of curvature of a crest, `D` has two minima
//! a few samples apart on either side of it), every sample interval over which `D'` turns from
//! falling to rising is refined too. The sign comes
//! from the vertical test (the curve is a graph over its baseline), which is exact. A
//! non-finite query gives a NaN answer (no panic, no endless loop).
//!
//! **Segments.** Along a segment the signed distance `F(s)` has stationary points only where
//! the curve's tangent at the nearest point is parallel to the segment (`g'(t) = slope`, solved
//! in closed form and mapped back along the curve normal: a crest inside a link) and kinks only
//! on the solid's medial axis, which lies on the vertical lines through the crests. Those
//! points, and the segment ends, are the candidates; each is evaluated exactly.

use core::f64::consts::{FRAC_PI_2, PI, TAU};

use nalgebra::Vector2;

use super::error::{WallError, finite};
use super::{
    ConvexFeature, FeatureContact, SegmentContact, SolidSide, WallPoint, better, lerp, ray_is_valid,
};

/// Sub-intervals per wavelength in the arclength table.
const ARCLENGTH_TABLE_INTERVALS: usize = 256;
/// Samples per wavelength in the nearest-point scan.
const SAMPLES_PER_WAVELENGTH: f64 = 32.0;
/// The most samples (or candidate wavelengths) a query visits each way: 2048 wavelengths of
/// scan, reached only by points tens of kilometres from a centimetre-amplitude wall; beyond it
/// the answer is the best point visited (its distance still an upper bound).
const MAX_SCAN_STEPS: u32 = 1 << 16;

/// A query point whose vertical gap `r0` has `r0 (1 + A k) A k^2` above this (`1 / (A k^2)`
/// is the smallest radius of curvature, `A k` the steepest slope) refines every sample
/// interval over which `D'` turns from falling to rising, not only the discrete minima of
/// its samples ([`Sinusoid::nearest`]); below it `D` is convex over the search's bracket.
const TWO_MINIMA_FRACTION: f64 = 0.5;

/// Three-point Gauss-Legendre nodes and weights on `[-1, 1]`.
const GAUSS_3: [(f64, f64); 3] = [
    (0.0, 0.888_888_888_888_889),
    (-0.774_596_669_241_483_4, 0.555_555_555_555_556),
    (0.774_596_669_241_483_4, 0.555_555_555_555_556),
];

/// Five-point Gauss-Legendre nodes and weights on `[-1, 1]`.
const GAUSS_5: [(f64, f64); 5] = [
    (0.0, 0.568_888_888_888_888_9),
    (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
    (0.906_179_845_938_664, 0.236_926_885_056_189_1),
];

/// A sinusoidal wall; arclength is measured along the curve from the parameter `t = 0` (the
/// baseline point), negative for `t < 0`. Tangent in the direction of increasing `t`.
#[derive(Clone, Debug, PartialEq)]
pub struct Sinusoid {
    baseline_point_m: Vector2<f64>,
    direction_rad: f64,
    u: Vector2<f64>,
    v: Vector2<f64>,
    amplitude_m: f64,
    frequency_per_m: f64,
    phase_rad: f64,
    solid: SolidSide,
    /// `k = 2 pi f`, radians per metre.
    wavenumber_rad_per_m: f64,
    /// Arclength at `t = j / (f N)`, `j = 0..=N`.
    arclength_table_m: Vec<f64>,
}

impl Sinusoid {
    /// The sinusoid through `baseline_point_m` (at `t = 0`) along `direction_rad`, with
    /// `amplitude_m` (>= 0), `frequency_per_m` (cycles per metre, > 0) and `phase_rad`, solid
    /// on `solid`'s side of the baseline direction (`Left`: the `+v` side).
    ///
    /// # Errors
    /// [`WallError::NotFinite`], [`WallError::NegativeAmplitude`],
    /// [`WallError::NonPositiveFrequency`].
    pub fn new(
        baseline_point_m: Vector2<f64>,
        direction_rad: f64,
        amplitude_m: f64,
        frequency_per_m: f64,
        phase_rad: f64,
        solid: SolidSide,
    ) -> Result<Sinusoid, WallError> {
        finite("baseline_point_m.x", 0, baseline_point_m.x)?;
        finite("baseline_point_m.y", 0, baseline_point_m.y)?;
        finite("direction_rad", 0, direction_rad)?;
        finite("amplitude_m", 0, amplitude_m)?;
        finite("frequency_per_m", 0, frequency_per_m)?;
        finite("phase_rad", 0, phase_rad)?;
        if amplitude_m < 0.0 {
            return Err(WallError::NegativeAmplitude { amplitude_m });
        }
        if frequency_per_m <= 0.0 {
            return Err(WallError::NonPositiveFrequency { frequency_per_m });
        }
        let (sin, cos) = direction_rad.sin_cos();
        let mut wall = Sinusoid {
            baseline_point_m,
            direction_rad,
            u: Vector2::new(cos, sin),
            v: Vector2::new(-sin, cos),
            amplitude_m,
            frequency_per_m,
            phase_rad,
            solid,
            wavenumber_rad_per_m: TAU * frequency_per_m,
            arclength_table_m: Vec::with_capacity(ARCLENGTH_TABLE_INTERVALS + 1),
        };
        let step = wall.wavelength_m() / ARCLENGTH_TABLE_INTERVALS as f64;
        let mut total_m = 0.0;
        wall.arclength_table_m.push(0.0);
        for j in 0..ARCLENGTH_TABLE_INTERVALS {
            let t0 = j as f64 * step;
            total_m += wall.arclength_between(&GAUSS_5, t0, t0 + step);
            wall.arclength_table_m.push(total_m);
        }
        Ok(wall)
    }

    /// The baseline point (curve parameter `t = 0`), metres.
    pub fn baseline_point_m(&self) -> Vector2<f64> {
        self.baseline_point_m
    }

    /// The baseline direction from the ground x-axis, radians.
    pub fn direction_rad(&self) -> f64 {
        self.direction_rad
    }

    /// The amplitude, metres.
    pub fn amplitude_m(&self) -> f64 {
        self.amplitude_m
    }

    /// The spatial frequency, cycles per metre.
    pub fn frequency_per_m(&self) -> f64 {
        self.frequency_per_m
    }

    /// The wavelength `1 / f`, metres.
    pub fn wavelength_m(&self) -> f64 {
        1.0 / self.frequency_per_m
    }

    /// The phase, radians.
    pub fn phase_rad(&self) -> f64 {
        self.phase_rad
    }

    /// Which side is solid.
    pub fn solid_side(&self) -> SolidSide {
        self.solid
    }

    /// The curve point at parameter `t_m` (ground frame).
    pub fn point_at_m(&self, t_m: f64) -> Vector2<f64> {
        self.baseline_point_m + self.u * t_m + self.v * self.g(t_m)
    }

    /// The arclength from `t = 0` to `t = t_m` (negative for `t_m < 0`), metres.
    pub fn arclength_at_m(&self, t_m: f64) -> f64 {
        let wavelength_m = self.wavelength_m();
        let periods = (t_m / wavelength_m).floor();
        let rest_m = (t_m - periods * wavelength_m).clamp(0.0, wavelength_m);
        let step = wavelength_m / ARCLENGTH_TABLE_INTERVALS as f64;
        let j = ((rest_m / step) as usize).min(ARCLENGTH_TABLE_INTERVALS - 1);
        let period_m = self.arclength_table_m[ARCLENGTH_TABLE_INTERVALS];
        periods * period_m
            + self.arclength_table_m[j]
            + self.arclength_between(&GAUSS_3, j as f64 * step, rest_m)
    }

    /// `g(t) = A sin(k t + phase)`.
    fn g(&self, t: f64) -> f64 {
        self.amplitude_m * (self.wavenumber_rad_per_m * t + self.phase_rad).sin()
    }

    /// `(g, g', g'')` at `t`.
    fn g_derivatives(&self, t: f64) -> (f64, f64, f64) {
        let k = self.wavenumber_rad_per_m;
        let (sin, cos) = (k * t + self.phase_rad).sin_cos();
        let a = self.amplitude_m;
        (a * sin, a * k * cos, -a * k * k * sin)
    }

    /// `int_t0^t1 sqrt(1 + g'^2) dt` by the Gauss-Legendre rule `rule` (for short
    /// intervals: [`GAUSS_5`] for the table's, [`GAUSS_3`] within one of them, whose
    /// `1 / 256` of a period leaves it an error of order `1e-20` m).
    fn arclength_between(&self, rule: &[(f64, f64)], t0: f64, t1: f64) -> f64 {
        let (mid, half) = (0.5 * (t0 + t1), 0.5 * (t1 - t0));
        rule.iter()
            .map(|&(x, w)| {
                // g' alone: a cos, not a sin_cos.
                let k = self.wavenumber_rad_per_m;
                let slope = self.amplitude_m * k * (k * (mid + half * x) + self.phase_rad).cos();
                w * (1.0 + slope * slope).sqrt()
            })
            .sum::<f64>()
            * half
    }

    /// `+1` if free space is at larger baseline-frame `y` (above the curve), else `-1`.
    fn free_sign(&self) -> f64 {
        match self.solid {
            SolidSide::Left => -1.0,
            SolidSide::Right => 1.0,
        }
    }

    /// The query point in the baseline frame `(x, y)`.
    fn local(&self, p_m: &Vector2<f64>) -> (f64, f64) {
        let r = p_m - self.baseline_point_m;
        (self.u.dot(&r), self.v.dot(&r))
    }

    /// The nearest curve parameter to the baseline-frame point `(x, y)` and the squared
    /// distance.
    fn nearest(&self, x: f64, y: f64) -> (f64, f64) {
        let r0 = (y - self.g(x)).abs();
        if !r0.is_finite() {
            return (x, f64::NAN);
        }
        if r0 == 0.0 || self.amplitude_m == 0.0 {
            return (x, r0 * r0);
        }
        let d2 = |t: f64| {
            let dy = self.g(t) - y;
            (t - x) * (t - x) + dy * dy
        };
        let band = (y.abs() - self.amplitude_m).max(0.0);
        let band2 = band * band;
        let h = (self.wavelength_m() / SAMPLES_PER_WAVELENGTH).min(0.25 * r0);
        let mut best = (x, r0 * r0);
        // Over the bracket `|t - x| <= r0`, `|g - y| <= r0 (1 + A k)`, so that
        // `D'' / 2 = 1 + g'^2 + (g - y) g'' >= 1 - r0 (1 + A k) A k^2`: where that product
        // is at most TWO_MINIMA_FRACTION, `D` is convex over the bracket and its one minimum
        // is next to its samples' discrete minimum.
        let (a, k) = (self.amplitude_m, self.wavenumber_rad_per_m);
        let two_minima = r0 * (1.0 + a * k) * a * k * k > TWO_MINIMA_FRACTION;
        if !two_minima {
            // `D` is convex over the bracket, which holds its one minimum (`D(x) = r0^2` and
            // `D > r0^2` outside): Newton's method from `x`, safeguarded by the bracket,
            // without a scan (a point near the wall: every contact's).
            let t = self.refine_bracketed(x, y, x - r0, x + r0, x, true);
            return (t, d2(t));
        }
        // `D(t)` and, where two minima can be near, `D'(t) / 2` (else `0`).
        let sample = |t: f64| {
            if two_minima {
                let (g, g1, _) = self.g_derivatives(t);
                let dy = g - y;
                ((t - x) * (t - x) + dy * dy, (t - x) + dy * g1)
            } else {
                (d2(t), 0.0)
            }
        };
        // `D'(x) / 2`, where both directions' scans start (only where it is read).
        let start_d1 = if two_minima { sample(x).1 } else { 0.0 };
        for direction in [1.0, -1.0] {
            // Samples t_i = x + direction * i h, i = -1, 0, 1, ...; a discrete local minimum
            // at the middle of three is refined, and so is every interval between two
            // samples over which `D'` turns from falling to rising: deep in the solid, past
            // the centre of curvature of a crest, `D` has two minima a few millimetres apart
            // on either side of the crest, nearly level with the maximum between them, and
            // the samples may show only one of them as a discrete minimum (a point 8.8 mm
            // into a wall of 37 mm amplitude and 9.1 cycles/m came out 4 um too deep).
            let mut prev2 = (x - direction * h, d2(x - direction * h));
            let mut prev = (x, best.1);
            let mut prev_d1 = start_d1;
            let mut i = 1.0;
            for _ in 0..MAX_SCAN_STEPS {
                let t = x + direction * i * h;
                let (here_d2, here_d1) = sample(t);
                let here = (t, here_d2);
                if prev.1 <= prev2.1 && prev.1 <= here.1 {
                    let refined = self.refine(x, y, prev.0 - h, prev.0 + h, prev.0);
                    let candidate = (refined, d2(refined));
                    for c in [candidate, prev] {
                        if c.1 < best.1 {
                            best = c;
                        }
                    }
                }
                // The interval between `prev` and `here`, in increasing `t`.
                let (lo, lo_d1, hi, hi_d1) = if direction > 0.0 {
                    (prev.0, prev_d1, t, here_d1)
                } else {
                    (t, here_d1, prev.0, prev_d1)
                };
                if two_minima && lo_d1 < 0.0 && hi_d1 > 0.0 {
                    let refined = self.refine(x, y, lo, hi, 0.5 * (lo + hi));
                    let candidate = (refined, d2(refined));
                    if candidate.1 < best.1 {
                        best = candidate;
                    }
                }
                prev_d1 = here_d1;
                let offset = prev.0 - x;
                if offset * offset + band2 > best.1 {
                    break;
                }
                prev2 = prev;
                prev = here;
                i += 1.0;
            }
        }
        best
    }

    /// Newton's method on `D'(t) = 2 ((t - x) + (g - y) g')` in `[lo, hi]` from `t`,
    /// safeguarded by bisection when `D'` changes sign over the bracket.
    fn refine(&self, x: f64, y: f64, lo: f64, hi: f64, t: f64) -> f64 {
        self.refine_bracketed(x, y, lo, hi, t, false)
    }

    /// [`Self::refine`]; with `convex`, `D` is known to be convex over `[lo, hi]` with its
    /// minimum inside, so that `D'` changes sign over it without evaluating it at the ends.
    fn refine_bracketed(
        &self,
        x: f64,
        y: f64,
        mut lo: f64,
        mut hi: f64,
        mut t: f64,
        convex: bool,
    ) -> f64 {
        let derivative = |t: f64| {
            let (g, g1, g2) = self.g_derivatives(t);
            ((t - x) + (g - y) * g1, 1.0 + g1 * g1 + (g - y) * g2)
        };
        // `D'` at the bracket's ends where evaluated (NaN where only known by sign): a
        // rejected Newton step takes the secant between them before halving, so that a root
        // at an end of the bracket (a scan sample on the minimum) is not approached by
        // halvings alone (40 of them were seen).
        let (mut f_lo, mut f_hi) = if convex {
            (f64::NAN, f64::NAN)
        } else {
            (derivative(lo).0, derivative(hi).0)
        };
        let bracketed = convex || (f_lo < 0.0 && f_hi > 0.0);
        for _ in 0..100 {
            let (f, fp) = derivative(t);
            if f == 0.0 {
                break;
            }
            if bracketed {
                if f < 0.0 {
                    (lo, f_lo) = (t, f);
                } else {
                    (hi, f_hi) = (t, f);
                }
            }
            let newton = t - f / fp;
            if fp > 0.0 && (newton - t).abs() <= 1e-15 * (1.0 + t.abs()) {
                // Converged: the step is below the resolution of `t`. (Tested before the
                // bracket: a root found with `f` rounded to the bracket's side is the
                // bracket's end, and a step "outside" it sent the search back to halvings,
                // some 20 of them, in most queries.)
                t = newton;
                break;
            }
            let next = if fp > 0.0 && newton > lo && newton < hi {
                newton
            } else if bracketed {
                let secant = lo - f_lo * (hi - lo) / (f_hi - f_lo);
                if secant > lo && secant < hi {
                    secant
                } else {
                    0.5 * (lo + hi)
                }
            } else {
                // No sign change to trust: keep the sample.
                return t;
            };
            let done = (next - t).abs() <= 1e-15 * (1.0 + t.abs());
            t = next;
            if done {
                break;
            }
        }
        t
    }

    /// The wall point at curve parameter `t` for a query point at baseline-frame height `y`
    /// and squared distance `d2`.
    fn wall_point(&self, t: f64, x: f64, y: f64, d2: f64) -> WallPoint {
        let (_, slope, curve) = self.g_derivatives(t);
        let tangent = (self.u + self.v * slope).normalize();
        let vertical = y - self.g(x);
        let gap_abs = d2.sqrt();
        let gap_m = if self.free_sign() * vertical >= 0.0 {
            gap_abs
        } else {
            -gap_abs
        };
        WallPoint {
            gap_m,
            closest_m: self.point_at_m(t),
            normal: self.solid.free_normal(&tangent),
            tangent,
            arclength_m: self.arclength_at_m(t),
            curvature_per_m: self.signed_curvature(slope, curve),
        }
    }

    /// The curvature of the curve where `g' = slope` and `g'' = curve`, signed positive where
    /// it bulges into free space.
    fn signed_curvature(&self, slope: f64, curve: f64) -> f64 {
        -self.free_sign() * curve / (1.0 + slope * slope).powf(1.5)
    }

    /// The phase `k t + phase` of the tangent point of crest `index` for a segment of
    /// baseline-frame slope `slope`, or `None` where the segment is steeper than the curve
    /// ever is (no tangent point bulging into free space).
    fn crest_phase(&self, index: i64, slope: f64) -> Option<f64> {
        let slope_amplitude = self.amplitude_m * self.wavenumber_rad_per_m;
        if slope_amplitude.is_nan() || slope_amplitude <= 0.0 || !slope.is_finite() {
            return None;
        }
        let c = slope / slope_amplitude;
        if c.is_nan() || c.abs() >= 1.0 {
            return None;
        }
        // g' = A k cos(u); the crest bulges into free space where -free g'' > 0, i.e.
        // free * sin(u) > 0.
        let u = self.free_sign() * c.acos();
        Some(u + TAU * index as f64)
    }

    /// The segment `a -> b` resting on crest `index` (see [`FeatureContact`]): the curve
    /// point whose tangent is parallel to the segment on the part of that period that bulges
    /// into free space. `None` for a segment steeper than the curve can be, or of no length.
    pub fn crest_feature_contact(
        &self,
        index: i64,
        a_m: &Vector2<f64>,
        b_m: &Vector2<f64>,
    ) -> Option<FeatureContact> {
        self.crest_feature_contact_where(index, a_m, b_m, |_, _| true)
    }

    /// [`Self::crest_feature_contact`] if `keep(gap_m, s)`, else `None`, the rest of the
    /// contact (its arclength, its roll) measured only for a crest kept.
    fn crest_feature_contact_where(
        &self,
        index: i64,
        a_m: &Vector2<f64>,
        b_m: &Vector2<f64>,
        keep: impl Fn(f64, f64) -> bool,
    ) -> Option<FeatureContact> {
        let d = b_m - a_m;
        let length2 = d.norm_squared();
        if !(length2 > 0.0 && length2.is_finite()) {
            return None;
        }
        let (dx, dy) = (self.u.dot(&d), self.v.dot(&d));
        if dx == 0.0 {
            return None;
        }
        let u = self.crest_phase(index, dy / dx)?;
        let k = self.wavenumber_rad_per_m;
        let t = (u - self.phase_rad) / k;
        let (_, slope, curve) = self.g_derivatives(t);
        let wall_m = self.point_at_m(t);
        let s = (wall_m - a_m).dot(&d) / length2;
        let point_m = a_m + d * s;
        let tangent_curve = (self.u + self.v * slope).normalize();
        let normal = self.solid.free_normal(&tangent_curve);
        let gap_m = normal.dot(&(point_m - wall_m));
        if !keep(gap_m, s) {
            return None;
        }
        // The tangent point rolls along the curve as the segment turns: with nu = -normal
        // (toward the wall) = sigma R90 dir, dt/dphi = sigma (dir . w') / (nu . w'').
        let dir = d / length2.sqrt();
        let nu = -normal;
        let sigma = nu.dot(&Vector2::new(-dir.y, dir.x));
        let w1 = self.u + self.v * slope;
        let w2 = self.v * curve;
        let nu_w2 = nu.dot(&w2);
        let roll_m_per_rad = if nu_w2 != 0.0 {
            let dt_dphi = sigma * dir.dot(&w1) / nu_w2;
            dir.dot(&w1) * dt_dphi
        } else {
            0.0
        };
        Some(FeatureContact {
            feature: ConvexFeature::Crest { index },
            s,
            point_m,
            wall_m,
            gap_m,
            normal,
            tangent: self.solid.tangent_from_normal(&normal),
            arclength_m: self.arclength_at_m(t),
            roll_m_per_rad,
            curvature_per_m: self.signed_curvature(slope, curve),
            supported: true,
        })
    }

    /// The crests that could press on the segment `a -> b` with a gap below `within_m`,
    /// appended to `out`: those whose tangent point lies within a period of the segment's
    /// extent along the baseline.
    pub fn features_near_segment(
        &self,
        a_m: &Vector2<f64>,
        b_m: &Vector2<f64>,
        within_m: f64,
        out: &mut Vec<FeatureContact>,
    ) {
        if self.amplitude_m == 0.0 || self.band_gap_lower_bound_m(a_m, b_m) > within_m {
            return;
        }
        let (xa, _) = self.local(a_m);
        let (xb, _) = self.local(b_m);
        let k = self.wavenumber_rad_per_m;
        let reach = within_m.max(0.0) + self.wavelength_m();
        let u_lo = k * (xa.min(xb) - reach) + self.phase_rad;
        let u_hi = k * (xa.max(xb) + reach) + self.phase_rad;
        let first = (u_lo / TAU).floor() as i64 - 1;
        let last = (u_hi / TAU).ceil() as i64 + 1;
        let mut index = first;
        while index <= last && index - first < i64::from(MAX_SCAN_STEPS) {
            if let Some(c) = self.crest_feature_contact_where(index, a_m, b_m, |gap_m, s| {
                gap_m < within_m && s > -1.0 && s < 2.0
            }) {
                out.push(c);
            }
            index += 1;
        }
    }

    /// The signed distance and true Euclidean nearest point (see [`WallPoint`] and the module
    /// docs); no allocation.
    pub fn signed_distance(&self, p_m: &Vector2<f64>) -> WallPoint {
        let (x, y) = self.local(p_m);
        let (t, d2) = self.nearest(x, y);
        self.wall_point(t, x, y, d2)
    }

    /// The deepest (or closest) point of `a -> b` (see the module docs); no allocation.
    pub fn segment_contact(&self, a_m: &Vector2<f64>, b_m: &Vector2<f64>) -> SegmentContact {
        // The end that may be nearer first; the other is searched only if its lower bound
        // does not already put it farther (strictly: a tie goes to `better`).
        let bound_a = self.point_gap_lower_bound_m(a_m);
        let bound_b = self.point_gap_lower_bound_m(b_m);
        let (first, second, second_bound) = if bound_b < bound_a {
            (1.0, 0.0, bound_a)
        } else {
            (0.0, 1.0, bound_b)
        };
        let near = self.at(a_m, b_m, first);
        let ends = if second_bound > near.wall.gap_m {
            near
        } else {
            better(near, self.at(a_m, b_m, second))
        };
        self.interior_candidates(a_m, b_m, ends.wall.gap_m, false)
            .map_or(ends, |inner| better(ends, inner))
    }

    /// A lower bound of the signed distance of `p_m` from its vertical gap (see
    /// [`Self::segment_gap_lower_bound_m`]); one `sin`.
    fn point_gap_lower_bound_m(&self, p_m: &Vector2<f64>) -> f64 {
        let (x, y) = self.local(p_m);
        self.gap_bound_of_vertical(self.free_sign() * (y - self.g(x)))
    }

    /// The deepest of the segment's interior candidate points (`0 < s < 1`: crest crossings
    /// and the points facing a parallel tangent), or `None`; no allocation.
    pub fn segment_interior_contact(
        &self,
        a_m: &Vector2<f64>,
        b_m: &Vector2<f64>,
    ) -> Option<SegmentContact> {
        // The ends' vertical gaps bound their distances from above: a looser search bound
        // than the distances, without a nearest-point search at each end.
        let free = self.free_sign();
        let vertical = |p: &Vector2<f64>| {
            let (x, y) = self.local(p);
            free * (y - self.g(x))
        };
        self.interior_candidates(a_m, b_m, vertical(a_m).min(vertical(b_m)), true)
    }

    /// The point of `a -> b` at `s` with its wall point.
    fn at(&self, a_m: &Vector2<f64>, b_m: &Vector2<f64>, s: f64) -> SegmentContact {
        let point_m = lerp(a_m, b_m, s);
        SegmentContact {
            s,
            point_m,
            wall: self.signed_distance(&point_m),
        }
    }

    /// The deepest interior candidate of `a -> b`; `ends_gap_m` is the smaller gap of its
    /// ends, or an upper bound on it. With `local_foot`, a stationary point's wall point is
    /// the foot it was found from (the curve point whose normal it lies on: the contact
    /// solver's view, continuous and without a nearest-point search), else the nearest point
    /// of the whole curve.
    fn interior_candidates(
        &self,
        a_m: &Vector2<f64>,
        b_m: &Vector2<f64>,
        ends_gap_m: f64,
        local_foot: bool,
    ) -> Option<SegmentContact> {
        let mut best: Option<SegmentContact> = None;
        if self.amplitude_m == 0.0 {
            return None;
        }
        let (xa, ya) = self.local(a_m);
        let (xb, yb) = self.local(b_m);
        let (dx, dy) = (xb - xa, yb - ya);
        let (x_min, x_max) = (xa.min(xb), xa.max(xb));
        let k = self.wavenumber_rad_per_m;
        let a = self.amplitude_m;
        let slope_amplitude = a * k;
        let slope = if dx != 0.0 { dy / dx } else { f64::INFINITY };
        let each = |lo: f64, hi: f64, base: f64, f: &mut dyn FnMut(f64)| {
            self.each_phase(lo, hi, base, f);
        };
        let roots = if slope.abs() <= slope_amplitude {
            let theta = (slope / slope_amplitude).clamp(-1.0, 1.0).acos();
            [Some(theta), Some(-theta)]
        } else {
            [None, None]
        };
        // Lowest vertical gap along the segment (sign-equivalent to the signed distance): its
        // candidates are the ends and the vertical points where g' = slope.
        let lowest = self.lowest_vertical_gap((xa, ya), (xb, yb));
        // The nearest parameter of any segment point s* that beats the ends lies within
        // |t - x(s*)| <= |F(s*)|: at most the best end gap if the segment stays free, at most
        // the deepest vertical penetration otherwise.
        let reach = if lowest >= 0.0 {
            ends_gap_m.max(0.0)
        } else {
            -lowest
        };
        let (lo, hi) = (x_min - reach, x_max + reach);
        let d_len2 = dx * dx + dy * dy;
        // Without `local_foot` every candidate's gap is its nearest point's: one whose lower
        // bound is above the ends' gap and the best candidate's so far cannot be the
        // deepest (strictly: ties are `better`'s), and is not searched.
        let beyond = |best: &Option<SegmentContact>, p_m: &Vector2<f64>| {
            let above = best.map_or(ends_gap_m, |b| b.wall.gap_m.min(ends_gap_m));
            !local_foot && self.point_gap_lower_bound_m(p_m) > above
        };
        // Crests: segment crossings of the vertical lines through the extrema.
        if dx != 0.0 {
            for base in [FRAC_PI_2, FRAC_PI_2 + PI] {
                each(lo.max(x_min), hi.min(x_max), base, &mut |t| {
                    let s = (t - xa) / dx;
                    if s > 0.0 && s < 1.0 {
                        if beyond(&best, &lerp(a_m, b_m, s)) {
                            return;
                        }
                        let c = self.at(a_m, b_m, s);
                        best = Some(best.map_or(c, |b| better(b, c)));
                    }
                });
            }
            // Stationary points: the curve tangent at t parallel to the segment; the segment
            // point on the curve normal there.
            for root in roots.iter().flatten() {
                each(lo, hi, *root, &mut |t| {
                    let (g, g1, _) = self.g_derivatives(t);
                    // Normal direction (-g', 1) in the baseline frame.
                    let (nx, ny) = (-g1, 1.0);
                    let (cx, cy) = (t - xa, g - ya);
                    let denom = dx * ny - dy * nx;
                    if denom != 0.0 && d_len2 > 0.0 {
                        let s = (cx * ny - cy * nx) / denom;
                        if s > 0.0 && s < 1.0 {
                            if beyond(&best, &lerp(a_m, b_m, s)) {
                                return;
                            }
                            let c = if local_foot {
                                let point_m = lerp(a_m, b_m, s);
                                let (x, y) = self.local(&point_m);
                                let d2 = (t - x) * (t - x) + (g - y) * (g - y);
                                SegmentContact {
                                    s,
                                    point_m,
                                    wall: self.wall_point(t, x, y, d2),
                                }
                            } else {
                                self.at(a_m, b_m, s)
                            };
                            best = Some(best.map_or(c, |b| better(b, c)));
                        }
                    }
                });
            }
        }
        best
    }

    /// A lower bound on the gap of every point of `a -> b`, without a nearest-point search:
    /// its height beyond the band `|y| <= A` on the free side where it is beyond the band,
    /// else its lowest vertical gap along it (at its ends or where the curve's slope is the
    /// segment's) as a distance ([`Self::gap_bound_of_vertical`]).
    pub(crate) fn segment_gap_lower_bound_m(&self, a_m: &Vector2<f64>, b_m: &Vector2<f64>) -> f64 {
        let free = self.free_sign();
        let (xa, ya) = self.local(a_m);
        let (xb, yb) = self.local(b_m);
        let beyond = (free * ya).min(free * yb) - self.amplitude_m;
        if beyond > 0.0 {
            return beyond;
        }
        self.gap_bound_of_vertical(self.lowest_vertical_gap((xa, ya), (xb, yb)))
    }

    /// A lower bound of the signed distance of a point at vertical gap `r`: a point `r > 0`
    /// above the graph of a function of slope at most `L = A k` is at least
    /// `r / sqrt(1 + L^2)` from it, and one `r < 0` below it at most `|r|` into it.
    fn gap_bound_of_vertical(&self, r: f64) -> f64 {
        if r > 0.0 {
            let slope_amplitude = self.amplitude_m * self.wavenumber_rad_per_m;
            r / (1.0 + slope_amplitude * slope_amplitude).sqrt()
        } else {
            r
        }
    }

    /// The height of `a -> b` beyond the band `|y| <= A` on the free side (`-inf` if it
    /// reaches into the band): a lower bound of the gap of the segment's line near it.
    fn band_gap_lower_bound_m(&self, a_m: &Vector2<f64>, b_m: &Vector2<f64>) -> f64 {
        let free = self.free_sign();
        let (_, ya) = self.local(a_m);
        let (_, yb) = self.local(b_m);
        let beyond = (free * ya).min(free * yb) - self.amplitude_m;
        if beyond > 0.0 {
            beyond
        } else {
            f64::NEG_INFINITY
        }
    }

    /// The lowest vertical gap `free (y - g(x))` along the baseline-frame segment `a -> b`:
    /// at its ends or where `g'` is the segment's slope (NaN for a NaN end).
    fn lowest_vertical_gap(&self, (xa, ya): (f64, f64), (xb, yb): (f64, f64)) -> f64 {
        let free = self.free_sign();
        let vertical = |x: f64, y: f64| free * (y - self.g(x));
        let ends = vertical(xa, ya);
        let end_b = vertical(xb, yb);
        if ends.is_nan() || end_b.is_nan() {
            return f64::NAN;
        }
        let mut lowest = ends.min(end_b);
        let dx = xb - xa;
        if dx == 0.0 || self.amplitude_m == 0.0 {
            return lowest;
        }
        let slope = (yb - ya) / dx;
        let slope_amplitude = self.amplitude_m * self.wavenumber_rad_per_m;
        // (A NaN slope has no roots either.)
        if slope.is_nan() || slope.abs() > slope_amplitude {
            return lowest;
        }
        let theta = (slope / slope_amplitude).clamp(-1.0, 1.0).acos();
        let (x_min, x_max) = (xa.min(xb), xa.max(xb));
        for root in [theta, -theta] {
            self.each_phase(x_min, x_max, root, &mut |t| {
                let y = ya + (t - xa) * slope;
                lowest = lowest.min(vertical(t, y));
            });
        }
        lowest
    }

    /// Calls `f` with every parameter `t` in `[lo, hi]` where `k t + phase = base + 2 pi j`
    /// (at most [`MAX_SCAN_STEPS`] of them).
    fn each_phase(&self, lo: f64, hi: f64, base: f64, f: &mut dyn FnMut(f64)) {
        let (k, phase) = (self.wavenumber_rad_per_m, self.phase_rad);
        let j0 = ((k * lo + phase - base) / TAU).ceil();
        let j1 = ((k * hi + phase - base) / TAU).floor();
        let mut j = j0;
        while j <= j1 && j - j0 < f64::from(MAX_SCAN_STEPS) {
            f((base + TAU * j - phase) / k);
            j += 1.0;
        }
    }

    /// The first point of the ray `origin + t direction`, `t` in `[0, max_m]`, on the curve.
    ///
    /// In the baseline frame the ray is `(x0 + t dx, y0 + t dy)` and its vertical offset
    /// from the curve, `f(t) = y0 + t dy - g(x0 + t dx)`, is zero exactly where it meets the
    /// curve (a graph over its baseline). Only the stretch of the ray within the band
    /// `|y| <= A` can meet it. `f` is stationary where `g'(x) = dy / dx`, at phases known in
    /// closed form (`k x + phase = +-acos(dy / (A k dx)) + 2 pi j`, none for a ray steeper
    /// than the curve ever is): between successive stationary points `f` is monotone, so
    /// each such piece holds at most one crossing, bracketed by a sign change of `f` at its
    /// ends and refined by bisection to `1e-12` m; the first piece that holds one gives the
    /// hit. No crossing is missed however close two of them lie (a ray grazing a crest), and
    /// a ray touching a crest tangentially hits it where `|f|` at the stationary point is
    /// within rounding of zero (`1e-13` of the amplitude plus the height). At most 65,536
    /// pieces are visited (a ray thousands of wavelengths long inside the band): beyond
    /// them, `None`. No allocation. `None` as well for no hit or not a ray
    /// (see [`super::Wall::ray_hit_m`]).
    pub fn ray_hit_m(
        &self,
        origin_m: &Vector2<f64>,
        direction: &Vector2<f64>,
        max_m: f64,
    ) -> Option<f64> {
        if !ray_is_valid(origin_m, direction, max_m) {
            return None;
        }
        let (x0, y0) = self.local(origin_m);
        let (dx, dy) = (self.u.dot(direction), self.v.dot(direction));
        let a = self.amplitude_m;
        let k = self.wavenumber_rad_per_m;
        let f = |t: f64| y0 + t * dy - self.g(x0 + t * dx);
        // The stretch of the ray within the band (with a rounding's slack).
        let band = a * (1.0 + 1e-12) + 1e-15;
        let (mut t_lo, mut t_hi) = (0.0_f64, max_m);
        if dy == 0.0 {
            if y0.abs() > band {
                return None;
            }
        } else {
            let (ta, tb) = ((-band - y0) / dy, (band - y0) / dy);
            t_lo = t_lo.max(ta.min(tb));
            t_hi = t_hi.min(ta.max(tb));
        }
        if t_lo > t_hi {
            return None;
        }
        let touch = 1e-13 * (a + 2.0 * y0.abs());
        // The stationary points of f in (t_lo, t_hi), in increasing t: two sequences (the
        // phases base = +theta and -theta, each every period), merged as they are walked.
        // Each is (its next t, its j): t at phase base + 2 pi j.
        let slope_amplitude = a * k * dx.abs();
        let stationary = slope_amplitude > dy.abs() && dx != 0.0;
        let theta = if stationary {
            (dy / (a * k * dx)).clamp(-1.0, 1.0).acos()
        } else {
            0.0
        };
        let bases = [theta, -theta];
        let step = dx.signum();
        let t_of = |base: f64, j: f64| ((base + TAU * j - self.phase_rad) / k - x0) / dx;
        let mut sequences: [Option<(f64, f64)>; 2] = [None, None];
        if stationary {
            for (slot, &base) in sequences.iter_mut().zip(&bases) {
                // The first j whose t exceeds t_lo: from two periods before it, on.
                let j_at_lo = ((k * (x0 + t_lo * dx) + self.phase_rad - base) / TAU).floor();
                let mut j = j_at_lo - 2.0 * step;
                let mut t = t_of(base, j);
                let mut guard = 0;
                while t <= t_lo && guard < 8 {
                    j += step;
                    t = t_of(base, j);
                    guard += 1;
                }
                if t.is_finite() && t > t_lo {
                    *slot = Some((t, j));
                }
            }
        }
        let mut ta = t_lo;
        let mut fa = f(ta);
        for _ in 0..MAX_SCAN_STEPS {
            if fa == 0.0 {
                return Some(ta);
            }
            // The next stationary point, or the stretch's end.
            let next = (0..2)
                .filter_map(|i| sequences[i].map(|(t, _)| (i, t)))
                .filter(|&(_, t)| t < t_hi)
                .min_by(|p, q| p.1.total_cmp(&q.1));
            let tb = next.map_or(t_hi, |(_, t)| t);
            let fb = f(tb);
            if fb != 0.0 && fa.signum() != fb.signum() {
                return Some(bisect_root(&f, ta, fa, tb));
            }
            if fb.abs() <= touch {
                return Some(tb);
            }
            let (i, _) = next?;
            if let Some((t, j)) = sequences[i].as_mut() {
                *j += step;
                *t = t_of(bases[i], *j);
            }
            ta = tb;
            fa = fb;
        }
        None
    }

    /// The sinusoid reflected `y -> -y` (ground frame): baseline point and direction
    /// reflected, the phase moved by half a period (the reflected `v` is minus the new
    /// baseline's), solid on the other side so that the reflected points of the solid are
    /// solid (a reflection flips the orientation); arclength is kept: a point's mirror image
    /// has its arclength (the speed `sqrt(1 + g'^2)` is unchanged by the half period).
    pub fn mirrored_about_x_axis(&self) -> Sinusoid {
        let mut mirrored = self.clone();
        mirrored.baseline_point_m = Vector2::new(self.baseline_point_m.x, -self.baseline_point_m.y);
        mirrored.direction_rad = -self.direction_rad;
        mirrored.u = Vector2::new(self.u.x, -self.u.y);
        mirrored.v = Vector2::new(-self.v.x, self.v.y);
        mirrored.phase_rad = if self.phase_rad > 0.0 {
            self.phase_rad - PI
        } else {
            self.phase_rad + PI
        };
        mirrored.solid = self.solid.swapped();
        mirrored
    }

    /// Moves the sinusoid by `offset_m` (arclength stays measured from the moved baseline
    /// point).
    pub fn translate(&mut self, offset_m: Vector2<f64>) {
        self.baseline_point_m += offset_m;
    }

    /// A copy moved by `offset_m`.
    pub fn translated(&self, offset_m: Vector2<f64>) -> Sinusoid {
        let mut moved = self.clone();
        moved.translate(offset_m);
        moved
    }
}

/// A root of `f` in `[lo, hi]` where `f(lo) = f_lo` and `f(hi)` have opposite signs, by
/// bisection to `1e-12` (or until the interval cannot be halved in floating point).
fn bisect_root(f: &impl Fn(f64) -> f64, mut lo: f64, mut f_lo: f64, mut hi: f64) -> f64 {
    for _ in 0..200 {
        if hi - lo <= 1e-12 {
            break;
        }
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        let f_mid = f(mid);
        if f_mid == 0.0 {
            return mid;
        }
        if f_mid.signum() == f_lo.signum() {
            lo = mid;
            f_lo = f_mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}
