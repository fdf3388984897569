//! A bounding-box hierarchy over a polyline's finite edges, so that a query costs what is
//! near it rather than the wall's size (issue #49: a laser scan of a wall has thousands of
//! edges, and a link touches a handful).
//!
//! A polyline's consecutive edges lie together, so the hierarchy is over runs of edge
//! indices: the root holds every finite edge (`1..edges - 1`; the first and last edges are
//! rays, which reach everywhere and every query checks on its own), each node splits its run
//! in halves, a leaf holds at most [`LEAF_EDGES`] edges. Each node keeps the bounding box of
//! its edges' vertices. Visits go left child first, so edges come out in increasing index
//! order: a query through the tree sees the edges a scan would, in the scan's order, less
//! those whose run's box it proves out of reach.

use nalgebra::Vector2;

/// Edges per leaf at most.
const LEAF_EDGES: usize = 8;

/// The deepest a query's explicit stack can get: a balanced tree over `2^40` leaves.
const MAX_DEPTH: usize = 64;

/// The hierarchy (see the module documentation).
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct EdgeTree {
    /// The nodes; the root is node 0.
    nodes: Vec<Node>,
}

/// A run of consecutive finite edges `first_edge..end_edge` with the box of their vertices
/// (`first_edge..=end_edge`).
#[derive(Clone, Debug, PartialEq)]
struct Node {
    first_edge: usize,
    end_edge: usize,
    lo_m: Vector2<f64>,
    hi_m: Vector2<f64>,
    /// The two halves, or none for a leaf.
    children: Option<[u32; 2]>,
}

impl Node {
    /// Whether the node's box meets the box `lo_m..hi_m`.
    fn meets(&self, lo_m: &Vector2<f64>, hi_m: &Vector2<f64>) -> bool {
        self.lo_m.x <= hi_m.x
            && lo_m.x <= self.hi_m.x
            && self.lo_m.y <= hi_m.y
            && lo_m.y <= self.hi_m.y
    }

    /// The squared distance from `p_m` to the node's box (0 inside it).
    fn distance2(&self, p_m: &Vector2<f64>) -> f64 {
        let dx = (self.lo_m.x - p_m.x).max(p_m.x - self.hi_m.x).max(0.0);
        let dy = (self.lo_m.y - p_m.y).max(p_m.y - self.hi_m.y).max(0.0);
        dx * dx + dy * dy
    }
}

impl EdgeTree {
    /// The hierarchy over the finite edges of the polyline through `vertices_m` (none for a
    /// polyline of fewer than three edges: its edges are all rays or one edge between them).
    pub fn new(vertices_m: &[Vector2<f64>]) -> EdgeTree {
        let edges = vertices_m.len().saturating_sub(1);
        if edges < 3 {
            return EdgeTree { nodes: Vec::new() };
        }
        // Edge `i` (from 1) is item `i - 1`, in the box of its two vertices.
        let boxes: Vec<(Vector2<f64>, Vector2<f64>)> = vertices_m[1..edges]
            .windows(2)
            .map(|w| (w[0].inf(&w[1]), w[0].sup(&w[1])))
            .collect();
        Self::over_items(&boxes, 1)
    }

    /// A hierarchy over items `0..boxes.len()`, item `i` in the box `boxes[i]` (`(lo, hi)`):
    /// the same runs of consecutive items, for items that lie together in order (the pieces
    /// of a wall cut at its concave corners). Its queries visit item indices.
    pub(crate) fn over_boxes(boxes: &[(Vector2<f64>, Vector2<f64>)]) -> EdgeTree {
        Self::over_items(boxes, 0)
    }

    /// The hierarchy over `boxes`, item `i` named `i + first` in the queries.
    fn over_items(boxes: &[(Vector2<f64>, Vector2<f64>)], first: usize) -> EdgeTree {
        let mut tree = EdgeTree { nodes: Vec::new() };
        if !boxes.is_empty() {
            tree.nodes.reserve(2 * (boxes.len() / LEAF_EDGES + 1));
            tree.build(boxes, first, 0, boxes.len());
        }
        tree
    }

