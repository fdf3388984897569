//! The geometry of a contact pair at a posture, with what its derivatives need (closed
//! form, no differences).
//!
//! Every pair has a **contact point** `X` on a link `L` (a link end, a hair tip, or the foot
//! of a wall feature on the link), a gap, and a unit normal `n` (into free space: the
//! direction the wall pushes the chain) and tangent `t`. The gap's gradient is always the
//! normal carried by the material point at `X`: `grad g = J_X^T n`, with `J_X` the Jacobian
//! of the chain point fixed to link `L` at `X` (for a chain point against a surface, the
//! signed distance's gradient; for a feature against a link, the envelope theorem: the
//! feature's own motion along the link changes the gap only to second order). What differs
//! is how `n`, `t` and `X` move to first order ([`Turn`]):
//! - against a surface, `X` is material and the normal turns as `X` moves along the
//!   tangent: `dn = k (t . dX) t`, `dt = -k (t . dX) n`, `k` the curvature of the distance's
//!   level set (`1 / gap` about a corner, `kappa / (1 + kappa gap)` along a curve,
//!   [`crate::walls::WallPoint::normal_turn_rate_per_m`]);
//! - a feature against a link turns `n` and `t` with the link (`dn = R90 n dphi_L`) and
//!   slides `X` along it: with `dir` the link's direction, `l` its length, `a` its proximal
//!   end and `sigma = -n . R90 dir`, `l ds = (sigma g + roll) dphi_L - dir . da`, where
//!   `roll` is how far the wall point moves along the link per radian the link turns (`0` at
//!   a corner, the crest's rolling at a crest).

use nalgebra::Vector2;

use super::pair::{ChainPoint, PairKey, PairKind};
use super::posture::{Posture, perp};
use crate::walls::WallPoint;
use crate::{Chain, Hair, Wall};

/// How a pair's normal, tangent and contact point move to first order (see the module
/// docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Turn {
    /// A material point against a surface: `dn = rate (t . dX) t`.
    Field {
        /// `rate`, 1/m.
        rate_per_m: f64,
    },
    /// A wall feature against a link: `n`, `t` turn with the link, the point slides along it.
    WithLink {
        /// The link's unit direction.
        dir: Vector2<f64>,
        /// Its length, metres.
        length_m: f64,
        /// `sigma g + roll`, metres per radian: the slide's part that comes from the link's
        /// turning.
        slide_m_per_rad: f64,
    },
}

/// A pair's geometry at one posture (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PairGeometry {
    /// The link the force acts on.
    pub link: usize,
    /// Where along the link (`0` proximal, `1` distal; a hair tip: its pivot's fraction).
    pub s: f64,
    /// The contact point `X` on the chain, metres.
    pub point_m: Vector2<f64>,
    /// The wall point it faces, metres.
    pub wall_m: Vector2<f64>,
    /// The gap, metres (`+inf` where a feature pair cannot be measured).
    pub gap_m: f64,
    /// The unit normal into free space.
    pub normal: Vector2<f64>,
    /// The unit tangent.
    pub tangent: Vector2<f64>,
    /// How they move.
    pub turn: Turn,
    /// For a hair tip, `dX / d beta` (its hair angle's column).
    pub hair_rate: Option<Vector2<f64>>,
    /// Whether the pair is what touches: a feature's foot on its link (within
    /// [`FOOT_TOLERANCE`]) and the link's normal in a corner's cone; always for a point.
    pub valid: bool,
}

/// A feature's foot this far (as a fraction of the link) beyond a link end still counts as
/// on the link: a corner at a joint rests on both of its links.
pub(crate) const FOOT_TOLERANCE: f64 = 1e-3;

impl PairGeometry {
    /// A placeholder at `point_m` (before the first evaluation).
    pub fn at(link: usize, s: f64, point_m: Vector2<f64>) -> PairGeometry {
        PairGeometry {
            link,
            s,
            point_m,
            wall_m: point_m,
            gap_m: f64::INFINITY,
            normal: Vector2::zeros(),
            tangent: Vector2::zeros(),
            turn: Turn::Field { rate_per_m: 0.0 },
            hair_rate: None,
            valid: true,
        }
    }
}

/// The hair on `link`: callers only ask for links that carry one.
pub(crate) fn hair_of(chain: &Chain, link: usize) -> &Hair {
    match chain.hairs().get(link) {
        Some(Some(hair)) => hair,
        // Pairs and hair coordinates are built from the chain's own hairs.
        _ => unreachable_hair(link),
    }
}

#[cold]
fn unreachable_hair(link: usize) -> ! {
    panic!("internal error: no hair on link {link}")
}

/// The point of the chain `point` in `posture` (hair angles `beta`), with its link and
/// fraction along it.
pub(crate) fn chain_point(
    chain: &Chain,
    posture: &Posture,
    beta: &[f64],
    point: ChainPoint,
) -> (usize, f64, Vector2<f64>) {
    match point {
        ChainPoint::Vertex(link) => (link, 1.0, posture.end_m[link]),
        ChainPoint::HairTip(link) => {
            let hair = hair_of(chain, link);
            let s = 1.0 - hair.pivot_from_distal_end_m / chain.link_lengths_m()[link];
            (link, s, posture.hair_tip(hair, link, beta[link]))
        }
    }
}

