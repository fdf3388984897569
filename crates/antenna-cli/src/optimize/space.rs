//! The search space of `antenna optimize`: coordinates in the unit box, each mapped to a
//! joint stiffness on a logarithmic scale between the bounds (a stiffness ratio matters, not
//! a difference), then, with `wires = "available"`, to the nearest stiffness a Nitinol wire
//! makes.
//!
//! ```text
//! per-joint:          k_j = k_min (k_max / k_min)^(u_j)                        j = 1..n
//! exponential-taper:  k_j = k_1 (k_n / k_1)^((x_j - x_1) / (x_n - x_1)),  k_1, k_n as above
//! ```
//!
//! `x_j` is joint `j`'s normalized position along the antenna (docs/model.md 5). A coordinate
//! outside `[0, 1]` (Nelder-Mead's simplex may step out) is projected onto the box: the best
//! profiles lie on the bounds (joints as stiff or as soft as allowed), which a projected
//! simplex reaches and keeps. Measured on the worked example (docs/optimize.md), reflecting
//! the coordinate back into the box instead found 171.8 mm against projection's 203.7 mm in
//! the same 300 sweeps.

use sim_core::{WireDiameter, available_wires, joint_positions, wire_stiffness_n_m_per_rad};

/// The family of stiffness profiles searched.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Family {
    /// One stiffness per joint: `n` coordinates.
    PerJoint,
    /// An exponential taper from the first joint's stiffness to the last one's (constant
    /// when they are equal): 2 coordinates.
    ExponentialTaper,
}

file_names!(Family {
    PerJoint => "per-joint",
    ExponentialTaper => "exponential-taper",
});

/// Which stiffnesses a joint can have.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wires {
    /// Any stiffness within the bounds.
    Any,
    /// Only what one of the available Nitinol wires makes (with the cable, docs/model.md 5),
    /// within the bounds.
    Available,
}

file_names!(Wires {
    Any => "any",
    Available => "available",
});

/// The coordinates of a search and the stiffnesses they stand for.
#[derive(Debug, Clone, PartialEq)]
pub struct Space {
    /// The family.
    pub family: Family,
    /// The stiffness bounds `(min, max)`, N m/rad, `0 < min < max`.
    pub bounds_n_m_per_rad: (f64, f64),
    /// Which stiffnesses a wire makes.
    pub wires: Wires,
    /// Each joint's normalized position along the antenna.
    positions: Vec<f64>,
    /// With [`Wires::Available`]: the wires within the bounds and their stiffness, softest
    /// first.
    choices: Vec<(WireDiameter, f64)>,
}

impl Space {
    /// The space of `family` for a chain of these link lengths.
    ///
    /// # Errors
    /// A sentence when the link lengths give no joint, or no available wire lies within the
    /// bounds with [`Wires::Available`].
    pub fn new(
        family: Family,
        bounds_n_m_per_rad: (f64, f64),
        wires: Wires,
        link_lengths_m: &[f64],
    ) -> Result<Space, String> {
        let positions = joint_positions(link_lengths_m).map_err(|e| e.to_string())?;
        let (lo, hi) = bounds_n_m_per_rad;
        let choices: Vec<(WireDiameter, f64)> = match wires {
            Wires::Any => Vec::new(),
            Wires::Available => {
                let choices: Vec<_> = available_wires()
                    .into_iter()
                    .map(|w| (w, wire_stiffness_n_m_per_rad(w)))
                    .filter(|&(_, k)| (lo..=hi).contains(&k))
                    .collect();
                if choices.is_empty() {
                    return Err(format!(
                        "no available wire makes a stiffness within [{lo}, {hi}] N m/rad"
                    ));
                }
                choices
            }
        };
        Ok(Space {
            family,
            bounds_n_m_per_rad,
            wires,
            positions,
            choices,
        })
    }

    /// The number of joints.
    pub fn joints(&self) -> usize {
        self.positions.len()
    }

    /// The number of coordinates.
    pub fn dim(&self) -> usize {
        match self.family {
            Family::PerJoint => self.joints(),
            Family::ExponentialTaper => 2,
        }
    }

    /// `k_min (k_max / k_min)^u`, `u` projected onto `[0, 1]` (NaN to 0).
    fn stiffness_at(&self, u: f64) -> f64 {
        let (lo, hi) = self.bounds_n_m_per_rad;
        let u = if u.is_nan() { 0.0 } else { u.clamp(0.0, 1.0) };
        (lo * (hi / lo).powf(u)).clamp(lo, hi)
    }

    /// The inverse of [`Self::stiffness_at`], clamped onto the box.
    fn coordinate_of(&self, k: f64) -> f64 {
        let (lo, hi) = self.bounds_n_m_per_rad;
        ((k / lo).ln() / (hi / lo).ln()).clamp(0.0, 1.0)
    }

