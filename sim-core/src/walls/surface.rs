//! Wall surfaces (docs/model.md 6-7): smooth (Coulomb friction) or rough (asperities that anchor
//! hair tips), and zones of different surface along one wall (the thesis's smooth zone followed
//! by felt or abrasive, 3.3.2).

use super::WallPoint;
use super::error::{WallError, finite};

/// The friction coefficient of a smooth wall when none is given (docs/model.md 6).
pub const SMOOTH_MU_DEFAULT: f64 = 0.3;

/// What a wall is made of at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Surface {
    /// Coulomb friction `|T| <= mu N` for links and hair tips alike.
    Smooth {
        /// Friction coefficient (>= 0).
        mu: f64,
    },
    /// Asperities (felt, abrasive) that anchor a hair tip loaded against its stop.
    Rough {
        /// Coulomb friction for links and for collapsed (folded) hairs (>= 0).
        mu: f64,
        /// The largest shear force (along the wall) an anchored hair tip holds, newtons.
        hold_shear_n: f64,
        /// The largest pull away from the wall an anchored hair tip holds, newtons.
        hold_tension_n: f64,
    },
}

impl Default for Surface {
    /// A smooth wall with `mu = 0.3` ([`SMOOTH_MU_DEFAULT`]).
    fn default() -> Self {
        Surface::Smooth {
            mu: SMOOTH_MU_DEFAULT,
        }
    }
}

impl Surface {
    /// The Coulomb friction coefficient (for a rough surface: of links and collapsed hairs).
    pub fn mu(&self) -> f64 {
        match *self {
            Surface::Smooth { mu } | Surface::Rough { mu, .. } => mu,
        }
    }

    /// Whether hair tips can anchor here.
    pub fn is_rough(&self) -> bool {
        matches!(self, Surface::Rough { .. })
    }

    /// Checks the parameters: `mu` and the holding strengths finite and `>= 0`.
    ///
    /// # Errors
    /// [`WallError::NegativeFriction`] or [`WallError::NegativeHold`].
    pub fn validate(&self) -> Result<(), WallError> {
        let mu = self.mu();
        if !(mu.is_finite() && mu >= 0.0) {
            return Err(WallError::NegativeFriction { mu });
        }
        if let Surface::Rough {
            hold_shear_n,
            hold_tension_n,
            ..
        } = *self
        {
            for (field, value_n) in [
                ("hold_shear_n", hold_shear_n),
                ("hold_tension_n", hold_tension_n),
            ] {
                if !(value_n.is_finite() && value_n >= 0.0) {
                    return Err(WallError::NegativeHold { field, value_n });
                }
            }
        }
        Ok(())
    }
}

/// The coordinate along a wall by which its surface zones are laid out.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ZoneAxis {
    /// [`WallPoint::arclength_m`]: travels with the wall when it is translated.
    Arclength,
    /// The world x coordinate of [`WallPoint::closest_m`]: boundaries shift by the x of a
    /// translation.
    WorldX,
}

/// The surface of a wall as a function of position along it: `first` up to the first
/// boundary, then each boundary's surface from that boundary (inclusive) on.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceMap {
    axis: ZoneAxis,
    first: Surface,
    boundaries: Vec<(f64, Surface)>,
}

impl Default for SurfaceMap {
    /// One smooth surface with `mu = 0.3` everywhere.
    fn default() -> Self {
        SurfaceMap {
            axis: ZoneAxis::Arclength,
            first: Surface::default(),
            boundaries: Vec::new(),
        }
    }
}

impl SurfaceMap {
    /// The same surface everywhere.
    ///
    /// # Errors
    /// As [`Surface::validate`].
    pub fn uniform(surface: Surface) -> Result<SurfaceMap, WallError> {
        Self::zoned(ZoneAxis::Arclength, surface, Vec::new())
    }

    /// Zones along `axis`: `first` below `boundaries[0].0`, then `boundaries[i].1` on
    /// `[boundaries[i].0, boundaries[i + 1].0)`. Boundaries in metres, strictly increasing.
    ///
    /// # Errors
    /// [`WallError::NotFinite`] for a non-finite boundary, [`WallError::ZonesNotIncreasing`],
    /// or an invalid surface ([`Surface::validate`]).
    pub fn zoned(
        axis: ZoneAxis,
        first: Surface,
        boundaries: Vec<(f64, Surface)>,
    ) -> Result<SurfaceMap, WallError> {
        first.validate()?;
        for (index, &(at_m, surface)) in boundaries.iter().enumerate() {
            finite("boundaries", index, at_m)?;
            surface.validate()?;
            if index > 0 && at_m <= boundaries[index - 1].0 {
                return Err(WallError::ZonesNotIncreasing { index });
            }
        }
        Ok(SurfaceMap {
            axis,
            first,
            boundaries,
        })
    }

    /// The zone coordinate.
    pub fn axis(&self) -> ZoneAxis {
        self.axis
    }

    /// The surface below the first boundary.
    pub fn first(&self) -> Surface {
        self.first
    }

    /// The zone boundaries (metres along [`Self::axis`]) and the surface from each on.
    pub fn boundaries(&self) -> &[(f64, Surface)] {
        &self.boundaries
    }

    /// The surface, if it is the same everywhere (no zones): then no point of the wall need
    /// be found to know it.
    pub fn uniform_surface(&self) -> Option<Surface> {
        self.boundaries.is_empty().then_some(self.first)
    }

    /// Whether any zone has friction or anchors hairs (`mu > 0` or rough).
    pub fn has_friction(&self) -> bool {
        std::iter::once(&self.first)
            .chain(self.boundaries.iter().map(|(_, s)| s))
            .any(|s| s.mu() > 0.0 || s.is_rough())
    }

    /// The surface at a point of the wall (found by [`super::Wall::signed_distance`]).
    pub fn surface_at(&self, point: &WallPoint) -> Surface {
        let at_m = match self.axis {
            ZoneAxis::Arclength => point.arclength_m,
            ZoneAxis::WorldX => point.closest_m.x,
        };
        // Boundaries are few (a handful of zones): a linear scan beats a binary search.
        self.boundaries
            .iter()
            .take_while(|(boundary_m, _)| at_m >= *boundary_m)
            .last()
            .map_or(self.first, |&(_, surface)| surface)
    }

    /// Shifts world-x zone boundaries by `offset_x_m` (a translation of the wall).
    pub(crate) fn translate_x(&mut self, offset_x_m: f64) {
        if self.axis == ZoneAxis::WorldX {
            for (boundary_m, _) in &mut self.boundaries {
                *boundary_m += offset_x_m;
            }
        }
    }
}
