//! A polyline wall (the thesis's trapezoid, 4.2.2): an open chain of straight edges whose first
//! and last edges extend to infinity as rays, so the wall splits the plane into a solid and a
//! free side.
//!
//! `segment_contact` is exact, from a finite candidate set: along a segment the signed
//! distance is, piece by piece (one piece per nearest feature: an edge line or a corner),
//! `+|linear|`/`+sqrt(quadratic)` (convex) in free space and their negatives (concave) in the
//! solid. So the minimum is at a segment end, at the foot of a corner on the segment (free
//! side: a corner poking into the middle of a link), or where two features are equidistant
//! (solid side: a crossing of the medial axis, e.g. a link pushed across a corner).

use nalgebra::Vector2;

use super::edge_tree::{EdgeTree, point_segment_distance2, segment_segment_distance2};
use super::error::{WallError, finite};
use super::{
    ConvexFeature, FeatureContact, SegmentContact, SolidSide, WallPoint, better, lerp, ray_is_valid,
};

/// A piece of a polyline cut at its concave corners
/// ([`Polyline::split_at_concave_corners_with_cuts`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ConcavePiece {
    /// The piece, running on along its end edges.
    pub polyline: Polyline,
    /// Its first vertex is a concave corner of the polyline it was cut from (not its end).
    pub cut_at_start: bool,
    /// Its last vertex is one.
    pub cut_at_end: bool,
}

/// An open polyline wall. Tangent from the first vertex toward the last; arclength from the
/// first vertex (negative along the first ray).
#[derive(Clone, Debug, PartialEq)]
pub struct Polyline {
    vertices_m: Vec<Vector2<f64>>,
    /// Unit tangent of edge `i` (vertex `i` to `i + 1`).
    tangents: Vec<Vector2<f64>>,
    /// Unit normal (into free space) of edge `i`.
    normals: Vec<Vector2<f64>>,
    /// Length of edge `i`, metres.
    lengths_m: Vec<f64>,
    /// Arclength of vertex `i` from vertex 0, metres.
    arclengths_m: Vec<f64>,
    solid: SolidSide,
    /// The finite edges in a hierarchy of runs with their bounding boxes, so that a query
    /// visits what is near it (empty for short polylines, searched edge by edge).
    tree: EdgeTree,
}

/// How far apart two edges' boxes may be and the edges still meet: the collinear test of
/// [`Polyline::edges_meet`] allows `1e-12` m off the line.
const BOX_SLACK_M: f64 = 1e-9;

/// Polylines with fewer finite edges than this are searched edge by edge.
const TREE_FROM_EDGES: usize = 32;

/// A stretch of a segment with at most this many edges within reach has its equidistance
/// candidates enumerated (`O(edges^2)`) rather than be halved again.
const LEAF_EDGES: usize = 8;

/// Halvings of a segment at most in the search for the distance field's minimum (a stretch
/// of `2^-20` of a 9 cm link is 0.1 um).
const MAX_HALVINGS: usize = 20;

/// How far outside a corner's normal cone (in the cone's own coordinates, the weights of the
/// two edge normals) a segment's normal still counts as in it: a segment flush with an edge
/// to the solve's precision. A link pressed flat on a digitized wall's edge, resting on the
/// edge's corner with its joint on the wall beyond, ends its solves up to `2e-7` outside the
/// cone; at `1e-9` it lost the corner on every other solve and took turns between the
/// corner and its joint for the whole step (soak 1093). `1e-6` radians tilts a 9 cm link's
/// far end `9e-8` m at most, which the link's own end pairs hold.
const CONE_ROUNDING: f64 = 1e-6;

/// The hierarchy of the finite edges of the polyline through `vertices_m`, or none if it has
/// fewer than [`TREE_FROM_EDGES`] edges.
fn edge_tree(vertices_m: &[Vector2<f64>]) -> EdgeTree {
    if vertices_m.len().saturating_sub(1) < TREE_FROM_EDGES {
        return EdgeTree::new(&[]);
    }
    EdgeTree::new(vertices_m)
}

/// Which feature of the polyline is nearest.
enum Nearest {
    /// The interior of edge `edge` (or one of the end rays), at `u_m` from its first vertex.
    Edge { edge: usize, u_m: f64 },
    /// An interior vertex.
    Vertex(usize),
}

impl Polyline {
    /// A polyline through `vertices_m` (ground frame, metres), solid on `solid`'s side of the
    /// tangent (which runs from the first vertex to the last). The first and the last edge
    /// extend to infinity. A trapezoidal bump on a wall along `+x` at `y = d`, solid above:
    /// `[(x0, d), (x1, d - h), (x2, d - h), (x3, d)]` with `SolidSide::Left`.
    ///
    /// # Errors
    /// [`WallError::TooFewVertices`] (< 2), [`WallError::NotFinite`],
    /// [`WallError::ZeroLengthEdge`], [`WallError::EdgeDoublesBack`] (a 180 degree turn),
    /// [`WallError::EdgesCross`] (two non-adjacent edges, end rays included, meet).
    pub fn new(vertices_m: Vec<Vector2<f64>>, solid: SolidSide) -> Result<Polyline, WallError> {
        let polyline = Polyline::build(vertices_m, solid)?;
        if let Some((first, second)) = polyline.first_crossing() {
            return Err(WallError::EdgesCross { first, second });
        }
        Ok(polyline)
    }

