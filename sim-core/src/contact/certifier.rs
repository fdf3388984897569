//! An independent check of a quasi-static state (docs/model.md 6: "every step is checked"):
//! recomputed from the posture and the reported contact forces with the crate's own
//! kinematics ([`crate::frame_poses`], [`crate::hair_poses`]) and the walls' own distance
//! queries, not from the solver's equations. It keeps no state: it reads the world and the
//! committed state, and writes nothing. [`super::QuasiStatic::step_to_pose`] (and so
//! [`super::QuasiStatic::step_to`]) runs it on every step it accepts and refuses a step that
//! fails it ([`super::ContactError::Uncertified`]). A contact's slip is recomputed too: its
//! material point now against where it was in the committed state the last (sub)step
//! started from (base pivot and base angle), not read from the solver.

use nalgebra::Vector2;

use super::committed::Committed;
use super::feature::{Contact, Feature, FrictionLaw, Slip};
use super::geometry::into_cone;
use super::world::World;
use crate::kinematics::hair::HairPose;
use crate::{Chain, Frame, Wall, hair_poses};

/// How far a state is from a frictional-contact equilibrium; every field is `0` for an
/// exact one, and `NaN` where something was not finite (which fails [`Self::holds`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EquilibriumCheck {
    /// The largest torque imbalance at a joint strictly inside its limits, or at a hair in
    /// contact strictly inside its range, N m.
    pub torque_residual_nm: f64,
    /// The largest stop torque of the wrong sign (a stop that would have to pull), N m.
    pub limit_sign_violation_nm: f64,
    /// The deepest penetration of a link or a hair tip into a wall, metres.
    pub penetration_m: f64,
    /// The largest violation of `N >= N_min` or `|T| <= bound` (the friction cone, or an
    /// anchored hair's holds), newtons: in the contact's own frame, and again with its
    /// force split along the wall's own normal where it touches (so a contact whose normal
    /// is not the wall's fails by the force the wall cannot exert).
    pub cone_violation_n: f64,
    /// The largest gap of a contact that carries a force (complementarity), metres.
    pub separation_m: f64,
    /// The largest slip of a contact reported stuck, metres (Coulomb: a stuck contact does
    /// not move), recomputed from the committed state the last (sub)step started from.
    pub stuck_slip_m: f64,
    /// The largest departure of a slipping contact's shear force from the friction limit
    /// (`|T| = bound`; the bound relaxed on a jam where it was), newtons.
    pub slip_force_violation_n: f64,
    /// The largest slip of a slipping contact in the direction of its own shear force (it
    /// must slip against it), metres.
    pub wrong_way_slip_m: f64,
}

/// The tolerances a state is certified against ([`EquilibriumCheck::holds`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CertifyTolerances {
    /// Torques, N m.
    pub torque_nm: f64,
    /// Lengths (penetration, separation, slip), metres.
    pub length_m: f64,
    /// Forces, newtons.
    pub force_n: f64,
}

/// A joint or hair this close to a limit is on it (the solver ends within its tolerance of
/// a limit, about `1e-12` rad).
const ON_LIMIT_RAD: f64 = 1e-9;

/// Forces below this are zero for the complementarity check (rounding of forces of order
/// 0.01-1 N).
pub(super) const FORCE_ZERO_N: f64 = 1e-12;

/// How far from a polyline corner a contact may press with any normal of the corner's cone,
/// metres: a contact solved against a piece of a wall cut at a concave corner lies on the
/// piece's straight run-on up to [`super::pieces::CUT_REACH_M`] past the corner.
const CORNER_REACH_M: f64 = super::pieces::CUT_REACH_M;

/// The distance, metres, by which a contact's point may stand off the wall point whose
/// normal it carries (the solver's points agree to about `1e-12` m): on a curve the normal
/// may turn by the curvature times it.
const NORMAL_SLACK_M: f64 = 1e-8;

