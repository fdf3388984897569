//! Which pairs take part in a step (the broad phase), which were missed, which let go.
//!
//! A step's pairs are every chain point within [`super::ContactSettings::margin_m`] of a
//! wall piece and every convex feature of a piece within the margin of a link (its foot on
//! the link, its cone holding the link's normal), with the posture carried to the step's
//! goal; and the contacts of the last step, with their forces and friction state as the
//! start. Where a point pair would hold the same material point as another pair or would be
//! singular (a joint on a corner a link rests on, a point on a convex corner), stand-ins
//! take its place, decided where the last step left the chain. After a solve, a point or
//! feature inside a wall that was not a pair joins, and a feature pair whose foot has left
//! its link (a corner crossing a joint) lets go, or passes on (a crest to the next link);
//! the step is then solved again.

use nalgebra::Vector2;

use super::ContactError;
use super::committed::Committed;
use super::feature::Slip;
use super::geometry::{FOOT_TOLERANCE, PairGeometry, chain_point, evaluate, into_cone};
use super::pair::{ChainPoint, Pair, PairKey, PairKind};
use super::pieces::{CUT_REACH_M, Pieces};
use super::posture::{Pose, Posture, theta_of};
use super::settings::ContactSettings;
use super::world::World;
use crate::walls::lerp;
use crate::walls::{ConvexFeature, FeatureContact, WallPoint};
use crate::{Chain, Wall};

/// How many pieces per chain point, and corners or crests per link, the broad phase keeps
/// (the nearest).
const NEAREST: usize = 3;

/// A feature poking through a link's line by `d` is inside the link only where the link's
/// point there is at least this fraction of `d` inside the wall. A corner turning by at
/// most 85 degrees, pushed `d` through a link whose normal lies at the edge of its cone,
/// leaves the link's point `d cos(85 deg) = 0.087 d` inside (replay `soak:4221:176`, kept by `soak_sweeps_fixed_since_still_finish`); a crest across a
/// steep tip link, out of the link's reach, leaves it on the wall (replay `soak:4221:258`, kept by `soak_sweeps_fixed_since_still_finish`: `d` = 6 cm,
/// the tip resting on the wall).
const THROUGH_LINE_DEPTH_FRACTION: f64 = 0.02;

/// A loaded corner pair that stood for a joint and ends a solve with its foot this far (as
/// a fraction of the link) or less past the link's end hands its force back to the joint's
/// point pair ([`Query::drop_stale_pairs`]).
const HAND_BACK_FRACTION: f64 = 1e-2;

/// The broad phase's own state: the postures it measures pairs in. Only its own methods
/// move them; the other stages see none of it.
#[derive(Debug, Default)]
pub(super) struct BroadPhase {
    /// The committed posture at the start of the (sub)step.
    start: Posture,
    /// The committed posture carried to the step's goal, then put at each solve's answer.
    probe: Posture,
}

/// What the broad phase reads of the other stages in one call.
#[derive(Clone, Copy)]
pub(super) struct Inputs<'a> {
    pub world: &'a World,
    pub committed: &'a Committed,
    /// Friction is off for the rest of the step: fresh pairs slide freely.
    pub friction_off: bool,
}

/// What a revision of the pairs after a converged solve found ([`BroadPhase::revise`]).
pub(super) struct Revision {
    /// Some pair let go, passed on, was handed over or joined: the step is solved again.
    pub changed: bool,
    /// No point or feature was found inside a wall.
    pub none_missed: bool,
}

impl BroadPhase {
    /// The pairs of a step to the base at `goal` (see the module docs), with the start
    /// posture at the committed state and the probe carried to `goal`; `predicted`, the
    /// driver's secant prediction of the joint angles there, decides which crests a sliding
    /// joint passes on to a link.
    ///
    /// # Errors
    /// [`ContactError::BaseInsideWall`] where the base link at `goal` is inside a wall.
    pub fn candidates(
        &mut self,
        inputs: Inputs<'_>,
        goal: Pose,
        predicted: Option<&[f64]>,
    ) -> Result<Vec<Pair>, ContactError> {
        let (chain, committed) = (inputs.world.chain(), inputs.committed);
        self.start
            .update(chain, committed.base_m(), committed.theta());
        self.probe.update_at(chain, goal, committed.theta());
        self.query(inputs).candidates(goal, predicted)
    }