    /// The joint stiffnesses, N m/rad, of the point `u` (one value per coordinate), made by
    /// wires with [`Wires::Available`].
    pub fn values(&self, u: &[f64]) -> Vec<f64> {
        let at = |i: usize| self.stiffness_at(u.get(i).copied().unwrap_or(0.0));
        let values: Vec<f64> = match self.family {
            Family::PerJoint => (0..self.joints()).map(at).collect(),
            Family::ExponentialTaper => {
                let (first, last) = (at(0), at(1));
                let x0 = self.positions[0];
                let span = self.positions[self.joints() - 1] - x0;
                self.positions
                    .iter()
                    .map(|&x| {
                        if span > 0.0 {
                            first * (last / first).powf((x - x0) / span)
                        } else {
                            first
                        }
                    })
                    .collect()
            }
        };
        self.made(&values)
    }

    /// The point whose stiffnesses are nearest `values` (a named profile's): per joint, each
    /// value's coordinate; for the taper, the first and the last joint's.
    pub fn coordinates(&self, values: &[f64]) -> Vec<f64> {
        match self.family {
            Family::PerJoint => values.iter().map(|&k| self.coordinate_of(k)).collect(),
            Family::ExponentialTaper => {
                let first = values.first().copied().unwrap_or(self.bounds_n_m_per_rad.0);
                let last = values.last().copied().unwrap_or(first);
                vec![self.coordinate_of(first), self.coordinate_of(last)]
            }
        }
    }

    /// `values` as the joints can have them: unchanged with [`Wires::Any`], else each the
    /// stiffness of the wire nearest it (a tie goes to the softer wire).
    pub fn made(&self, values: &[f64]) -> Vec<f64> {
        match self.wires {
            Wires::Any => values.to_vec(),
            Wires::Available => values
                .iter()
                .map(|&k| self.nearest_wire(k).map_or(k, |(_, made)| made))
                .collect(),
        }
    }

    /// With [`Wires::Available`], the wire nearest `k` and its stiffness.
    pub fn nearest_wire(&self, k: f64) -> Option<(WireDiameter, f64)> {
        let mut best: Option<(WireDiameter, f64)> = None;
        for &(wire, made) in &self.choices {
            if best.is_none_or(|(_, b)| (made - k).abs() < (b - k).abs()) {
                best = Some((wire, made));
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LINKS: [f64; 9] = [0.04; 9];

    #[test]
    fn the_box_maps_onto_the_bounds_logarithmically() {
        let space = Space::new(Family::PerJoint, (0.004, 0.064), Wires::Any, &LINKS).unwrap();
        assert_eq!(space.dim(), 8);
        let k = space.values(&[0.0, 0.25, 0.5, 1.0, -3.0, 7.0, f64::NAN, 0.75]);
        let expected = [0.004, 0.008, 0.016, 0.064, 0.004, 0.064, 0.004, 0.032];
        for (got, want) in k.iter().zip(expected) {
            assert!((got - want).abs() < 1e-15, "{k:?}");
        }
        let back = space.coordinates(&k);
        for (u, want) in back.iter().zip([0.0, 0.25, 0.5, 1.0, 0.0, 1.0, 0.0, 0.75]) {
            assert!((u - want).abs() < 1e-12, "{back:?}");
        }
    }

    #[test]
    fn the_taper_is_exponential_between_its_ends() {
        let space =
            Space::new(Family::ExponentialTaper, (0.004, 0.064), Wires::Any, &LINKS).unwrap();
        assert_eq!(space.dim(), 2);
        let k = space.values(&[1.0, 0.0]);
        assert_eq!(k.len(), 8);
        assert!((k[0] - 0.064).abs() < 1e-15 && (k[7] - 0.004).abs() < 1e-15);
        // equal joint spacing: a constant ratio from joint to joint, 16^(1/7)
        for w in k.windows(2) {
            assert!((w[0] / w[1] - 16f64.powf(1.0 / 7.0)).abs() < 1e-12, "{k:?}");
        }
        assert!(
            space
                .values(&[0.5, 0.5])
                .iter()
                .all(|&v| (v - 0.016).abs() < 1e-15)
        );
        assert_eq!(space.coordinates(&k).len(), 2);
    }

    #[test]
    fn available_wires_snap_to_the_nearest_within_the_bounds() {
        let space = Space::new(Family::PerJoint, (0.004, 0.082), Wires::Available, &LINKS).unwrap();
        let wires: Vec<f64> = available_wires()
            .into_iter()
            .map(wire_stiffness_n_m_per_rad)
            .filter(|k| (0.004..=0.082).contains(k))
            .collect();
        for k in space.values(&[0.0, 0.1, 0.3, 0.5, 0.7, 0.8, 0.9, 1.0]) {
            assert!(wires.contains(&k), "{k} is no wire's");
        }
        // the stiffest wire (0.030 in, 0.0450 N m/rad) for anything above it
        let (wire, k) = space.nearest_wire(0.082).unwrap();
        assert_eq!(wire.thousandths_in(), 30);
        assert!((k - 0.0450).abs() < 1e-4);
        assert!(
            Space::new(Family::PerJoint, (0.05, 0.08), Wires::Available, &LINKS)
                .unwrap_err()
                .contains("no available wire")
        );
    }
}
