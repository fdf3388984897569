//! The ray query of a sinusoid: crossings bracketed between the stationary points of the
//! ray's offset from the curve, refined by bisection.

use core::f64::consts::TAU;

use nalgebra::Vector2;

use super::{MAX_SCAN_STEPS, Sinusoid};
use crate::walls::ray_is_valid;

impl Sinusoid {
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
    /// (see [`crate::walls::Wall::ray_hit_m`]).
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
