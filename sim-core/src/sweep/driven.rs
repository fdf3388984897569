//! A sweep driven from outside, one base pose at a time: what a rig does (a stage carries the
//! base, a servo turns the base link) and what a replay of a rig's recorded steps does.
//!
//! [`place_at`] puts the antenna against the walls as a scene's [`Placement`](super::Placement)
//! says, with the base at a given pose; [`step_base_to`] moves the base to the next pose: a
//! new base angle first turns the base link keeping the joint angles (the contact problem is
//! rebuilt there, its base backed off the walls by as much as the turn would put the antenna
//! into them), then the base pivot steps to its new position ([`QuasiStatic::step_to`]). One
//! implementation serves the simulated rig (`antenna-sim-physics`) and a replay of its
//! recorded poses, so a replay takes exactly the rig's path (friction makes the posture depend
//! on it).
//!
//! A turn by [`step_base_to`] starts the contacts afresh (a servo turning the base link
//! between a rig's stage steps). A base that moves and turns continuously (a mobile robot)
//! is stepped by [`QuasiStatic::step_to_pose`] instead, which turns the base within the
//! step and keeps the contacts, their friction state and the hair deflections.
//!
//! ```
//! use nalgebra::Vector2;
//! use sim_core::sweep::{BasePose, Placement, SweepScene, place_at, step_base_to};
//! use sim_core::{Chain, InitialGuess, Line, SolidSide, Wall};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let chain = Chain::builder(8)
//!     .link_length_m(0.04)
//!     .base_angle_rad(30f64.to_radians())
//!     .stiffness_nm_per_rad(0.01)
//!     .build()?;
//! let wall = Wall::smooth(Line::new(Vector2::new(0.0, 0.2), -8f64.to_radians(), SolidSide::Left)?);
//! let scene = SweepScene {
//!     placement: Placement::TipOnWall { wall: 0, ahead_m: 0.0, start: InitialGuess::C },
//!     ..SweepScene::new(chain, vec![wall])
//! };
//! let start = BasePose { base_m: Vector2::zeros(), base_angle_rad: 30f64.to_radians() };
//! let (mut sim, note, _) = place_at(&scene, &start)?;
//! assert!(note.starts_with("tip placed on wall 0"));
//! let ahead = BasePose { base_m: Vector2::new(0.01, 0.0), ..start };
//! step_base_to(&mut sim, &ahead)?;
//! assert_eq!(sim.base_m(), ahead.base_m);
//! assert!(!sim.contacts().is_empty());
//! # Ok(())
//! # }
//! ```

use nalgebra::Vector2;

use super::{SweepError, SweepScene};
use crate::contact::{ContactError, QuasiStatic, StepReport};
use crate::{Frame, frame_poses};

/// How far off the walls a turned antenna is put before it steps back, metres.
pub const TURN_CLEARANCE_M: f64 = 1e-3;

/// Where the base is: the base pivot in the ground frame and the base link's angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BasePose {
    /// The base pivot, ground frame, metres.
    pub base_m: Vector2<f64>,
    /// The base link's angle from the ground x-axis, radians.
    pub base_angle_rad: f64,
}

/// The scene's placement ([`SweepScene::placement`]) done with the base at `pose` instead of
/// the scene's start (its base pivot at `pose.base_m`, its base link at
/// `pose.base_angle_rad`); returns the simulation, what was done in words and the settling's
/// report.
///
/// # Errors
/// As [`super::Sweep::new`]'s placement: [`SweepError::Placement`],
/// [`SweepError::PlacementSolve`], [`SweepError::Contact`], [`SweepError::Step`]; a base
/// angle that is not finite is [`SweepError::Contact`] ([`ContactError::NotFinite`]).
pub fn place_at(
    scene: &SweepScene,
    pose: &BasePose,
) -> Result<(QuasiStatic, String, StepReport), SweepError> {
    let chain = scene
        .chain
        .with_base_angle_rad(pose.base_angle_rad)
        .map_err(|_| not_finite(pose.base_angle_rad))?;
    let at = SweepScene {
        chain,
        base_start_m: pose.base_m,
        ..scene.clone()
    };
    super::placement::place(&at)
}

/// Moves the base of `sim` to `pose`: turns the base link first if its angle changed
/// ([`turn_base`]), then steps the base pivot there ([`QuasiStatic::step_to`]).
///
/// # Errors
/// As [`turn_base`] and [`QuasiStatic::step_to`].
pub fn step_base_to(sim: &mut QuasiStatic, pose: &BasePose) -> Result<StepReport, ContactError> {
    if pose.base_angle_rad != sim.chain().base_angle_rad() {
        turn_base(sim, pose.base_angle_rad)?;
    }
    sim.step_to(pose.base_m)
}

