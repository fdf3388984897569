//! The convex corners of a polyline, the features that can press on a link between its ends:
//! which vertices are convex, the ones near a wall point or a segment, a segment resting on
//! one, and a point against one of a corner's edges.

use nalgebra::Vector2;

use super::{Polyline, cross};
use crate::walls::{ConvexFeature, FeatureContact, SolidSide, WallPoint};

/// How far outside a corner's normal cone (in the cone's own coordinates, the weights of the
/// two edge normals) a segment's normal still counts as in it: a segment flush with an edge
/// to the solve's precision. A link pressed flat on a digitized wall's edge, resting on the
/// edge's corner with its joint on the wall beyond, ends its solves up to `2e-7` outside the
/// cone; at `1e-9` it lost the corner on every other solve and took turns between the
/// corner and its joint for the whole step (replay `soak:4221:1093`, kept by `soak_sweeps_fixed_since_still_finish`). `1e-6` radians tilts a 9 cm link's
/// far end `9e-8` m at most, which the link's own end pairs hold.
const CONE_ROUNDING: f64 = 1e-6;

impl Polyline {
    /// The convex corners at the ends of the edge that `wall_point` (an answer of
    /// [`Self::signed_distance`]) lies on, or the convex corner it is: `O(log vertices)`.
    pub fn convex_corners_by(&self, wall_point: &WallPoint) -> [Option<usize>; 2] {
        let a = wall_point.arclength_m;
        let convex = |k: usize| self.is_convex(k).then_some(k);
        match self.arclengths_m.binary_search_by(|v| v.total_cmp(&a)) {
            Ok(vertex) => [convex(vertex), None],
            // Between vertices `at - 1` and `at` (before the first or past the last: on an
            // end ray, whose one vertex is not a corner).
            Err(at) => [at.checked_sub(1).and_then(convex), convex(at)],
        }
    }

    /// A point `p_m` against one edge of convex corner `vertex`, the edge taken as its whole
    /// line: the signed distance to the line of the edge arriving at the corner
    /// (`after = false`) or leaving it (`after = true`), with that edge's normal and tangent
    /// (they do not turn: curvature `0`) and the foot on the line. Unlike the distance to the
    /// polyline, it stays smooth as the point passes the corner (past it, the line runs on
    /// through free space: near the corner the solid is where both lines' distances are
    /// negative). `None` if `vertex` is not a convex corner.
    pub fn corner_edge_point(
        &self,
        vertex: usize,
        after: bool,
        p_m: &Vector2<f64>,
    ) -> Option<WallPoint> {
        if !self.is_convex(vertex) {
            return None;
        }
        let edge = if after { vertex } else { vertex - 1 };
        let corner_m = self.vertices_m[vertex];
        let normal = self.normals[edge];
        let tangent = self.tangents[edge];
        let along_m = tangent.dot(&(p_m - corner_m));
        Some(WallPoint {
            gap_m: normal.dot(&(p_m - corner_m)),
            closest_m: corner_m + tangent * along_m,
            normal,
            tangent,
            arclength_m: self.arclengths_m[vertex] + along_m,
            curvature_per_m: 0.0,
        })
    }

    /// Whether interior vertex `k` bulges into free space (its free-side angle is over 180
    /// degrees).
    pub(super) fn is_convex(&self, k: usize) -> bool {
        if k == 0 || k >= self.tangents.len() {
            return false;
        }
        let turn = cross(&self.tangents[k - 1], &self.tangents[k]);
        match self.solid {
            SolidSide::Left => turn > 0.0,
            SolidSide::Right => turn < 0.0,
        }
    }

    /// The segment `a -> b` resting on convex corner `vertex` (see [`FeatureContact`]): the
    /// gap along the segment's normal, oriented into free space, and whether the segment's
    /// normal lies in the corner's normal cone (between the normals of its two edges: a
    /// segment standing steeply beside a corner rests on one of its edges, not on it). `None`
    /// if the corner is not convex or the segment has no length.
    pub fn corner_feature_contact(
        &self,
        vertex: usize,
        a_m: &Vector2<f64>,
        b_m: &Vector2<f64>,
    ) -> Option<FeatureContact> {
        if !self.is_convex(vertex) {
            return None;
        }
        let d = b_m - a_m;
        let length2 = d.norm_squared();
        if !(length2 > 0.0 && length2.is_finite()) {
            return None;
        }
        let dir = d / length2.sqrt();
        let (n1, n2) = (self.normals[vertex - 1], self.normals[vertex]);
        let pseudo = (n1 + n2).normalize();
        let mut normal = Vector2::new(-dir.y, dir.x);
        if normal.dot(&pseudo) < 0.0 {
            normal = -normal;
        }
        let det = cross(&n1, &n2);
        let (alpha, beta) = (cross(&normal, &n2) / det, cross(&n1, &normal) / det);
        // On the cone's boundary (the segment flush with an edge, resting on its corner and
        // along the edge) to rounding: a solve that lays a link flat on an edge ends there.
        let supported = alpha >= -CONE_ROUNDING && beta >= -CONE_ROUNDING;
        let v = self.vertices_m[vertex];
        let s = (v - a_m).dot(&d) / length2;
        let point_m = a_m + d * s;
        Some(FeatureContact {
            feature: ConvexFeature::Corner { vertex },
            s,
            point_m,
            wall_m: v,
            gap_m: normal.dot(&(point_m - v)),
            normal,
            tangent: self.solid.tangent_from_normal(&normal),
            arclength_m: self.arclengths_m[vertex],
            roll_m_per_rad: 0.0,
            curvature_per_m: f64::INFINITY,
            supported,
        })
    }

