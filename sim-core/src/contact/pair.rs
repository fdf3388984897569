//! Contact pairs: what of the chain can touch what of a wall, each with its own normal force
//! and its own friction (feature pairs).
//!
//! - [`PairKind::Point`]: a point of the chain (a link end, or a hair tip) against the
//!   surface of a wall piece, measured by the signed distance (its normal turns around a
//!   corner and along a curve).
//! - [`PairKind::Link`]: a convex feature of a wall piece (a polyline corner, a sinusoid
//!   crest) against the inside of a link, measured along the link's normal.
//! - [`PairKind::CornerEdge`]: a chain point on a convex polyline corner, against the line
//!   of the corner's edge it lies on. The point's distance to the piece turns its normal at
//!   `1 / gap` about the corner, without bound as the point reaches it, and Newton's method
//!   cannot follow a point sliding over the corner's end of an edge; the line is smooth
//!   there. A point loaded on the line where it runs on past the corner is on no wall: the
//!   pair lets go and the point slips off the corner (see
//!   [`super::broad_phase`]).
//!
//! A wall corner at a joint is then up to four pairs (the joint against the piece, the corner
//! against each of the joint's two links), so the force the wall exerts there can point
//! anywhere in the cone between the links' normals and the corner's; a link lying on a crest
//! while its end touches the wall elsewhere is two pairs. Walls are seen in *pieces*
//! ([`super::pieces`]): polylines cut at their concave corners, so that each piece's signed
//! distance is smooth in free space.

use nalgebra::Vector2;

use super::feature::{Feature, FrictionLaw, Slip};
use super::geometry::PairGeometry;
use crate::walls::ConvexFeature;

/// A point of the chain that can touch a wall surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(crate) enum ChainPoint {
    /// The distal end `p_i` of link `i` (`1..=n`): joint `i + 1`, or the tip.
    Vertex(usize),
    /// The tip of the hair on link `i`.
    HairTip(usize),
}

/// What touches what (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(crate) enum PairKind {
    /// A chain point against the piece's surface.
    Point(ChainPoint),
    /// A convex feature of the piece against the inside of `link`.
    Link {
        /// The link.
        link: usize,
        /// The feature.
        feature: ConvexFeature,
    },
    /// A chain point on a convex corner (`feature`) against the line of the corner's edge
    /// leaving it (`after`) or arriving at it (the one it lies on).
    CornerEdge {
        /// The chain point.
        point: ChainPoint,
        /// The corner.
        feature: ConvexFeature,
        /// Which of its edges.
        after: bool,
    },
}

impl ChainPoint {
    /// The link the point belongs to.
    pub fn link(self) -> usize {
        match self {
            ChainPoint::Vertex(i) | ChainPoint::HairTip(i) => i,
        }
    }
}

/// A pair's identity, from step to step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(crate) struct PairKey {
    /// The link the pair acts on (first, so that pairs sort by link).
    pub link: usize,
    /// What touches.
    pub kind: PairKind,
    /// The wall piece.
    pub piece: usize,
}

impl PairKey {
    /// A chain point against piece `piece`.
    pub fn point(point: ChainPoint, piece: usize) -> PairKey {
        PairKey {
            link: point.link(),
            kind: PairKind::Point(point),
            piece,
        }
    }

    /// Chain point `point` on convex corner `feature` of piece `piece`, against the line of
    /// the corner's edge leaving it (`after`) or arriving at it.
    pub fn corner_edge(
        point: ChainPoint,
        feature: ConvexFeature,
        after: bool,
        piece: usize,
    ) -> PairKey {
        PairKey {
            link: point.link(),
            kind: PairKind::CornerEdge {
                point,
                feature,
                after,
            },
            piece,
        }
    }

    /// The chain point of a point or corner-edge pair (`None` for a link pair).
    pub fn chain_point(&self) -> Option<ChainPoint> {
        match self.kind {
            PairKind::Point(point) | PairKind::CornerEdge { point, .. } => Some(point),
            PairKind::Link { .. } => None,
        }
    }

