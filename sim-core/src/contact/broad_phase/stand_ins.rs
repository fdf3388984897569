//! Stand-ins: a point pair that would hold the same material point as another pair, or be
//! singular (a joint on a corner a link rests on, a point on a convex corner), handed to the
//! pairs that stand for it; crests passed from a sliding or stuck joint onto a link.

use nalgebra::Vector2;

use super::touching::past_end_through_line;
use super::{CORNER_CAPTURE_M, HAND_BACK_FRACTION, Query, carry};
use crate::contact::feature::Slip;
use crate::contact::geometry::{FOOT_TOLERANCE, chain_point};
use crate::contact::pair::{ChainPoint, Pair, PairKey, PairKind};
use crate::contact::posture::{Pose, Posture, theta_of};
use crate::walls::{ConvexFeature, WallPoint};

impl Query<'_> {
    /// For a joint at a convex corner of piece `piece` (its nearest point of the piece,
    /// `wall_point`, is the corner, or lies on an edge ending at it): the pairs of the
    /// joint's two links with that corner where a link rests on it at the joint (the
    /// corner's foot at the link's joint end within [`FOOT_TOLERANCE`], or anywhere on the
    /// link where the joint is nearest to the corner itself; the link's normal in the
    /// corner's cone). They stand for the joint's own pair: at the same material point, the
    /// joint's pair (against the edge, or the corner with a normal undefined when the joint
    /// sits on it) would be a second normal and a second stick condition on the point that
    /// the links' pairs already hold, and Newton's system on both is singular. The links'
    /// pairs have smooth gaps and normals, and their forces span the cone between the
    /// links' normals. `[None, None]` for a hair tip, a joint away from the corners, or a
    /// corner no link rests on at the joint (a joint bent into a point against it): the
    /// point pair stands.
    pub(super) fn joint_corner_pairs(
        &self,
        posture: &Posture,
        point: ChainPoint,
        piece: usize,
        wall_point: &WallPoint,
    ) -> [Option<PairKey>; 2] {
        let ChainPoint::Vertex(joint) = point else {
            return [None, None];
        };
        let shape = &self.pieces.walls[piece].shape;
        let at_corner = wall_point.curvature_per_m == f64::INFINITY;
        let mut out = [None, None];
        for feature in shape.convex_features_by(wall_point).into_iter().flatten() {
            let rests_on = |link: usize, joint_end: f64| {
                (link >= 1 && link <= self.chain.n())
                    .then(|| {
                        shape.feature_contact(
                            feature,
                            &posture.start_of(link),
                            &posture.end_m[link],
                        )
                    })
                    .flatten()
                    .filter(|fc| {
                        // Past the tip no link follows to take the corner over: the tip's
                        // own pair stands for a corner beyond it.
                        let past_end = if link == self.chain.n() {
                            0.0
                        } else {
                            FOOT_TOLERANCE
                        };
                        let on_link = if at_corner {
                            fc.s >= -FOOT_TOLERANCE && fc.s <= 1.0 + past_end
                        } else {
                            (fc.s - joint_end).abs() <= FOOT_TOLERANCE && fc.s <= 1.0 + past_end
                        };
                        fc.supported
                            && on_link
                            && !past_end_through_line(fc, self.settings.penetration_tolerance_m)
                    })
                    .map(|_| PairKey::link(link, feature, piece))
            };
            let found = [rests_on(joint, 1.0), rests_on(joint + 1, 0.0)];
            if found.iter().any(Option::is_some) {
                out = found;
                break;
            }
        }
        out
    }

    /// The pairs that stand for chain point `point` (at `x_m`, its nearest point of piece
    /// `piece` `wall_point`) against the piece where a point pair would be singular: the
    /// links resting on a corner at a joint ([`Self::joint_corner_pairs`]), else the point
    /// on a convex corner against the line of the edge it lies on
    /// ([`Self::corner_point_pairs`]); `[None, None]` where the point pair stands.
    pub(super) fn stand_ins(
        &self,
        posture: &Posture,
        point: ChainPoint,
        piece: usize,
        wall_point: &WallPoint,
        x_m: &Vector2<f64>,
    ) -> [Option<PairKey>; 2] {
        let mut links = self.joint_corner_pairs(posture, point, piece, wall_point);
        if links.iter().any(Option::is_some) {
            // The tip has no second link to span the corner's cone with the tip link: the
            // tip against the line of the corner's edge it lies on stands beside the tip
            // link's pair. Alone, the tip link's pair holds the tip's force normal to the
            // link, and a tip resting on the corner that needs more than that (pressed on
            // the edge past it) was never an equilibrium of a plain solve: the solve slid
            // the corner past the tip along the link's line, and the snap's flow came to
            // rest where no plain solve converged (replay `soak:4221:1261`, 4 links on a digitized
            // trapezoid: its placement's settle stopped after 100,000 Newton iterations).
            if point == ChainPoint::Vertex(self.chain.n()) && links[1].is_none() {
                links[1] = self.corner_point_pairs(point, piece, wall_point, x_m)[0];
            }
            return links;
        }
        self.corner_point_pairs(point, piece, wall_point, x_m)
    }

    /// For chain point `point` at `x_m` within [`CORNER_CAPTURE_M`] of a convex corner of
    /// piece `piece` (found by its nearest point `wall_point`): the point against the line
    /// of the corner's edge it lies on ([`PairKind::CornerEdge`]; past the corner, the edge
    /// whose line it is nearest). `[None, None]` elsewhere.
    pub(super) fn corner_point_pairs(
        &self,
        point: ChainPoint,
        piece: usize,
        wall_point: &WallPoint,
        x_m: &Vector2<f64>,
    ) -> [Option<PairKey>; 2] {
        let shape = &self.pieces.walls[piece].shape;
        let on_edge = wall_point.curvature_per_m.is_finite();
        for (end, feature) in shape.convex_features_by(wall_point).into_iter().enumerate() {
            let Some(feature) = feature else { continue };
            if !shape
                .corner_m(feature)
                .is_some_and(|c| (x_m - c).norm() <= CORNER_CAPTURE_M)
            {
                continue;
            }
            // On an edge, the corner at its start (`end = 0`) is the one the edge leaves.
            let after = if on_edge {
                end == 0
            } else {
                let gap = |after| {
                    shape
                        .corner_edge_point(feature, after, x_m)
                        .map_or(f64::INFINITY, |wp| wp.gap_m)
                };
                gap(true) < gap(false)
            };
            return [
                Some(PairKey::corner_edge(point, feature, after, piece)),
                None,
            ];
        }
        [None, None]
    }

    /// Replaces each point pair of `pairs` that has stand-ins in `posture` (hair angles
    /// `beta`) by them ([`Self::stand_ins`]: a joint on a corner a link rests on, a point on
    /// a convex corner); a stand-in that is not yet a pair starts from the point pair's
    /// forces and friction state. Whether a pair carrying force was replaced (the step must
    /// then be solved again).
    /// A stand-in in `refused` (one that handed its force back in this (sub)step, see
    /// [`Self::drop_stale_pairs`]) is not taken again: the point pair stands.
    pub(super) fn hand_point_pairs_to_stand_ins(
        &self,
        posture: &Posture,
        beta: &[f64],
        pairs: &mut Vec<Pair>,
        refused: &[PairKey],
    ) -> bool {
        let mut changed = false;
        let mut i = 0;
        while i < pairs.len() {
            let key = pairs[i].key;
            let stand_ins = match key.kind {
                PairKind::Point(point) => {
                    let (_, _, x) = chain_point(self.chain, posture, beta, point);
                    let wall_point = self.pieces.walls[key.piece].signed_distance(&x);
                    self.stand_ins(posture, point, key.piece, &wall_point, &x)
                }
                _ => [None, None],
            };
            if stand_ins.iter().all(Option::is_none)
                || stand_ins.iter().flatten().any(|k| refused.contains(k))
            {
                i += 1;
                continue;
            }
            let old = pairs.remove(i);
            changed |= old.is_loaded();
            let mut handed = false;
            for key in stand_ins.into_iter().flatten() {
                if pairs.iter().any(|c| c.key == key) {
                    continue;
                }
                let mut c = self.fresh_pair(key);
                if !handed {
                    carry(&mut c, &old);
                    handed = true;
                }
                pairs.push(c);
            }
        }
        changed
    }

    /// [`Self::hand_point_pairs_to_stand_ins`] at the solution `x` (hair coordinates
    /// `hair_links`), with the probe posture there ([`BroadPhase::probe_at`]).
    pub(super) fn hand_point_pairs_to_stand_ins_at_probe(
        &self,
        x: &[f64],
        hair_links: &[usize],
        pairs: &mut Vec<Pair>,
        refused: &[PairKey],
    ) -> bool {
        let beta = self.beta_of(x, hair_links);
        self.hand_point_pairs_to_stand_ins(self.probe, &beta, pairs, refused)
    }

    /// Removes the fresh pairs of a link with a corner at a joint whose own pair stands and
    /// is loaded (the last step's solution has the joint on the wall beside the corner,
    /// with no link resting on it): both would hold the same material point, and Newton's
    /// system on both is singular. If the step brings the link onto the corner, the link
    /// joins as any feature inside a link does, after the solve.
    ///
    /// A crest has no single point to compare: where the joint's pair is loaded and stuck
    /// (it does not move along the crest), a crest pair of either of the joint's links
    /// whose foot lies past that link's end at the joint ([`Self::crest_past_joint`])
    /// measures the link's line run on past the joint, which no matter of the link
    /// touches, at the joint's own contact. On the thesis's 14.2 cycles/m sinusoid under 30
    /// links (mu = 0.3), joint 23 stuck on a crest for 35 steps while the crest's foot on
    /// link 24's line went from 0.1% to 1.4% of the link before its start, 6 nm to 1.1 um
    /// through that line: with both pairs each full step's solve failed after 40 to 120
    /// Newton iterations and the step was taken in halves (p99 123 Newton iterations per
    /// step over 20 s; 5 without the line's pair). A sliding joint keeps them: its crest is
    /// on its way onto the next link (under 150 links, dropping them there too took 32,099
    /// -> 47,530 Newton iterations over the same 20 s).
    pub(super) fn drop_links_doubling_loaded_joints(&self, pairs: &mut Vec<Pair>) {
        let mut doubled: Vec<PairKey> = Vec::new();
        for c in pairs.iter() {
            let PairKind::Point(ChainPoint::Vertex(joint)) = c.key.kind else {
                continue;
            };
            if !c.is_loaded() {
                continue;
            }
            let piece = &self.pieces.walls[c.key.piece];
            let wall_point = piece.signed_distance(&self.start.end_m[joint]);
            for feature in piece
                .shape
                .convex_features_by(&wall_point)
                .into_iter()
                .flatten()
            {
                for link in [joint, joint + 1] {
                    doubled.push(PairKey::link(link, feature, c.key.piece));
                }
            }
            if c.slip == Slip::Stuck {
                doubled.extend(
                    pairs
                        .iter()
                        .filter(|d| self.crest_past_joint(d, joint, c.key.piece))
                        .map(|d| d.key),
                );
            }
        }
        pairs.retain(|c| c.is_loaded() || !doubled.contains(&c.key));
    }

    /// Hands the force of a joint sliding on a crest to the crest's pair of one of the
    /// joint's links whose foot, past the link's end at the joint where the last step left
    /// the chain, the driver's secant prediction at `goal` (`predicted`) puts on the
    /// link: the crest passes from the joint onto that link in this step. The joint's pair
    /// leaves the step (the two would hold one contact). On the thesis's 14.2 cycles/m
    /// sinusoid under 110 links, joint 87 slid on a crest whose foot on link 88 was 1.3% of
    /// the link before its start: with both pairs the step's solve failed, the step was
    /// halved, and the halves found the crest 6% and 11% into link 88 (30 Newton
    /// iterations, 62 in all). Over 20 s of that sinusoid, steps over 40 Newton iterations:
    /// 37 -> 32 under 150 links, 26 -> 23 under 110, 20 -> 19 under 100, none more at any N
    /// from 4 to 150. With the last posture carried with the base as the prediction
    /// instead, which puts every such foot some 5% of a link further on, under 100 links
    /// joint 64 handed a crest to link 65 that stayed past its start (20 -> 21). Only on a
    /// surface with friction (dropped for the step or not: under 4 links, where friction
    /// locks the antenna in most steps, step 1019 took 1,118 -> 6 Newton iterations): on a
    /// frictionless sinusoid of 1.2 mm crests under 150 links (replay `soak:4221:181`) the hand-over took
    /// 8,448 -> 11,720 Newton iterations.
    pub(super) fn hand_sliding_joints_onto_links(
        &self,
        pairs: &mut Vec<Pair>,
        goal: Pose,
        predicted: Option<&[f64]>,
    ) {
        // The sliding joints and the crest pairs past them, by index in `pairs`.
        let mut passing: Vec<(usize, usize)> = Vec::new();
        for (j, c) in pairs.iter().enumerate() {
            let PairKind::Point(ChainPoint::Vertex(joint)) = c.key.kind else {
                continue;
            };
            if !c.is_loaded() || c.slip == Slip::Stuck || c.law.shear_bound(1.0).0 <= 0.0 {
                continue;
            }
            passing.extend(
                pairs
                    .iter()
                    .enumerate()
                    .filter(|(_, d)| !d.is_loaded() && self.crest_past_joint(d, joint, c.key.piece))
                    .map(|(l, _)| (j, l)),
            );
        }
        if passing.is_empty() {
            return;
        }
        let Some(predicted) = predicted else {
            return;
        };
        let mut ahead = self.start.clone();
        ahead.update_at(self.chain, goal, &theta_of(self.theta, predicted));
        let mut left: Vec<usize> = Vec::new();
        for (j, l) in passing {
            let on_link = self
                .crest_foot(&pairs[l].key, &ahead)
                .is_some_and(|(_, s)| (0.0..=1.0).contains(&s));
            if on_link && !left.contains(&j) {
                let joint_pair = pairs[j];
                carry(&mut pairs[l], &joint_pair);
                left.push(j);
            }
        }
        left.sort_unstable();
        for j in left.into_iter().rev() {
            pairs.remove(j);
        }
    }

    /// Whether `pair` is a crest of piece `piece` against link `joint` or `joint + 1` whose
    /// foot, where the last step left the chain, lies past that link's end at joint
    /// `joint` (the distal end of link `joint`).
    pub(super) fn crest_past_joint(&self, pair: &Pair, joint: usize, piece: usize) -> bool {
        if pair.key.piece != piece || (pair.key.link != joint && pair.key.link != joint + 1) {
            return false;
        }
        self.crest_foot(&pair.key, self.start)
            .is_some_and(|(link, s)| if link == joint { s > 1.0 } else { s < 0.0 })
    }

    /// The link of `pair` and its crest's foot along it (`0` proximal, `1` distal; beyond
    /// them off the link) in `posture`; `None` for a pair that is not a crest against a
    /// link, or whose foot cannot be measured.
    pub(super) fn crest_foot(&self, key: &PairKey, posture: &Posture) -> Option<(usize, f64)> {
        let PairKind::Link {
            link,
            feature: feature @ ConvexFeature::Crest { .. },
        } = key.kind
        else {
            return None;
        };
        self.pieces.walls[key.piece]
            .shape
            .feature_contact(feature, &posture.start_of(link), &posture.end_m[link])
            .map(|fc| (link, fc.s))
    }

    /// Whether the crest of the link pair `other` (the other link at a joint whose crest
    /// pair's foot slid past its link's end there) can take that crest on: `other` is a
    /// flexible link's pair with a crest, and at the solution (the probe posture,
    /// [`BroadPhase::probe_at`]) the link is no steeper than the crest's flanks, so that the crest
    /// has a foot on the link's line ([`Self::crest_foot`]). See
    /// [`Self::drop_stale_pairs`].
    pub(super) fn crest_passes_on(&self, other: &PairKey) -> bool {
        let PairKind::Link {
            link,
            feature: ConvexFeature::Crest { .. },
        } = other.kind
        else {
            return false;
        };
        (1..=self.chain.n()).contains(&link) && self.crest_foot(other, self.probe).is_some()
    }

    /// Hands the force of a joint stuck on a crest to a `missed` crest pair of one of the
    /// joint's links whose foot, at the solution (the probe posture, [`BroadPhase::probe_at`]),
    /// lies on the link within [`HAND_BACK_FRACTION`] of the joint: the link has come
    /// down onto the crest beside the joint's contact, and the two pairs would hold the
    /// same contact (Newton's system on both is singular). The joint's pair leaves the
    /// step, and the link's pair is recorded in `handed_over` (it does not hand back in
    /// this (sub)step).
    pub(super) fn hand_stuck_joints_to_missed_links(
        &self,
        pairs: &mut Vec<Pair>,
        missed: &mut [Pair],
        handed_over: &mut Vec<PairKey>,
    ) {
        for m in missed.iter_mut() {
            let PairKind::Link {
                link,
                feature: ConvexFeature::Crest { .. },
            } = m.key.kind
            else {
                continue;
            };
            let s = self.geometry_in(self.probe, &m.key, m.geo).s;
            let joint = if (1.0 - HAND_BACK_FRACTION..=1.0).contains(&s) {
                link
            } else if (0.0..=HAND_BACK_FRACTION).contains(&s) && link >= 2 {
                link - 1
            } else {
                continue;
            };
            let stuck_joint = pairs.iter().position(|c| {
                c.key == PairKey::point(ChainPoint::Vertex(joint), m.key.piece)
                    && c.is_loaded()
                    && c.slip == Slip::Stuck
            });
            if let Some(k) = stuck_joint {
                let joint_pair = pairs.remove(k);
                carry(m, &joint_pair);
                handed_over.push(m.key);
            }
        }
    }
}
