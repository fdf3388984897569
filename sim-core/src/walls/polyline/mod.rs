//! A polyline wall (the thesis's trapezoid, 4.2.2): an open chain of straight edges whose first
//! and last edges extend to infinity as rays, so the wall splits the plane into a solid and a
//! free side.
//!
//! One concept a file, each an `impl Polyline` block: this one holds the shape (its
//! construction, accessors, the hierarchy of its edges' boxes, mirror and translate);
//! `crossing.rs` the crossing checks (edges that meet, a segment across the wall);
//! `distance.rs` the nearest point and signed distance, the normal cone and a segment's gap
//! lower bound; `segment_contact.rs` the deepest point of a segment (the halved search, the
//! equidistance candidates, a corner's contact); `features.rs` the convex corners (which are
//! convex, those near a segment, a segment resting on one, a point against one's edge);
//! `concave.rs` the cut at concave corners; `flat.rs` the vertices that are no corners;
//! `ray.rs` the ray query.

mod concave;
mod crossing;
mod distance;
mod features;
mod flat;
mod ray;
mod segment_contact;

use nalgebra::Vector2;

use super::SolidSide;
use super::edge_tree::EdgeTree;
use super::error::{WallError, finite};

pub use concave::ConcavePiece;

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

/// Polylines with fewer finite edges than this are searched edge by edge.
const TREE_FROM_EDGES: usize = 32;

/// The hierarchy of the finite edges of the polyline through `vertices_m`, or none if it has
/// fewer than [`TREE_FROM_EDGES`] edges.
fn edge_tree(vertices_m: &[Vector2<f64>]) -> EdgeTree {
    if vertices_m.len().saturating_sub(1) < TREE_FROM_EDGES {
        return EdgeTree::new(&[]);
    }
    EdgeTree::new(vertices_m)
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

#[cfg(test)]
mod tests {
    use nalgebra::Vector2;
    use proptest::prelude::*;

    use super::{EdgeTree, Polyline};
    use crate::walls::SolidSide;

    /// A noisy line of `count` vertices along `+x` (a digitized wall).
    pub(super) fn noisy_line(count: usize, seed: u64) -> Polyline {
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
    }
}