/// `max` that keeps a NaN (`f64::max` drops it).
fn worst(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

impl EquilibriumCheck {
    /// Whether every residual is within its tolerance (torques in N m, lengths in m,
    /// forces in N); a NaN anywhere fails.
    pub fn holds(&self, torque_nm: f64, length_m: f64, force_n: f64) -> bool {
        self.torque_residual_nm <= torque_nm
            && self.limit_sign_violation_nm <= torque_nm
            && self.penetration_m <= length_m
            && self.cone_violation_n <= force_n
            && self.separation_m <= length_m
            && self.stuck_slip_m <= length_m
            && self.slip_force_violation_n <= force_n
            && self.wrong_way_slip_m <= length_m
    }

    /// [`Self::holds`] against `tolerances`.
    pub fn holds_within(&self, tolerances: &CertifyTolerances) -> bool {
        self.holds(
            tolerances.torque_nm,
            tolerances.length_m,
            tolerances.force_n,
        )
    }

    /// The conditions that fail `tolerances`, in words (empty when it holds).
    pub fn failures(&self, tolerances: &CertifyTolerances) -> Vec<String> {
        let mut out = Vec::new();
        let mut test = |name: &str, value: f64, tolerance: f64, unit: &str| {
            if value.is_nan() || value > tolerance {
                out.push(format!(
                    "{name} {value:.3e} {unit} (tolerance {tolerance:.1e})"
                ));
            }
        };
        test(
            "torque imbalance",
            self.torque_residual_nm,
            tolerances.torque_nm,
            "N m",
        );
        test(
            "stop torque of the wrong sign",
            self.limit_sign_violation_nm,
            tolerances.torque_nm,
            "N m",
        );
        test("penetration", self.penetration_m, tolerances.length_m, "m");
        test(
            "friction cone violated by",
            self.cone_violation_n,
            tolerances.force_n,
            "N",
        );
        test(
            "a loaded contact's gap",
            self.separation_m,
            tolerances.length_m,
            "m",
        );
        test(
            "a stuck contact's slip",
            self.stuck_slip_m,
            tolerances.length_m,
            "m",
        );
        test(
            "a slipping contact off its friction limit by",
            self.slip_force_violation_n,
            tolerances.force_n,
            "N",
        );
        test(
            "a contact slipping with its shear force by",
            self.wrong_way_slip_m,
            tolerances.length_m,
            "m",
        );
        out
    }
}

/// The independent check of a committed state among its world (see the module docs).
pub(super) struct Certifier<'a> {
    world: &'a World,
    committed: &'a Committed,
}

