//! [`SimPhysics`]: the posture of a scene's antenna against its walls for a stage position
//! and a servo angle.

use antenna_protocol::TouchBits;
use nalgebra::Vector2;
use sim_core::contact::{QuasiStatic, StepReport};
use sim_core::sweep::{BasePose, SweepScene, place_at, step_base_to};
use sim_core::{ChainContact, closes_switch, touch_bits_from_contacts};

/// Why the physics could not be built or stepped.
#[derive(Debug, thiserror::Error)]
pub enum PhysicsError {
    /// sim-core refused the scene, its placement failed, or a step found no equilibrium.
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
    /// The walls' force on the tip, newtons (0 out of contact).
    pub tip_force_n: f64,
    /// Steps so far in which the contact solver relaxed something to get through (friction
    /// dropped, a residual accepted above the tolerance): every step is certified by
    /// sim-core's independent check, and these are said.
    pub relaxed_steps: u64,
    /// What the last step relaxed, in words (empty when nothing).
    pub relaxations: Vec<String>,
    /// The stage position and base pose the physics was solved at for this state (the
    /// truth a live wall estimate is checked against); `None` only in a default state.
    pub solved_at: Option<(f64, BasePose)>,
}

/// What a recorded physics step was.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepKind {
    /// The scene's placement, done afresh with the base at the step's pose
    /// ([`sim_core::sweep::place_at`]).
    Place,
    /// One step from the previous posture to the step's pose
    /// ([`sim_core::sweep::step_base_to`]).
    Step,
}

/// One placement or step of the physics, as [`SimPhysics::record_steps`] keeps it.
#[derive(Debug, Clone, PartialEq)]
pub struct PhysicsStep {
    /// A placement or a step.
    pub kind: StepKind,
    /// The stage position it was for, metres.
    pub stage_m: f64,
    /// The base pose it was for (from the stage position and the servo angle).
    pub pose: BasePose,
    /// The joint angles `theta_1..theta_n` it gave, radians.
    pub joint_angles_rad: Vec<f64>,
}

/// A scene's antenna against its walls, carried by the stage and turned by the servo (see
/// the crate documentation).
#[derive(Debug)]
pub struct SimPhysics {
    scene: SweepScene,
    /// The unit direction of motion.
    direction: Vector2<f64>,
    sim: QuasiStatic,
    state: SimState,
    note: String,
    contacts: Vec<ChainContact>,
    touch_bits: Vec<u8>,
    touch_threshold_n: f64,
    relaxed_steps: u64,
    recording: bool,
    steps: Vec<PhysicsStep>,
}

impl SimPhysics {
    /// The physics of `scene`, placed as the scene says with the stage and the servo at 0.
    ///
    /// # Errors
    /// [`PhysicsError::Model`] naming what sim-core refused (the placement, a wall through
    /// the base link).
    pub fn new(scene: SweepScene) -> Result<Self, PhysicsError> {
        let v = scene.motion.velocity_m_per_s;
        let direction = if v == Vector2::zeros() || !v.iter().all(|c| c.is_finite()) {
            Vector2::new(1.0, 0.0)
        } else {
            v.normalize()
        };
        let start = BasePose {
            base_m: scene.base_start_m,
            base_angle_rad: scene.chain.base_angle_rad(),
        };
        let (sim, note, report) =
            place_at(&scene, &start).map_err(model("the scene's placement with the stage at 0"))?;
        let n = sim.chain().n();
        let mut physics = Self {
            scene,
            direction,
            sim,
            state: SimState::default(),
            note,
            contacts: Vec::new(),
            touch_bits: vec![0; n + 1],
            touch_threshold_n: 0.0,
            relaxed_steps: 0,
            recording: false,
            steps: Vec::new(),
        };
        physics.state = physics.sense(&report)?;
        physics.state.solved_at = Some((0.0, start));
        Ok(physics)
    }

    /// The scene the physics was built from.
    pub fn scene(&self) -> &SweepScene {
        &self.scene
    }

    /// The simulation as it stands (chain, walls, posture, contacts).
    pub fn sim(&self) -> &QuasiStatic {
        &self.sim
    }

    /// The unit direction of motion the stage carries the base along.
    pub fn direction(&self) -> Vector2<f64> {
        self.direction
    }

    /// What the last placement did, in words.
    pub fn placement_note(&self) -> &str {
        &self.note
    }

    /// The state after the last placement or step.
    pub fn state(&self) -> &SimState {
        &self.state
    }

    /// The base pose for the stage at `stage_m` and the servo at `servo_rad`: the pivot at
    /// `base_start_m + stage_m * direction`, the base link at the scene's base angle plus
    /// `servo_rad`.
    pub fn base_pose(&self, stage_m: f64, servo_rad: f64) -> BasePose {
        BasePose {
            base_m: self.scene.base_start_m + self.direction * stage_m,
            base_angle_rad: self.scene.chain.base_angle_rad() + servo_rad,
        }
    }

