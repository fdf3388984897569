//! After a solve: the points and features found inside a wall that no pair holds (missed),
//! and the pairs that are no longer what touches (stale: let go, passed on, handed back).

use super::{CORNER_CAPTURE_M, HAND_BACK_FRACTION, NEAREST, Query, carry, held_by_corner};
use crate::contact::pair::{ChainPoint, Pair, PairKey, PairKind};
use crate::walls::ConvexFeature;

impl Query<'_> {
    /// The pairs inside a wall after a solve to `x` (hair coordinates `hair_links`), with
    /// the probe posture at `x` ([`BroadPhase::probe_at`]), that are not pairs yet: per chain
    /// point and per link the [`NEAREST`] deepest. A link pushed into a rough stretch of
    /// wall (a digitized wall's noise) had every asperity under it join at once: up to 181
    /// pairs and 340 rank-one terms in one Newton system (issue #49), whose dense border
    /// (an LU, and an SVD where many corners pressing on one link make it rank deficient)
    /// was 70% of `examples/wall_digitized.toml`'s sweep. The deepest hold the link out;
    /// any still inside join in the next round (57.6 s -> 2.8 s for that sweep's first 6 s,
    /// every step certified; the CI sample's trajectories unchanged).
    pub(super) fn missed_pairs(
        &self,
        x: &[f64],
        hair_links: &[usize],
        pairs: &[Pair],
    ) -> Vec<Pair> {
        let tol = self.settings.penetration_tolerance_m;
        let beta = self.beta_of(x, hair_links);
        self.touching(self.probe, &beta, -tol, NEAREST)
            .into_iter()
            .filter(|key| {
                !pairs
                    .iter()
                    .any(|c| c.key == *key || held_by_corner(c, key))
            })
            .map(|key| self.fresh_pair(key))
            .collect()
    }

    /// Removes the feature pairs that are not what touches at the solution (a feature whose
    /// foot has left its link, or whose cone no longer holds the link's normal) and the
    /// corner-edge pairs that no longer stand for their point ([`CornerEdgeState`]); whether
    /// one of them was active (the step must then be solved again).
    ///
    /// A loaded corner-edge pair whose point the solution puts past its corner on the
    /// edge's line ([`CornerEdgeState::PastCorner`]) is handed, with its force, to the line
    /// of the corner's other edge: a point whose motion carries it around the corner (a
    /// hair tip on a circle about its joint, pressed onto the lip of a step) comes to rest
    /// on the other edge within nanometres of the corner, where a point pair's normal turns
    /// at `1 / gap` and Newton's method stalls. Past the other edge's corner too, the point
    /// is clear of both edges and the pair lets go.
    ///
    /// A loaded corner pair standing for a joint ([`Self::joint_corner_pairs`]) whose foot
    /// the solution puts just past the link's end at the joint, where the joint's other
    /// link does not rest on the corner either, hands its force back to the joint's point
    /// pair: the joint slid off the corner onto the edge beside it, and dropped without a
    /// hand-over the joint would lose its contact for the next solve (and swing into the
    /// wall).
    ///
    /// A loaded crest pair whose foot the solution puts past its link's end at a joint
    /// hands its force on to the crest's pair of the joint's other link, however far past,
    /// wherever that link can rest on the crest ([`Self::crest_passes_on`]): a crest is
    /// smooth, and a chain bent around it passes its contact from link to link, the joint
    /// between them clear of the crest. Only where the other link is steeper than the
    /// crest's flanks (it cannot be tangent to the crest) does the joint ride over it: the
    /// joint's point pair takes the force back as from a corner. On the thesis's 14.2
    /// cycles/m sinusoid under 110 links, step 1014: the crest's foot on link 73 slid to
    /// 2.6% past the link's end, and the pair was dropped with no hand-over (past the 1% a
    /// joint takes a corner back from); the solve without it failed, the halved steps
    /// handed the crest to joint 73, whose solves stalled at a residual of 1e-9 m, and
    /// after twelve halvings a snap's flow put the crest 1.2% into link 74 (1,229 Newton
    /// iterations; the joints moved 1.3e-4 rad). Handed to link 74's pair, the step takes
    /// 5. Over 20 s of that sinusoid, under every N from 30 to 150 no step snaps (14 to 24
    /// did from 60 links on) and at most 6 of 2,000 take more than 40 Newton iterations
    /// (the p99 77 -> 7 under 110 links, 147 -> 7 under 150). Handed on where the other
    /// link cannot rest on the crest, 16 soak sweeps failed (13 of them placements on
    /// sinusoids of 20-30 mm crest radius under 40 mm links; replays `soak:4221:603`, `soak:4221:1125`). A crest
    /// pair that handed its crest on once in a (sub)step hands it on no more: past its link's
    /// end again (within [`HAND_BACK_FRACTION`]), the crest lies between the two links'
    /// lines, each foot past the joint, and the joint rides over it; its pair takes the
    /// force back, even where it is already in the step unloaded (where it kept no force,
    /// the crest's was lost). Without friction, 150 links along the same sinusoid handed a
    /// crest between links 124 and 125 in every round of a snap's flow and failed at t =
    /// 2.74 s; the sweep now finishes (p99 31 over 20 s). Barring the crest's way back to
    /// the link that handed it on instead cost the frictionless sweep under 72 links a p99
    /// of 206 (28 this way) and did not help with friction.
    ///
    /// Each pair hands over at most once in a (sub)step (a crest's pair twice: on to the
    /// other link, and then to its joint): `handed_over` records them, and a point pair is
    /// not handed to a stand-in recorded there ([`Self::hand_point_pairs_to_stand_ins`]).
    pub(super) fn drop_stale_pairs(
        &self,
        pairs: &mut Vec<Pair>,
        handed_over: &mut Vec<PairKey>,
    ) -> bool {
        let before = pairs.len();
        let mut active = false;
        let mut handed: Vec<Pair> = Vec::new();
        // Unloaded pairs already in the step that take over a force: the other link's at a
        // joint (a corner's), or the joint's own (a crest's handed back).
        let mut taken_over: Vec<(PairKey, Pair)> = Vec::new();
        // The corners that links rest on at the solution.
        let resting: Vec<PairKey> = pairs
            .iter()
            .filter(|c| c.geo.valid && matches!(c.key.kind, PairKind::Link { .. }))
            .map(|c| c.key)
            .collect();
        pairs.retain(|c| {
            let state = self.corner_edge_state(c);
            let keep = c.geo.valid
                && self.pair_on_real_wall(&c.key, &c.geo.point_m, c.geo.gap_m)
                && state == CornerEdgeState::OnCorner;
            if !keep && c.is_loaded() {
                active = true;
                match (state, c.key.kind) {
                    (CornerEdgeState::Left, _) => {
                        if let Some(point) = c.key.chain_point() {
                            let mut h = self.fresh_pair(PairKey::point(point, c.key.piece));
                            carry(&mut h, c);
                            handed.push(h);
                        }
                    }
                    (
                        CornerEdgeState::PastCorner,
                        PairKind::CornerEdge {
                            point,
                            feature,
                            after,
                        },
                    ) => {
                        let other = PairKey::corner_edge(point, feature, !after, c.key.piece);
                        if !handed_over.contains(&other) && !handed_over.contains(&c.key) {
                            handed_over.push(c.key);
                            let mut h = self.fresh_pair(other);
                            carry(&mut h, c);
                            handed.push(h);
                        }
                    }
                    (_, PairKind::Link { link, feature }) => {
                        // A corner or crest slid past the link's end at a joint: the
                        // joint's other link takes the force over where it rests on the
                        // feature, or where a crest passes on to it; else the joint's own
                        // pair takes the force back (a corner that stood for the joint),
                        // and does not hand it to the feature again in this (sub)step.
                        // The joint at the end the foot is nearer, its other link, and
                        // that end's fraction along this link.
                        let (end, other, end_s) = if c.geo.s < 0.5 {
                            (link - 1, link - 1, 0.0)
                        } else {
                            (link, link + 1, 1.0)
                        };
                        let at_end = (c.geo.s - end_s).abs() <= HAND_BACK_FRACTION;
                        let other_key = PairKey::link(other, feature, c.key.piece);
                        let is_crest = matches!(feature, ConvexFeature::Crest { .. });
                        if resting.contains(&other_key) {
                            // The joint's other link rests on the corner: its pair takes
                            // the force over (started unloaded, the solve found no way
                            // from one link to the other, replay `soak:4221:1590`).
                            taken_over.push((other_key, *c));
                        } else if self.crest_passes_on(&other_key) && !handed_over.contains(&c.key)
                        {
                            handed_over.push(c.key);
                            let mut h = self.fresh_pair(other_key);
                            carry(&mut h, c);
                            handed.push(h);
                        } else if at_end && end >= 1 && (!handed_over.contains(&c.key) || is_crest)
                        {
                            // (A crest handed on once in this (sub)step and past its link's
                            // end again goes to the joint: it lies between the two links'
                            // lines.)
                            handed_over.push(c.key);
                            let point = PairKey::point(ChainPoint::Vertex(end), c.key.piece);
                            if is_crest {
                                // Unloaded, the joint's pair would keep no force, and the
                                // crest's would be lost for the next round.
                                taken_over.push((point, *c));
                            }
                            let mut h = self.fresh_pair(point);
                            carry(&mut h, c);
                            handed.push(h);
                        }
                    }
                    _ => {}
                }
            }
            keep
        });
        for (key, old) in &taken_over {
            if let Some(p) = pairs.iter_mut().find(|p| p.key == *key && !p.is_loaded()) {
                carry(p, old);
            }
        }
        let changed = active && pairs.len() < before;
        handed.retain(|h| !pairs.iter().any(|c| c.key == h.key));
        pairs.extend(handed);
        changed
    }

    /// Where a corner-edge pair's point is at the solution (any other pair: on its
    /// corner).
    fn corner_edge_state(&self, c: &Pair) -> CornerEdgeState {
        let PairKind::CornerEdge { feature, .. } = c.key.kind else {
            return CornerEdgeState::OnCorner;
        };
        let piece = &self.pieces.walls[c.key.piece];
        let near = piece
            .shape
            .corner_m(feature)
            .is_some_and(|corner| (c.geo.point_m - corner).norm() <= CORNER_CAPTURE_M);
        let tol = self
            .settings
            .penetration_tolerance_m
            .max(self.settings.acceptable_m);
        if !near {
            // Along its own edge, the edge's line is the wall: the pair stands (a point pair
            // would restart the next round at the corner, where its normal turns at
            // `1 / gap`). Past the edge's other end, or lifted off where the piece is
            // nearer than the line, the point's own pair takes over.
            let at_piece = piece.signed_distance(&c.geo.point_m);
            let on_own_edge = at_piece.curvature_per_m == 0.0
                && at_piece.normal.dot(&c.geo.normal) > 1.0 - 1e-12
                && (at_piece.gap_m - c.geo.gap_m).abs() <= tol
                && self.on_real_wall(c.key.piece, &c.geo.point_m, c.geo.gap_m);
            return if on_own_edge {
                CornerEdgeState::OnCorner
            } else {
                CornerEdgeState::Left
            };
        }
        if c.is_loaded() && piece.signed_distance(&c.geo.point_m).gap_m > tol {
            CornerEdgeState::PastCorner
        } else {
            CornerEdgeState::OnCorner
        }
    }
}

/// Where a corner-edge pair's point is after a solve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum CornerEdgeState {
    /// Within [`CORNER_CAPTURE_M`] of the corner and on the wall (or not loaded), or on
    /// the edge's own stretch of wall (where the edge's line is the wall): the pair stands.
    OnCorner,
    /// Farther from the corner and off its own edge (past the edge's other end, or lifted
    /// off where the piece is nearer than the edge's line): the point's own pair takes
    /// over, with the force. Along its own edge the pair stands ([`Self::OnCorner`]).
    Left,
    /// Loaded while off the wall beside the corner: pressed onto the edge's line where it
    /// runs on past the corner through free space, where no wall holds it. A point cannot
    /// rest loaded on a convex corner without friction to hold it (any load in the
    /// corner's normal cone slides it onto one edge or the other); it slips off the corner
    /// and the pair lets go, without handing its force on, so that the point comes down
    /// wherever it lands (a pair then joins as any point inside a wall does).
    PastCorner,
}
