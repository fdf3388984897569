//! What the physics is built from: the antenna and its flat wall, in the terms of antennad's
//! `[sim.antenna]` and `[sim.wall]` (and of the stream's `hello`).

/// The simulated antenna: `links` flexible links of `link_length_m` after a base link of the
/// same length, joint stiffness from a named sim-core profile.
#[derive(Debug, Clone, PartialEq)]
pub struct AntennaSpec {
    /// Flexible links (one per segment).
    pub links: usize,
    /// Length of every link, the base link too, metres.
    pub link_length_m: f64,
    /// A sim-core stiffness profile name (`constant`, `linear`, ...).
    pub stiffness_profile: String,
    /// The profile's smallest joint stiffness, N m/rad.
    pub k_min_n_m_per_rad: f64,
    /// The profile's largest joint stiffness, N m/rad.
    pub k_max_n_m_per_rad: f64,
    /// The base link's angle from the stage's track with the servo at 0, degrees.
    pub base_angle_deg: f64,
}

impl Default for AntennaSpec {
    /// antennad's default simulated antenna: nine 40 mm links, `linear` from 0.01 to
    /// 0.05 N m/rad, mounted at 30 degrees.
    fn default() -> Self {
        Self {
            links: 9,
            link_length_m: 0.04,
            stiffness_profile: "linear".to_owned(),
            k_min_n_m_per_rad: 0.01,
            k_max_n_m_per_rad: 0.05,
            base_angle_deg: 30.0,
        }
    }
}

impl AntennaSpec {
    /// The named stiffness profile, or `None` if sim-core has none of that name.
    pub fn profile(&self) -> Option<sim_core::StiffnessProfile> {
        sim_core::StiffnessProfile::NAMED
            .into_iter()
            .find(|p| p.name() == self.stiffness_profile)
    }
}

/// A flat wall: the line `distance_m` from the stage's track at the track's origin, tilted
/// `angle_deg` toward the track as the stage moves forward, solid beyond it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlatWallSpec {
    /// Distance from the track at its origin, metres.
    pub distance_m: f64,
    /// Angle to the track, degrees (positive: the wall comes closer as the stage moves
    /// forward).
    pub angle_deg: f64,
    /// Coulomb friction coefficient against the antenna.
    pub mu: f64,
}

impl Default for FlatWallSpec {
    /// antennad's default simulated wall: 0.42 m away, 30 degrees, mu 0.3.
    fn default() -> Self {
        Self {
            distance_m: 0.42,
            angle_deg: 30.0,
            mu: 0.3,
        }
    }
}
