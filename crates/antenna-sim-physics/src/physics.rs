//! [`SimPhysics`]: the posture of the antenna against its wall for a base position and angle.

use antenna_protocol::TouchBits;
use nalgebra::Vector2;
use sim_core::contact::{ContactSettings, QuasiStatic};
use sim_core::{
    Chain, ChainContact, Line, SolidSide, Surface, SurfaceMap, Wall, closes_switch,
    touch_bits_from_contacts,
};

use crate::spec::{AntennaSpec, FlatWallSpec};

/// How far off the wall a turned antenna is put before it steps back, metres.
const TURN_CLEARANCE_M: f64 = 1e-3;

/// Why the physics could not be built or stepped.
#[derive(Debug, thiserror::Error)]
pub enum PhysicsError {
    /// The stiffness profile's name is not one of sim-core's.
    #[error("unknown stiffness profile {name:?}")]
    UnknownProfile {
        /// The name given.
        name: String,
    },
    /// sim-core refused the antenna or the wall, or a step found no equilibrium.
    #[error("{context}: {source}")]
    Model {
        /// What was being done, e.g. `the antenna with the stage at 150.0 mm`.
        context: String,
        /// sim-core's error.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A touch threshold that is negative or not finite.
    #[error("touch threshold {threshold_n} N: must be finite and at least 0")]
    TouchThreshold {
        /// The threshold given, newtons.
        threshold_n: f64,
    },
}

fn model<E: std::error::Error + Send + Sync + 'static>(
    context: impl Into<String>,
) -> impl FnOnce(E) -> PhysicsError {
    let context = context.into();
    move |source| PhysicsError::Model {
        context,
        source: Box::new(source),
    }
}

/// The physical state the simulated segments sense.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SimState {
    /// Joint angles `theta_1..theta_n`, radians.
    pub joint_angles_rad: Vec<f64>,
    /// Raw touch switches per segment (a switch closed by a contact whose force is at least
    /// the touch threshold, [`SimPhysics::set_touch_threshold_n`]).
    pub touch: Vec<TouchBits>,
    /// The wall's force on the tip, newtons (0 out of contact).
    pub tip_force_n: f64,
    /// Steps so far in which the contact solver relaxed something to get through (friction
    /// dropped, a residual accepted above the tolerance): every step is certified by
    /// sim-core's independent check, and these are said.
    pub relaxed_steps: u64,
    /// What the last step relaxed, in words (empty when nothing).
    pub relaxations: Vec<String>,
}

/// The antenna against the wall: the posture for a stage position and base angle.
#[derive(Debug)]
pub struct SimPhysics {
    sim: QuasiStatic,
    contacts: Vec<ChainContact>,
    touch_bits: Vec<u8>,
    touch_threshold_n: f64,
    relaxed_steps: u64,
}

impl SimPhysics {
    /// The antenna of `antenna` at rest in front of `wall`, the stage at 0.
    ///
    /// # Errors
    /// [`PhysicsError::UnknownProfile`], or [`PhysicsError::Model`] naming what sim-core
    /// refused (the stiffness bounds, the chain, the wall, a rest posture inside the wall).
    pub fn new(antenna: &AntennaSpec, wall: &FlatWallSpec) -> Result<Self, PhysicsError> {
        let lengths = vec![antenna.link_length_m; antenna.links + 1];
        let profile = antenna
            .profile()
            .ok_or_else(|| PhysicsError::UnknownProfile {
                name: antenna.stiffness_profile.clone(),
            })?;
        let k = profile
            .stiffness_n_m_per_rad(
                &lengths,
                antenna.k_min_n_m_per_rad,
                antenna.k_max_n_m_per_rad,
            )
            .map_err(model("sim.antenna stiffness"))?;
        let chain = Chain::builder(antenna.links)
            .link_length_m(antenna.link_length_m)
            .base_angle_rad(antenna.base_angle_deg.to_radians())
            .stiffnesses_nm_per_rad(k)
            .build()
            .map_err(model("sim.antenna"))?;
        let wall = wall_of(wall)?;
        let theta = chain.rest_theta();
        let sim = QuasiStatic::new(
            chain,
            vec![wall],
            Vector2::zeros(),
            &theta,
            ContactSettings::default(),
        )
        .map_err(model(
            "sim.antenna at rest with the stage at 0 against sim.wall",
        ))?;
        Ok(Self {
            touch_bits: vec![0; theta.len()],
            sim,
            contacts: Vec::new(),
            touch_threshold_n: 0.0,
            relaxed_steps: 0,
        })
    }