    /// The pairs inside a wall at the answer `x` of a solve that failed (hair coordinates
    /// `hair_links`) that are not among `pairs`, the probe put at `x`.
    pub fn missed_after_failure(
        &mut self,
        inputs: Inputs<'_>,
        goal: Pose,
        x: &[f64],
        hair_links: &[usize],
        pairs: &[Pair],
    ) -> Vec<Pair> {
        self.probe_at(inputs, x, goal);
        self.query(inputs).missed_pairs(x, hair_links, pairs)
    }

    /// Revises `pairs` after a solve to `x` converged, the probe put at `x`: pairs that are
    /// no longer what touches let go (or pass on), point pairs hand over to stand-ins, and
    /// the points and features found inside a wall join (a joint stuck beside a link come
    /// down onto its crest handing its force to the link). `handed_over` collects the pairs
    /// handed over in this (sub)step.
    pub fn revise(
        &mut self,
        inputs: Inputs<'_>,
        goal: Pose,
        x: &[f64],
        hair_links: &[usize],
        pairs: &mut Vec<Pair>,
        handed_over: &mut Vec<PairKey>,
    ) -> Revision {
        self.probe_at(inputs, x, goal);
        let q = self.query(inputs);
        let mut changed = q.drop_stale_pairs(pairs, handed_over);
        changed |= q.hand_point_pairs_to_stand_ins_at_probe(x, hair_links, pairs, handed_over);
        let mut missed = q.missed_pairs(x, hair_links, pairs);
        let none_missed = missed.is_empty();
        changed |= !none_missed;
        // A link come down onto a crest beside its joint stuck there takes the joint's
        // force (the thesis's sinusoid at t = 3.03 s under 30 to 150 links: the solve with
        // both stalled, 46 to 67 Newton iterations, and the fixed point handed it so).
        q.hand_stuck_joints_to_missed_links(pairs, &mut missed, handed_over);
        pairs.extend(missed);
        Revision {
            changed,
            none_missed,
        }
    }

    /// Whether, with no pair standing and every hair open, every link and hair tip with the
    /// base at `goal` is farther than the candidate margin from every wall by the broad
    /// phase's bound ([`crate::WallShape::segment_gap_lower_bound_m`]).
    pub fn clear_of_walls(&mut self, world: &World, committed: &Committed, goal: Pose) -> bool {
        if !committed.pairs().is_empty() {
            return false;
        }
        let chain = world.chain();
        let beta = committed.beta();
        let hairs_open = chain
            .hairs()
            .iter()
            .zip(beta)
            .all(|(h, &b)| h.is_none_or(|h| b == h.rest_angle_rad()));
        if !hairs_open {
            return false;
        }
        let margin_m = world.settings().margin_m;
        self.probe.update_at(chain, goal, committed.theta());
        let probe = &self.probe;
        world.walls().iter().all(|wall| {
            (0..=chain.n()).all(|link| {
                wall.segment_gap_lower_bound_m(&probe.start_of(link), &probe.end_m[link]) > margin_m
            }) && chain.hairs().iter().enumerate().all(|(link, hair)| {
                hair.as_ref().is_none_or(|hair| {
                    wall.gap_lower_bound_m(&probe.hair_tip(hair, link, beta[link])) > margin_m
                })
            })
        })
    }

    /// The committed posture must be outside every wall (a chain placed, before its first
    /// step).
    ///
    /// # Errors
    /// [`ContactError::BaseInsideWall`] or [`ContactError::StartInsideWall`] for the first
    /// link or hair tip inside a wall by more than the penetration tolerance.
    pub fn check_start(
        &mut self,
        world: &World,
        committed: &Committed,
    ) -> Result<(), ContactError> {
        let (chain, settings) = (world.chain(), world.settings());
        let tol = settings.penetration_tolerance_m;
        let base_m = committed.base_m();
        self.probe.update(chain, base_m, committed.theta());
        let probe = &self.probe;
        for (w, wall) in world.walls().iter().enumerate() {
            check_base(settings, w, wall, probe, base_m)?;
            for link in 1..=chain.n() {
                let sc = wall.segment_contact(&probe.start_of(link), &probe.end_m[link]);
                if sc.wall.gap_m < -tol {
                    return Err(ContactError::StartInsideWall {
                        wall: w,
                        link,
                        hair: "",
                        depth_m: -sc.wall.gap_m,
                        at_x_m: sc.point_m.x,
                        at_y_m: sc.point_m.y,
                    });
                }
                if let Some(Some(hair)) = chain.hairs().get(link) {
                    let tip = probe.hair_tip(hair, link, committed.beta()[link]);
                    let gap = wall.signed_distance(&tip).gap_m;
                    if gap < -tol {
                        return Err(ContactError::StartInsideWall {
                            wall: w,
                            link,
                            hair: " (its hair tip)",
                            depth_m: -gap,
                            at_x_m: tip.x,
                            at_y_m: tip.y,
                        });
                    }
                }
            }
        }
        Ok(())
    }

