//! The simulated rig, used when no hardware is configured: a virtual I2C bus ([`SimBus`])
//! whose segments run `firmware-segment`'s own logic, and one simulated world ([`SimWorld`]):
//! the scene of `[sim] scene` ([`crate::config::scene`], the mapping from a scene to the rig)
//! as the stage (simulated, [`crate::sim::devices::SimStage`], or real) carries its base along
//! the scene's direction of motion and the servo turns its base link.
//!
//! # Contact
//! The physics is `antenna-sim-physics`' [`SimPhysics`] (shared with `antenna-monitor`'s
//! prediction): sim-core's quasi-static contact solver on the scene's chain (hairs included)
//! and walls (any shape, their zones and friction), every link and joint kept out of the
//! walls, Coulomb friction that sticks and slips, snaps followed downhill, a segment's touch
//! switches closing where its link touches a wall. The scene's `[start]` placement is done
//! when a trial starts, after homing ([`SimWorld::place`]). Every placement and step is kept
//! ([`SimWorld::take_steps`]) and recorded in the trial, so that a trial can be replayed
//! through sim-core's stepper.
//!
//! # Sensors
//! The segments' sensors are the scene's `[sensors]` (ideal when it has none): each segment's
//! Hall sensor then has its joint's calibration offset and gain error and seeded noise on
//! each of its ten-bit conversions, which the firmware's own oversampling turns into the
//! twelve-bit reading ([`sim_bus`]), and a touch switch closes only for a contact pressing at
//! least `touch_threshold_n` ([`sim_physics`]). The touch debounce is the firmware's own, and
//! the sensors are sampled once per poll (`bus.poll_hz`).

use crate::config::{Config, SimFaultKind};
use crate::sim::bus::{SegmentFault, SimBus, SimSegment};
use antenna_bus::{HallErrors, HallSensor};
pub use antenna_sim_physics::{PhysicsStep, SimPhysics, SimState, StepKind};
use anyhow::{Context, Result};
use sim_core::Sensors;
use sim_core::sweep::BasePose;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// The physics of `config`'s scene (`[sim] scene`), placed with the stage and the servo at 0,
/// its touch switches closed by contacts of at least the scene's `[sensors]
/// touch_threshold_n`.
///
/// # Errors
/// When the scene's placement fails with the stage at 0.
pub fn sim_physics(config: &Config) -> Result<SimPhysics> {
    let rig = &config.sim.rig;
    let scene = rig
        .sweep_scene()
        .with_context(|| format!("the scene {}", rig.source))?;
    let mut physics =
        SimPhysics::new(scene).with_context(|| format!("the scene {}", rig.source))?;
    physics
        .set_touch_threshold_n(config.sensor_settings().touch_threshold_n)
        .with_context(|| format!("the scene {}: [sensors] touch_threshold_n", rig.source))?;
    Ok(physics)
}

/// The virtual bus of `config.bus`: one simulated segment per configured segment, each with
/// its own calibration and its Hall sensor as the scene's `[sensors]` says: segment `k` (base to tip)
/// senses joint `k + 1`, with that joint's calibration offset and gain error (given, or drawn
/// from the seed by sim-core's [`Sensors`]) and its own noise stream of the seed, `k + 1`
/// (stream 0 is the calibration draw's), so that its noise does not depend on the others'.
///
/// # Errors
/// When the scene's `[sensors]` does not fit the bus (a configuration that passed
/// [`Config::from_toml_str`] always does).
pub fn sim_bus(config: &Config) -> Result<SimBus> {
    let settings = config.sensor_settings();
    let segments = &config.bus.segments;
    let sensors = Sensors::new(&settings, segments.len()).context("the scene's [sensors]")?;
    let (offsets_counts, gain_errors) = (sensors.offset_counts(), sensors.gain_error());
    segments
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let errors = HallErrors {
                noise_counts: settings.angle_noise_counts,
                offset_counts: offsets_counts.get(k + 1).copied().unwrap_or_default(),
                gain_error: gain_errors.get(k + 1).copied().unwrap_or_default(),
            };
            let hall = HallSensor::new(errors, settings.seed, k as u64 + 1)
                .with_context(|| format!("the scene's [sensors] for bus.segments[{k}]"))?;
            Ok(SimSegment::new(s.address, s.calibration()).with_hall_sensor(hall))
        })
        .collect::<Result<Vec<_>>>()
        .map(SimBus::new)
}

/// The polling thread's hook for the simulated rig: the segments sense the shared state and
/// run one sampling period of their firmware before each poll.
pub fn sense(state: Arc<Mutex<SimState>>) -> impl FnMut(&mut SimBus, Duration) + Send + 'static {
    sense_keeping_poses(state, Arc::new(SensedPoses::default()))
}