    /// Sets the force a contact needs to close the touch switch under it, newtons (`0`, the
    /// default: every contact closes its switch). A contact closes it when the magnitude of
    /// the wall's force on the chain there is at least this.
    ///
    /// # Errors
    /// [`PhysicsError::TouchThreshold`] for a negative or non-finite threshold (the one in
    /// force is kept).
    pub fn set_touch_threshold_n(&mut self, threshold_n: f64) -> Result<(), PhysicsError> {
        if !(threshold_n.is_finite() && threshold_n >= 0.0) {
            return Err(PhysicsError::TouchThreshold { threshold_n });
        }
        self.touch_threshold_n = threshold_n;
        Ok(())
    }

    /// The force a contact needs to close its touch switch, newtons.
    pub fn touch_threshold_n(&self) -> f64 {
        self.touch_threshold_n
    }

    /// The posture with the base at `base_x_m` along the track and the base link at
    /// `base_angle_rad`: one quasi-static step from the last one.
    ///
    /// # Errors
    /// [`PhysicsError::Model`] when the step or the turn finds no equilibrium.
    pub fn update(&mut self, base_x_m: f64, base_angle_rad: f64) -> Result<SimState, PhysicsError> {
        if base_angle_rad != self.sim.chain().base_angle_rad() {
            self.turn_base(base_angle_rad)?;
        }
        let report = self
            .sim
            .step_to(Vector2::new(base_x_m, 0.0))
            .map_err(model(format!(
                "the antenna with the stage at {:.1} mm",
                base_x_m * 1e3
            )))?;
        if report.relaxed() {
            self.relaxed_steps += 1;
        }
        let contacts = self.sim.contacts();
        let threshold_n = self.touch_threshold_n;
        self.contacts.clear();
        self.contacts.extend(
            contacts
                .iter()
                .filter(|c| closes_switch(c, threshold_n))
                .map(|c| c.chain_contact()),
        );
        touch_bits_from_contacts(&self.contacts, &mut self.touch_bits)
            .map_err(model("touch bits"))?;
        let n = self.sim.chain().n();
        Ok(SimState {
            joint_angles_rad: self.sim.theta_rad()[1..].to_vec(),
            touch: self.touch_bits[1..]
                .iter()
                .map(|&b| TouchBits::from_bits_truncate(b))
                .collect(),
            tip_force_n: contacts
                .iter()
                .filter(|c| c.feature.link() == n)
                .map(|c| c.normal_force_n)
                .sum(),
            relaxed_steps: self.relaxed_steps,
            relaxations: report.relaxations(),
        })
    }

    /// Turns the base link to `base_angle_rad` keeping the joint angles: the solver is
    /// rebuilt there, its base first backed off along the wall's normal by as much as the
    /// turn would put the antenna into the wall (the next step brings it back on).
    fn turn_base(&mut self, base_angle_rad: f64) -> Result<(), PhysicsError> {
        let chain = self
            .sim
            .chain()
            .with_base_angle_rad(base_angle_rad)
            .map_err(model("base angle"))?;
        let mut theta = self.sim.theta_rad().to_vec();
        theta[0] = base_angle_rad;
        let base = self.sim.base_m();
        let walls = self.sim.walls().to_vec();
        let poses = sim_core::frame_poses(&chain, &theta, sim_core::Frame::GROUND)
            .map_err(model("poses after the turn"))?;
        let mut back_m = Vector2::zeros();
        for wall in &walls {
            for link in 0..=chain.n() {
                let p = base
                    + poses
                        .position_m(sim_core::Frame::link(link))
                        .unwrap_or_default();
                let d = wall.signed_distance(&p);
                let inside_m = -d.gap_m + TURN_CLEARANCE_M;
                if inside_m > 0.0 && inside_m * d.normal.norm() > back_m.norm() {
                    back_m = d.normal * inside_m;
                }
            }
        }
        self.sim = QuasiStatic::new(chain, walls, base + back_m, &theta, *self.sim.settings())
            .map_err(model("the antenna turned on its base"))?;
        Ok(())
    }
}

