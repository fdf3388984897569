//! The walls as the contacts see them: polylines cut at their concave corners (the solver's
//! walls have no flat vertices, see [`super::QuasiStatic::new`]).
//!
//! The signed distance to a polyline has a kink along the bisector of each concave corner
//! (where the free side's angle is under 180 degrees): a point pressed into such a corner
//! touches both of its edges, two contacts with two normals. Cut there, each piece has only
//! convex corners and a signed distance that is smooth in free space; the solid is the union
//! of the pieces' solids near each cut, so a point stays out of the wall by staying out of
//! every piece. Straight pieces on one line (a trapezoid's top before and after its dip) are
//! one wall, not two copies of every contact.

use nalgebra::Vector2;

use crate::walls::edge_tree::EdgeTree;
use crate::{Surface, Wall, WallShape};

/// The contact pieces of `walls` and the wall each belongs to.
#[derive(Clone, Debug, Default)]
pub(crate) struct Pieces {
    /// The pieces.
    pub walls: Vec<Wall>,
    /// `piece_of[i]`: the index of the wall piece `i` belongs to.
    pub piece_of: Vec<usize>,
    /// `cut[i]`: piece `i` is one of several cut from its wall (its ends at the cuts go on
    /// straight past them).
    pub cut: Vec<bool>,
    /// `cut_ends[i]`: whether piece `i`'s first and last vertices are cuts (concave corners
    /// of its wall, not the wall's own ends).
    pub cut_ends: Vec<(bool, bool)>,
    /// `own_arclengths_m[i]`: the arclengths of piece `i`'s first and last vertices.
    pub own_arclengths_m: Vec<(f64, f64)>,
    /// `bounds_m[i]`: the bounding box of piece `i`'s vertices where both its ends are cuts
    /// (its contacts then lie near it, see [`Pieces::may_touch`]), else `None`.
    pub bounds_m: Vec<Option<(Vector2<f64>, Vector2<f64>)>>,
    /// The polyline pieces (`boxed[i]`: the piece of tree item `i`, in increasing order)
    /// and a box hierarchy over their vertices' boxes: a digitized wall is cut into
    /// thousands of pieces, and a chain point or a link is near a few of them
    /// ([`Self::near_box`]).
    boxed: Vec<usize>,
    tree: EdgeTree,
    /// The pieces without a vertices' box (lines, sinusoids): near everything.
    unboxed: Vec<usize>,
    /// The pieces without [`Self::bounds_m`] (not cut at both ends: their run-on reaches
    /// everywhere).
    open: Vec<usize>,
    /// `wall_cut[w]`: wall `w` is cut into several pieces.
    wall_cut: Vec<bool>,
}

/// How far past a cut a piece's straight run-on still counts, metres.
///
/// At a concave corner the run-on of each piece lies inside the other: a point outside the
/// other piece whose foot is past the cut is at least as far from this piece's run-on as
/// from the other piece, so the other piece's pair holds it and this one is redundant. The
/// run-on matters only about the corner itself, where a point pressed into it touches
/// both; farther on, on a wall with many small concave corners (a digitized one, whose
/// pieces all lie nearly on one line), the run-on of a distant piece passes within rounding
/// of a corner it has nothing to do with, and three pieces pressing on one point make the
/// contact equations degenerate. The allowance is a Newton iterate's wander about a corner.
pub(crate) const CUT_REACH_M: f64 = 1e-4;

/// Up to this many pieces, [`Pieces::near_box`] hands them all out.
const FEW_PIECES: usize = 16;

impl Pieces {
    /// Cuts `walls` into pieces.
    pub fn new(walls: &[Wall]) -> Pieces {
        let mut pieces = Pieces::default();
        for (w, wall) in walls.iter().enumerate() {
            match &wall.shape {
                WallShape::Polyline(polyline) => {
                    let split = polyline.split_at_concave_corners_with_cuts();
                    let cut = split.len() > 1;
                    for piece in split {
                        let (first_m, last_m) = piece.polyline.arclength_range_m();
                        pieces
                            .bounds_m
                            .push((piece.cut_at_start && piece.cut_at_end).then(|| {
                                let v = piece.polyline.vertices_m();
                                v.iter()
                                    .fold((v[0], v[0]), |(lo, hi), p| (lo.inf(p), hi.sup(p)))
                            }));
                        pieces.own_arclengths_m.push((first_m, last_m));
                        pieces.cut_ends.push((piece.cut_at_start, piece.cut_at_end));
                        pieces
                            .walls
                            .push(Wall::new(piece.polyline, wall.surfaces.clone()));
                        pieces.piece_of.push(w);
                        pieces.cut.push(cut);
                    }
                }
                _ => {
                    pieces.unboxed.push(pieces.walls.len());
                    pieces.walls.push(wall.clone());
                    pieces.piece_of.push(w);
                    pieces.cut.push(false);
                    pieces.cut_ends.push((false, false));
                    pieces.bounds_m.push(None);
                    pieces
                        .own_arclengths_m
                        .push((f64::NEG_INFINITY, f64::INFINITY));
                }
            }
        }
        let mut boxes = Vec::new();
        for (i, piece) in pieces.walls.iter().enumerate() {
            if let WallShape::Polyline(p) = &piece.shape {
                let v = p.vertices_m();
                boxes.push(
                    v.iter()
                        .fold((v[0], v[0]), |(lo, hi), p| (lo.inf(p), hi.sup(p))),
                );
                pieces.boxed.push(i);
            }
            if pieces.bounds_m[i].is_none() {
                pieces.open.push(i);
            }
        }
        pieces.tree = EdgeTree::over_boxes(&boxes);
        pieces.wall_cut = vec![false; walls.len()];
        for (i, &w) in pieces.piece_of.iter().enumerate() {
            pieces.wall_cut[w] |= pieces.cut[i];
        }
        pieces
    }