impl<'a> Certifier<'a> {
    pub fn new(world: &'a World, committed: &'a Committed) -> Certifier<'a> {
        Certifier { world, committed }
    }

    fn chain(&self) -> &'a Chain {
        self.world.chain()
    }

    fn walls(&self) -> &'a [Wall] {
        self.world.walls()
    }

    fn theta_rad(&self) -> &'a [f64] {
        self.committed.theta()
    }

    fn hair_angles_rad(&self) -> &'a [f64] {
        self.committed.beta()
    }

    fn base_m(&self) -> Vector2<f64> {
        self.committed.base_m()
    }

    fn tip_force_n(&self) -> Vector2<f64> {
        self.world.tip_force_n()
    }

    fn hand_force_n(&self) -> Vector2<f64> {
        self.committed.hand_force_n()
    }

    fn contacts(&self) -> Vec<Contact> {
        let mut out = Vec::with_capacity(self.committed.pairs().len());
        self.committed
            .contacts_into(&self.world.pieces().piece_of, &mut out);
        out
    }

    /// The tolerances [`super::QuasiStatic::step_to`] certifies every step against: ten times what the
    /// solver's acceptable residual ([`super::ContactSettings::acceptable_m`]) allows, in
    /// each unit (torques through the stiffest joint over the mean link length, forces
    /// through the contact scale `k_mean / L^2`), and the penetration tolerance.
    pub fn tolerances(&self) -> CertifyTolerances {
        let k = &self.chain().stiffness_nm_per_rad()[1..];
        let k_max = k.iter().copied().fold(1e-12_f64, f64::max);
        let k_mean = if k.is_empty() {
            k_max
        } else {
            k.iter().sum::<f64>() / k.len() as f64
        };
        let lengths = self.chain().link_lengths_m();
        let l_mean = lengths.iter().sum::<f64>() / lengths.len() as f64;
        let settings = self.world.settings();
        let residual_m = 10.0 * settings.acceptable_m.max(settings.tolerance_m);
        CertifyTolerances {
            torque_nm: residual_m * k_max / l_mean,
            length_m: residual_m.max(10.0 * settings.penetration_tolerance_m),
            force_n: residual_m * k_mean.max(1e-3) / (l_mean * l_mean),
        }
    }

    /// Re-derives the equilibrium conditions of the current state: the torque balance at
    /// every joint and hair from the contact forces reported by [`Self::contacts`] (and the
    /// tip load), the joint-limit multipliers' signs, non-penetration of every link and
    /// hair tip, the friction cone, Coulomb's law (stuck contacts do not slip, slipping ones
    /// are at the limit against their slip) and the complementarity of forces and gaps.
    pub fn check(&self) -> EquilibriumCheck {
        let mut out = EquilibriumCheck::default();
        let chain = self.chain();
        let n = chain.n();
        let theta = self.theta_rad();
        let base = self.base_m();
        let Ok(poses) = crate::frame_poses(chain, theta, Frame::GROUND) else {
            out.torque_residual_nm = f64::NAN;
            return out;
        };
        let ends: Vec<Vector2<f64>> = (0..=n)
            .map(|i| {
                base + poses
                    .position_m(Frame::link(i))
                    .unwrap_or(Vector2::new(f64::NAN, f64::NAN))
            })
            .collect();
        let start_of = |link: usize| if link == 0 { base } else { ends[link - 1] };
        let hairs =
            hair_poses(chain, theta, self.hair_angles_rad(), Frame::GROUND).unwrap_or_default();
        let hair_tip = |link: usize| {
            hairs
                .iter()
                .find(|h| h.link == link)
                .map(|h| (base + h.pivot_m, base + h.tip_m))
        };
        let contacts = self.contacts();
        // Each contact's slip over the last (sub)step, recomputed: its material point now
        // against the same point in the committed state the (sub)step started from (its
        // base pivot and base angle, its joint and hair angles), along the contact's
        // tangent.
        let slips = self.recomputed_slips_m(&ends, &hairs, base);
        // Where each contact's force acts, from the feature alone.
        let point_of = |c: &Contact| match c.feature {
            Feature::Vertex { link } => Some(ends[link]),
            Feature::Link { link } => Some(start_of(link) + (ends[link] - start_of(link)) * c.s),
            Feature::HairTip { link } => hair_tip(link).map(|(_, tip)| tip),
        };
        // Torques about each joint j (at p_(j-1)) of the forces on links >= j.
        let k = chain.stiffness_nm_per_rad();
        let rest = chain.rest_angles_rad();
        let limits = chain.joint_limits();
        let mut loads: Vec<(usize, Vector2<f64>, Vector2<f64>)> = Vec::new();
        for c in &contacts {
            match point_of(c) {
                Some(x) => loads.push((c.feature.link(), x, c.force_n())),
                None => out.torque_residual_nm = f64::NAN,
            }
        }
        let tip_force = self.tip_force_n() + self.hand_force_n();
        if tip_force != Vector2::zeros() {
            loads.push((n, ends[n], tip_force));
        }
        for j in 1..=n {
            let joint = ends[j - 1];
            let mut tau = k[j] * (theta[j] - rest[j]);
            for &(link, x, f) in &loads {
                if link >= j {
                    let arm = x - joint;
                    tau -= arm.x * f.y - arm.y * f.x;
                }
            }
            let lim = limits[j];
            let on_cw = theta[j] <= lim.cw_rad + ON_LIMIT_RAD;
            let on_ccw = theta[j] >= lim.ccw_rad - ON_LIMIT_RAD;
            if on_cw && on_ccw {
                continue;
            } else if on_cw {
                out.limit_sign_violation_nm = worst(out.limit_sign_violation_nm, -tau);
            } else if on_ccw {
                out.limit_sign_violation_nm = worst(out.limit_sign_violation_nm, tau);
            } else {
                out.torque_residual_nm = worst(out.torque_residual_nm, tau.abs());
            }
        }
        // Hairs in contact: spring torque against the contact forces' moment about the
        // pivot.
        let mut hair_links: Vec<usize> = contacts
            .iter()
            .filter_map(|c| match c.feature {
                Feature::HairTip { link } => Some(link),
                _ => None,
            })
            .collect();
        hair_links.sort_unstable();
        hair_links.dedup();
        for link in hair_links {
            let (Some((pivot, tip)), Some(Some(hair))) = (hair_tip(link), chain.hairs().get(link))
            else {
                out.torque_residual_nm = f64::NAN;
                continue;
            };
            let beta = self.hair_angles_rad()[link];
            // d tip / d beta = rate * R90 (tip - pivot).
            let arm = tip - pivot;
            let rate = Vector2::new(-arm.y, arm.x) * hair.direction_rate();
            let mut g = hair.spring_gradient_nm(beta);
            for c in contacts
                .iter()
                .filter(|c| c.feature == Feature::HairTip { link })
            {
                g -= rate.dot(&c.force_n());
            }
            if beta >= hair.max_angle_rad() - ON_LIMIT_RAD {
                out.limit_sign_violation_nm = worst(out.limit_sign_violation_nm, g);
            } else if beta <= ON_LIMIT_RAD {
                out.limit_sign_violation_nm = worst(out.limit_sign_violation_nm, -g);
            } else {
                out.torque_residual_nm = worst(out.torque_residual_nm, g.abs());
            }
        }
        // Non-penetration of every link and hair tip.
        for wall in self.walls() {
            // A link or hair tip whose broad-phase bound is not below zero cannot be in the
            // wall (the penetration is at least zero below), and is not searched.
            for (link, end) in ends.iter().enumerate() {
                let start = start_of(link);
                if wall.segment_gap_lower_bound_m(&start, end) >= 0.0 {
                    continue;
                }
                let sc = wall.segment_contact(&start, end);
                out.penetration_m = worst(out.penetration_m, -sc.wall.gap_m);
            }
            for h in &hairs {
                let tip = base + h.tip_m;
                if wall.gap_lower_bound_m(&tip) >= 0.0 {
                    continue;
                }
                let gap = wall.signed_distance(&tip).gap_m;
                out.penetration_m = worst(out.penetration_m, -gap);
            }
        }
        // Cone, Coulomb's law and complementarity.
        let shear_zero_n = self.tolerances().force_n.max(FORCE_ZERO_N);
        for (c, &slip_m) in contacts.iter().zip(&slips) {
            // `N >= N_min` and the shear bound at normal force `normal_n`.
            let cone_at = |normal_n: f64| {
                let (min_n, bound) = match c.law {
                    FrictionLaw::Coulomb { mu } => (0.0, mu * normal_n.max(0.0)),
                    FrictionLaw::Anchored {
                        hold_shear_n,
                        hold_tension_n,
                    } => (-hold_tension_n, hold_shear_n),
                };
                (min_n, c.relaxed_shear_bound_n.unwrap_or(bound))
            };
            let (min_n, bound) = cone_at(c.normal_force_n);
            out.cone_violation_n = worst(
                worst(out.cone_violation_n, min_n - c.normal_force_n),
                c.shear_force_n.abs() - bound,
            );
            match c.slip {
                Slip::Stuck => out.stuck_slip_m = worst(out.stuck_slip_m, slip_m.abs()),
                Slip::Forward | Slip::Backward => {
                    // At the limit, against the slip.
                    let at_limit = (c.shear_force_n.abs() - bound).abs();
                    out.slip_force_violation_n = worst(out.slip_force_violation_n, at_limit);
                    // A shear force within the force tolerance has no direction the check
                    // can tell (a contact grazing the wall with N of order 1e-9 N slides
                    // with a shear of rounding size, either sign): its size is held to the
                    // bound just above, within the same tolerance.
                    let wrong_way = if c.shear_force_n > shear_zero_n {
                        slip_m
                    } else if c.shear_force_n < -shear_zero_n {
                        -slip_m
                    } else {
                        0.0
                    };
                    out.wrong_way_slip_m = worst(out.wrong_way_slip_m, wrong_way);
                }
            }
            if let Some(x) = point_of(c)
                && c.force_n().norm() > FORCE_ZERO_N
            {
                let wall = &self.walls()[c.wall];
                let wp = wall.signed_distance(&x);
                out.separation_m = worst(out.separation_m, wp.gap_m.abs());
                // The same cone in the wall's own frame: the normal the contact presses
                // along (a link's own normal for a link resting on a corner or a crest,
                // else the contact's) turned into the normals the wall can press with where
                // the contact is (its normal on a smooth point, within what the point's gap
                // allows on a curve; a corner's cone near a corner), and the force split
                // along it. A contact whose normal is not the wall's fails here, by the
                // force the wall cannot exert.
                let slack_rad = if wp.curvature_per_m.is_finite() {
                    wp.curvature_per_m.abs() * (wp.gap_m.abs() + NORMAL_SLACK_M)
                } else {
                    0.0
                } + 1e-9;
                let cone = wall.shape.normal_cone(&wp, CORNER_REACH_M);
                let pressed = match c.feature {
                    Feature::Link { link } => {
                        let d = ends[link] - start_of(link);
                        let across = Vector2::new(-d.y, d.x) / d.norm();
                        if across.dot(&c.normal) < 0.0 {
                            -across
                        } else {
                            across
                        }
                    }
                    Feature::Vertex { .. } | Feature::HairTip { .. } => c.normal,
                };
                let n = into_cone(pressed, cone, slack_rad);
                let force = c.force_n();
                let normal_n = force.dot(&n);
                let shear_n = force.dot(&Vector2::new(-n.y, n.x));
                let (min_n, wall_bound) = cone_at(normal_n);
                out.cone_violation_n = worst(
                    worst(out.cone_violation_n, min_n - normal_n),
                    shear_n.abs() - wall_bound,
                );
            }
            for v in [c.normal_force_n, c.shear_force_n, slip_m] {
                if !v.is_finite() {
                    out.cone_violation_n = f64::NAN;
                }
            }
        }
        if theta
            .iter()
            .chain(self.hair_angles_rad())
            .any(|v| !v.is_finite())
        {
            out.torque_residual_nm = f64::NAN;
        }
        out.penetration_m = worst(out.penetration_m, 0.0);
        out
    }
}

