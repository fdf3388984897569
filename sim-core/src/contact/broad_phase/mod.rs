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
use super::geometry::{PairGeometry, chain_point, evaluate};
use super::pair::{Pair, PairKey, PairKind};
use super::pieces::Pieces;
use super::posture::{Pose, Posture, theta_of};
use super::settings::ContactSettings;
use super::world::World;
use crate::{Chain, Wall};

mod real_wall;
mod revise;
mod stand_ins;
mod touching;

/// How many pieces per chain point, and corners or crests per link, the broad phase keeps
/// (the nearest).
const NEAREST: usize = 3;

/// A loaded corner pair that stood for a joint and ends a solve with its foot this far (as
/// a fraction of the link) or less past the link's end hands its force back to the joint's
/// point pair ([`Query::drop_stale_pairs`]).
const HAND_BACK_FRACTION: f64 = 1e-2;

/// How near a convex corner (metres) a chain point counts as on it: its point pair is then
/// replaced by a corner-edge pair ([`PairKind::CornerEdge`]), which stands while the point
/// is on the corner or on the edge's own stretch of wall and hands back when it leaves
/// them ([`CornerEdgeState`]). The radius only has to catch a solve that stopped short of
/// the corner (a point sliding onto it).
const CORNER_CAPTURE_M: f64 = 1e-6;

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
}

/// Whether pair `c` is a corner-edge pair of the same chain point and piece as the point
/// pair `key` (which it stands for).
fn held_by_corner(c: &Pair, key: &PairKey) -> bool {
    matches!(c.key.kind, PairKind::CornerEdge { .. })
        && matches!(key.kind, PairKind::Point(_))
        && c.key.piece == key.piece
        && c.key.chain_point() == key.chain_point()
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