/// [`sense`], keeping the pose the physics was solved at for each poll in `poses`, by the
/// poll's time (the truth a live wall estimate is checked against).
pub fn sense_keeping_poses(
    state: Arc<Mutex<SimState>>,
    poses: Arc<SensedPoses>,
) -> impl FnMut(&mut SimBus, Duration) + Send + 'static {
    let mut copy = SimState::default();
    move |bus, now| {
        if let Ok(shared) = state.lock() {
            copy.clone_from(&shared);
        }
        if let Some(solved_at) = copy.solved_at {
            poses.push(u64::try_from(now.as_nanos()).unwrap_or(u64::MAX), solved_at);
        }
        for (k, (&angle, &touch)) in copy.joint_angles_rad.iter().zip(&copy.touch).enumerate() {
            if let Some(segment) = bus.segment_mut(k) {
                segment.set_angle_rad(angle);
                segment.set_touch(touch);
            }
        }
        bus.sample_all();
    }
}

/// The stage position and base pose each poll of the simulated segments sensed, by the
/// poll's time (`PollRecord::t_ns`), newest last; the oldest are dropped beyond
/// [`SensedPoses::CAPACITY`].
#[derive(Debug, Default)]
pub struct SensedPoses {
    entries: Mutex<VecDeque<(u64, (f64, BasePose))>>,
}

impl SensedPoses {
    /// Entries kept at most (4 s of polls at 1 kHz).
    pub const CAPACITY: usize = 4096;

    fn push(&self, t_ns: u64, solved_at: (f64, BasePose)) {
        if let Ok(mut entries) = self.entries.lock() {
            if entries.len() >= Self::CAPACITY {
                entries.pop_front();
            }
            entries.push_back((t_ns, solved_at));
        }
    }

    /// The stage position and base pose the poll at `t_ns` sensed, if kept; that entry and
    /// every older one are taken out.
    pub fn take_at(&self, t_ns: u64) -> Option<(f64, BasePose)> {
        let mut entries = self.entries.lock().ok()?;
        let mut found = None;
        while let Some(&(t, solved_at)) = entries.front() {
            if t > t_ns {
                break;
            }
            entries.pop_front();
            if t == t_ns {
                found = Some(solved_at);
            }
        }
        found
    }
}

/// The polling thread's hook `sense`, with `sim.faults` applied first by the time since the
/// start: each listed segment has its fault from `from_s` until `until_s`, and none otherwise.
pub fn sense_with_faults(
    mut sense: impl FnMut(&mut SimBus, Duration) + Send + 'static,
    config: &Config,
) -> impl FnMut(&mut SimBus, Duration) + Send + 'static {
    let faults: Vec<(usize, SegmentFault, Duration, Duration)> = config
        .sim
        .faults
        .iter()
        .filter_map(|f| {
            let index = config
                .bus
                .segments
                .iter()
                .position(|s| s.address == f.address)?;
            let kind = match f.kind {
                SimFaultKind::Nack => SegmentFault::Nack,
                SimFaultKind::Pec => SegmentFault::CorruptPec,
                SimFaultKind::Stuck => SegmentFault::StuckCounter,
                SimFaultKind::Hang => SegmentFault::Hang,
            };
            Some((
                index,
                kind,
                Duration::from_secs_f64(f.from_s),
                Duration::from_secs_f64(f.until_s),
            ))
        })
        .collect();
    let segments = config.bus.segments.len();
    move |bus, now| {
        if !faults.is_empty() {
            for k in 0..segments {
                let fault = faults
                    .iter()
                    .find(|(index, _, from, until)| *index == k && *from <= now && now < *until)
                    .map_or(SegmentFault::None, |f| f.1);
                if let Some(segment) = bus.segment_mut(k) {
                    segment.set_fault(fault);
                }
            }
        }
        sense(bus, now);
    }
}

/// The one simulated world: the antenna's physics, moved by the stage and the base servo
/// (simulated or real, whichever the rig has), its state shared with the polling thread's
/// [`sense`] hook. Solved again only when the stage or the base has moved; every placement
/// and step is kept with the time it was made ([`Self::take_steps`]).
#[derive(Debug)]
pub struct SimWorld {
    physics: SimPhysics,
    state: Arc<Mutex<SimState>>,
    solved_for: Option<(f64, f64)>,
    steps: Vec<(Duration, PhysicsStep)>,
}

impl SimWorld {
    /// The world of `config`'s scene, publishing its state to `state`.
    ///
    /// # Errors
    /// When the physics does not accept the scene (its placement fails with the stage at 0).
    pub fn new(config: &Config, state: Arc<Mutex<SimState>>) -> Result<Self> {
        let mut physics = sim_physics(config)?;
        physics.record_steps(true);
        let world = Self {
            physics,
            state,
            solved_for: None,
            steps: Vec::new(),
        };
        world.publish(world.physics.state().clone());
        Ok(world)
    }