    /// The pairs within `within_m` of touching in `posture` (hair angles `beta`): per chain
    /// point and per link the `keep` nearest ([`Query::touching`]).
    pub fn touching(
        &self,
        inputs: Inputs<'_>,
        posture: &Posture,
        beta: &[f64],
        within_m: f64,
        keep: usize,
    ) -> Vec<PairKey> {
        self.query(inputs).touching(posture, beta, within_m, keep)
    }

    /// Puts the probe posture at the solution `x` of a step to `goal` (hair angles are not
    /// part of it; [`Query::missed_pairs`] takes them from `x`).
    fn probe_at(&mut self, inputs: Inputs<'_>, x: &[f64], goal: Pose) {
        let theta = theta_of(inputs.committed.theta(), x);
        self.probe.update_at(inputs.world.chain(), goal, &theta);
    }

    /// The queries over the postures as they are.
    fn query<'a>(&'a self, inputs: Inputs<'a>) -> Query<'a> {
        let (world, committed) = (inputs.world, inputs.committed);
        Query {
            world,
            chain: world.chain(),
            walls: world.walls(),
            pieces: world.pieces(),
            settings: world.settings(),
            theta: committed.theta(),
            beta: committed.beta(),
            pairs: committed.pairs(),
            start: &self.start,
            probe: &self.probe,
            friction_off: inputs.friction_off,
        }
    }
}

/// The base link must stay out of every wall.
fn check_base(
    settings: &ContactSettings,
    w: usize,
    wall: &Wall,
    posture: &Posture,
    base_m: Vector2<f64>,
) -> Result<(), ContactError> {
    let tol = settings.penetration_tolerance_m;
    if wall.segment_gap_lower_bound_m(&posture.base_m, &posture.end_m[0]) >= -tol {
        return Ok(());
    }
    let sc = wall.segment_contact(&posture.base_m, &posture.end_m[0]);
    if sc.wall.gap_m < -tol {
        return Err(ContactError::BaseInsideWall {
            wall: w,
            depth_m: -sc.wall.gap_m,
            base_x_m: base_m.x,
            base_y_m: base_m.y,
        });
    }
    Ok(())
}

/// The broad phase's queries, over its postures and the other stages' state, all read
/// only.
struct Query<'a> {
    world: &'a World,
    chain: &'a Chain,
    walls: &'a [Wall],
    pieces: &'a Pieces,
    settings: &'a ContactSettings,
    /// The committed joint angles, hair angles and contacts.
    theta: &'a [f64],
    beta: &'a [f64],
    pairs: &'a [Pair],
    start: &'a Posture,
    probe: &'a Posture,
    friction_off: bool,
}

