//! The deepest (or closest) point of a segment against a sinusoid.
//!
//! **Segments.** Along a segment the signed distance `F(s)` has stationary points only where
//! the curve's tangent at the nearest point is parallel to the segment (`g'(t) = slope`, solved
//! in closed form and mapped back along the curve normal: a crest inside a link) and kinks only
//! on the solid's medial axis, which lies on the vertical lines through the crests. Those
//! points, and the segment ends, are the candidates; each is evaluated exactly.

use core::f64::consts::{FRAC_PI_2, PI};

use nalgebra::Vector2;

use super::Sinusoid;
use crate::walls::{SegmentContact, better, lerp};

impl Sinusoid {
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
}
