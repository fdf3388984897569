//! The walls as the contacts see them: polylines cut at their concave corners.
//!
//! The signed distance to a polyline has a kink along the bisector of each concave corner
//! (where the free side's angle is under 180 degrees): a point pressed into such a corner
//! touches both of its edges, two contacts with two normals. Cut there, each piece has only
//! convex corners and a signed distance that is smooth in free space; the solid is the union
//! of the pieces' solids near each cut, so a point stays out of the wall by staying out of
//! every piece. Straight pieces on one line (a trapezoid's top before and after its dip) are
//! one wall, not two copies of every contact.

use nalgebra::Vector2;

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
}

impl Pieces {
    /// Cuts `walls` into pieces.
    pub fn new(walls: &[Wall]) -> Pieces {
        let mut pieces = Pieces::default();
        for (w, wall) in walls.iter().enumerate() {
            match &wall.shape {
                WallShape::Polyline(polyline) => {
                    let split = polyline.split_at_concave_corners();
                    let cut = split.len() > 1;
                    for piece in split {
                        pieces.walls.push(Wall::new(piece, wall.surfaces.clone()));
                        pieces.piece_of.push(w);
                        pieces.cut.push(cut);
                    }
                }
                _ => {
                    pieces.walls.push(wall.clone());
                    pieces.piece_of.push(w);
                    pieces.cut.push(false);
                }
            }
        }
        pieces
    }

    /// The surface of the wall that piece `piece` belongs to at its point nearest to
    /// `point_m` (zones are laid out along the whole wall).
    pub fn surface_at(&self, walls: &[Wall], piece: usize, point_m: &Vector2<f64>) -> Surface {
        let wall = &walls[self.piece_of[piece]];
        wall.surface_at(&wall.signed_distance(point_m))
    }
}
