//! The crests of a sinusoid, the features that can press on a link between its ends: the
//! tangent point of a crest for a segment's direction, a segment resting on it, and the
//! crests near a segment.

use core::f64::consts::TAU;

use nalgebra::Vector2;

use super::{MAX_SCAN_STEPS, Sinusoid};
use crate::walls::{ConvexFeature, FeatureContact};

impl Sinusoid {
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
}