    /// [`Self::new`] without the check for crossing edges: the edges' frames, lengths,
    /// arclengths and runs.
    fn build(vertices_m: Vec<Vector2<f64>>, solid: SolidSide) -> Result<Polyline, WallError> {
        if vertices_m.len() < 2 {
            return Err(WallError::TooFewVertices {
                count: vertices_m.len(),
            });
        }
        for (index, v) in vertices_m.iter().enumerate() {
            finite("vertices_m.x", index, v.x)?;
            finite("vertices_m.y", index, v.y)?;
        }
        let edges = vertices_m.len() - 1;
        let mut tangents = Vec::with_capacity(edges);
        let mut normals = Vec::with_capacity(edges);
        let mut lengths_m = Vec::with_capacity(edges);
        let mut arclengths_m = Vec::with_capacity(vertices_m.len());
        arclengths_m.push(0.0);
        for (index, pair) in vertices_m.windows(2).enumerate() {
            let d = pair[1] - pair[0];
            let length_m = d.norm();
            if !(length_m > 0.0 && length_m.is_finite()) {
                return Err(WallError::ZeroLengthEdge { index });
            }
            let t = d / length_m;
            tangents.push(t);
            normals.push(solid.free_normal(&t));
            lengths_m.push(length_m);
            arclengths_m.push(arclengths_m[index] + length_m);
        }
        for vertex in 1..edges {
            let (t0, t1) = (tangents[vertex - 1], tangents[vertex]);
            if cross(&t0, &t1).abs() <= 1e-12 && t0.dot(&t1) < 0.0 {
                return Err(WallError::EdgeDoublesBack { vertex });
            }
        }
        let tree = edge_tree(&vertices_m);
        let polyline = Polyline {
            vertices_m,
            tangents,
            normals,
            lengths_m,
            arclengths_m,
            solid,
            tree,
        };
        Ok(polyline)
    }

