//! A polyline without its vertices that are no corners at a tolerance (Douglas and
//! Peucker's recursion).

use nalgebra::Vector2;

use super::{Polyline, edge_tree};
use crate::walls::edge_tree::point_segment_distance2;

impl Polyline {
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
}