/// Turns the base link of `sim` to `base_angle_rad` keeping the joint angles: the contact
/// problem is rebuilt there (its contacts and hair deflections start afresh, the tip load
/// and settings are kept), its base first backed off along a wall's normal by as much as
/// the turn would put the antenna into that wall plus [`TURN_CLEARANCE_M`] (the next step
/// brings it back on).
///
/// # Errors
/// [`ContactError::NotFinite`] for an angle that is not finite; as [`QuasiStatic::new`]
/// when the turned antenna cannot be set up.
pub fn turn_base(sim: &mut QuasiStatic, base_angle_rad: f64) -> Result<(), ContactError> {
    let chain = sim
        .chain()
        .with_base_angle_rad(base_angle_rad)
        .map_err(|_| not_finite_contact(base_angle_rad))?;
    let mut theta = sim.theta_rad().to_vec();
    theta[0] = base_angle_rad;
    let base = sim.base_m();
    let walls = sim.walls().to_vec();
    let poses = frame_poses(&chain, &theta, Frame::GROUND)
        .map_err(|_| not_finite_contact(base_angle_rad))?;
    let mut back_m = Vector2::zeros();
    for wall in &walls {
        for link in 0..=chain.n() {
            let p = base + poses.position_m(Frame::link(link)).unwrap_or_default();
            let d = wall.signed_distance(&p);
            let inside_m = -d.gap_m + TURN_CLEARANCE_M;
            if inside_m > 0.0 && inside_m * d.normal.norm() > back_m.norm() {
                back_m = d.normal * inside_m;
            }
        }
    }
    let tip_force_n = sim.tip_force_n();
    let mut turned = QuasiStatic::new(chain, walls, base + back_m, &theta, *sim.settings())?;
    turned.set_tip_force_n(tip_force_n);
    *sim = turned;
    Ok(())
}

fn not_finite_contact(value: f64) -> ContactError {
    ContactError::NotFinite {
        argument: "base_angle_rad",
        index: 0,
        value,
    }
}

fn not_finite(value: f64) -> SweepError {
    SweepError::Contact(not_finite_contact(value))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sweep::{Placement, Sweep};
    use crate::{Chain, InitialGuess, Line, SolidSide, Wall};

    fn scene() -> SweepScene {
        let chain = Chain::builder(8)
            .link_length_m(0.04)
            .base_angle_rad(30f64.to_radians())
            .stiffness_nm_per_rad(0.01)
            .build()
            .unwrap();
        let wall = Wall::smooth(
            Line::new(Vector2::new(0.0, 0.2), -8f64.to_radians(), SolidSide::Left).unwrap(),
        );
        SweepScene {
            placement: Placement::TipOnWall {
                wall: 0,
                ahead_m: 0.0,
                start: InitialGuess::C,
            },
            ..SweepScene::new(chain, vec![wall])
        }
    }

    /// Placed at the scene's own start and stepped along its motion, the driven sweep is the
    /// sweep, bit for bit.
    #[test]
    fn driven_along_the_motion_it_is_the_sweep() {
        let scene = SweepScene {
            motion: crate::sweep::Motion {
                duration_s: 0.2,
                ..crate::sweep::Motion::default()
            },
            ..scene()
        };
        let mut sweep = Sweep::new(scene.clone()).unwrap();
        let start = BasePose {
            base_m: scene.base_start_m,
            base_angle_rad: scene.chain.base_angle_rad(),
        };
        let (mut sim, _, _) = place_at(&scene, &start).unwrap();
        assert_eq!(
            sim.theta_rad(),
            sweep.placed().unwrap().theta_rad.as_slice()
        );
        while let Some(step) = sweep.next_step() {
            let step = step.unwrap();
            step_base_to(
                &mut sim,
                &BasePose {
                    base_m: step.base_m,
                    ..start
                },
            )
            .unwrap();
            assert_eq!(sim.theta_rad(), step.theta_rad.as_slice());
        }
    }

    #[test]
    fn a_turn_keeps_the_joint_angles_and_backs_off_the_wall() {
        let scene = scene();
        let start = BasePose {
            base_m: Vector2::zeros(),
            base_angle_rad: scene.chain.base_angle_rad(),
        };
        let (mut sim, _, _) = place_at(&scene, &start).unwrap();
        let joints = sim.theta_rad()[1..].to_vec();
        turn_base(&mut sim, 40f64.to_radians()).unwrap();
        assert_eq!(&sim.theta_rad()[1..], joints.as_slice());
        assert_eq!(sim.chain().base_angle_rad(), 40f64.to_radians());
        // Turned toward the wall, the antenna was backed off it.
        assert!(sim.base_m().norm() > 0.0);
        step_base_to(
            &mut sim,
            &BasePose {
                base_m: Vector2::zeros(),
                base_angle_rad: 40f64.to_radians(),
            },
        )
        .unwrap();
        assert_eq!(sim.base_m(), Vector2::zeros());
        assert!(turn_base(&mut sim, f64::NAN).is_err());
    }
}
