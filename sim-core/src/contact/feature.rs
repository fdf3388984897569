//! What touches a wall, and how: contact features, friction laws and the reported contacts.

use nalgebra::Vector2;

use crate::ChainContact;

/// A part of the chain that can touch a wall.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Feature {
    /// The distal end of link `link` (`1..=n`): joint `link + 1`, or the tip for `link = n`.
    Vertex {
        /// The link whose distal end it is.
        link: usize,
    },
    /// A point inside link `link` (`1..=n`): where a wall corner or crest meets the link
    /// between its ends.
    Link {
        /// The link.
        link: usize,
    },
    /// The tip of the hair on link `link`.
    HairTip {
        /// The link carrying the hair.
        link: usize,
    },
}

impl Feature {
    /// The link the feature belongs to.
    pub fn link(&self) -> usize {
        match *self {
            Feature::Vertex { link } | Feature::Link { link } | Feature::HairTip { link } => link,
        }
    }

    /// Whether this is a hair tip.
    pub fn is_hair(&self) -> bool {
        matches!(self, Feature::HairTip { .. })
    }
}

/// The friction law at one contact (docs/model.md 6-7).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FrictionLaw {
    /// Coulomb: `N >= 0`, `|T| <= mu N`; sticks below the limit, slips at it.
    Coulomb {
        /// Friction coefficient.
        mu: f64,
    },
    /// A hair tip anchored in a rough surface: the tip is held on the wall and sticks, up to
    /// `hold_shear_n` along the wall (loaded beyond it, it slides at that force) and
    /// `hold_tension_n` away from it (pulled harder, it lets go: the step is solved again
    /// with the tip as a Coulomb contact, free to lift off).
    Anchored {
        /// Shear holding strength, newtons.
        hold_shear_n: f64,
        /// Tension holding strength, newtons.
        hold_tension_n: f64,
    },
}

impl FrictionLaw {
    /// The smallest normal force of the complementarity condition: `0` for Coulomb; an
    /// anchored tip is held to the wall (bilateral, `-inf`), and is let go by the step
    /// driver when its tension exceeds the hold.
    pub(crate) fn min_normal_n(&self) -> f64 {
        match *self {
            FrictionLaw::Coulomb { .. } => 0.0,
            FrictionLaw::Anchored { .. } => f64::NEG_INFINITY,
        }
    }

    /// Whether this is an anchored hair tip's law.
    pub fn is_anchored(&self) -> bool {
        matches!(self, FrictionLaw::Anchored { .. })
    }

    /// The shear bound `B` for a normal force `normal_n`, and `dB/dN`.
    pub(crate) fn shear_bound(&self, normal_n: f64) -> (f64, f64) {
        match *self {
            FrictionLaw::Coulomb { mu } => {
                if normal_n > 0.0 {
                    (mu * normal_n, mu)
                } else {
                    (0.0, 0.0)
                }
            }
            FrictionLaw::Anchored { hold_shear_n, .. } => (hold_shear_n, 0.0),
        }
    }
}

/// Whether a contact stuck or slipped over the last step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Slip {
    /// The contact point did not move along the wall (`|T| < bound`).
    Stuck,
    /// It slid in the `+tangent` direction; the shear force is at `-bound`.
    Forward,
    /// It slid in the `-tangent` direction; the shear force is at `+bound`.
    Backward,
}

impl Slip {
    /// `"stuck"`, `"forward"` or `"backward"`.
    pub fn name(&self) -> &'static str {
        match self {
            Slip::Stuck => "stuck",
            Slip::Forward => "forward",
            Slip::Backward => "backward",
        }
    }
}

/// One contact of the chain with a wall after a step: where, how hard, and stuck or slipping.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// What touches.
    pub feature: Feature,
    /// Which wall (index into the walls given).
    pub wall: usize,
    /// Where along the link (`0` proximal end, `1` distal end); for a hair tip the fraction
    /// of its pivot on the link.
    pub s: f64,
    /// The touching point of the chain, ground frame, metres.
    pub point_m: Vector2<f64>,
    /// The wall's unit normal at the contact, into free space (toward the antenna).
    pub normal: Vector2<f64>,
    /// The wall's unit tangent at the contact.
    pub tangent: Vector2<f64>,
    /// The normal force the wall exerts on the chain, newtons (`>= 0`; negative only for an
    /// anchored hair holding in tension).
    pub normal_force_n: f64,
    /// The shear force the wall exerts on the chain along `tangent`, newtons.
    pub shear_force_n: f64,
    /// The friction law that held.
    pub law: FrictionLaw,
    /// Stuck or slipping over the step.
    pub slip: Slip,
    /// How far the contact point slid along the wall during the step, metres (signed along
    /// `tangent`; exactly what the solver found, `0` to rounding when stuck).
    pub slip_m: f64,
    /// `Some(B)` where this step's friction was relaxed at the contact (a jam, see
    /// [`super::StepReport::jams`]): its shear force was bounded by `B` (`0`: it slid
    /// without friction) instead of its law's bound.
    pub relaxed_shear_bound_n: Option<f64>,
}

impl Contact {
    /// The force the wall exerts on the chain, ground frame, newtons.
    pub fn force_n(&self) -> Vector2<f64> {
        self.normal * self.normal_force_n + self.tangent * self.shear_force_n
    }

    /// Whether the contact is an anchored hair tip.
    pub fn is_anchored(&self) -> bool {
        matches!(self.law, FrictionLaw::Anchored { .. })
    }

    /// The contact as the metrics and mapping take it.
    pub fn chain_contact(&self) -> ChainContact {
        ChainContact {
            link: self.feature.link(),
            s: self.s,
            point_m: self.point_m,
        }
    }
}
