//! The distance queries of a polyline: the nearest feature and the signed distance to it
//! (through the edge hierarchy for a long polyline), the normals the wall can press with at
//! a wall point, and a segment's gap lower bound (the broad phase).

use nalgebra::Vector2;

use super::{Polyline, cross};
use crate::walls::WallPoint;
use crate::walls::edge_tree::{point_segment_distance2, segment_segment_distance2};

/// Which feature of the polyline is nearest.
enum Nearest {
    /// The interior of edge `edge` (or one of the end rays), at `u_m` from its first vertex.
    Edge { edge: usize, u_m: f64 },
    /// An interior vertex.
    Vertex(usize),
}

impl Polyline {
    /// The nearest feature to `p_m` and the squared distance to it: the first edge (by
    /// index) at the least distance. Through the tree, the runs of edges whose bounding box
    /// is farther than the best edge so far are skipped (the answer is the same).
    fn nearest(&self, p_m: &Vector2<f64>) -> (Nearest, f64) {
        let last = self.tangents.len() - 1;
        let mut best = (Nearest::Edge { edge: 0, u_m: 0.0 }, f64::INFINITY);
        let mut best_edge = usize::MAX;
        let consider = |edge: usize, best: &mut (Nearest, f64), best_edge: &mut usize| {
            let (lo, hi) = self.range_m(edge);
            let u = self.tangents[edge].dot(&(p_m - self.vertices_m[edge]));
            let u_m = u.clamp(lo, hi);
            let q = self.vertices_m[edge] + self.tangents[edge] * u_m;
            let d2 = (p_m - q).norm_squared();
            if d2 < best.1 || (d2 == best.1 && edge < *best_edge) {
                let feature = if u_m == 0.0 && edge > 0 {
                    Nearest::Vertex(edge)
                } else if u_m == hi && edge < last {
                    Nearest::Vertex(edge + 1)
                } else {
                    Nearest::Edge { edge, u_m }
                };
                *best = (feature, d2);
                *best_edge = edge;
            }
        };
        if self.tree.is_empty() {
            for edge in 0..=last {
                consider(edge, &mut best, &mut best_edge);
            }
            return best;
        }
        consider(0, &mut best, &mut best_edge);
        consider(last, &mut best, &mut best_edge);
        // The runs that can still hold an edge as near, nearest first (a tight bound early).
        let best = core::cell::RefCell::new((best, best_edge));
        self.tree.edges_near_point(
            p_m,
            || best.borrow().0.1,
            |edge| {
                let (b, e) = &mut *best.borrow_mut();
                consider(edge, b, e);
            },
        );
        best.into_inner().0
    }

    /// The normals the wall can press with at `wall_point` (this polyline's
    /// [`Self::signed_distance`] of some point), as the two ends of their cone: an edge's
    /// own normal twice, or, at an interior vertex or within `within_m` of one along an
    /// edge, the normals of the vertex's two edges (before, after). Found from the point's
    /// arclength, `O(log edges)`, no allocation.
    pub fn normal_cone(&self, wall_point: &WallPoint, within_m: f64) -> [Vector2<f64>; 2] {
        let last = self.tangents.len() - 1;
        let s_m = wall_point.arclength_m;
        // The edge whose stretch of arclength holds the point (the end rays beyond the
        // first and last vertices belong to the end edges).
        let edge = self.arclengths_m[1..=last].partition_point(|&a| a <= s_m);
        let u_m = s_m - self.arclengths_m[edge];
        let vertex = if u_m <= within_m && edge > 0 {
            edge
        } else if u_m >= self.lengths_m[edge] - within_m && edge < last {
            edge + 1
        } else {
            return [self.normals[edge]; 2];
        };
        [self.normals[vertex - 1], self.normals[vertex]]
    }

    /// A lower bound of the signed distance of every point of `a -> b` (see
    /// [`crate::WallShape::segment_gap_lower_bound_m`]): for a long polyline, the segment's
    /// distance to the wall (its end rays, then the runs of edges near it through the tree,
    /// `O(log edges)` where few edges are near) if the segment stays in free space (it does
    /// not meet the wall and its start is free), else its start's gap less its length (the
    /// distance is 1-Lipschitz). A short polyline (fewer than 32 edges) has none (`-inf`):
    /// its search costs what the bound would.
    pub(crate) fn segment_gap_lower_bound_m(&self, a_m: &Vector2<f64>, b_m: &Vector2<f64>) -> f64 {
        if self.tree.is_empty() {
            return f64::NEG_INFINITY;
        }
        let last = self.tangents.len() - 1;
        let best = core::cell::Cell::new(
            self.segment_edge_distance2(0, a_m, b_m)
                .min(self.segment_edge_distance2(last, a_m, b_m)),
        );
        self.tree.edges_near_segment(
            a_m,
            b_m,
            || best.get(),
            |edge| best.set(best.get().min(self.segment_edge_distance2(edge, a_m, b_m))),
        );
        let start_gap_m = self.signed_distance(a_m).gap_m;
        let distance_m = best.get().sqrt();
        if distance_m > 0.0 && start_gap_m > 0.0 {
            // (Less a relative rounding allowance: a bound, never above the true distance.)
            distance_m * (1.0 - 1e-12)
        } else {
            start_gap_m.min(0.0) - (b_m - a_m).norm()
        }
    }

