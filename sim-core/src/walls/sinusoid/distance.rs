//! The signed distance to a sinusoid.
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

use nalgebra::Vector2;

use super::{MAX_SCAN_STEPS, Sinusoid};
use crate::walls::WallPoint;

/// Samples per wavelength in the nearest-point scan.
const SAMPLES_PER_WAVELENGTH: f64 = 32.0;

/// A query point whose vertical gap `r0` has `r0 (1 + A k) A k^2` above this (`1 / (A k^2)`
/// is the smallest radius of curvature, `A k` the steepest slope) refines every sample
/// interval over which `D'` turns from falling to rising, not only the discrete minima of
/// its samples ([`Sinusoid::nearest`]); below it `D` is convex over the search's bracket.
const TWO_MINIMA_FRACTION: f64 = 0.5;

impl Sinusoid {
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
    pub(super) fn wall_point(&self, t: f64, x: f64, y: f64, d2: f64) -> WallPoint {
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

    /// The signed distance and true Euclidean nearest point (see [`WallPoint`] and the module
    /// docs); no allocation.
    pub fn signed_distance(&self, p_m: &Vector2<f64>) -> WallPoint {
        let (x, y) = self.local(p_m);
        let (t, d2) = self.nearest(x, y);
        self.wall_point(t, x, y, d2)
    }
}
