//! The broad phase's one query: which pairs are within a distance of touching in a posture.

use nalgebra::Vector2;

use super::Query;
use crate::contact::geometry::{FOOT_TOLERANCE, chain_point};
use crate::contact::pair::{ChainPoint, PairKey};
use crate::contact::pieces::CUT_REACH_M;
use crate::contact::posture::Posture;
use crate::walls::lerp;
use crate::walls::{FeatureContact, WallPoint};

/// A feature poking through a link's line by `d` is inside the link only where the link's
/// point there is at least this fraction of `d` inside the wall. A corner turning by at
/// most 85 degrees, pushed `d` through a link whose normal lies at the edge of its cone,
/// leaves the link's point `d cos(85 deg) = 0.087 d` inside (replay `soak:4221:176`, kept by `soak_sweeps_fixed_since_still_finish`); a crest across a
/// steep tip link, out of the link's reach, leaves it on the wall (replay `soak:4221:258`, kept by `soak_sweeps_fixed_since_still_finish`: `d` = 6 cm,
/// the tip resting on the wall).
const THROUGH_LINE_DEPTH_FRACTION: f64 = 0.02;

impl Query<'_> {
    /// The pairs of `posture` (hair angles `beta`) with a gap below `within_m`: per chain
    /// point and per link, the `keep` nearest (deepest).
    pub(super) fn touching(
        &self,
        posture: &Posture,
        beta: &[f64],
        within_m: f64,
        keep: usize,
    ) -> Vec<PairKey> {
        let n = self.chain.n();
        let mut keys = Vec::new();
        let mut features: Vec<FeatureContact> = Vec::new();
        // A feature whose foot is just past a link's end is a pair of the link while it is
        // near (it hands over to the end's point pair without chatter), but it is not in
        // the link: only a foot on the link itself makes a link inside a wall (a solve
        // that ends with such a pair's foot past the end drops it, and the link swings
        // past a corner its end does not reach).
        let foot_tolerance = if within_m > 0.0 { FOOT_TOLERANCE } else { 0.0 };
        let mut near: Vec<(f64, PairKey)> = Vec::new();
        // Per wall, its own nearest point to the chain point at hand (only where a piece of
        // it is cut, and once).
        let mut real: Vec<Option<WallPoint>> = Vec::with_capacity(self.walls.len());
        // The pieces near the chain point or link at hand (the broad phase over pieces: a
        // digitized wall is thousands of them).
        let mut near_pieces: Vec<usize> = Vec::new();
        let take = |near: &mut Vec<(f64, PairKey)>, keys: &mut Vec<PairKey>| {
            near.sort_by(|a, b| a.0.total_cmp(&b.0));
            keys.extend(near.drain(..).take(keep).map(|(_, k)| k));
        };
        for link in 1..=n {
            let mut points = vec![ChainPoint::Vertex(link)];
            if self.chain.hairs().get(link).is_some_and(Option::is_some) {
                points.push(ChainPoint::HairTip(link));
            }
            for point in points {
                let (_, _, x) = chain_point(self.chain, posture, beta, point);
                real.clear();
                real.resize(self.walls.len(), None);
                // A piece cut at both ends can hold the point only within
                // `Pieces::may_touch`'s reach of its vertices' box; the reach takes each cut
                // wall's own gap at the point (the one the loop below uses).
                let mut reach_m = within_m.max(0.0);
                for (wall, at) in real.iter_mut().enumerate() {
                    if self.pieces.wall_is_cut(wall) {
                        let gap_m = at
                            .get_or_insert_with(|| self.walls[wall].signed_distance(&x))
                            .gap_m;
                        reach_m = reach_m.max(gap_m.abs());
                    }
                }
                let reach_m = reach_m + CUT_REACH_M + self.settings.penetration_tolerance_m;
                self.pieces.near_box(
                    &x.add_scalar(-reach_m),
                    &x.add_scalar(reach_m),
                    true,
                    &mut near_pieces,
                );
                for &w in &near_pieces {
                    let piece = &self.pieces.walls[w];
                    // The broad phase: a piece the point cannot come within `within_m` of.
                    if piece.gap_lower_bound_m(&x) >= within_m {
                        continue;
                    }
                    let real_point = if self.pieces.cut[w] {
                        let wall = self.pieces.piece_of[w];
                        let at =
                            *real[wall].get_or_insert_with(|| self.walls[wall].signed_distance(&x));
                        if !self.pieces.may_touch(
                            w,
                            &x,
                            at.gap_m,
                            within_m,
                            self.settings.penetration_tolerance_m,
                        ) {
                            continue;
                        }
                        Some(at)
                    } else {
                        None
                    };
                    let wall_point = piece.signed_distance(&x);
                    let gap_m = wall_point.gap_m;
                    if gap_m < within_m
                        && real_point.is_none_or(|r| self.on_real_wall_at(w, &wall_point, &r))
                    {
                        let stand_ins = self.stand_ins(posture, point, w, &wall_point, &x);
                        if stand_ins.iter().any(Option::is_some) {
                            keys.extend(stand_ins.into_iter().flatten());
                        } else {
                            near.push((gap_m, PairKey::point(point, w)));
                        }
                    }
                }
                take(&mut near, &mut keys);
            }
            // The pieces whose corners can be near the link (`features_near_segment`'s own
            // box: the link's grown by the margin and half its length).
            let (a_m, b_m) = (posture.start_of(link), posture.end_m[link]);
            let reach_m = within_m.max(0.0) + 0.5 * (b_m - a_m).norm();
            self.pieces.near_box(
                &a_m.inf(&b_m).add_scalar(-reach_m),
                &a_m.sup(&b_m).add_scalar(reach_m),
                false,
                &mut near_pieces,
            );
            for &w in &near_pieces {
                let piece = &self.pieces.walls[w];
                features.clear();
                piece.shape.features_near_segment(
                    &posture.start_of(link),
                    &posture.end_m[link],
                    within_m,
                    &mut features,
                );
                for fc in &features {
                    // A feature that pokes through the link's line where the link itself is
                    // not that deep in the wall (a crest across a steep link, beyond the
                    // link's reach), or just past the link's end (the line run on past a
                    // bent joint cuts into a corner that rests on the joint's other link),
                    // is not what the link touches.
                    // A thin spike of a rough wall (a digitized one's noise) can poke through
                    // the link with the link's point at the foot outside it, the link
                    // passing through the spike's flank beside the foot: the link's deepest
                    // point near the foot ([`THROUGH_LINE_WINDOW`]) counts too.
                    let tol = self.settings.penetration_tolerance_m;
                    let shallow = |gap_m: f64| gap_m > THROUGH_LINE_DEPTH_FRACTION * fc.gap_m;
                    let through_line_only = past_end_through_line(fc, tol)
                        || (fc.gap_m < -tol
                            && shallow(piece.signed_distance(&fc.point_m).gap_m)
                            && shallow(depth_near_foot(
                                piece,
                                &posture.start_of(link),
                                &posture.end_m[link],
                                fc,
                            )));
                    if fc.supported
                        && !through_line_only
                        && fc.s >= -foot_tolerance
                        && fc.s <= 1.0 + foot_tolerance
                    {
                        near.push((fc.gap_m, PairKey::link(link, fc.feature, w)));
                    }
                }
            }
            take(&mut near, &mut keys);
        }
        keys.sort();
        keys.dedup();
        keys
    }
}