    /// Builds the node over items `start..end` of `boxes` (named from `first`) and returns
    /// its index.
    fn build(
        &mut self,
        boxes: &[(Vector2<f64>, Vector2<f64>)],
        first: usize,
        start: usize,
        end: usize,
    ) -> u32 {
        let index = self.nodes.len();
        let (lo_m, hi_m) = boxes[start + 1..end]
            .iter()
            .fold(boxes[start], |(lo, hi), (l, h)| (lo.inf(l), hi.sup(h)));
        self.nodes.push(Node {
            first_edge: first + start,
            end_edge: first + end,
            lo_m,
            hi_m,
            children: None,
        });
        if end - start > LEAF_EDGES {
            let mid = start + (end - start) / 2;
            let left = self.build(boxes, first, start, mid);
            let right = self.build(boxes, first, mid, end);
            self.nodes[index].children = Some([left, right]);
        }
        index as u32
    }

    /// Whether the tree is empty (fewer than three edges).
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Calls `visit` with every finite edge of the leaves whose box meets `lo_m..hi_m`, in
    /// increasing order, until `visit` returns `false`. Returns `false` if it stopped early.
    pub(crate) fn edges_meeting_box(
        &self,
        lo_m: &Vector2<f64>,
        hi_m: &Vector2<f64>,
        visit: impl FnMut(usize) -> bool,
    ) -> bool {
        // (Every node that meets the box has "distance" 0: ties keep the left half first.)
        self.walk(
            |node| if node.meets(lo_m, hi_m) { 0.0 } else { 1.0 },
            || 0.0,
            visit,
        )
    }

    /// Calls `visit` with the finite edges of every leaf whose box is within
    /// `sqrt(best_d2())` of `p_m` (`best_d2` read again before each node: the caller's best
    /// squared distance so far, which `visit` lowers), nearer halves first. A leaf farther
    /// than the best is skipped, one as far is not: ties are seen.
    pub fn edges_near_point(
        &self,
        p_m: &Vector2<f64>,
        best_d2: impl FnMut() -> f64,
        mut visit: impl FnMut(usize),
    ) {
        self.walk(
            |node| node.distance2(p_m),
            best_d2,
            |edge| {
                visit(edge);
                true
            },
        );
    }

    /// Calls `visit` with the finite edges of every leaf whose box is within
    /// `sqrt(best_d2())` of the segment `a_m -> b_m`, nearer halves first (as
    /// [`Self::edges_near_point`], for a segment).
    pub fn edges_near_segment(
        &self,
        a_m: &Vector2<f64>,
        b_m: &Vector2<f64>,
        best_d2: impl FnMut() -> f64,
        mut visit: impl FnMut(usize),
    ) {
        self.walk(
            |node| segment_box_distance2(a_m, b_m, &node.lo_m, &node.hi_m),
            best_d2,
            |edge| {
                visit(edge);
                true
            },
        );
    }