    /// The first pair (in the order of the first edge, then the second) of non-adjacent
    /// edges that meet, end rays included. Edge by edge for a short polyline; a long one
    /// (a digitized wall) checks each finite edge against the edges whose runs' boxes meet
    /// its box (through the tree) and its end rays against every edge: `O(E log E)` for a
    /// wall that does not fold onto itself, where every pair took 0.15 s for 10,000 points.
    fn first_crossing(&self) -> Option<(usize, usize)> {
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

    /// The arclengths of the first and last vertices, metres.
    pub fn arclength_range_m(&self) -> (f64, f64) {
        (
            self.arclengths_m[0],
            self.arclengths_m[self.arclengths_m.len() - 1],
        )
    }

    /// The vertices, metres.
    pub fn vertices_m(&self) -> &[Vector2<f64>] {
        &self.vertices_m
    }

    /// Which side is solid.
    pub fn solid_side(&self) -> SolidSide {
        self.solid
    }

    /// The polyline cut at its concave corners (where the free side has an angle under 180
    /// degrees), each piece running on along its end edges: the solid is the union of the
    /// pieces' solids near each cut, and a point pressed into a concave corner touches two
    /// pieces, each with a smooth distance (the distance to the whole polyline has a kink
    /// along the corner's bisector). Without concave corners, the polyline itself.
    pub fn split_at_concave_corners(&self) -> Vec<Polyline> {
        self.split_at_concave_corners_with_cuts()
            .into_iter()
            .map(|piece| piece.polyline)
            .collect()
    }

    /// [`Self::split_at_concave_corners`], with which ends of each piece are cuts (a piece
    /// standing for several straight pieces on one line has none: its line is theirs).
    pub fn split_at_concave_corners_with_cuts(&self) -> Vec<ConcavePiece> {
        let mut pieces = Vec::new();
        let mut first = 0;
        let last = self.vertices_m.len() - 1;
        for k in 1..self.tangents.len() {
            let turn = cross(&self.tangents[k - 1], &self.tangents[k]);
            let concave = match self.solid {
                SolidSide::Left => turn < 0.0,
                SolidSide::Right => turn > 0.0,
            };
            if concave {
                pieces.push(ConcavePiece {
                    polyline: self.piece(first, k),
                    cut_at_start: first > 0,
                    cut_at_end: true,
                });
                first = k;
            }
        }
        pieces.push(ConcavePiece {
            polyline: self.piece(first, last),
            cut_at_start: first > 0,
            cut_at_end: false,
        });
        // A straight piece is an infinite line; two of them on one line (the trapezoid's
        // top before and after its dip) are one wall, not two copies of every contact.
        let mut unique: Vec<ConcavePiece> = Vec::with_capacity(pieces.len());
        for piece in pieces {
            let line = piece.polyline.straight_line();
            let duplicate = line.and_then(|line| {
                unique.iter().position(|u| {
                    u.polyline.straight_line().is_some_and(|other| {
                        (line.0 - other.0).norm() < 1e-12 && (line.1 - other.1).abs() < 1e-12
                    })
                })
            });
            match duplicate {
                Some(kept) => {
                    unique[kept].cut_at_start = false;
                    unique[kept].cut_at_end = false;
                }
                None => unique.push(piece),
            }
        }
        unique
    }

    /// The polyline without the vertices that are not corners at `tolerance_m`: a vertex
    /// within `tolerance_m` of the chord that replaces it is dropped, by Douglas and
    /// Peucker's recursion (keep the ends; between two kept vertices, keep the vertex
    /// farthest from their chord if it lies farther than `tolerance_m`, and recurse on both
    /// sides). Every vertex dropped lies within `tolerance_m` of the edge that replaces it,
    /// so the wall moves by at most that much; a test of each vertex against its neighbours'
    /// chord would not bound it, as small turns add up along a finely sampled curve, which
    /// keeps its shape here. Kept vertices keep their arclengths (a point's arclength stays
    /// the wall's own). Without a vertex to drop (the usual case), a copy.
    ///
    /// A laser scan of a straight edge, its points rounded to the nanometre, is its two
    /// ends: the trapezoid of `examples/wall_polyline.toml` sampled at 2,000 points an edge
    /// is its six vertices again at a tolerance of 1 nm (`examples/wall_sampled_2000.toml`).
    ///
    /// ```
    /// use nalgebra::Vector2;
    /// use sim_core::{Polyline, SolidSide};
    ///
    /// let points: Vec<_> = (0..=100)
    ///     .map(|k| Vector2::new(k as f64 * 1e-3, if k % 2 == 0 { 0.0 } else { 4e-10 }))
    ///     .collect();
    /// let scan = Polyline::new(points, SolidSide::Left).unwrap();
    /// let flat = scan.without_flat_vertices(1e-9);
    /// assert_eq!(flat.vertices_m(), &[Vector2::new(0.0, 0.0), Vector2::new(0.1, 0.0)]);
    /// assert_eq!(scan.without_flat_vertices(1e-10), scan);
    /// ```
    pub fn without_flat_vertices(&self, tolerance_m: f64) -> Polyline {
        let count = self.vertices_m.len();
        let mut keep = vec![false; count];
        keep[0] = true;
        keep[count - 1] = true;
        let mut stack = vec![(0, count - 1)];
        while let Some((first, last)) = stack.pop() {
            let (a, b) = (self.vertices_m[first], self.vertices_m[last]);
            let farthest = (first + 1..last)
                .map(|k| (point_segment_distance2(&self.vertices_m[k], &a, &b), k))
                .fold(None, |best: Option<(f64, usize)>, c| match best {
                    Some(b) if b.0 >= c.0 => Some(b),
                    _ => Some(c),
                });
            if let Some((distance2, k)) = farthest
                && distance2 > tolerance_m * tolerance_m
            {
                keep[k] = true;
                stack.push((k, last));
                stack.push((first, k));
            }
        }
        if keep.iter().all(|&k| k) {
            return self.clone();
        }
        let kept: Vec<usize> = (0..count).filter(|&k| keep[k]).collect();
        let vertices_m: Vec<Vector2<f64>> = kept.iter().map(|&k| self.vertices_m[k]).collect();
        let arclengths_m: Vec<f64> = kept.iter().map(|&k| self.arclengths_m[k]).collect();
        let mut tangents = Vec::with_capacity(kept.len() - 1);
        let mut lengths_m = Vec::with_capacity(kept.len() - 1);
        for pair in vertices_m.windows(2) {
            let d = pair[1] - pair[0];
            let length_m = d.norm();
            tangents.push(d / length_m);
            lengths_m.push(length_m);
        }
        let normals = tangents.iter().map(|t| self.solid.free_normal(t)).collect();
        let tree = edge_tree(&vertices_m);
        Polyline {
            vertices_m,
            tangents,
            normals,
            lengths_m,
            arclengths_m,
            solid: self.solid,
            tree,
        }
    }

    /// For a polyline whose edges all run one way: its line as (normal, offset), with
    /// `normal . p = offset` on it.
    fn straight_line(&self) -> Option<(Vector2<f64>, f64)> {
        let n = self.normals[0];
        let straight = self.normals.iter().all(|m| (m - n).norm() < 1e-12)
            && self
                .vertices_m
                .iter()
                .all(|v| (n.dot(v) - n.dot(&self.vertices_m[0])).abs() < 1e-12);
        straight.then(|| (n, n.dot(&self.vertices_m[0])))
    }

    /// The piece from vertex `first` to vertex `last` (with its end rays).
    fn piece(&self, first: usize, last: usize) -> Polyline {
        let vertices_m = self.vertices_m[first..=last].to_vec();
        let tangents = self.tangents[first..last].to_vec();
        let normals = self.normals[first..last].to_vec();
        let lengths_m = self.lengths_m[first..last].to_vec();
        let arclengths_m = self.arclengths_m[first..=last].to_vec();
        let tree = edge_tree(&vertices_m);
        Polyline {
            vertices_m,
            tangents,
            normals,
            lengths_m,
            arclengths_m,
            solid: self.solid,
            tree,
        }
    }

    /// The parameter range of edge `i` in metres from its first vertex (infinite for the end
    /// rays).
    fn range_m(&self, edge: usize) -> (f64, f64) {
        let lo = if edge == 0 { f64::NEG_INFINITY } else { 0.0 };
        let hi = if edge + 1 == self.tangents.len() {
            f64::INFINITY
        } else {
            self.lengths_m[edge]
        };
        (lo, hi)
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

    /// The deepest (or closest) point of `a -> b` (see the module docs), no allocation.
    /// `O(edges)` where the segment stays in free space; where part of it may be in the
    /// solid, the stretches of it that can dip below the best point found so far are halved
    /// until few edges are within their reach, and the pairs of those features are checked,
    /// each by a nearest-point query (soak 835, a 4-link antenna along a digitized wall of
    /// 300 points: its sweep took 6.3 s with the pairs of every feature within reach of a
    /// whole link, 0.1 s by halves, step for step the same).
    pub fn segment_contact(&self, a_m: &Vector2<f64>, b_m: &Vector2<f64>) -> SegmentContact {
        let (start, end) = (self.at(a_m, b_m, 0.0), self.at(a_m, b_m, 1.0));
        let ends = better(start, end);
        self.interior_candidates(a_m, b_m, [start.wall.gap_m, end.wall.gap_m], false)
            .map_or(ends, |inner| better(ends, inner))
    }

    /// The deepest of the segment's interior candidate points (`0 < s < 1`: convex corners
    /// against the segment, measured along the segment's normal, and the equidistance points
    /// of the module docs), or `None`; no allocation. A contact solver's view: unlike
    /// [`Self::segment_contact`] (the distance field's minimum), a corner pressed into the
    /// segment keeps one smooth gap and normal.
    pub fn segment_interior_contact(
        &self,
        a_m: &Vector2<f64>,
        b_m: &Vector2<f64>,
    ) -> Option<SegmentContact> {
        let (start, end) = (self.at(a_m, b_m, 0.0), self.at(a_m, b_m, 1.0));
        self.interior_candidates(a_m, b_m, [start.wall.gap_m, end.wall.gap_m], true)
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

    /// The deepest interior candidate of `a -> b`; `ends_gap_m` are the gaps of its ends
    /// (the solid-side candidates matter only if part of the segment is in the solid).
    /// With `corner_geometry`, a convex corner's contact is measured along the segment's
    /// normal ([`Self::corner_contact`]), else by the signed distance of its foot.
    fn interior_candidates(
        &self,
        a_m: &Vector2<f64>,
        b_m: &Vector2<f64>,
        ends_gap_m: [f64; 2],
        corner_geometry: bool,
    ) -> Option<SegmentContact> {
        let d = b_m - a_m;
        let [start_gap_m, end_gap_m] = ends_gap_m;
        let deepest_end_m = start_gap_m.min(end_gap_m);
        // The solid-side candidates matter only if part of the segment is in the solid: an
        // end is, or the segment crosses the wall.
        let needs_solid_side = deepest_end_m <= 0.0 || self.crosses(a_m, b_m);
        let best_cell = core::cell::Cell::new(None::<SegmentContact>);
        let consider_contact = |c: SegmentContact| {
            best_cell.set(Some(best_cell.get().map_or(c, |b| better(b, c))));
        };
        let consider = |s: f64| {
            if s > 0.0 && s < 1.0 {
                consider_contact(self.at(a_m, b_m, s));
            }
        };
        let d2 = d.norm_squared();
        let edges = self.tangents.len();
        if d2 > 0.0 {
            // Convex corners against the segment: the corner and its foot on the segment,
            // the normal the segment's own (a corner has no normal of its own: the distance
            // from a point just inside the corner jumps between its two edges).
            let corner = |k: usize| {
                let s = (self.vertices_m[k] - a_m).dot(&d) / d2;
                if s > 0.0 && s < 1.0 {
                    let corner = if corner_geometry {
                        self.corner_contact(k, a_m, b_m, s)
                    } else {
                        None
                    };
                    let c = corner.unwrap_or_else(|| self.at(a_m, b_m, s));
                    consider_contact(c);
                }
            };
            if self.tree.is_empty() || corner_geometry {
                (1..edges).for_each(corner);
            } else {
                // Through the tree, the corners that can hold the minimum: in free space
                // (both ends free, no crossing) the minimum is the distance to the nearest
                // feature, so a corner whose foot holds it lies within the ends' smaller gap
                // of the segment; else within the reach of the stretch (`Reach`). A corner
                // farther off has a foot no deeper than the minimum.
                let (lo_m, hi_m) = if needs_solid_side {
                    reach_box(a_m, b_m, ends_gap_m)
                } else {
                    let reach_m = deepest_end_m * (1.0 + 1e-9) + 1e-12;
                    (
                        a_m.inf(b_m).add_scalar(-reach_m),
                        a_m.sup(b_m).add_scalar(reach_m),
                    )
                };
                self.corners_in_box(&lo_m, &hi_m, corner);
            }
            if !needs_solid_side {
                return best_cell.get();
            }
            if corner_geometry {
                self.equidistance_candidates(a_m, b_m, (0.0, 1.0), ends_gap_m, &consider);
            } else {
                // The distance field's minimum (at most 0 here: an end is in the solid or
                // the segment crosses the wall): only stretches whose Lipschitz bound can
                // reach below the best found so far are searched (see `deepest_stretches`).
                let floor = || {
                    best_cell
                        .get()
                        .map_or(deepest_end_m, |b| b.wall.gap_m.min(deepest_end_m))
                        .min(0.0)
                };
                self.deepest_stretches(a_m, b_m, (0.0, 1.0), ends_gap_m, 0, &floor, &consider);
            }
        }
        best_cell.get()
    }

    /// The distance field's minimum over the stretch `s0..s1` of `a -> b` (`gaps_m` at its
    /// ends), searched by halves: a stretch whose 1-Lipschitz bound
    /// `(g(s0) + g(s1) - |b - a| (s1 - s0)) / 2` is above `floor()` (the best found so far)
    /// cannot hold the minimum and is skipped; one with at most [`LEAF_EDGES`] edges within
    /// reach (or [`MAX_HALVINGS`] deep) has its equidistance candidates enumerated. On a
    /// digitized wall of hundreds of edges a link lying along it had `O(edges^2)` candidates,
    /// each a nearest-point query; the halves touch only the stretch that dips into the wall.
    #[allow(clippy::too_many_arguments)]
    fn deepest_stretches(
        &self,
        a_m: &Vector2<f64>,
        b_m: &Vector2<f64>,
        (s0, s1): (f64, f64),
        gaps_m: [f64; 2],
        depth: usize,
        floor: &impl Fn() -> f64,
        consider: &impl Fn(f64),
    ) {
        let length_m = (b_m - a_m).norm() * (s1 - s0);
        let bound_m = 0.5 * (gaps_m[0] + gaps_m[1] - length_m);
        // (A picometre of slack for the rounding of the bound: no stretch that can tie the
        // best is skipped.)
        if bound_m - 1e-12 > floor() {
            return;
        }
        let (p0, p1) = (lerp(a_m, b_m, s0), lerp(a_m, b_m, s1));
        // (The scan stops at the first edge past the leaf's size.)
        let few = self
            .edges_within_reach(&p0, &p1, gaps_m)
            .nth(LEAF_EDGES)
            .is_none();
        if few || depth >= MAX_HALVINGS {
            self.equidistance_candidates(a_m, b_m, (s0, s1), gaps_m, consider);
            return;
        }
        let mid = 0.5 * (s0 + s1);
        let mid_gap_m = self.signed_distance(&lerp(a_m, b_m, mid)).gap_m;
        let halves = [
            ((s0, mid), [gaps_m[0], mid_gap_m]),
            ((mid, s1), [mid_gap_m, gaps_m[1]]),
        ];
        // The half with the lower bound first: it tightens the floor for the other.
        let first = usize::from(gaps_m[1] < gaps_m[0]);
        for k in [first, 1 - first] {
            let (stretch, gaps) = halves[k];
            self.deepest_stretches(a_m, b_m, stretch, gaps, depth + 1, floor, consider);
        }
    }

    /// The edges that can be nearest to a point of `p0 -> p1` (gaps `gaps_m` at its ends):
    /// the signed distance changes by at most the distance moved, so no point of it is
    /// deeper than `(|g(p0)| + |g(p1)| + |p1 - p0|) / 2`, and an edge nearest to one of its
    /// points lies within that of it. An end ray reaches everywhere.
    fn edges_within_reach(
        &self,
        p0: &Vector2<f64>,
        p1: &Vector2<f64>,
        gaps_m: [f64; 2],
    ) -> impl Iterator<Item = usize> + '_ {
        let reach = Reach::new(p0, p1, gaps_m);
        let edges = self.tangents.len();
        let scan = self.tree.is_empty();
        // Without a tree, every edge; with one, the rays and the runs whose boxes meet the
        // reach's box (the edges come in increasing order either way).
        let mut near: Vec<usize> = Vec::new();
        if !scan {
            near.push(0);
            self.tree.edges_meeting_box(&reach.lo_m, &reach.hi_m, |i| {
                near.push(i);
                true
            });
            near.push(edges - 1);
        }
        let all = (0..edges).filter(move |_| scan);
        all.chain(near)
            .filter(move |&i| self.within_reach(i, &reach))
    }

    /// Whether edge `i` can be nearest to a point of the stretch `reach` describes: an end
    /// ray always can; a finite edge must meet its box and lie within its distance of
    /// both ends ([`Reach`]).
    fn within_reach(&self, i: usize, reach: &Reach) -> bool {
        let (lo, hi) = self.range_m(i);
        if lo.is_infinite() || hi.is_infinite() {
            return true;
        }
        let (v, w) = (self.vertices_m[i], self.vertices_m[i + 1]);
        let (e_lo, e_hi) = (v.inf(&w), v.sup(&w));
        let (lo_m, hi_m) = (reach.lo_m, reach.hi_m);
        if !(e_lo.x <= hi_m.x && e_hi.x >= lo_m.x && e_lo.y <= hi_m.y && e_hi.y >= lo_m.y) {
            return false;
        }
        let edge_distance_squared = |p: &Vector2<f64>| {
            let t = (p - v).dot(&self.tangents[i]).clamp(0.0, self.lengths_m[i]);
            (v + self.tangents[i] * t - p).norm_squared()
        };
        edge_distance_squared(&reach.p0_m) <= reach.r0_m * reach.r0_m
            && edge_distance_squared(&reach.p1_m) <= reach.r1_m * reach.r1_m
    }

    /// Passes to `consider` the parameters `s` in `s0..=s1` of `a -> b` (its stretch
    /// `s0..s1` has gaps `gaps_m` at its ends) equidistant from two features within reach
    /// of the stretch: two edge lines, an edge line and a corner, or two corners.
    fn equidistance_candidates(
        &self,
        a_m: &Vector2<f64>,
        b_m: &Vector2<f64>,
        (s0, s1): (f64, f64),
        gaps_m: [f64; 2],
        consider: &impl Fn(f64),
    ) {
        let d = b_m - a_m;
        let d2 = d.norm_squared();
        let edges = self.tangents.len();
        let (p0, p1) = (lerp(a_m, b_m, s0), lerp(a_m, b_m, s1));
        let reach = Reach::new(&p0, &p1, gaps_m);
        let (lo_m, hi_m) = (reach.lo_m, reach.hi_m);
        let inside =
            |v: &Vector2<f64>| v.x >= lo_m.x && v.x <= hi_m.x && v.y >= lo_m.y && v.y <= hi_m.y;
        let near_corner = |k: &usize| inside(&self.vertices_m[*k]);
        let within = |s: f64| {
            if s >= s0 && s <= s1 {
                consider(s);
            }
        };
        // The edges within reach lie in one span of indices besides the two end rays, and
        // every corner within reach ends one of them: the loops below run over that span
        // only, in the same order (on a digitized wall of hundreds of edges a stretch deep
        // in the solid scanned every edge for every edge within reach, soak 1274: 9 s of a
        // placement).
        let (first, last) = self
            .edges_within_reach(&p0, &p1, gaps_m)
            .filter(|&i| i != 0 && i + 1 != edges)
            .fold((usize::MAX, 0), |(lo, hi), i| (lo.min(i), hi.max(i)));
        let span = if first <= last { first..last + 1 } else { 0..0 };
        let reach_indices = || {
            let rays = [0, edges.saturating_sub(1)];
            core::iter::once(rays[0])
                .chain(span.clone())
                .chain(core::iter::once(rays[1]).filter(move |&r| r > rays[0]))
                .filter(|&i| self.within_reach(i, &reach))
        };
        let corners = if edges <= 2 {
            1..edges
        } else if first <= last {
            first..(last + 2).min(edges)
        } else {
            0..0
        };
        let near_corners = || corners.clone().filter(near_corner);
        // Equidistant from two edge lines: (alpha_i + beta_i s) = +-(alpha_j + beta_j s).
        let line = |i: usize| {
            let n = self.normals[i];
            (n.dot(&(a_m - self.vertices_m[i])), n.dot(&d))
        };
        for i in reach_indices() {
            let (ai, bi) = line(i);
            for j in reach_indices().filter(|&j| j > i) {
                let (aj, bj) = line(j);
                for sign in [1.0, -1.0] {
                    let denom = bi - sign * bj;
                    if denom != 0.0 {
                        within(-(ai - sign * aj) / denom);
                    }
                }
            }
            // Equidistant from edge line i and corner k: (alpha + beta s)^2 = |a - v + s d|^2.
            for k in near_corners() {
                let r = a_m - self.vertices_m[k];
                let qa = bi * bi - d2;
                let qb = 2.0 * (ai * bi - r.dot(&d));
                let qc = ai * ai - r.norm_squared();
                for_roots(qa, qb, qc, &mut |s| within(s));
            }
        }
        // Equidistant from two corners: the perpendicular bisector.
        for k in near_corners() {
            for m in near_corners().filter(|&m| m > k) {
                let (v, w) = (self.vertices_m[k], self.vertices_m[m]);
                let denom = 2.0 * d.dot(&(w - v));
                if denom != 0.0 {
                    within((w.norm_squared() - v.norm_squared() - 2.0 * a_m.dot(&(w - v))) / denom);
                }
            }
        }
    }

    /// The contact of the segment `a -> b` with corner `k` at the corner's foot `s`, if the
    /// corner is convex (it pokes into free space): the gap along the segment's normal
    /// (oriented into free space, as the corner's pseudo-normal), the corner as the wall point.
    fn corner_contact(
        &self,
        k: usize,
        a_m: &Vector2<f64>,
        b_m: &Vector2<f64>,
        s: f64,
    ) -> Option<SegmentContact> {
        let turn = cross(&self.tangents[k - 1], &self.tangents[k]);
        let convex = match self.solid {
            SolidSide::Left => turn > 0.0,
            SolidSide::Right => turn < 0.0,
        };
        if !convex {
            return None;
        }
        let d = (b_m - a_m).normalize();
        let pseudo = (self.normals[k - 1] + self.normals[k]).normalize();
        let mut normal = Vector2::new(-d.y, d.x);
        if normal.dot(&pseudo) < 0.0 {
            normal = -normal;
        }
        // The segment can rest on the corner only if its normal lies in the corner's normal
        // cone (between the normals of its two edges); otherwise the corner is off to the
        // side of it (a segment standing steeply beside a corner would be measured along
        // its own normal, across the corner's edges, to a corner metres away).
        let (n1, n2) = (self.normals[k - 1], self.normals[k]);
        let det = cross(&n1, &n2);
        let (alpha, beta) = (cross(&normal, &n2) / det, cross(&n1, &normal) / det);
        if !(alpha >= 0.0 && beta >= 0.0) {
            return None;
        }
        let point_m = lerp(a_m, b_m, s);
        let v = self.vertices_m[k];
        let gap_m = normal.dot(&(point_m - v));
        // A corner pressing through the segment puts the segment's point at its foot inside
        // the solid; a corner far off that merely lies behind the segment's line does not.
        if gap_m < 0.0 && self.signed_distance(&point_m).gap_m >= 0.0 {
            return None;
        }
        Some(SegmentContact {
            s,
            point_m,
            wall: WallPoint {
                gap_m,
                closest_m: v,
                normal,
                tangent: self.solid.tangent_from_normal(&normal),
                arclength_m: self.arclengths_m[k],
                curvature_per_m: f64::INFINITY,
            },
        })
    }

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
    fn is_convex(&self, k: usize) -> bool {
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

    /// Whether the segment `a -> b` crosses an edge (end rays included); through the tree,
    /// the finite edges whose runs' boxes meet the segment's box.
    fn crosses(&self, a_m: &Vector2<f64>, b_m: &Vector2<f64>) -> bool {
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

    /// Calls `visit` with every interior vertex (corner) inside the box `lo_m..hi_m`, in
    /// increasing order: a scan, or the ends of the edges the tree finds near the box.
    fn corners_in_box(
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

    /// The first point of the ray `origin + t direction`, `t` in `[0, max_m]`, on the
    /// polyline: every edge and both end rays intersected in closed form (an edge accepts a
    /// crossing within `1e-12` m beyond its ends, so that a ray through a vertex is not lost
    /// to rounding between its two edges; a ray running along an edge meets it where it
    /// enters it), the smallest `t`. `None` if the ray meets none, or is not a ray (see
    /// [`super::Wall::ray_hit_m`]). `O(edges)`, no allocation.
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

    /// The polyline reflected `y -> -y` (ground frame), its vertices in the same order and
    /// solid on the other side of its reflected tangent, so that the reflected points of the
    /// solid are solid (a reflection flips the orientation); arclength is kept: a point's
    /// mirror image has its arclength.
    pub fn mirrored_about_x_axis(&self) -> Polyline {
        let flip = |p: &Vector2<f64>| Vector2::new(p.x, -p.y);
        let solid = self.solid.swapped();
        let tangents: Vec<Vector2<f64>> = self.tangents.iter().map(flip).collect();
        let normals = tangents.iter().map(|t| solid.free_normal(t)).collect();
        let mut tree = self.tree.clone();
        tree.mirror_about_x_axis();
        Polyline {
            vertices_m: self.vertices_m.iter().map(flip).collect(),
            tangents,
            normals,
            lengths_m: self.lengths_m.clone(),
            arclengths_m: self.arclengths_m.clone(),
            solid,
            tree,
        }
    }

    /// Moves the polyline by `offset_m`, without allocating.
    pub fn translate(&mut self, offset_m: Vector2<f64>) {
        for v in &mut self.vertices_m {
            *v += offset_m;
        }
        self.tree.translate(&offset_m);
    }

    /// A copy moved by `offset_m`.
    pub fn translated(&self, offset_m: Vector2<f64>) -> Polyline {
        let mut moved = self.clone();
        moved.translate(offset_m);
        moved
    }
}

/// The z component of `a x b`.
fn cross(a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

/// Calls `f` with each real root of `qa s^2 + qb s + qc = 0` (the linear case included).
pub(crate) fn for_roots(qa: f64, qb: f64, qc: f64, f: &mut impl FnMut(f64)) {
    let scale = qa.abs().max(qb.abs()).max(qc.abs());
    if scale == 0.0 {
        return;
    }
    if qa.abs() <= 1e-14 * scale {
        if qb != 0.0 {
            f(-qc / qb);
        }
        return;
    }
    let disc = qb * qb - 4.0 * qa * qc;
    if disc < 0.0 {
        return;
    }
    // The numerically stable pair of roots.
    let q = -0.5 * (qb + qb.signum() * disc.sqrt());
    if q != 0.0 {
        f(q / qa);
        f(qc / q);
    } else {
        f(0.0);
    }
}

/// Where the edges that can be nearest to a point of the stretch `p0 -> p1` (gaps `g0`,
/// `g1` at its ends, length `l`) lie. Its box is [`reach_box`]. Besides, a point `p` of it
/// is at most `|g0| + l` from the boundary, so its nearest edge is within `|g0| + 2 l` of
/// `p0` (and `|g1| + 2 l` of `p1`); as no edge is nearer to `p0` than `|g0|`, for a short
/// stretch deep in the solid that is a thin ring, where the box held every edge within
/// `|g|` (soak 1274: a placement measuring links 90 mm inside a digitized wall spent 9 s
/// enumerating pairs of them).
struct Reach {
    lo_m: Vector2<f64>,
    hi_m: Vector2<f64>,
    p0_m: Vector2<f64>,
    p1_m: Vector2<f64>,
    r0_m: f64,
    r1_m: f64,
}

impl Reach {
    fn new(p0: &Vector2<f64>, p1: &Vector2<f64>, gaps_m: [f64; 2]) -> Self {
        let (lo_m, hi_m) = reach_box(p0, p1, gaps_m);
        let length_m = (p1 - p0).norm();
        // (A relative slack for the rounding of the distances: no edge that can be nearest
        // is left out.)
        let slack = |r: f64| r * (1.0 + 1e-9) + 1e-12;
        Reach {
            lo_m,
            hi_m,
            p0_m: *p0,
            p1_m: *p1,
            r0_m: slack(gaps_m[0].abs() + 2.0 * length_m),
            r1_m: slack(gaps_m[1].abs() + 2.0 * length_m),
        }
    }
}

/// The box around `p0 -> p1` grown by its reach (see [`Polyline::edges_within_reach`]).
fn reach_box(
    p0: &Vector2<f64>,
    p1: &Vector2<f64>,
    gaps_m: [f64; 2],
) -> (Vector2<f64>, Vector2<f64>) {
    let reach_m = 0.5 * (gaps_m[0].abs() + gaps_m[1].abs() + (p1 - p0).norm());
    (
        p0.inf(p1).add_scalar(-reach_m),
        p0.sup(p1).add_scalar(reach_m),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

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

    /// A noisy line of `count` vertices along `+x` (a digitized wall).
    fn noisy_line(count: usize, seed: u64) -> Polyline {
        let mut state = seed | 1;
        let mut noise = || {
            // xorshift: a fixed, dependency-free sequence in [-1, 1).
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        };
        let vertices = (0..count)
            .map(|i| Vector2::new(i as f64 * 2e-3, 4e-4 * noise()))
            .collect();
        Polyline::new(vertices, SolidSide::Right).unwrap()
    }

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

        /// The distance field's minimum over a segment searched by halves (only stretches
        /// whose Lipschitz bound can beat the best) is exactly the one found by enumerating
        /// every equidistance candidate of the whole segment, on digitized walls of up to
        /// 400 edges and links from 5 mm to 15 cm dipping up to 3 mm into them.
        #[test]
        fn the_halved_search_finds_the_exhaustive_minimum(
            count in 33usize..400,
            seed in any::<u64>(),
            x in -0.05f64..0.8,
            y in -0.003f64..0.003,
            angle_rad in -3.2f64..3.2,
            length_m in 0.005f64..0.15,
        ) {
            let wall = noisy_line(count, seed);
            let a = Vector2::new(x, y);
            let b = a + Vector2::new(angle_rad.cos(), angle_rad.sin()) * length_m;
            let halved = wall.segment_contact(&a, &b);
            // The oracle: the ends, the corners' feet, and where part of the segment is in
            // the solid every equidistance candidate of the whole segment.
            let (start, end) = (wall.at(&a, &b, 0.0), wall.at(&a, &b, 1.0));
            let best = core::cell::Cell::new(better(start, end));
            let consider = |s: f64| {
                if s > 0.0 && s < 1.0 {
                    best.set(better(best.get(), wall.at(&a, &b, s)));
                }
            };
            let d = b - a;
            for k in 1..wall.tangents.len() {
                consider((wall.vertices_m[k] - a).dot(&d) / d.norm_squared());
            }
            let gaps = [start.wall.gap_m, end.wall.gap_m];
            if gaps[0].min(gaps[1]) <= 0.0 || wall.crosses(&a, &b) {
                wall.equidistance_candidates(&a, &b, (0.0, 1.0), gaps, &consider);
            }
            prop_assert_eq!(halved, best.get());
        }

        /// The queries through the tree answer as the scans do on digitized walls of up to
        /// 400 edges, for segments from 5 mm to 15 cm near and in them: the deepest point
        /// (the same contact), the corners near a segment (the same list, in order), the
        /// crossing test; and the segment's gap bound is a bound, exact where the segment
        /// stays in free space.
        #[test]
        fn tree_queries_answer_as_scans(
            count in 33usize..400,
            seed in any::<u64>(),
            x in -0.05f64..0.8,
            y in -0.01f64..0.03,
            angle_rad in -3.2f64..3.2,
            length_m in 0.005f64..0.15,
            within_m in 0.0f64..0.01,
        ) {
            let wall = noisy_line(count, seed);
            prop_assert!(!wall.tree.is_empty());
            let mut plain = wall.clone();
            plain.tree = EdgeTree::new(&[]);
            let a = Vector2::new(x, y);
            let b = a + Vector2::new(angle_rad.cos(), angle_rad.sin()) * length_m;
            let by_tree = wall.segment_contact(&a, &b);
            let by_scan = plain.segment_contact(&a, &b);
            prop_assert_eq!(by_tree.wall.gap_m, by_scan.wall.gap_m);
            prop_assert_eq!(by_tree, by_scan);
            prop_assert_eq!(wall.crosses(&a, &b), plain.crosses(&a, &b));
            let (mut near_tree, mut near_scan) = (Vec::new(), Vec::new());
            wall.features_near_segment(&a, &b, within_m, &mut near_tree);
            plain.features_near_segment(&a, &b, within_m, &mut near_scan);
            prop_assert_eq!(near_tree, near_scan);
            let bound_m = wall.segment_gap_lower_bound_m(&a, &b);
            prop_assert!(bound_m <= by_scan.wall.gap_m, "{bound_m} > {}", by_scan.wall.gap_m);
            if by_scan.wall.gap_m > 0.0 {
                prop_assert!(
                    (bound_m - by_scan.wall.gap_m).abs() <= 1e-12 * (1.0 + by_scan.wall.gap_m),
                    "{bound_m} against {}", by_scan.wall.gap_m
                );
            }
        }

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