    /// The pieces whose vertices lie in part in the box `lo_m..hi_m` could, and the pieces
    /// with no box (lines, sinusoids) and, with `open`, the pieces not cut at both ends:
    /// into `out`, in increasing order. A broad phase: a piece whose vertices' box misses
    /// the box is left out (through the tree, `O(log pieces)` where few are near).
    pub fn near_box(
        &self,
        lo_m: &Vector2<f64>,
        hi_m: &Vector2<f64>,
        open: bool,
        out: &mut Vec<usize>,
    ) {
        out.clear();
        if self.walls.len() <= FEW_PIECES {
            // (Few pieces: each is checked by the caller's own tests; a query costs more.)
            out.extend(0..self.walls.len());
            return;
        }
        out.extend_from_slice(&self.unboxed);
        if open {
            out.extend_from_slice(&self.open);
        }
        self.tree.edges_meeting_box(lo_m, hi_m, |item| {
            out.push(self.boxed[item]);
            true
        });
        out.sort_unstable();
        out.dedup();
    }

    /// Whether wall `wall` is cut into several pieces.
    pub fn wall_is_cut(&self, wall: usize) -> bool {
        self.wall_cut[wall]
    }

    /// The arclengths along its wall between which a chain point's foot on piece `piece`
    /// may lie: past a cut end by at most [`CUT_REACH_M`], unbounded at the wall's own ends.
    pub fn reach_m(&self, piece: usize) -> (f64, f64) {
        let (first_m, last_m) = self.own_arclengths_m[piece];
        let (cut_at_start, cut_at_end) = self.cut_ends[piece];
        (
            if cut_at_start {
                first_m - CUT_REACH_M
            } else {
                f64::NEG_INFINITY
            },
            if cut_at_end {
                last_m + CUT_REACH_M
            } else {
                f64::INFINITY
            },
        )
    }

    /// Whether chain point `x_m`, `real_gap_m` from the whole wall, can be a contact of
    /// piece `piece` with a gap under `within_m` (a broad phase: `false` only where it
    /// cannot). A pair of a piece cut at both ends has its foot on the piece's own edges or
    /// within [`CUT_REACH_M`] past a cut (or, inside the wall, the wall's nearest point on
    /// them), and the piece's gap is at least the wall's less the penetration tolerance
    /// `tol_m`: the point lies within `max(within_m, |real_gap_m|) + CUT_REACH_M + tol_m` of
    /// the piece's vertices' bounding box.
    pub fn may_touch(
        &self,
        piece: usize,
        x_m: &Vector2<f64>,
        real_gap_m: f64,
        within_m: f64,
        tol_m: f64,
    ) -> bool {
        let Some((lo, hi)) = self.bounds_m[piece] else {
            return true;
        };
        let reach = within_m.max(real_gap_m.abs()) + CUT_REACH_M + tol_m;
        let dx = (lo.x - x_m.x).max(x_m.x - hi.x).max(0.0);
        let dy = (lo.y - x_m.y).max(x_m.y - hi.y).max(0.0);
        dx * dx + dy * dy <= reach * reach
    }

    /// The surface of the wall that piece `piece` belongs to at its point nearest to
    /// `point_m` (zones are laid out along the whole wall).
    pub fn surface_at(&self, walls: &[Wall], piece: usize, point_m: &Vector2<f64>) -> Surface {
        let wall = &walls[self.piece_of[piece]];
        if let Some(surface) = wall.surfaces.uniform_surface() {
            return surface;
        }
        wall.surface_at(&wall.signed_distance(point_m))
    }
}