    /// The one walk of every query: a node whose `distance2` is above `bound()` is skipped,
    /// of two halves the nearer comes first (the left one on a tie, so that a box query's
    /// edges come in increasing order), and `visit` gets each edge of the leaves reached
    /// until it returns `false` (then the walk returns `false`).
    fn walk(
        &self,
        distance2: impl Fn(&Node) -> f64,
        mut bound: impl FnMut() -> f64,
        mut visit: impl FnMut(usize) -> bool,
    ) -> bool {
        if self.nodes.is_empty() {
            return true;
        }
        let mut stack = [0u32; MAX_DEPTH];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if distance2(node) > bound() {
                continue;
            }
            match node.children {
                Some([left, right]) => {
                    let (dl, dr) = (
                        distance2(&self.nodes[left as usize]),
                        distance2(&self.nodes[right as usize]),
                    );
                    // The nearer half on top of the stack.
                    let (near, far) = if dr < dl {
                        (right, left)
                    } else {
                        (left, right)
                    };
                    stack[top] = far;
                    stack[top + 1] = near;
                    top += 2;
                }
                None => {
                    for edge in node.first_edge..node.end_edge {
                        if !visit(edge) {
                            return false;
                        }
                    }
                }
            }
        }
        true
    }

    /// The tree of the polyline moved by `offset_m`.
    pub fn translate(&mut self, offset_m: &Vector2<f64>) {
        for node in &mut self.nodes {
            node.lo_m += offset_m;
            node.hi_m += offset_m;
        }
    }

    /// The tree of the polyline reflected `y -> -y` (its edges keep their indices).
    pub fn mirror_about_x_axis(&mut self) {
        for node in &mut self.nodes {
            let (lo_y, hi_y) = (node.lo_m.y, node.hi_m.y);
            node.lo_m.y = -hi_y;
            node.hi_m.y = -lo_y;
        }
    }
}