    /// The convex corners that could press on the segment `a -> b` with a gap below
    /// `within_m`, appended to `out`: those within `within_m` plus half the segment's
    /// length of its bounding box (a corner poking through a segment lies within the
    /// box grown by its depth), whose cone holds the segment's normal; `O(log vertices)`
    /// through the tree where few corners are near.
    pub fn features_near_segment(
        &self,
        a_m: &Vector2<f64>,
        b_m: &Vector2<f64>,
        within_m: f64,
        out: &mut Vec<FeatureContact>,
    ) {
        let reach = within_m.max(0.0) + 0.5 * (b_m - a_m).norm();
        let (lo, hi) = (
            a_m.inf(b_m).add_scalar(-reach),
            a_m.sup(b_m).add_scalar(reach),
        );
        self.corners_in_box(&lo, &hi, |vertex| {
            if let Some(c) = self.corner_feature_contact(vertex, a_m, b_m)
                && c.supported
                && c.gap_m < within_m
            {
                out.push(c);
            }
        });
    }

    /// Calls `visit` with every interior vertex (corner) inside the box `lo_m..hi_m`, in
    /// increasing order: a scan, or the ends of the edges the tree finds near the box.
    pub(super) fn corners_in_box(
        &self,
        lo_m: &Vector2<f64>,
        hi_m: &Vector2<f64>,
        mut visit: impl FnMut(usize),
    ) {
        let inside =
            |v: &Vector2<f64>| v.x >= lo_m.x && v.x <= hi_m.x && v.y >= lo_m.y && v.y <= hi_m.y;
        if self.tree.is_empty() {
            for k in 1..self.tangents.len() {
                if inside(&self.vertices_m[k]) {
                    visit(k);
                }
            }
            return;
        }
        // Corner k ends edge k - 1 and starts edge k: the finite edges `1..edges - 1` the
        // tree holds end at every interior vertex. Adjacent edges share one: each once.
        let mut next = 1;
        self.tree.edges_meeting_box(lo_m, hi_m, |edge| {
            for k in edge.max(next)..=edge + 1 {
                if inside(&self.vertices_m[k]) {
                    visit(k);
                }
            }
            next = edge + 2;
            true
        });
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector2;
    use proptest::prelude::*;

    use crate::walls::{Polyline, SolidSide};

    proptest! {
        /// A segment lying flush on an edge and running on past its convex corner rests on
        /// the corner (its normal on the boundary of the corner's cone, to rounding), at
        /// zero gap: a link laid flat on an edge keeps its corner pair.
        #[test]
        fn a_segment_flush_with_an_edge_rests_on_its_corner(
            turn_deg in 5.0f64..85.0,
            heading_rad in -3.2f64..3.2,
            from in 0.05f64..0.95,
            past in 0.01f64..0.9,
        ) {
            let (c, s) = (heading_rad.cos(), heading_rad.sin());
            let rotate = |x: f64, y: f64| Vector2::new(c * x - s * y, s * x + c * y);
            let turn = turn_deg.to_radians();
            let corner = rotate(0.0, 0.0);
            let wall = Polyline::new(
                vec![
                    rotate(-0.1, 0.0),
                    corner,
                    rotate(0.1 * turn.cos(), -0.1 * turn.sin()),
                ],
                SolidSide::Right,
            )
            .unwrap();
            prop_assert!(wall.is_convex(1));
            let a = rotate(-0.1 * from, 0.0);
            let b = rotate(0.1 * past, 0.0);
            let fc = wall.corner_feature_contact(1, &a, &b).unwrap();
            prop_assert!(fc.supported, "flush segment not supported: {fc:?}");
            prop_assert!(fc.gap_m.abs() < 1e-15, "gap {}", fc.gap_m);
            prop_assert!((fc.point_m - corner).norm() < 1e-15);
        }
    }
}
