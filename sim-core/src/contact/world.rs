//! What a step is taken in: the chain, the walls (and their contact pieces), the loads and
//! the settings. Every stage reads it; none writes it during a step. Only the driver's
//! public methods change it, between steps ([`super::QuasiStatic::set_tip_force_n`],
//! [`super::QuasiStatic::hold_tip`], [`super::QuasiStatic::set_settings`], and the base
//! angle a turned step leaves the chain at).

use nalgebra::Vector2;

use super::feature::FrictionLaw;
use super::pieces::Pieces;
use super::posture::{Pose, rotate};
use super::settings::ContactSettings;
use crate::{Chain, Wall};

/// The chain among its walls, its loads and the solver's settings (see the module docs).
#[derive(Debug)]
pub(super) struct World {
    chain: Chain,
    /// The walls without their flat vertices ([`crate::Polyline::without_flat_vertices`]).
    walls: Vec<Wall>,
    /// The walls as the contacts see them ([`Pieces`]); contacts are reported against
    /// `walls`.
    pieces: Pieces,
    settings: ContactSettings,
    /// The farthest a point of the chain can be from the base pivot, metres: the links'
    /// lengths and the longest hair (a turn of the base by `a` radians moves a point by at
    /// most `reach_m a`).
    reach_m: f64,
    tip_force_n: Vector2<f64>,
    /// A hand holding the tip at this offset from the base pivot, given with the base link
    /// at `hand_angle_rad` (the offset turns with the base).
    hand_offset_m: Option<Vector2<f64>>,
    hand_angle_rad: f64,
}

impl World {
    /// `chain` among `walls` (kept without their vertices within the penetration tolerance
    /// of their chords), no load, nothing held.
    pub fn new(chain: Chain, walls: &[Wall], settings: ContactSettings) -> World {
        // A vertex within the penetration tolerance of the chord that replaces it is not a
        // corner: see `Polyline::without_flat_vertices`.
        let walls: Vec<Wall> = walls
            .iter()
            .map(|w| w.without_flat_vertices(settings.penetration_tolerance_m))
            .collect();
        let pieces = Pieces::new(&walls);
        let hair_reach_m = chain
            .hairs()
            .iter()
            .flatten()
            .map(|h| h.pivot_in_link_m().norm() + h.length_m)
            .fold(0.0_f64, f64::max);
        let reach_m = chain.total_length_m() + hair_reach_m;
        World {
            chain,
            walls,
            pieces,
            settings,
            reach_m,
            tip_force_n: Vector2::zeros(),
            hand_offset_m: None,
            hand_angle_rad: 0.0,
        }
    }

    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    pub fn walls(&self) -> &[Wall] {
        &self.walls
    }

    pub fn pieces(&self) -> &Pieces {
        &self.pieces
    }

    pub fn settings(&self) -> &ContactSettings {
        &self.settings
    }

    pub fn reach_m(&self) -> f64 {
        self.reach_m
    }

    pub fn tip_force_n(&self) -> Vector2<f64> {
        self.tip_force_n
    }

    /// Whether a hand holds the tip.
    pub fn holds_tip(&self) -> bool {
        self.hand_offset_m.is_some()
    }

    /// The point the hand holding the tip pulls it to with the base at `at` (its offset
    /// turned by the base's turn since the hand took hold); `None` without a hand.
    pub fn hand_target(&self, at: Pose) -> Option<Vector2<f64>> {
        self.hand_offset_m.map(|o| {
            let turn_rad = at.angle_rad - self.hand_angle_rad;
            if turn_rad == 0.0 {
                at.base_m + o
            } else {
                at.base_m + rotate(turn_rad, o)
            }
        })
    }

    /// The friction law of a fresh contact on piece `piece` at `point_m`: the surface's
    /// Coulomb law (a hair tip anchors only once it touches, see the driver's anchoring).
    pub fn coulomb_at(&self, piece: usize, point_m: &Vector2<f64>) -> FrictionLaw {
        FrictionLaw::Coulomb {
            mu: self.pieces.surface_at(&self.walls, piece, point_m).mu(),
        }
    }

    /// Whether any wall has friction (or anchoring) anywhere.
    pub fn has_friction(&self) -> bool {
        self.walls.iter().any(|w| w.surfaces.has_friction())
    }

    /// The Newton iterations a step may take ([`ContactSettings::step_iteration_budget`]:
    /// `max_step_iterations`, scaled with the chain's joints by default).
    pub fn step_budget(&self) -> usize {
        self.settings.step_iteration_budget(self.chain.n())
    }

    pub fn set_tip_force_n(&mut self, tip_force_n: Vector2<f64>) {
        self.tip_force_n = tip_force_n;
    }

    /// A hand holds the tip at `offset_m` from the pivot with the base link at
    /// `base_angle_rad`, or lets go (`None`).
    pub fn hold_tip(&mut self, offset_m: Option<Vector2<f64>>, base_angle_rad: f64) {
        self.hand_offset_m = offset_m;
        self.hand_angle_rad = base_angle_rad;
    }

    /// Replaces the settings (validated by the caller).
    pub fn set_settings(&mut self, settings: ContactSettings) {
        self.settings = settings;
    }

    /// Keeps the chain's base angle ([`Chain::base_angle_rad`]) at `theta0_rad` (the solver
    /// itself reads only the committed `theta_0`): a turned step replaces the chain by its
    /// copy at the new angle, once per step.
    pub fn turn_chain_to(&mut self, theta0_rad: f64) {
        if self.chain.base_angle_rad() != theta0_rad
            && let Ok(turned) = self.chain.with_base_angle_rad(theta0_rad)
        {
            self.chain = turned;
        }
    }
}