/// The squared distance from the segment `a -> b` to the box `lo..hi` (0 where they meet):
/// the segment clipped to the box (Liang and Barsky) meets it, else the distance between
/// two disjoint convex shapes is that of a vertex of one to the other.
pub(super) fn segment_box_distance2(
    a_m: &Vector2<f64>,
    b_m: &Vector2<f64>,
    lo_m: &Vector2<f64>,
    hi_m: &Vector2<f64>,
) -> f64 {
    let d = b_m - a_m;
    let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
    let mut meets = true;
    for (p, q) in [
        (-d.x, a_m.x - lo_m.x),
        (d.x, hi_m.x - a_m.x),
        (-d.y, a_m.y - lo_m.y),
        (d.y, hi_m.y - a_m.y),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                meets = false;
                break;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    if meets && t0 <= t1 {
        return 0.0;
    }
    let point_box = |p: &Vector2<f64>| {
        let dx = (lo_m.x - p.x).max(p.x - hi_m.x).max(0.0);
        let dy = (lo_m.y - p.y).max(p.y - hi_m.y).max(0.0);
        dx * dx + dy * dy
    };
    let corners = [
        *lo_m,
        Vector2::new(hi_m.x, lo_m.y),
        *hi_m,
        Vector2::new(lo_m.x, hi_m.y),
    ];
    corners
        .iter()
        .map(|c| point_segment_distance2(c, a_m, b_m))
        .fold(point_box(a_m).min(point_box(b_m)), f64::min)
}

/// The squared distance from `p_m` to the segment `a -> b`.
pub(super) fn point_segment_distance2(
    p_m: &Vector2<f64>,
    a_m: &Vector2<f64>,
    b_m: &Vector2<f64>,
) -> f64 {
    let d = b_m - a_m;
    let d2 = d.norm_squared();
    let s = if d2 > 0.0 {
        ((p_m - a_m).dot(&d) / d2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a_m + d * s - p_m).norm_squared()
}

/// The squared distance between the segments `a -> b` and `c -> d` (0 where they meet): two
/// disjoint segments are nearest at an end of one of them.
pub(super) fn segment_segment_distance2(
    a_m: &Vector2<f64>,
    b_m: &Vector2<f64>,
    c_m: &Vector2<f64>,
    d_m: &Vector2<f64>,
) -> f64 {
    let (u, v) = (b_m - a_m, d_m - c_m);
    let denom = u.x * v.y - u.y * v.x;
    if denom != 0.0 {
        let r = c_m - a_m;
        let s = (r.x * v.y - r.y * v.x) / denom;
        let t = (r.x * u.y - r.y * u.x) / denom;
        if (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t) {
            return 0.0;
        }
    }
    point_segment_distance2(a_m, c_m, d_m)
        .min(point_segment_distance2(b_m, c_m, d_m))
        .min(point_segment_distance2(c_m, a_m, b_m))
        .min(point_segment_distance2(d_m, a_m, b_m))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn walk(count: usize, seed: u64) -> Vec<Vector2<f64>> {
        let mut state = seed;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let mut p = Vector2::zeros();
        (0..count)
            .map(|_| {
                p += Vector2::new(0.01 + 0.01 * next(), 0.02 * next());
                p
            })
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// A box query visits, in order, exactly the edges of a scan whose run's box meets
        /// the query box, and among them every edge whose own box does.
        #[test]
        fn box_query_is_a_filtered_scan(
            count in 4usize..300, seed in any::<u64>(),
            cx in -0.5f64..4.0, cy in -0.3f64..0.3, w in 0.0f64..0.5,
        ) {
            let v = walk(count, seed);
            let tree = EdgeTree::new(&v);
            let (lo, hi) = (Vector2::new(cx - w, cy - w), Vector2::new(cx + w, cy + w));
            let mut seen = Vec::new();
            tree.edges_meeting_box(&lo, &hi, |e| { seen.push(e); true });
            prop_assert!(seen.windows(2).all(|p| p[0] < p[1]));
            for e in 1..count - 2 {
                let (a, b) = (v[e], v[e + 1]);
                let (elo, ehi) = (a.inf(&b), a.sup(&b));
                let meets = elo.x <= hi.x && lo.x <= ehi.x && elo.y <= hi.y && lo.y <= ehi.y;
                if meets {
                    prop_assert!(seen.contains(&e), "edge {e} missed");
                }
            }
        }

        /// The nearest-point search by the tree finds the exhaustive minimum.
        #[test]
        fn nearest_by_tree_is_exact(
            count in 4usize..300, seed in any::<u64>(),
            px in -0.5f64..4.0, py in -0.5f64..0.5,
        ) {
            let v = walk(count, seed);
            let tree = EdgeTree::new(&v);
            let p = Vector2::new(px, py);
            let d2 = |e: usize| point_segment_distance2(&p, &v[e], &v[e + 1]);
            let exhaustive = (1..count - 2).map(d2).fold(f64::INFINITY, f64::min);
            let best = core::cell::Cell::new(f64::INFINITY);
            tree.edges_near_point(&p, || best.get(), |e| best.set(best.get().min(d2(e))));
            prop_assert_eq!(best.get(), exhaustive);
            let best = core::cell::Cell::new(f64::INFINITY);
            let q = p + Vector2::new(0.05, -0.02);
            let seg = |e: usize| segment_segment_distance2(&p, &q, &v[e], &v[e + 1]);
            let exhaustive = (1..count - 2).map(seg).fold(f64::INFINITY, f64::min);
            tree.edges_near_segment(&p, &q, || best.get(), |e| best.set(best.get().min(seg(e))));
            prop_assert_eq!(best.get(), exhaustive);
        }

        /// The segment-to-box distance is that of dense samples of the segment, to the
        /// sampling's resolution, and never above it.
        #[test]
        fn segment_box_distance_matches_samples(
            ax in -1.0f64..1.0, ay in -1.0f64..1.0, bx in -1.0f64..1.0, by in -1.0f64..1.0,
        ) {
            let (a, b) = (Vector2::new(ax, ay), Vector2::new(bx, by));
            let (lo, hi) = (Vector2::new(-0.2, -0.1), Vector2::new(0.3, 0.25));
            let exact = segment_box_distance2(&a, &b, &lo, &hi).sqrt();
            let sampled = (0..=2000)
                .map(|k| {
                    let p = a + (b - a) * (k as f64 / 2000.0);
                    let dx = (lo.x - p.x).max(p.x - hi.x).max(0.0);
                    let dy = (lo.y - p.y).max(p.y - hi.y).max(0.0);
                    (dx * dx + dy * dy).sqrt()
                })
                .fold(f64::INFINITY, f64::min);
            prop_assert!(exact <= sampled + 1e-12);
            prop_assert!(sampled - exact <= (b - a).norm() / 2000.0 + 1e-12);
        }
    }
}