impl Query<'_> {
    /// The pairs of a step to the base at `goal` (see the module docs).
    fn candidates(&self, goal: Pose, predicted: Option<&[f64]>) -> Result<Vec<Pair>, ContactError> {
        for (w, wall) in self.walls.iter().enumerate() {
            check_base(self.settings, w, wall, self.probe, goal.base_m)?;
        }
        let mut out: Vec<Pair> = self
            // Per chain point and per link, the nearest few (a rough or digitized wall puts
            // dozens of pieces and corners within the margin of one link; the nearest are
            // what it can touch next, and anything the solve pushes into a wall joins after
            // it).
            .touching(self.probe, self.beta, self.settings.margin_m, NEAREST)
            .into_iter()
            .map(|key| self.fresh_pair(key))
            .collect();
        for old in self.pairs {
            if let Some(c) = out.iter_mut().find(|c| c.key == old.key) {
                carry(c, old);
                continue;
            }
            // A contact that is no longer within the margin stays a pair while it can be
            // measured (the solve lets it go if it must).
            let mut c = self.fresh_pair(old.key);
            let geo = self.geometry_in(self.probe, &old.key, c.geo);
            if geo.valid && self.pair_on_real_wall(&old.key, &geo.point_m, geo.gap_m) {
                carry(&mut c, old);
                out.push(c);
            } else if old.normal_force_n > 0.0 && self.touches_where_left(old) {
                // A loaded pair that the probe (the last posture carried with the base)
                // takes off what it touches, but that touches it where the last step left
                // the chain: a stuck contact does not move with the base. A corner whose
                // foot the probe puts past its link's end may keep resting on the link (a
                // tip hooked on a convex corner); a point carried off its piece's stretch
                // of wall may stay pressed on it (a tip wedged in a concave corner). It
                // stays a pair; the solve lets it go if it leaves.
                carry(&mut c, old);
                out.push(c);
            } else if let Some(next) = out
                .iter_mut()
                .filter(|c| c.key.piece == old.key.piece && c.normal_force_n == 0.0)
                .min_by(|a, b| {
                    let da = (a.start_m - old.geo.point_m).norm();
                    let db = (b.start_m - old.geo.point_m).norm();
                    da.total_cmp(&db)
                })
            {
                // Its feature left the link: the nearest pair on the piece starts from its
                // forces (a corner crossing a joint hands its load to the joint's pairs).
                next.normal_force_n = old.normal_force_n;
                next.shear_force_n = old.shear_force_n;
                next.normal_active = old.normal_active;
            }
        }
        // A point pair that a corner-edge pair of the last step stands for stays out.
        let held: Vec<PairKey> = out
            .iter()
            .filter(|c| out.iter().any(|e| held_by_corner(e, &c.key)))
            .map(|c| c.key)
            .collect();
        out.retain(|c| !held.contains(&c.key));
        // A contact of the last step at a joint that sits on a corner hands its load to the
        // links resting on the corner (a point on a convex corner, to the edge it lies on),
        // decided where the last step left the chain: the probe posture is only a guess,
        // and a guess that puts a link on the corner at a loaded joint that the solution
        // then leaves beside it makes a step whose equations miss what touches.
        self.hand_point_pairs_to_stand_ins(self.start, self.beta, &mut out, &[]);
        self.drop_links_doubling_loaded_joints(&mut out);
        self.hand_sliding_joints_onto_links(&mut out, goal, predicted);
        Ok(out)
    }

    /// Whether the last step's pair `old` touches what it pairs with where the last step
    /// left the chain: a link's corner with its foot on the link, a point on its piece's
    /// own stretch of wall. (A corner-edge pair is decided by its own rule,
    /// [`CornerEdgeState`].)
    fn touches_where_left(&self, old: &Pair) -> bool {
        match old.key.kind {
            PairKind::Link { .. } => self.geometry_in(self.start, &old.key, old.geo).valid,
            PairKind::Point(_) => self.pair_on_real_wall(&old.key, &old.geo.point_m, old.geo.gap_m),
            PairKind::CornerEdge { .. } => false,
        }
    }

    /// `key`'s geometry in `posture` (with the current hair angles), evaluated over `geo`
    /// (what a pair that cannot be measured keeps).
    fn geometry_in(&self, posture: &Posture, key: &PairKey, mut geo: PairGeometry) -> PairGeometry {
        evaluate(
            self.chain,
            &self.pieces.walls[key.piece],
            posture,
            self.beta,
            key,
            &mut geo,
        );
        geo
    }

    /// The pairs of `posture` (hair angles `beta`) with a gap below `within_m`: per chain
    /// point and per link, the `keep` nearest (deepest).
    fn touching(
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
    fn joint_corner_pairs(
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
    fn stand_ins(
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
    fn corner_point_pairs(
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
    fn hand_point_pairs_to_stand_ins(
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
    fn drop_links_doubling_loaded_joints(&self, pairs: &mut Vec<Pair>) {
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
    fn hand_sliding_joints_onto_links(
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
    fn crest_past_joint(&self, pair: &Pair, joint: usize, piece: usize) -> bool {
        if pair.key.piece != piece || (pair.key.link != joint && pair.key.link != joint + 1) {
            return false;
        }
        self.crest_foot(&pair.key, self.start)
            .is_some_and(|(link, s)| if link == joint { s > 1.0 } else { s < 0.0 })
    }

    /// The link of `pair` and its crest's foot along it (`0` proximal, `1` distal; beyond
    /// them off the link) in `posture`; `None` for a pair that is not a crest against a
    /// link, or whose foot cannot be measured.
    fn crest_foot(&self, key: &PairKey, posture: &Posture) -> Option<(usize, f64)> {
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
    fn crest_passes_on(&self, other: &PairKey) -> bool {
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
    fn hand_stuck_joints_to_missed_links(
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

    /// The hair angles of a solution `x` whose hair coordinates are those of `hair_links`
    /// (the others as committed).
    fn beta_of(&self, x: &[f64], hair_links: &[usize]) -> Vec<f64> {
        let n = self.chain.n();
        let mut beta = self.beta.to_vec();
        for (h, &l) in hair_links.iter().enumerate() {
            beta[l] = x[n + h];
        }
        beta
    }

    /// [`Self::hand_point_pairs_to_stand_ins`] at the solution `x` (hair coordinates
    /// `hair_links`), with the probe posture there ([`BroadPhase::probe_at`]).
    fn hand_point_pairs_to_stand_ins_at_probe(
        &self,
        x: &[f64],
        hair_links: &[usize],
        pairs: &mut Vec<Pair>,
        refused: &[PairKey],
    ) -> bool {
        let beta = self.beta_of(x, hair_links);
        self.hand_point_pairs_to_stand_ins(self.probe, &beta, pairs, refused)
    }

    /// A fresh pair `key`: its material point where it touches (or comes nearest) at the
    /// start of the step, the surface's Coulomb law (none on a frictionless step), no
    /// force.
    fn fresh_pair(&self, key: PairKey) -> Pair {
        let start = &self.start;
        let (link, s, point) = match key.kind {
            PairKind::Point(point) | PairKind::CornerEdge { point, .. } => {
                chain_point(self.chain, start, self.beta, point)
            }
            PairKind::Link { link, feature } => {
                let piece = &self.pieces.walls[key.piece];
                let at = |posture: &Posture| {
                    piece.shape.feature_contact(
                        feature,
                        &posture.start_of(link),
                        &posture.end_m[link],
                    )
                };
                // Where the feature's foot is at the start of the step; one that had not
                // reached the link yet enters it by the end nearer to where it is now.
                let s = at(start)
                    .or_else(|| at(self.probe))
                    .map_or(0.5, |fc| fc.s)
                    .clamp(0.0, 1.0);
                (link, s, start.link_point(link, s))
            }
        };
        let law = self.world.coulomb_at(key.piece, &point);
        let mut pair = Pair::new(key, law, link, s, point);
        // On a step whose friction was let go every pair slides freely, however it joins
        // (a candidate, a point missed, a stand-in a pair is handed over to).
        pair.frictionless = self.friction_off;
        pair
    }

    /// The pairs inside a wall after a solve to `x` (hair coordinates `hair_links`), with
    /// the probe posture at `x` ([`BroadPhase::probe_at`]), that are not pairs yet: per chain
    /// point and per link the [`NEAREST`] deepest. A link pushed into a rough stretch of
    /// wall (a digitized wall's noise) had every asperity under it join at once: up to 181
    /// pairs and 340 rank-one terms in one Newton system (issue #49), whose dense border
    /// (an LU, and an SVD where many corners pressing on one link make it rank deficient)
    /// was 70% of `examples/wall_digitized.toml`'s sweep. The deepest hold the link out;
    /// any still inside join in the next round (57.6 s -> 2.8 s for that sweep's first 6 s,
    /// every step certified; the CI sample's trajectories unchanged).
    fn missed_pairs(&self, x: &[f64], hair_links: &[usize], pairs: &[Pair]) -> Vec<Pair> {
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
    fn drop_stale_pairs(&self, pairs: &mut Vec<Pair>, handed_over: &mut Vec<PairKey>) -> bool {
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

/// How near a convex corner (metres) a chain point counts as on it: its point pair is then
/// replaced by a corner-edge pair ([`PairKind::CornerEdge`]), which stands while the point
/// is on the corner or on the edge's own stretch of wall and hands back when it leaves
/// them ([`CornerEdgeState`]). The radius only has to catch a solve that stopped short of
/// the corner (a point sliding onto it).
pub(crate) const CORNER_CAPTURE_M: f64 = 1e-6;

/// Whether feature `fc` pokes through its segment's line (by more than `tolerance_m`) past
/// the segment's end: the line of a link run on past a bent joint cuts into a corner that
/// rests on the joint's other link, which is no contact of this link.
fn past_end_through_line(fc: &FeatureContact, tolerance_m: f64) -> bool {
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

/// Whether pair `c` is a corner-edge pair of the same chain point and piece as the point
/// pair `key` (which it stands for).
fn held_by_corner(c: &Pair, key: &PairKey) -> bool {
    matches!(c.key.kind, PairKind::CornerEdge { .. })
        && matches!(key.kind, PairKind::Point(_))
        && c.key.piece == key.piece
        && c.key.chain_point() == key.chain_point()
}

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
    fn on_real_wall(&self, piece: usize, x_m: &Vector2<f64>, gap_m: f64) -> bool {
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
    fn on_real_wall_at(&self, piece: usize, at_piece: &WallPoint, real: &WallPoint) -> bool {
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
    fn pair_on_real_wall(&self, key: &PairKey, x_m: &Vector2<f64>, gap_m: f64) -> bool {
        match key.kind {
            PairKind::Point(_) => self.on_real_wall(key.piece, x_m, gap_m),
            PairKind::Link { .. } | PairKind::CornerEdge { .. } => true,
        }
    }
}

/// A contact of the last step carries its forces, law and modes into the next step's pair
/// (the friction state the model remembers).
fn carry(c: &mut Pair, old: &Pair) {
    c.normal_force_n = old.normal_force_n;
    c.shear_force_n = old.shear_force_n;
    c.law = old.law;
    c.normal_active = old.normal_active;
    c.slip = old.slip;
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use nalgebra::Vector2;

    use super::super::pair::PairKind;
    use super::super::settings::ContactSettings;
    use super::{BroadPhase, Committed, Inputs, World};
    use crate::{Chain, Polyline, SolidSide, Wall};

    /// A thin spike of a rough wall, leaning, poked 0.5 mm through a link: the link crosses
    /// the spike's flank 0.4 mm from the foot of its tip, where the link's point is outside
    /// the spike (as at step 1,745 of `examples/wall_digitized.toml`, where the step's
    /// answer left the link 15 um inside the wall with no pair to hold it). The spike's
    /// corner is still a pair of the link.
    #[test]
    fn a_leaning_spike_through_a_link_beside_its_foot_is_a_pair_of_the_link() {
        let chain = Chain::builder(2)
            .link_length_m(0.04)
            .stiffness_nm_per_rad(0.02)
            .build()
            .unwrap();
        let spike = Polyline::new(
            vec![
                Vector2::new(0.0, 0.1),
                Vector2::new(0.059, 0.1),
                Vector2::new(0.0605, 0.0985),
                Vector2::new(0.0592, 0.1),
                Vector2::new(0.2, 0.1),
            ],
            SolidSide::Left,
        )
        .unwrap();
        let theta = chain.rest_theta();
        let beta = vec![0.0; chain.hairs().len()];
        // Placed clear of the wall, then probed with link 1 along y = 0.099 m.
        let world = World::new(chain, &[Wall::smooth(spike)], ContactSettings::default());
        let committed = Committed::new(Vector2::new(0.0, 0.09), theta, beta);
        let mut broad_phase = BroadPhase::default();
        broad_phase
            .check_start(&world, &committed)
            .expect("placed clear of the wall");
        let across = Vector2::new(0.0, 0.099);
        broad_phase
            .probe
            .update(world.chain(), across, committed.theta());
        let query = broad_phase.query(Inputs {
            world: &world,
            committed: &committed,
            friction_off: false,
        });
        let tol = world.settings().penetration_tolerance_m;
        let keys = query.touching(query.probe, query.beta, -tol, usize::MAX);
        assert!(
            keys.iter()
                .any(|k| k.link == 1 && matches!(k.kind, PairKind::Link { .. })),
            "the spike's corner is not a pair of link 1: {keys:?}"
        );
        // The link is inside the wall there, as the certification sees it.
        let probe = &broad_phase.probe;
        let deepest = world.walls()[0].segment_contact(&probe.end_m[0], &probe.end_m[1]);
        assert!(deepest.wall.gap_m < -1e-5, "{deepest:?}");
    }
}