impl Certifier<'_> {
    /// The slip of each contact (in [`Self::contacts`]' order) over the last committed
    /// (sub)step, metres: along the contact's tangent, its material point (the point of the
    /// chain that touched at the start: a link end, a point along a link, a hair tip) in
    /// the current posture (`ends`, `hairs`, the pivot at `base`) less the same point in
    /// the state the (sub)step started from (the committed state's start), both from the
    /// crate's own kinematics. `NaN` where a point cannot be computed.
    fn recomputed_slips_m(
        &self,
        ends: &[Vector2<f64>],
        hairs: &[HairPose],
        base: Vector2<f64>,
    ) -> Vec<f64> {
        let pairs = self.committed.pairs();
        if pairs.is_empty() {
            return Vec::new();
        }
        let chain = self.chain();
        let start = self.committed.step_start();
        let nan = Vector2::new(f64::NAN, f64::NAN);
        let start_poses = crate::frame_poses(chain, start.theta(), Frame::GROUND).ok();
        // The end of link `i` in the start state (the pivot for `i = None`).
        let start_end = |i: Option<usize>| match (i, &start_poses) {
            (None, _) => start.base_m(),
            (Some(i), Some(poses)) => {
                start.base_m() + poses.position_m(Frame::link(i)).unwrap_or(nan)
            }
            (Some(_), None) => nan,
        };
        // Hair tips only where a hair touches (their poses cost a second pass).
        let start_hairs = if pairs.iter().any(|p| p.key.hair_link().is_some()) {
            hair_poses(chain, start.theta(), start.beta(), Frame::GROUND).unwrap_or_default()
        } else {
            Vec::new()
        };
        let point = |base: Vector2<f64>, ends: &[Vector2<f64>], link: usize, s: f64| {
            let from = if link == 0 { base } else { ends[link - 1] };
            from + (ends[link] - from) * s
        };
        let start_point = |link: usize, s: f64| {
            let from = start_end(link.checked_sub(1));
            from + (start_end(Some(link)) - from) * s
        };
        let tip = |hairs: &[HairPose], base: Vector2<f64>, link: usize| {
            hairs
                .iter()
                .find(|h| h.link == link)
                .map_or(nan, |h| base + h.tip_m)
        };
        pairs
            .iter()
            .map(|pair| {
                let (now, then) = match pair.key.hair_link() {
                    Some(link) => (
                        tip(hairs, base, link),
                        tip(&start_hairs, start.base_m(), link),
                    ),
                    None => {
                        let (link, s) = (pair.material_link, pair.material_s);
                        (point(base, ends, link, s), start_point(link, s))
                    }
                };
                pair.geo.tangent.dot(&(now - then))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::contact::{ContactSettings, QuasiStatic};
    use crate::{Chain, Polyline, SolidSide, Surface, SurfaceMap, Wall};

    /// A frictionless wedge under a straight antenna, lowered onto its corner (link 2
    /// rests on it) and the tip onto a line beside it: certified as solved. Each contact's
    /// frame turned by `delta` (forces kept, so the contact's own cone still holds) fails
    /// the cone in the wall's frame by the force the wall cannot exert, `N sin(delta)`.
    #[test]
    fn a_contact_pressing_off_the_walls_normal_fails_the_cone() {
        let chain = Chain::builder(3)
            .link_length_m(0.04)
            .stiffness_nm_per_rad(0.02)
            .build()
            .unwrap();
        let wedge = Polyline::new(
            vec![
                Vector2::new(0.055, -0.05),
                Vector2::new(0.095, -0.01),
                Vector2::new(0.135, -0.05),
            ],
            SolidSide::Right,
        )
        .unwrap();
        let frictionless = SurfaceMap::uniform(Surface::Smooth { mu: 0.0 }).unwrap();
        let theta = chain.rest_theta();
        let mut sim = QuasiStatic::new(
            chain,
            vec![Wall::new(wedge, frictionless)],
            Vector2::zeros(),
            &theta,
            ContactSettings::default(),
        )
        .unwrap();
        for k in 1..=40 {
            sim.step_to(Vector2::new(0.0, -0.02 * f64::from(k) / 40.0))
                .unwrap();
        }
        let check = sim.check();
        assert!(check.holds(1e-10, 1e-10, 1e-10), "{check:?}");
        let pairs = sim.committed().pairs();
        let loaded: Vec<usize> = (0..pairs.len())
            .filter(|&i| pairs[i].normal_force_n > 1e-6)
            .collect();
        assert!(!loaded.is_empty(), "nothing touches");
        let delta: f64 = 0.01;
        for &i in &loaded {
            let mut turned = sim.committed().clone();
            let geo = &mut turned.pairs_mut()[i].geo;
            let (sin, cos) = delta.sin_cos();
            let turn = |v: Vector2<f64>| Vector2::new(v.x * cos - v.y * sin, v.x * sin + v.y * cos);
            geo.normal = turn(geo.normal);
            geo.tangent = turn(geo.tangent);
            let check = Certifier::new(sim.world(), &turned).check();
            let expected = pairs[i].normal_force_n * delta.sin();
            assert!(
                (check.cone_violation_n - expected).abs() < 1e-6 * expected,
                "pair {i}: cone violation {} N, expected {expected} N",
                check.cone_violation_n
            );
        }
    }
}