/// The flat wall as a sim-core wall: a line through `(0, distance_m)` at `-angle_deg` to the
/// track (it comes closer as the stage moves forward), solid beyond it, smooth with `mu`.
fn wall_of(wall: &FlatWallSpec) -> Result<Wall, PhysicsError> {
    let line = Line::new(
        Vector2::new(0.0, wall.distance_m),
        -wall.angle_deg.to_radians(),
        SolidSide::Left,
    )
    .map_err(model("sim.wall"))?;
    let surface =
        SurfaceMap::uniform(Surface::Smooth { mu: wall.mu }).map_err(model("sim.wall.mu"))?;
    Ok(Wall::new(line, surface))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_antenna_bends_only_once_it_reaches_the_wall() {
        let antenna = AntennaSpec::default();
        let mut physics = SimPhysics::new(&antenna, &FlatWallSpec::default()).unwrap();
        let base = antenna.base_angle_deg.to_radians();
        let free = physics.update(0.0, base).unwrap();
        assert_eq!(free.tip_force_n, 0.0);
        assert!(free.joint_angles_rad.iter().all(|a| a.abs() < 1e-9));
        let pressed = physics.update(0.15, base).unwrap();
        assert!(pressed.tip_force_n > 0.0);
        assert!(pressed.joint_angles_rad.iter().all(|a| a.abs() > 0.01));
        assert!(pressed.joint_angles_rad.iter().sum::<f64>().abs() > 0.2);
        assert!(pressed.touch[8].any());
        let back = physics.update(0.0, base).unwrap();
        assert!(back.joint_angles_rad.iter().all(|a| a.abs() < 1e-6));
    }

    /// The touch threshold (issue #18): only contacts pressing at least that hard close a
    /// switch; the physics itself is the same, and threshold 0 is every contact.
    #[test]
    fn a_touch_threshold_suppresses_light_contacts() {
        let antenna = AntennaSpec::default();
        let base = antenna.base_angle_deg.to_radians();
        let sweep: Vec<f64> = (0..=40).map(|k| f64::from(k) * 0.005).collect();
        // Every contact's force over the sweep, with threshold 0 (the default).
        let mut any = SimPhysics::new(&antenna, &FlatWallSpec::default()).unwrap();
        let mut explicit = SimPhysics::new(&antenna, &FlatWallSpec::default()).unwrap();
        explicit.set_touch_threshold_n(0.0).unwrap();
        let mut forces_n = Vec::new();
        let mut states = Vec::new();
        for &x in &sweep {
            let state = any.update(x, base).unwrap();
            assert_eq!(explicit.update(x, base).unwrap(), state);
            forces_n.extend(any.sim.contacts().iter().map(|c| c.force_n().norm()));
            states.push(state);
        }
        forces_n.sort_by(f64::total_cmp);
        assert!(forces_n.len() > 10, "{forces_n:?}");
        let threshold_n = forces_n[forces_n.len() / 2];
        assert!(forces_n[0] < threshold_n, "{forces_n:?}");

        let mut firm = SimPhysics::new(&antenna, &FlatWallSpec::default()).unwrap();
        firm.set_touch_threshold_n(threshold_n).unwrap();
        assert_eq!(firm.touch_threshold_n(), threshold_n);
        let (mut suppressed, mut kept) = (0, 0);
        for (&x, any_state) in sweep.iter().zip(&states) {
            let state = firm.update(x, base).unwrap();
            assert_eq!(state.joint_angles_rad, any_state.joint_angles_rad);
            let mut expected = vec![0u8; antenna.links + 1];
            let pressing: Vec<ChainContact> = firm
                .sim
                .contacts()
                .iter()
                .filter(|c| c.force_n().norm() >= threshold_n)
                .map(|c| c.chain_contact())
                .collect();
            touch_bits_from_contacts(&pressing, &mut expected).unwrap();
            for (k, (bits, any_bits)) in state.touch.iter().zip(&any_state.touch).enumerate() {
                assert_eq!(bits.bits(), expected[k + 1]);
                // A switch the threshold opens was closed without it, never the other way.
                assert_eq!(bits.bits() & !any_bits.bits(), 0);
                suppressed += (any_bits.bits() & !bits.bits()).count_ones();
                kept += bits.bits().count_ones();
            }
        }
        assert!(suppressed > 0 && kept > 0, "{suppressed} {kept}");
        assert!(matches!(
            firm.set_touch_threshold_n(-0.1),
            Err(PhysicsError::TouchThreshold { .. })
        ));
        assert!(firm.set_touch_threshold_n(f64::NAN).is_err());
        assert_eq!(firm.touch_threshold_n(), threshold_n);
    }

    #[test]
    fn an_unknown_profile_is_named() {
        let antenna = AntennaSpec {
            stiffness_profile: "wobbly".to_owned(),
            ..AntennaSpec::default()
        };
        let error = SimPhysics::new(&antenna, &FlatWallSpec::default()).unwrap_err();
        assert_eq!(error.to_string(), "unknown stiffness profile \"wobbly\"");
    }
}
