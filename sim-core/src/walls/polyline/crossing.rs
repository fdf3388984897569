//! The crossing checks of a polyline: the first pair of its edges that meet (a polyline must
//! not cross itself, [`Polyline::new`]), and whether a segment crosses the wall.

use nalgebra::Vector2;

use super::{Polyline, cross};

/// How far apart two edges' boxes may be and the edges still meet: the collinear test of
/// [`Polyline::edges_meet`] allows `1e-12` m off the line.
const BOX_SLACK_M: f64 = 1e-9;

impl Polyline {
    /// The first pair (in the order of the first edge, then the second) of non-adjacent
    /// edges that meet, end rays included. Edge by edge for a short polyline; a long one
    /// (a digitized wall) checks each finite edge against the edges whose runs' boxes meet
    /// its box (through the tree) and its end rays against every edge: `O(E log E)` for a
    /// wall that does not fold onto itself, where every pair took 0.15 s for 10,000 points.
    pub(super) fn first_crossing(&self) -> Option<(usize, usize)> {
        let edges = self.tangents.len();
        if self.tree.is_empty() {
            return self.first_crossing_of_every_pair();
        }
        let mut first: Option<(usize, usize)> = None;
        let mut consider = |i: usize, j: usize| {
            let (a, b) = (i.min(j), i.max(j));
            if b >= a + 2 && first.is_none_or(|f| (a, b) < f) && self.edges_meet(a, b) {
                first = Some((a, b));
            }
        };
        for j in 0..edges {
            consider(0, j);
            consider(edges - 1, j);
        }
        for i in 1..edges - 1 {
            let (v, w) = (self.vertices_m[i], self.vertices_m[i + 1]);
            let (lo, hi) = (
                v.inf(&w).add_scalar(-BOX_SLACK_M),
                v.sup(&w).add_scalar(BOX_SLACK_M),
            );
            self.tree.edges_meeting_box(&lo, &hi, |j| {
                if j >= i + 2 {
                    consider(i, j);
                }
                true
            });
        }
        first
    }

    /// [`Self::first_crossing`] by every pair of edges.
    fn first_crossing_of_every_pair(&self) -> Option<(usize, usize)> {
        let edges = self.tangents.len();
        (0..edges).find_map(|first| {
            (first + 2..edges)
                .find(|&second| self.edges_meet(first, second))
                .map(|second| (first, second))
        })
    }

    /// Whether edges `i` and `j` (as clamped to their ranges) share a point.
    fn edges_meet(&self, i: usize, j: usize) -> bool {
        let (ai, ti) = (self.vertices_m[i], self.tangents[i]);
        let (aj, tj) = (self.vertices_m[j], self.tangents[j]);
        let (lo_i, hi_i) = self.range_m(i);
        let (lo_j, hi_j) = self.range_m(j);
        let denom = cross(&ti, &tj);
        let r = aj - ai;
        if denom.abs() <= 1e-12 {
            // Parallel: they meet only if collinear with overlapping ranges.
            if cross(&ti, &r).abs() > 1e-12 {
                return false;
            }
            let start = ti.dot(&r);
            let sign = ti.dot(&tj);
            let (w0, w1) = (start + sign * lo_j, start + sign * hi_j);
            let (w_lo, w_hi) = (w0.min(w1), w0.max(w1));
            return w_lo <= hi_i && w_hi >= lo_i;
        }
        let u = cross(&r, &tj) / denom;
        let w = cross(&r, &ti) / denom;
        u >= lo_i && u <= hi_i && w >= lo_j && w <= hi_j
    }

    /// Whether the segment `a -> b` crosses an edge (end rays included); through the tree,
    /// the finite edges whose runs' boxes meet the segment's box.
    pub(super) fn crosses(&self, a_m: &Vector2<f64>, b_m: &Vector2<f64>) -> bool {
        let d = b_m - a_m;
        let crosses_edge = |edge: usize| {
            let t = self.tangents[edge];
            let denom = cross(&d, &t);
            if denom == 0.0 {
                return false;
            }
            let r = self.vertices_m[edge] - a_m;
            let s = cross(&r, &t) / denom;
            let u = cross(&r, &d) / denom;
            let (lo, hi) = self.range_m(edge);
            (0.0..=1.0).contains(&s) && u >= lo && u <= hi
        };
        let edges = self.tangents.len();
        if self.tree.is_empty() {
            return (0..edges).any(crosses_edge);
        }
        if crosses_edge(0) || crosses_edge(edges - 1) {
            return true;
        }
        !self
            .tree
            .edges_meeting_box(&a_m.inf(b_m), &a_m.sup(b_m), |edge| !crosses_edge(edge))
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector2;
    use proptest::prelude::*;

    use super::super::tests::noisy_line;
    use crate::walls::{Polyline, SolidSide, WallError};

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// The runs' search for crossings finds the pair every pair's check finds first, on
        /// random walks long enough to be cut into runs (most of them cross themselves) and on
        /// noisy lines (which do not).
        #[test]
        fn the_crossing_search_by_runs_finds_the_first_pair(
            steps in proptest::collection::vec((-3.1..3.1f64, 0.001..0.02f64), 40..160),
            noisy_seed in any::<u64>(),
        ) {
            let mut p = Vector2::new(0.0, 0.0);
            let mut vertices = vec![p];
            let mut heading = 0.0_f64;
            for (turn, length) in &steps {
                heading += 0.4 * turn;
                p += Vector2::new(heading.cos(), heading.sin()) * *length;
                vertices.push(p);
            }
            let edges = vertices.len() - 1;
            let walk = unchecked(vertices, SolidSide::Left);
            prop_assert!(!walk.tree.is_empty());
            prop_assert_eq!(walk.tangents.len(), edges);
            prop_assert_eq!(walk.first_crossing(), walk.first_crossing_of_every_pair());
            let noisy = noisy_line(200, noisy_seed);
            prop_assert_eq!(noisy.first_crossing(), None);
        }
    }

    /// The polyline through `vertices`, not checked for crossing edges.
    fn unchecked(vertices: Vec<Vector2<f64>>, solid: SolidSide) -> Polyline {
        Polyline::build(vertices, solid).unwrap()
    }

    /// A spiral of 100 edges, turning 20 degrees an edge, crosses itself; the search by runs
    /// reports the pair every pair's check reports first, and so does `Polyline::new`.
    #[test]
    fn a_spiral_crosses_itself_where_every_pair_says() {
        let mut p = Vector2::new(0.0, 0.0);
        let mut vertices = vec![p];
        for k in 0..100 {
            let heading = f64::from(k) * 20f64.to_radians();
            p += Vector2::new(heading.cos(), heading.sin()) * (0.01 + 1e-4 * f64::from(k));
            vertices.push(p);
        }
        let spiral = unchecked(vertices.clone(), SolidSide::Right);
        let first = spiral.first_crossing_of_every_pair();
        assert!(first.is_some());
        assert_eq!(spiral.first_crossing(), first);
        let Err(WallError::EdgesCross {
            first: a,
            second: b,
        }) = Polyline::new(vertices, SolidSide::Right)
        else {
            panic!("the spiral is refused for crossing itself");
        };
        assert_eq!(Some((a, b)), first);
    }
}