/// Evaluates `key`'s geometry against `piece` in `posture` (hair angles `beta`) into
/// `geo`. A feature pair that cannot be measured (a link steeper than the crest can be
/// tangent to) keeps its last normal and point with an infinite gap and is not valid.
pub(crate) fn evaluate(
    chain: &Chain,
    piece: &Wall,
    posture: &Posture,
    beta: &[f64],
    key: &PairKey,
    geo: &mut PairGeometry,
) {
    match key.kind {
        PairKind::Point(point) => {
            let (link, s, x) = chain_point(chain, posture, beta, point);
            let wp = piece.signed_distance(&x);
            *geo = point_geometry(chain, posture, beta, point, link, s, x, &wp);
        }
        PairKind::CornerEdge {
            point,
            feature,
            after,
        } => {
            let (link, s, x) = chain_point(chain, posture, beta, point);
            match piece.shape.corner_edge_point(feature, after, &x) {
                Some(wp) => *geo = point_geometry(chain, posture, beta, point, link, s, x, &wp),
                None => {
                    geo.link = link;
                    geo.gap_m = f64::INFINITY;
                    geo.valid = false;
                }
            }
        }
        PairKind::Link { link, feature } => {
            let (a, b) = (posture.start_of(link), posture.end_m[link]);
            match piece.shape.feature_contact(feature, &a, &b) {
                Some(fc) => {
                    let d = b - a;
                    let length_m = d.norm();
                    let dir = d / length_m;
                    let sigma = -fc.normal.dot(&perp(dir));
                    *geo = PairGeometry {
                        link,
                        s: fc.s,
                        point_m: fc.point_m,
                        wall_m: fc.wall_m,
                        gap_m: fc.gap_m,
                        normal: fc.normal,
                        tangent: fc.tangent,
                        turn: Turn::WithLink {
                            dir,
                            length_m,
                            slide_m_per_rad: sigma * fc.gap_m + fc.roll_m_per_rad,
                        },
                        hair_rate: None,
                        valid: fc.supported
                            && fc.s >= -FOOT_TOLERANCE
                            && fc.s <= 1.0 + FOOT_TOLERANCE,
                    };
                }
                None => {
                    geo.link = link;
                    geo.gap_m = f64::INFINITY;
                    geo.valid = false;
                }
            }
        }
    }
}

/// The geometry of chain point `point` (on `link` at fraction `s`, at `x`) against the
/// surface point `wp`.
#[allow(clippy::too_many_arguments)]
fn point_geometry(
    chain: &Chain,
    posture: &Posture,
    beta: &[f64],
    point: ChainPoint,
    link: usize,
    s: f64,
    x: Vector2<f64>,
    wp: &WallPoint,
) -> PairGeometry {
    PairGeometry {
        link,
        s,
        point_m: x,
        wall_m: wp.closest_m,
        gap_m: wp.gap_m,
        normal: wp.normal,
        tangent: wp.tangent,
        turn: Turn::Field {
            rate_per_m: wp.normal_turn_rate_per_m(),
        },
        hair_rate: match point {
            ChainPoint::HairTip(link) => {
                Some(posture.hair_tip_rate(hair_of(chain, link), link, beta[link]))
            }
            ChainPoint::Vertex(_) => None,
        },
        valid: true,
    }
}

/// `J_X^T w` for the chain point `X` fixed to link `link` (and, for a hair tip, its hair
/// angle's column `hair_rate`): the joint entries `1..=link` (`cross(X - p_(j-1), w)`) into
/// `joints` (all `n` written), the hair entry returned (`0` without a hair).
pub(crate) fn generalized(
    posture: &Posture,
    geo: &PairGeometry,
    w: Vector2<f64>,
    joints: &mut [f64],
) -> f64 {
    let x = geo.point_m;
    for (j, out) in joints.iter_mut().enumerate() {
        // Joint j + 1 sits at p_j.
        *out = if j < geo.link {
            super::posture::cross(x - posture.end_m[j], w)
        } else {
            0.0
        };
    }
    geo.hair_rate.map_or(0.0, |rate| rate.dot(&w))
}

/// `n` turned into the cone of unit normals from `cone[0]` to `cone[1]` (the shorter way
/// round), widened by `slack_rad` on each side: `n` itself where it lies inside.
pub(crate) fn into_cone(n: Vector2<f64>, cone: [Vector2<f64>; 2], slack_rad: f64) -> Vector2<f64> {
    let angle = |u: &Vector2<f64>, v: &Vector2<f64>| (u.x * v.y - u.y * v.x).atan2(u.dot(v));
    let [a, b] = cone;
    let width = angle(&a, &b);
    let (lo, hi) = if width >= 0.0 {
        (-slack_rad, width + slack_rad)
    } else {
        (width - slack_rad, slack_rad)
    };
    let turn = angle(&a, &n).clamp(lo, hi);
    let (sin, cos) = turn.sin_cos();
    Vector2::new(a.x * cos - a.y * sin, a.x * sin + a.y * cos)
}