    /// Keeps (or stops keeping) every placement and step from now on
    /// ([`Self::take_steps`]).
    pub fn record_steps(&mut self, on: bool) {
        self.recording = on;
        if !on {
            self.steps.clear();
        }
    }

    /// The placements and steps kept since the last call, oldest first.
    pub fn take_steps(&mut self) -> Vec<PhysicsStep> {
        std::mem::take(&mut self.steps)
    }

    /// Sets the force a contact needs to close the touch switch under it, newtons (`0`, the
    /// default: every contact closes its switch). A contact closes it when the magnitude of
    /// the wall's force on the chain there is at least this. The state of the last step is
    /// sensed again with it.
    ///
    /// # Errors
    /// [`PhysicsError::TouchThreshold`] for a negative or non-finite threshold (the one in
    /// force is kept).
    pub fn set_touch_threshold_n(&mut self, threshold_n: f64) -> Result<(), PhysicsError> {
        if !(threshold_n.is_finite() && threshold_n >= 0.0) {
            return Err(PhysicsError::TouchThreshold { threshold_n });
        }
        self.touch_threshold_n = threshold_n;
        let relaxations = std::mem::take(&mut self.state.relaxations);
        let mut state = self.sense(&StepReport::default())?;
        state.relaxations = relaxations;
        self.state = state;
        Ok(())
    }

    /// The force a contact needs to close its touch switch, newtons.
    pub fn touch_threshold_n(&self) -> f64 {
        self.touch_threshold_n
    }

    /// The scene's placement done afresh with the stage at `stage_m` and the servo at
    /// `servo_rad` (a trial starting on the simulated rig).
    ///
    /// # Errors
    /// [`PhysicsError::Model`] when the placement fails there (the physics is then as it
    /// was).
    pub fn place(&mut self, stage_m: f64, servo_rad: f64) -> Result<SimState, PhysicsError> {
        let pose = self.base_pose(stage_m, servo_rad);
        let (sim, note, report) = place_at(&self.scene, &pose).map_err(model(format!(
            "the scene's placement with the stage at {:.1} mm",
            stage_m * 1e3
        )))?;
        self.sim = sim;
        self.note = note;
        self.finish(StepKind::Place, stage_m, pose, &report)
    }

    /// The posture with the stage at `stage_m` and the servo at `servo_rad`: one
    /// quasi-static step from the last one (the base link turned first if the servo moved).
    ///
    /// # Errors
    /// [`PhysicsError::Model`] when the step or the turn finds no equilibrium.
    pub fn update(&mut self, stage_m: f64, servo_rad: f64) -> Result<SimState, PhysicsError> {
        let pose = self.base_pose(stage_m, servo_rad);
        let report = step_base_to(&mut self.sim, &pose).map_err(model(format!(
            "the antenna with the stage at {:.1} mm",
            stage_m * 1e3
        )))?;
        self.finish(StepKind::Step, stage_m, pose, &report)
    }

    fn finish(
        &mut self,
        kind: StepKind,
        stage_m: f64,
        pose: BasePose,
        report: &StepReport,
    ) -> Result<SimState, PhysicsError> {
        if report.relaxed() {
            self.relaxed_steps += 1;
        }
        self.state = self.sense(report)?;
        self.state.solved_at = Some((stage_m, pose));
        if self.recording {
            self.steps.push(PhysicsStep {
                kind,
                stage_m,
                pose,
                joint_angles_rad: self.state.joint_angles_rad.clone(),
            });
        }
        Ok(self.state.clone())
    }

