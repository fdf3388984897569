//! Hairs anchoring in rough surfaces, and letting go (docs/model.md 7).
//!
//! A hair tip touching a rough zone open against its stop anchors: the asperities hook it,
//! and the anchored solve decides whether the load presses the hair against its stop (it
//! stays) or folds it (it is let go again, and does not anchor again in the same step). An
//! anchored tip pulled harder than the surface's tension hold lets go. Where anchored hairs
//! wedge the antenna so that no posture nearby is an equilibrium, the anchors are torn out
//! and the step is solved without them, which the step reports (a relaxation).

use super::QuasiStatic;
use crate::Surface;
use crate::contact::feature::FrictionLaw;
use crate::contact::geometry::hair_of;
use crate::contact::pair::{Pair, PairKey};
use crate::contact::report::StepReport;

/// The pairs anchored and let go during one (sub)step (each changes once per step).
#[derive(Debug, Default)]
pub(super) struct AnchorRounds {
    demoted: Vec<PairKey>,
    promoted: Vec<PairKey>,
}

impl QuasiStatic {
    /// Anchors hair tips touching a rough zone open against their stops, lets go of those
    /// folded off their stops or pulled beyond the tension hold, after a solve to `x`;
    /// whether any changed (the step must then be solved again).
    pub(super) fn update_anchors(
        &self,
        x: &[f64],
        hair_links: &[usize],
        pairs: &mut [Pair],
        rounds: &mut AnchorRounds,
    ) -> bool {
        let n = self.world.chain().n();
        let mut changed = false;
        for pair in pairs.iter_mut() {
            let Some(link) = pair.key.hair_link() else {
                continue;
            };
            let hair = hair_of(self.world.chain(), link);
            // A hair tip that joined in this round (no coordinate yet) is open on its stop.
            let beta = hair_links
                .iter()
                .position(|&l| l == link)
                .and_then(|i| x.get(n + i))
                .copied()
                .unwrap_or(hair.rest_angle_rad());
            let on_stop = hair.on_stop(beta, 1e-12);
            let surface = self.world.pieces().surface_at(
                self.world.walls(),
                pair.key.piece,
                &pair.geo.point_m,
            );
            match (pair.law, surface) {
                (FrictionLaw::Anchored { hold_tension_n, .. }, _)
                    if !on_stop || pair.normal_force_n < -hold_tension_n =>
                {
                    pair.law = FrictionLaw::Coulomb { mu: surface.mu() };
                    rounds.demoted.push(pair.key);
                    changed = true;
                }
                (
                    FrictionLaw::Coulomb { .. },
                    Surface::Rough {
                        hold_shear_n,
                        hold_tension_n,
                        ..
                    },
                ) if on_stop
                    && !self.anchoring_blocked
                    && pair.normal_active
                    && pair.normal_force_n > 0.0
                    && !rounds.demoted.contains(&pair.key)
                    && !rounds.promoted.contains(&pair.key) =>
                {
                    // Touching a rough zone open against its stop: the asperities hook the
                    // tip. The anchored solve decides whether the load presses the hair
                    // against its stop (it stays) or folds it (it is let go again).
                    pair.law = FrictionLaw::Anchored {
                        hold_shear_n,
                        hold_tension_n,
                    };
                    rounds.promoted.push(pair.key);
                    changed = true;
                }
                _ => {}
            }
        }
        changed
    }

    /// Tears out every anchored hair (they become Coulomb contacts) and blocks anchoring for
    /// the rest of the step; whether there was any.
    pub(super) fn release_anchors(&mut self, report: &mut StepReport) -> bool {
        let world = &self.world;
        let released = self
            .committed
            .tear_out_anchors(|c| world.coulomb_at(c.key.piece, &c.geo.point_m));
        report.anchors_released += released;
        self.anchoring_blocked = released > 0;
        released > 0
    }
}
