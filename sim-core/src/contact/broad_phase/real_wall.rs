//! Whether a point touching a wall piece touches the wall the piece was cut from.

use nalgebra::Vector2;

use super::Query;
use crate::contact::geometry::into_cone;
use crate::contact::pair::{PairKey, PairKind};
use crate::contact::pieces::CUT_REACH_M;
use crate::walls::WallPoint;

impl Query<'_> {
    /// Whether chain point `x_m`, `gap_m` from piece `piece`, touches the wall the piece was
    /// cut from there.
    ///
    /// A piece of a polyline cut at a concave corner goes on straight past the cut (so that
    /// its signed distance stays smooth there). Past the cut by more than
    /// [`CUT_REACH_M`](super::pieces::CUT_REACH_M) the run-on is redundant with the
    /// neighbouring piece (see there), and a point whose foot lies there is not this
    /// piece's contact. Near the cut the run-on lies inside the neighbouring piece, where
    /// the wall's own signed distance is at most the piece's; farther on it can pass
    /// through the free space in front of another part of the wall (a short edge's line
    /// reaching back over a bump), where the wall is farther than the piece says: that is
    /// no wall at all. (On a piece's own edges the wall's distance is never more than the
    /// piece's.)
    pub(super) fn on_real_wall(&self, piece: usize, x_m: &Vector2<f64>, gap_m: f64) -> bool {
        if !self.pieces.cut[piece] {
            return true;
        }
        let mut at_piece = self.pieces.walls[piece].signed_distance(x_m);
        // The gap the pair measured (its evaluation's), with the piece's foot.
        at_piece.gap_m = gap_m;
        let real = self.walls[self.pieces.piece_of[piece]].signed_distance(x_m);
        self.on_real_wall_at(piece, &at_piece, &real)
    }

    /// [`Self::on_real_wall`] of a point whose nearest points on the cut piece `piece` and
    /// on the whole wall are `at_piece` and `real`.
    pub(super) fn on_real_wall_at(
        &self,
        piece: usize,
        at_piece: &WallPoint,
        real: &WallPoint,
    ) -> bool {
        let tol = self.settings.penetration_tolerance_m;
        let gap_m = at_piece.gap_m;
        if real.gap_m > gap_m + tol {
            return false;
        }
        let (from_m, to_m) = self.pieces.reach_m(piece);
        // Inside the wall, the piece whose own edges hold the wall's nearest point pushes
        // the point out, wherever its foot on the piece lies.
        let owns_nearest = || {
            let (first_m, last_m) = self.pieces.own_arclengths_m[piece];
            (first_m..=last_m).contains(&real.arclength_m)
        };
        // Farther along its run-on than a cut's reach (past an uncut end, or one line that
        // stands for several collinear pieces), the piece's line is the wall only where the
        // wall presses with the line's normal (replay `soak:4221:680`: a trapezoid's top line
        // run on back to where it leaves the wall through another edge, a tip wedged there).
        let (first_m, last_m) = self.pieces.own_arclengths_m[piece];
        let along_wall = || {
            let wall = &self.walls[self.pieces.piece_of[piece]];
            let cone = wall.shape.normal_cone(real, CUT_REACH_M);
            let n = at_piece.normal;
            (into_cone(n, cone, 1e-9) - n).norm() <= 1e-9
        };
        ((from_m..=to_m).contains(&at_piece.arclength_m)
            && ((first_m - CUT_REACH_M..=last_m + CUT_REACH_M).contains(&at_piece.arclength_m)
                || along_wall()))
            || (gap_m < -tol && owns_nearest())
    }

    /// [`Self::on_real_wall`] for a point pair (feature and corner-edge pairs are at corners
    /// and crests of the wall itself).
    pub(super) fn pair_on_real_wall(&self, key: &PairKey, x_m: &Vector2<f64>, gap_m: f64) -> bool {
        match key.kind {
            PairKind::Point(_) => self.on_real_wall(key.piece, x_m, gap_m),
            PairKind::Link { .. } | PairKind::CornerEdge { .. } => true,
        }
    }
}
