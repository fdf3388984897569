//! Quasi-static sweeps (thesis 3.3, 4.2): the base moves at a set velocity for a set time in
//! fixed steps; every step is a [`QuasiStatic`] step with its contacts, friction and hairs,
//! and the wall-following metrics of docs/model.md 8.
//!
//! A sweep starts from a [`Placement`]: the rest posture as it is, an approach (the base
//! starts away from a wall and moves onto it, which leaves the antenna projecting forward),
//! the tip placed on a wall with the distal part bent back (the thesis 4.2.1 start: a pinned
//! equilibrium, released), or explicit angles. What was done is in [`Sweep::placement_note`].
//!
//! # Example
//! ```
//! use nalgebra::Vector2;
//! use sim_core::sweep::{Motion, Placement, Sweep, SweepScene};
//! use sim_core::{Chain, InitialGuess, Line, SolidSide, Wall};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let chain = Chain::builder(8)
//!     .link_length_m(0.04)
//!     .base_angle_rad(30f64.to_radians())
//!     .stiffness_nm_per_rad(0.01)
//!     .build()?;
//! // The thesis's 4.2.1 wall: 8 degrees to the track, 0.2 m from the base, smooth (mu = 0.3).
//! let wall = Wall::smooth(Line::new(Vector2::new(0.0, 0.2), -8f64.to_radians(), SolidSide::Left)?);
//! let scene = SweepScene {
//!     placement: Placement::TipOnWall { wall: 0, ahead_m: 0.05, start: InitialGuess::C },
//!     motion: Motion { velocity_m_per_s: Vector2::new(0.0167, 0.0), duration_s: 1.0, step_s: 0.01 },
//!     ..SweepScene::new(chain, vec![wall])
//! };
//! let mut sweep = Sweep::new(scene)?;
//! println!("{}", sweep.placement_note());
//! let mut last = None;
//! while let Some(step) = sweep.next_step() {
//!     last = Some(step?);
//! }
//! let last = last.expect("100 steps");
//! assert!((last.t_s - 1.0).abs() < 1e-9);
//! assert!(!last.contacts.is_empty());
//! # Ok(())
//! # }
//! ```

mod driven;
mod placement;

use nalgebra::Vector2;

use crate::contact::{Contact, ContactError, ContactSettings, QuasiStatic, StepReport};
use crate::sensing::metrics::{
    FlipState, flip_state, point_of_bend, point_of_contact, preview_distance_m,
};
use crate::{Chain, ChainContact, EquilibriumError, InitialGuess, touch_bits_from_contacts};
use crate::{MappingError, Wall};

pub use driven::{BasePose, TURN_CLEARANCE_M, place_at, step_base_to, turn_base};
pub use placement::Placement;

/// How the base moves: a constant velocity for a set time, in fixed steps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motion {
    /// Base velocity, ground frame, m/s (its direction is the direction of motion for the
    /// preview distance and the flip).
    pub velocity_m_per_s: Vector2<f64>,
    /// How long the base moves, seconds.
    pub duration_s: f64,
    /// The time step, seconds (the thesis records at 100-120 Hz: 0.01 s).
    pub step_s: f64,
}

impl Default for Motion {
    /// The thesis's 4.2.1 sweep: 16.7 mm/s along x for 50 s at 100 Hz.
    fn default() -> Self {
        Motion {
            velocity_m_per_s: Vector2::new(0.0167, 0.0),
            duration_s: 50.0,
            step_s: 0.01,
        }
    }
}

impl Motion {
    /// The number of steps: `round(duration / step)`.
    pub fn steps(&self) -> usize {
        (self.duration_s / self.step_s).round().max(0.0) as usize
    }

    /// The direction of motion, radians from the ground x-axis (0 when standing still).
    pub fn direction_rad(&self) -> f64 {
        let v = self.velocity_m_per_s;
        if v == Vector2::zeros() {
            0.0
        } else {
            v.y.atan2(v.x)
        }
    }
}

/// Everything a sweep needs.
#[derive(Clone, Debug)]
pub struct SweepScene {
    /// The antenna.
    pub chain: Chain,
    /// The walls.
    pub walls: Vec<Wall>,
    /// Where the base pivot starts (before any placement moves), ground frame, metres.
    pub base_start_m: Vector2<f64>,
    /// How the base moves.
    pub motion: Motion,
    /// How the antenna is put against the walls before the sweep.
    pub placement: Placement,
    /// A dead load at the tip, newtons (usually none).
    pub tip_force_n: Vector2<f64>,
    /// Solver options.
    pub settings: ContactSettings,
}