    /// What the segments sense of the current posture.
    fn sense(&mut self, report: &StepReport) -> Result<SimState, PhysicsError> {
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
            solved_at: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim_core::sweep::{Motion, Placement};
    use sim_core::{
        Chain, InitialGuess, Line, SolidSide, StiffnessProfile, Surface, SurfaceMap, Wall,
    };

    /// The thesis's 4.2.1 rig: nine 40 mm links at 30 degrees, fast-exponential from 0.004 to
    /// 0.082 N m/rad, the 8-degree wall 0.2 m above the base with `mu`, tip placed on it.
    fn scene(mu: f64) -> SweepScene {
        let lengths = vec![0.04; 9];
        let k = StiffnessProfile::FastExponential
            .stiffness_n_m_per_rad(&lengths, 0.004, 0.082)
            .unwrap();
        let chain = Chain::builder(8)
            .link_length_m(0.04)
            .base_angle_rad(30f64.to_radians())
            .stiffnesses_nm_per_rad(k)
            .build()
            .unwrap();
        let line = Line::new(Vector2::new(0.0, 0.2), -8f64.to_radians(), SolidSide::Left).unwrap();
        let wall = Wall::new(line, SurfaceMap::uniform(Surface::Smooth { mu }).unwrap());
        SweepScene {
            placement: Placement::TipOnWall {
                wall: 0,
                ahead_m: 0.0,
                start: InitialGuess::C,
            },
            motion: Motion::default(),
            ..SweepScene::new(chain, vec![wall])
        }
    }

    #[test]
    fn the_stage_carries_the_base_along_the_motion_and_the_servo_turns_it() {
        // No wall: the antenna at rest is carried along.
        let mut scene = scene(0.3);
        scene.walls.clear();
        scene.placement = Placement::Rest;
        scene.base_start_m = Vector2::new(0.01, -0.02);
        scene.motion.velocity_m_per_s = Vector2::new(3.0, 4.0);
        let mut physics = SimPhysics::new(scene).unwrap();
        let pose = physics.base_pose(0.5, 0.1);
        assert!((pose.base_m - Vector2::new(0.31, 0.38)).norm() < 1e-15);
        assert_eq!(pose.base_angle_rad, 30f64.to_radians() + 0.1);
        physics.record_steps(true);
        physics.update(0.001, 0.0).unwrap();
        physics.update(0.001, 0.02).unwrap();
        physics.place(0.002, 0.0).unwrap();
        let steps = physics.take_steps();
        let kinds: Vec<StepKind> = steps.iter().map(|s| s.kind).collect();
        assert_eq!(kinds, [StepKind::Step, StepKind::Step, StepKind::Place]);
        assert_eq!(steps[1].pose.base_angle_rad, 30f64.to_radians() + 0.02);
        assert_eq!(steps[2].stage_m, 0.002);
        assert!(physics.take_steps().is_empty());
    }

    #[test]
    fn the_antenna_bends_along_the_wall_as_the_stage_moves() {
        let mut physics = SimPhysics::new(scene(0.3)).unwrap();
        let placed = physics.state().clone();
        assert!(placed.tip_force_n > 0.0);
        assert!(placed.touch[7].any());
        let mut last = placed.clone();
        for k in 1..=100 {
            last = physics.update(f64::from(k) * 2e-3, 0.0).unwrap();
        }
        let max_bend = last
            .joint_angles_rad
            .iter()
            .fold(0f64, |m, a| m.max(a.abs()));
        assert!(max_bend.to_degrees() > 10.0, "{last:?}");
        // Placed again where it is, the antenna is put back as the scene says.
        let again = physics.place(0.0, 0.0).unwrap();
        assert_eq!(again.joint_angles_rad, placed.joint_angles_rad);
    }

    /// The touch threshold (issue #18): only contacts pressing at least that hard close a
    /// switch; the physics itself is the same, and threshold 0 is every contact.
    #[test]
    fn a_touch_threshold_suppresses_light_contacts() {
        let sweep: Vec<f64> = (0..=40).map(|k| f64::from(k) * 0.005).collect();
        // Every contact's force over the sweep, with threshold 0 (the default).
        let mut any = SimPhysics::new(scene(0.3)).unwrap();
        let mut explicit = SimPhysics::new(scene(0.3)).unwrap();
        explicit.set_touch_threshold_n(0.0).unwrap();
        let mut forces_n = Vec::new();
        let mut states = Vec::new();
        for &x in &sweep {
            let state = any.update(x, 0.0).unwrap();
            assert_eq!(explicit.update(x, 0.0).unwrap(), state);
            forces_n.extend(any.sim.contacts().iter().map(|c| c.force_n().norm()));
            states.push(state);
        }
        forces_n.sort_by(f64::total_cmp);
        assert!(forces_n.len() > 10, "{forces_n:?}");
        let threshold_n = forces_n[forces_n.len() / 2];
        assert!(forces_n[0] < threshold_n, "{forces_n:?}");

        let mut firm = SimPhysics::new(scene(0.3)).unwrap();
        firm.set_touch_threshold_n(threshold_n).unwrap();
        assert_eq!(firm.touch_threshold_n(), threshold_n);
        let (mut suppressed, mut kept) = (0, 0);
        for (&x, any_state) in sweep.iter().zip(&states) {
            let state = firm.update(x, 0.0).unwrap();
            assert_eq!(state.joint_angles_rad, any_state.joint_angles_rad);
            let mut expected = vec![0u8; 9];
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

    /// Friction makes the path matter: the same stage travel on a frictionless wall and on
    /// a wall with mu = 1 bends the antenna differently.
    #[test]
    fn the_wall_friction_is_the_scene_s() {
        let run = |mu: f64| {
            let mut physics = SimPhysics::new(scene(mu)).unwrap();
            let mut last = physics.state().clone();
            for k in 1..=50 {
                last = physics.update(f64::from(k) * 2e-3, 0.0).unwrap();
            }
            last.joint_angles_rad
        };
        let (slippery, rough) = (run(0.0), run(1.0));
        let difference = slippery
            .iter()
            .zip(&rough)
            .fold(0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(difference.to_degrees() > 1.0, "{slippery:?} {rough:?}");
    }

    #[test]
    fn a_placement_that_cannot_be_done_is_named() {
        let mut scene = scene(0.3);
        scene.placement = Placement::TipOnWall {
            wall: 3,
            ahead_m: 0.0,
            start: InitialGuess::C,
        };
        let error = SimPhysics::new(scene).unwrap_err().to_string();
        assert!(
            error.starts_with("the scene's placement with the stage at 0: placement: wall 3"),
            "{error}"
        );
    }
}
