//! Lower bounds of a sinusoid's signed distance without a nearest-point search, from the
//! vertical gap to the curve (a graph over its baseline) and the band `|y| <= A` it lies in:
//! the broad phase, and the cut-offs of the segment and crest searches.

use nalgebra::Vector2;

use super::Sinusoid;

impl Sinusoid {
    /// A lower bound of the signed distance of `p_m` from its vertical gap (see
    /// [`Self::segment_gap_lower_bound_m`]); one `sin`.
    pub(super) fn point_gap_lower_bound_m(&self, p_m: &Vector2<f64>) -> f64 {
        let (x, y) = self.local(p_m);
        self.gap_bound_of_vertical(self.free_sign() * (y - self.g(x)))
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
    pub(super) fn band_gap_lower_bound_m(&self, a_m: &Vector2<f64>, b_m: &Vector2<f64>) -> f64 {
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
    pub(super) fn lowest_vertical_gap(&self, (xa, ya): (f64, f64), (xb, yb): (f64, f64)) -> f64 {
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
}