impl SweepScene {
    /// A scene with the base at the origin, [`Motion::default`], the rest posture as is, no
    /// load and default settings.
    pub fn new(chain: Chain, walls: Vec<Wall>) -> SweepScene {
        SweepScene {
            chain,
            walls,
            base_start_m: Vector2::zeros(),
            motion: Motion::default(),
            placement: Placement::Rest,
            tip_force_n: Vector2::zeros(),
            settings: ContactSettings::default(),
        }
    }
}

/// Why a sweep could not start or go on.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SweepError {
    /// The motion is not usable.
    #[error("motion: `{field}` = {value} is out of range: {expected}")]
    BadMotion {
        /// The field.
        field: &'static str,
        /// The value given.
        value: f64,
        /// What is allowed.
        expected: &'static str,
    },
    /// The placement could not be done.
    #[error("placement: {0}")]
    Placement(String),
    /// The pinned equilibrium of a placement failed.
    #[error("placement: {0}")]
    PlacementSolve(#[from] EquilibriumError),
    /// A step failed.
    #[error("step {step} (t = {t_s:.3} s): {source}")]
    Step {
        /// The step number (1-based; 0 for the placement).
        step: usize,
        /// Its time, seconds.
        t_s: f64,
        /// What went wrong.
        source: ContactError,
    },
    /// The contact problem could not be set up.
    #[error(transparent)]
    Contact(#[from] ContactError),
    /// Touch bits could not be derived.
    #[error(transparent)]
    Mapping(#[from] MappingError),
}

/// The state after one step of a sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepStep {
    /// The step number: 0 is the placed posture, then `1..=steps`.
    pub step: usize,
    /// Time since the sweep started, seconds.
    pub t_s: f64,
    /// The base pivot, ground frame, metres.
    pub base_m: Vector2<f64>,
    /// Joint angles `theta_0..theta_n`, radians.
    pub theta_rad: Vec<f64>,
    /// Hair angles per link (`0` where there is no hair), radians.
    pub hair_angles_rad: Vec<f64>,
    /// The contacts.
    pub contacts: Vec<Contact>,
    /// The point of bend: the joint with the greatest `|theta_j|` (docs/model.md 8).
    pub bend_joint: Option<usize>,
    /// The point of contact: the most proximal contact's nearest point number (joint `j`,
    /// or `n + 1` for the tip).
    pub contact_joint: Option<usize>,
    /// The preview distance, metres (docs/model.md 8); `None` without contacts.
    pub preview_m: Option<f64>,
    /// The distal segment against the nearest wall (docs/model.md 7): its angle and whether it
    /// has flipped (beyond 90 degrees). `None` without walls.
    pub flip: Option<FlipState>,
    /// The touch bits per link (bit `k`: switch `k`, from each contact's place on its link).
    pub touch_bits: Vec<u8>,
    /// What the solver did.
    pub report: StepReport,
}

impl SweepStep {
    /// Whether the distal segment has flipped.
    pub fn flipped(&self) -> bool {
        self.flip.is_some_and(|f| f.flipped)
    }
}

/// A sweep in progress: yields one [`SweepStep`] per step ([`Sweep::next_step`]).
#[derive(Debug)]
pub struct Sweep {
    sim: QuasiStatic,
    motion: Motion,
    base_start_m: Vector2<f64>,
    step: usize,
    steps: usize,
    note: String,
    placed: Option<SweepStep>,
    chain_contacts: Vec<ChainContact>,
}

impl Sweep {
    /// Places the antenna ([`SweepScene::placement`]) and gets ready to sweep.
    ///
    /// # Errors
    /// [`SweepError::BadMotion`], [`SweepError::Placement`] and
    /// [`SweepError::PlacementSolve`] (the placement failed, with the reason),
    /// [`SweepError::Contact`].
    pub fn new(scene: SweepScene) -> Result<Sweep, SweepError> {
        let motion = scene.motion;
        for (field, value, ok, expected) in [
            (
                "step_s",
                motion.step_s,
                motion.step_s.is_finite() && motion.step_s > 0.0,
                "finite and > 0",
            ),
            (
                "duration_s",
                motion.duration_s,
                motion.duration_s.is_finite() && motion.duration_s >= 0.0,
                "finite and >= 0",
            ),
            (
                "velocity_m_per_s.x",
                motion.velocity_m_per_s.x,
                motion.velocity_m_per_s.x.is_finite(),
                "finite",
            ),
            (
                "velocity_m_per_s.y",
                motion.velocity_m_per_s.y,
                motion.velocity_m_per_s.y.is_finite(),
                "finite",
            ),
        ] {
            if !ok {
                return Err(SweepError::BadMotion {
                    field,
                    value,
                    expected,
                });
            }
        }
        let (sim, note, report) = placement::place(&scene)?;
        let mut sweep = Sweep {
            sim,
            motion,
            base_start_m: scene.base_start_m,
            step: 0,
            steps: motion.steps(),
            note,
            placed: None,
            chain_contacts: Vec::new(),
        };
        let placed = sweep.record(0, 0.0, report)?;
        sweep.placed = Some(placed);
        Ok(sweep)
    }

    /// What the placement did, in words (for the output's header).
    pub fn placement_note(&self) -> &str {
        &self.note
    }

    /// The state after placement (step 0).
    pub fn placed(&self) -> Option<&SweepStep> {
        self.placed.as_ref()
    }

    /// The number of steps the sweep takes.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// The simulation (chain, walls, state).
    pub fn sim(&self) -> &QuasiStatic {
        &self.sim
    }

    /// Whether the current state is a strict local minimum ([`QuasiStatic::is_stable`]).
    pub fn is_stable(&mut self) -> bool {
        self.sim.is_stable()
    }

    /// The motion.
    pub fn motion(&self) -> &Motion {
        &self.motion
    }

    /// The next step, or `None` when the sweep is done.
    pub fn next_step(&mut self) -> Option<Result<SweepStep, SweepError>> {
        if self.step >= self.steps {
            return None;
        }
        self.step += 1;
        let t_s = self.step as f64 * self.motion.step_s;
        let base = self.base_start_m + self.motion.velocity_m_per_s * t_s;
        let step = self.step;
        Some(
            self.sim
                .step_to(base)
                .map_err(|source| SweepError::Step { step, t_s, source })
                .and_then(|report| self.record(step, t_s, report)),
        )
    }

    /// The metrics of the current state.
    fn record(
        &mut self,
        step: usize,
        t_s: f64,
        report: StepReport,
    ) -> Result<SweepStep, SweepError> {
        let sim = &self.sim;
        let contacts = sim.contacts();
        self.chain_contacts.clear();
        self.chain_contacts
            .extend(contacts.iter().map(Contact::chain_contact));
        let theta = sim.theta_rad().to_vec();
        let base = sim.base_m();
        let direction = self.motion.direction_rad();
        let mut touch_bits = vec![0; theta.len()];
        touch_bits_from_contacts(&self.chain_contacts, &mut touch_bits)?;
        Ok(SweepStep {
            step,
            t_s,
            base_m: base,
            bend_joint: point_of_bend(&theta),
            contact_joint: point_of_contact(&self.chain_contacts).map(|p| p.joint),
            preview_m: preview_distance_m(&self.chain_contacts, &base, direction),
            flip: distal_flip(sim, direction),
            theta_rad: theta,
            hair_angles_rad: sim.hair_angles_rad().to_vec(),
            contacts,
            touch_bits,
            report,
        })
    }
}

/// The distal segment's flip state against the wall nearest to it.
fn distal_flip(sim: &QuasiStatic, direction_rad: f64) -> Option<FlipState> {
    let chain = sim.chain();
    let n = chain.n();
    let poses = crate::frame_poses(chain, sim.theta_rad(), crate::Frame::GROUND).ok()?;
    let base = sim.base_m();
    let start = base + poses.position_m(crate::Frame::link(n.saturating_sub(1)))?;
    let tip = base + poses.position_m(crate::Frame::link(n))?;
    sim.walls()
        .iter()
        .filter_map(|w| flip_state(w, &start, &tip, direction_rad))
        .min_by(|a, b| a.contact.wall.gap_m.total_cmp(&b.contact.wall.gap_m))
}

/// The standard starts, by name, for placements ([`InitialGuess`]).
pub fn initial_guess_by_name(name: &str) -> Option<InitialGuess> {
    match name {
        "straight" => Some(InitialGuess::Straight),
        "C" => Some(InitialGuess::C),
        "S" => Some(InitialGuess::S),
        "mirror-C" => Some(InitialGuess::C.mirrored()),
        "mirror-S" => Some(InitialGuess::S.mirrored()),
        _ => None,
    }
}