    /// The squared distance between the segment `a -> b` and edge `edge` (an end ray as the
    /// ray it is): 0 where they cross, else that of an end of one to the other.
    fn segment_edge_distance2(&self, edge: usize, a_m: &Vector2<f64>, b_m: &Vector2<f64>) -> f64 {
        let (lo, hi) = self.range_m(edge);
        if lo.is_finite() && hi.is_finite() {
            let (v, w) = (self.vertices_m[edge], self.vertices_m[edge + 1]);
            return segment_segment_distance2(a_m, b_m, &v, &w);
        }
        let (v, t) = (self.vertices_m[edge], self.tangents[edge]);
        let d = b_m - a_m;
        let denom = cross(&d, &t);
        if denom != 0.0 {
            let r = v - a_m;
            let s = cross(&r, &t) / denom;
            let u = cross(&r, &d) / denom;
            if (0.0..=1.0).contains(&s) && u >= lo && u <= hi {
                return 0.0;
            }
        }
        let point_edge = |p: &Vector2<f64>| {
            let u = t.dot(&(p - v)).clamp(lo, hi);
            (v + t * u - p).norm_squared()
        };
        let mut distance2 = point_edge(a_m).min(point_edge(b_m));
        for end_m in [lo, hi] {
            if end_m.is_finite() {
                distance2 = distance2.min(point_segment_distance2(&(v + t * end_m), a_m, b_m));
            }
        }
        distance2
    }

    /// The signed distance and nearest point (see [`WallPoint`]); `O(edges)`, no allocation.
    pub fn signed_distance(&self, p_m: &Vector2<f64>) -> WallPoint {
        match self.nearest(p_m) {
            (Nearest::Edge { edge, u_m }, _) => {
                let closest_m = self.vertices_m[edge] + self.tangents[edge] * u_m;
                WallPoint {
                    gap_m: self.normals[edge].dot(&(p_m - closest_m)),
                    closest_m,
                    normal: self.normals[edge],
                    tangent: self.tangents[edge],
                    arclength_m: self.arclengths_m[edge] + u_m,
                    curvature_per_m: 0.0,
                }
            }
            (Nearest::Vertex(vertex), d2) => {
                let v = self.vertices_m[vertex];
                let pseudo = self.normals[vertex - 1] + self.normals[vertex];
                let pseudo = pseudo / pseudo.norm();
                let r = p_m - v;
                let distance_m = d2.sqrt();
                let sign = if pseudo.dot(&r) < 0.0 { -1.0 } else { 1.0 };
                let normal = if distance_m > 0.0 {
                    r * (sign / distance_m)
                } else {
                    pseudo
                };
                WallPoint {
                    gap_m: sign * distance_m,
                    closest_m: v,
                    normal,
                    tangent: self.solid.tangent_from_normal(&normal),
                    arclength_m: self.arclengths_m[vertex],
                    curvature_per_m: if self.is_convex(vertex) {
                        f64::INFINITY
                    } else {
                        f64::NEG_INFINITY
                    },
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector2;
    use proptest::prelude::*;

    use super::super::tests::noisy_line;
    use crate::walls::edge_tree::EdgeTree;

    proptest! {
        /// The nearest-point search through the tree gives exactly what the edge-by-edge one
        /// does.
        #[test]
        fn tree_search_is_exact(
            count in 33usize..400,
            seed in any::<u64>(),
            x in -0.05f64..0.9,
            y in -0.02f64..0.02,
        ) {
            let wall = noisy_line(count, seed);
            prop_assert!(!wall.tree.is_empty());
            let mut plain = wall.clone();
            plain.tree = EdgeTree::new(&[]);
            let p = Vector2::new(x, y);
            prop_assert_eq!(wall.signed_distance(&p), plain.signed_distance(&p));
            // On a vertex, and half-way along an edge (ties between edges).
            let k = (seed as usize) % count;
            let v = wall.vertices_m()[k];
            prop_assert_eq!(wall.signed_distance(&v), plain.signed_distance(&v));
            if k + 1 < count {
                let mid = (v + wall.vertices_m()[k + 1]) * 0.5;
                prop_assert_eq!(wall.signed_distance(&mid), plain.signed_distance(&mid));
            }
        }
    }
}