/// Whether feature `fc` pokes through its segment's line (by more than `tolerance_m`) past
/// the segment's end: the line of a link run on past a bent joint cuts into a corner that
/// rests on the joint's other link, which is no contact of this link.
pub(super) fn past_end_through_line(fc: &FeatureContact, tolerance_m: f64) -> bool {
    fc.gap_m < -tolerance_m && !(0.0..=1.0).contains(&fc.s)
}

/// The window about a feature's foot on a link, in multiples of the feature's depth through
/// the link's line, within which the link's own deepest point shows that the feature is in
/// the link: a spike of half-angle `a` pushed `d` through the line holds the line's points
/// within `d tan(a)` of its foot, and a leaning one holds them off the foot by as much
/// again (noise of 0.1 mm every 0.1 mm: flanks of up to 80 degrees, `tan = 5.7`).
const THROUGH_LINE_WINDOW: f64 = 10.0;

/// The gap of the deepest point of the link `a -> b` against `piece` within
/// [`THROUGH_LINE_WINDOW`] times the depth of feature `fc` of its foot (`+inf` for a link of
/// no length).
fn depth_near_foot(
    piece: &crate::Wall,
    a_m: &Vector2<f64>,
    b_m: &Vector2<f64>,
    fc: &FeatureContact,
) -> f64 {
    let length_m = (b_m - a_m).norm();
    if length_m.is_nan() || length_m <= 0.0 {
        return f64::INFINITY;
    }
    let half = THROUGH_LINE_WINDOW * fc.gap_m.abs() / length_m;
    let (s0, s1) = ((fc.s - half).max(0.0), (fc.s + half).min(1.0));
    if s0.is_nan() || s1.is_nan() || s0 >= s1 {
        return f64::INFINITY;
    }
    piece
        .segment_contact(&lerp(a_m, b_m, s0), &lerp(a_m, b_m, s1))
        .wall
        .gap_m
}