    /// A convex feature of piece `piece` against the inside of `link`.
    pub fn link(link: usize, feature: ConvexFeature, piece: usize) -> PairKey {
        PairKey {
            link,
            kind: PairKind::Link { link, feature },
            piece,
        }
    }

    /// The reported feature of the chain.
    pub fn feature(&self) -> Feature {
        match self.kind {
            PairKind::Point(point) | PairKind::CornerEdge { point, .. } => match point {
                ChainPoint::Vertex(link) => Feature::Vertex { link },
                ChainPoint::HairTip(link) => Feature::HairTip { link },
            },
            PairKind::Link { link, .. } => Feature::Link { link },
        }
    }

    /// The hair whose tip this is, if any.
    pub fn hair_link(&self) -> Option<usize> {
        match self.chain_point() {
            Some(ChainPoint::HairTip(link)) => Some(link),
            _ => None,
        }
    }
}

/// A contact pair during a step: its identity, its friction law and state, the material
/// point that touched at the start of the step, its forces, and its geometry at the current
/// coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Pair {
    pub key: PairKey,
    pub law: FrictionLaw,
    /// The link and fraction along it of the material point that touched at the start of the
    /// step (a link end: `s = 1`; a hair tip: its link and its pivot's fraction).
    pub material_link: usize,
    pub material_s: f64,
    /// That material point's position at the start of the step.
    pub start_m: Vector2<f64>,
    /// The normal force on the chain, newtons.
    pub normal_force_n: f64,
    /// The shear force on the chain along the tangent, newtons.
    pub shear_force_n: f64,
    /// The geometry at the current coordinates (filled by the evaluation).
    pub geo: PairGeometry,
    /// The material point's position now.
    pub material_m: Vector2<f64>,
    /// Its slip along the tangent since the start of the step, metres.
    pub slip_m: f64,
    /// Whether the normal constraint is active (touching).
    pub normal_active: bool,
    /// Stuck or slipping.
    pub slip: Slip,
    /// When set, the shear bound is `mu` times this normal force instead of the current one
    /// (the Tresca problem of docs/model.md 6's fixed point on the normal forces).
    pub tresca_n: Option<f64>,
    /// `Some(B)` where this step's solution bounded the shear force by `B` instead of the
    /// law's bound (a jam in the fixed point on the normal forces).
    pub relaxed_bound_n: Option<f64>,
    /// Friction is off for this pair in this step (the step's frictional equilibrium was
    /// not found: [`super::StepReport::friction_dropped`]).
    pub frictionless: bool,
}

impl Pair {
    /// A fresh pair with no force, its material point at `material_link`/`material_s`,
    /// `start_m` at the start of the step.
    pub fn new(
        key: PairKey,
        law: FrictionLaw,
        material_link: usize,
        material_s: f64,
        start_m: Vector2<f64>,
    ) -> Pair {
        Pair {
            key,
            law,
            material_link,
            material_s,
            start_m,
            normal_force_n: 0.0,
            shear_force_n: 0.0,
            geo: PairGeometry::at(key.link, material_s, start_m),
            material_m: start_m,
            slip_m: 0.0,
            normal_active: false,
            slip: Slip::Stuck,
            tresca_n: None,
            relaxed_bound_n: None,
            frictionless: false,
        }
    }

    /// Whether the pair touches or carries a force (as opposed to a fresh candidate): one
    /// that lets go or hands over must have the step solved again.
    pub fn is_loaded(&self) -> bool {
        self.normal_active || self.normal_force_n != 0.0
    }

    /// Whether the pair can carry shear at all: not where friction is dropped for the step
    /// or the surface has none (mu = 0, an anchor that holds no shear).
    pub fn has_friction(&self) -> bool {
        !self.frictionless && self.law.shear_bound(1.0).0 > 0.0
    }

    /// The force the wall exerts on the chain, ground frame, newtons.
    pub fn force_n(&self) -> Vector2<f64> {
        self.geo.normal * self.normal_force_n + self.geo.tangent * self.shear_force_n
    }
}
