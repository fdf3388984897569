//! The ray query of a polyline: every edge and both end rays in closed form.

use nalgebra::Vector2;

use super::{Polyline, cross};
use crate::walls::ray_is_valid;

impl Polyline {
    /// The first point of the ray `origin + t direction`, `t` in `[0, max_m]`, on the
    /// polyline: every edge and both end rays intersected in closed form (an edge accepts a
    /// crossing within `1e-12` m beyond its ends, so that a ray through a vertex is not lost
    /// to rounding between its two edges; a ray running along an edge meets it where it
    /// enters it), the smallest `t`. `None` if the ray meets none, or is not a ray (see
    /// [`crate::walls::Wall::ray_hit_m`]). `O(edges)`, no allocation.
    pub fn ray_hit_m(
        &self,
        origin_m: &Vector2<f64>,
        direction: &Vector2<f64>,
        max_m: f64,
    ) -> Option<f64> {
        if !ray_is_valid(origin_m, direction, max_m) {
            return None;
        }
        const SLACK_M: f64 = 1e-12;
        let mut best: Option<f64> = None;
        for edge in 0..self.tangents.len() {
            let t = self.tangents[edge];
            let r = self.vertices_m[edge] - origin_m;
            let (lo, hi) = self.range_m(edge);
            let denom = cross(direction, &t);
            let hit = if denom.abs() <= 1e-15 {
                // Parallel: a hit only if the ray runs along the edge's line.
                if cross(&r, &t).abs() > SLACK_M {
                    continue;
                }
                // The ray's parameter at the edge's points: d . r + u (d . t), d . t = +-1.
                let along = direction.dot(&t);
                let ends = [
                    direction.dot(&r) + along * lo,
                    direction.dot(&r) + along * hi,
                ];
                let (first, last) = (ends[0].min(ends[1]), ends[0].max(ends[1]));
                if last < 0.0 {
                    continue;
                }
                first.max(0.0)
            } else {
                let ray_t = cross(&r, &t) / denom;
                let u = cross(&r, direction) / denom;
                if !(u >= lo - SLACK_M && u <= hi + SLACK_M) || ray_t < 0.0 {
                    continue;
                }
                ray_t
            };
            if hit <= max_m && best.is_none_or(|b| hit < b) {
                best = Some(hit);
            }
        }
        best
    }
}
