//! A polyline cut at its concave corners: pieces each with a smooth distance near its cut.

use nalgebra::Vector2;

use super::{Polyline, cross, edge_tree};
use crate::walls::SolidSide;

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

impl Polyline {
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
}