    /// What the last placement did, in words.
    pub fn placement_note(&self) -> &str {
        self.physics.placement_note()
    }

    /// The stage at `stage_m` and the base servo at `servo_rad`, at `now`: the antenna
    /// settles there (if either moved since the last call) and the segments sense it from
    /// now on.
    ///
    /// # Errors
    /// When the contact solver fails.
    pub fn move_to(&mut self, stage_m: f64, servo_rad: f64, now: Duration) -> Result<()> {
        let key = (stage_m, servo_rad);
        if self.solved_for != Some(key) {
            let solved = self.physics.update(stage_m, servo_rad)?;
            self.solved_for = Some(key);
            self.keep_steps(now);
            self.publish(solved);
        }
        Ok(())
    }

    /// The scene's placement, done afresh with the stage at `stage_m` and the servo at
    /// `servo_rad`, at `now` (a trial starting).
    ///
    /// # Errors
    /// When the placement fails there (the antenna stays as it was).
    pub fn place(&mut self, stage_m: f64, servo_rad: f64, now: Duration) -> Result<()> {
        let placed = self.physics.place(stage_m, servo_rad)?;
        self.solved_for = Some((stage_m, servo_rad));
        self.keep_steps(now);
        self.publish(placed);
        Ok(())
    }

    /// The placements and steps made since the last call, each with its time, oldest first.
    pub fn take_steps(&mut self) -> Vec<(Duration, PhysicsStep)> {
        std::mem::take(&mut self.steps)
    }

    fn keep_steps(&mut self, now: Duration) {
        // Bounded: nobody taking them (a test driving the rig by hand) keeps the newest.
        if self.steps.len() >= MAX_KEPT_STEPS {
            self.steps.drain(..MAX_KEPT_STEPS / 2);
        }
        self.steps
            .extend(self.physics.take_steps().into_iter().map(|s| (now, s)));
    }

    fn publish(&self, state: SimState) {
        if let Ok(mut shared) = self.state.lock() {
            *shared = state;
        }
    }
}

/// Steps kept for [`SimWorld::take_steps`] at most (the motion thread takes them after every
/// rig call).
const MAX_KEPT_STEPS: usize = 100_000;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_configuration_places_the_thesis_antenna_on_its_wall() {
        let state = Arc::new(Mutex::new(SimState::default()));
        let mut world = SimWorld::new(&Config::default(), Arc::clone(&state)).unwrap();
        assert!(world.placement_note().starts_with("tip placed on wall 0"));
        let placed = state.lock().unwrap().clone();
        assert_eq!(placed.joint_angles_rad.len(), 8);
        assert!(placed.tip_force_n > 0.0);
        world.move_to(0.01, 0.0, Duration::from_millis(5)).unwrap();
        world.move_to(0.01, 0.0, Duration::from_millis(6)).unwrap();
        world.place(0.01, 0.0, Duration::from_millis(7)).unwrap();
        let steps = world.take_steps();
        let kinds: Vec<(Duration, StepKind)> = steps.iter().map(|(t, s)| (*t, s.kind)).collect();
        assert_eq!(
            kinds,
            [
                (Duration::from_millis(5), StepKind::Step),
                (Duration::from_millis(7), StepKind::Place)
            ]
        );
        assert_eq!(steps[0].1.stage_m, 0.01);
    }

    #[test]
    fn a_configured_fault_holds_its_segment_for_its_window_only() {
        let mut config = Config::default();
        let address = config.bus.segments[2].address;
        config.sim.faults = vec![crate::config::SimFaultConfig {
            address,
            kind: SimFaultKind::Nack,
            from_s: 1.0,
            until_s: 2.0,
        }];
        let mut bus = sim_bus(&config).unwrap();
        let sensed = Arc::new(std::sync::atomic::AtomicUsize::new(0));
        let counter = Arc::clone(&sensed);
        let mut hook = sense_with_faults(
            move |_: &mut SimBus, _| {
                counter.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            },
            &config,
        );
        let mut faults = |bus: &mut SimBus, now_s: f64| {
            hook(bus, Duration::from_secs_f64(now_s));
            (0..config.bus.segments.len())
                .map(|k| bus.segment_mut(k).map(|s| s.fault()))
                .collect::<Vec<_>>()
        };
        let none = vec![Some(SegmentFault::None); 8];
        assert_eq!(faults(&mut bus, 0.5), none);
        let mut nack = none.clone();
        nack[2] = Some(SegmentFault::Nack);
        assert_eq!(faults(&mut bus, 1.0), nack);
        assert_eq!(faults(&mut bus, 1.999), nack);
        assert_eq!(faults(&mut bus, 2.0), none);
        assert_eq!(sensed.load(std::sync::atomic::Ordering::Relaxed), 4);
    }
}
