//! The simulated rig, used when no hardware is configured: a virtual I2C bus ([`SimBus`])
//! whose segments run `firmware-segment`'s own logic, a [`FakeStage`] and a [`FakeServo`]
//! that move in real time at their set speeds, and joint angles from sim-core's equilibrium
//! solver as the stage carries the antenna along a configured wall.
//!
//! # Contact
//! sim-core's quasi-static contact solver ([`sim_core::contact::QuasiStatic`]): every link
//! and joint kept out of the wall, Coulomb friction that sticks and slips (`mu` of
//! `[sim.wall]`), snaps followed downhill. Each new stage position is a step of the sweep; a
//! new base angle rebuilds the solver from the current posture, backed off the wall if the
//! turn would put the antenna into it, and steps back. A segment's touch switches close
//! where its link touches the wall (`sim_core::touch_bits_from_contacts`).

use crate::acquisition::{
    AcquisitionEvent, MotionSettings, PollReport, PollSettings, Rig, Shared, event_channel,
    spawn_motion, spawn_poller,
};
use crate::clock::TrialClock;
use crate::config::{Config, TrialConfig, WallConfig};
use crate::poll::{Poller, SegmentHealth};
use crate::sim_bus::{SimBus, SimSegment};
use crate::stage::{Homed, LimitedStage};
use crate::{FakeServo, FakeStage, Servo};
use antenna_protocol::TouchBits;
use anyhow::{Context, Result, anyhow};
use nalgebra::Vector2;
use sim_core::contact::{ContactSettings, QuasiStatic};
use sim_core::{
    Chain, ChainContact, Line, SolidSide, Surface, SurfaceMap, Wall, touch_bits_from_contacts,
};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// The physical state the simulated segments sense.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SimState {
    /// Joint angles `theta_1..theta_n`, radians.
    pub joint_angles_rad: Vec<f64>,
    /// Raw touch switches per segment.
    pub touch: Vec<TouchBits>,
    /// The wall's force on the tip, newtons (0 out of contact).
    pub tip_force_n: f64,
}

/// The antenna against the wall: the posture for a stage position and base angle.
#[derive(Debug)]
pub struct SimPhysics {
    sim: QuasiStatic,
    contacts: Vec<ChainContact>,
    touch_bits: Vec<u8>,
}

impl SimPhysics {
    /// The antenna of `config.sim.antenna` (one link per segment) at rest in front of its
    /// wall, the stage at 0.
    pub fn new(config: &Config) -> Result<Self> {
        let antenna = &config.sim.antenna;
        let lengths = vec![antenna.link_length_m; antenna.links + 1];
        let profile = antenna
            .profile()
            .ok_or_else(|| anyhow!("unknown stiffness profile {:?}", antenna.stiffness_profile))?;
        let k = profile
            .stiffness_n_m_per_rad(
                &lengths,
                antenna.k_min_n_m_per_rad,
                antenna.k_max_n_m_per_rad,
            )
            .context("sim.antenna stiffness")?;
        let chain = Chain::builder(antenna.links)
            .link_length_m(antenna.link_length_m)
            .base_angle_rad(antenna.base_angle_deg.to_radians())
            .stiffnesses_nm_per_rad(k)
            .build()
            .context("sim.antenna")?;
        let wall = wall_of(&config.sim.wall)?;
        let theta = chain.rest_theta();
        let sim = QuasiStatic::new(
            chain,
            vec![wall],
            Vector2::zeros(),
            &theta,
            ContactSettings::default(),
        )
        .context("sim.antenna at rest with the stage at 0 against sim.wall")?;
        Ok(Self {
            touch_bits: vec![0; theta.len()],
            sim,
            contacts: Vec::new(),
        })
    }

    /// The posture with the base at `base_x_m` along the track and the base link at
    /// `base_angle_rad`: one quasi-static step from the last one.
    pub fn update(&mut self, base_x_m: f64, base_angle_rad: f64) -> Result<SimState> {
        if base_angle_rad != self.sim.chain().base_angle_rad() {
            self.turn_base(base_angle_rad)?;
        }
        self.sim
            .step_to(Vector2::new(base_x_m, 0.0))
            .with_context(|| format!("the antenna with the stage at {:.1} mm", base_x_m * 1e3))?;
        let contacts = self.sim.contacts();
        self.contacts.clear();
        self.contacts
            .extend(contacts.iter().map(|c| c.chain_contact()));
        touch_bits_from_contacts(&self.contacts, &mut self.touch_bits).context("touch bits")?;
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
        })
    }

    /// Turns the base link to `base_angle_rad` keeping the joint angles: the solver is
    /// rebuilt there, its base first backed off along the wall's normal by as much as the
    /// turn would put the antenna into the wall (the next step brings it back on).
    fn turn_base(&mut self, base_angle_rad: f64) -> Result<()> {
        let chain = self
            .sim
            .chain()
            .with_base_angle_rad(base_angle_rad)
            .context("base angle")?;
        let mut theta = self.sim.theta_rad().to_vec();
        theta[0] = base_angle_rad;
        let base = self.sim.base_m();
        let walls = self.sim.walls().to_vec();
        let poses = sim_core::frame_poses(&chain, &theta, sim_core::Frame::GROUND)
            .context("poses after the turn")?;
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
            .context("the antenna turned on its base")?;
        Ok(())
    }
}

/// How far off the wall a turned antenna is put before it steps back, metres.
const TURN_CLEARANCE_M: f64 = 1e-3;

/// `[sim.wall]` as a sim-core wall: a line through `(0, distance_m)` at `-angle_deg` to the
/// track (it comes closer as the stage moves forward), solid beyond it, smooth with `mu`.
fn wall_of(config: &WallConfig) -> Result<Wall> {
    let line = Line::new(
        Vector2::new(0.0, config.distance_m),
        -config.angle_deg.to_radians(),
        SolidSide::Left,
    )
    .context("sim.wall")?;
    let surface = SurfaceMap::uniform(Surface::Smooth { mu: config.mu }).context("sim.wall.mu")?;
    Ok(Wall::new(line, surface))
}

/// The simulated stage and servo, moving in real time, with the antenna following them.
#[derive(Debug)]
pub struct SimRig {
    stage: LimitedStage<FakeStage, Homed>,
    servo: FakeServo,
    physics: SimPhysics,
    state: Shared<SimState>,
    mount_rad: f64,
    advanced_to: Duration,
    solved_for: Option<(f64, f64)>,
}

impl SimRig {
    /// The rig of `config`, its stage homed at 0 mm; the antenna's state is written to
    /// `state` for the simulated segments to sense.
    pub fn new(config: &Config, state: Shared<SimState>) -> Result<Self> {
        let geometry = config.stage_geometry().context("stage geometry")?;
        let stage = LimitedStage::new(FakeStage::new(), geometry)
            .online()
            .map_err(|e| anyhow!("{e}"))?
            .home()
            .map_err(|e| anyhow!("{e}"))?;
        let mut rig = Self {
            stage,
            servo: FakeServo::new(),
            physics: SimPhysics::new(config)?,
            state,
            mount_rad: config.sim.antenna.base_angle_deg.to_radians(),
            advanced_to: Duration::ZERO,
            solved_for: None,
        };
        rig.advance(Duration::ZERO)?;
        Ok(rig)
    }

    /// The stage, e.g. to check a position in a test.
    pub fn stage_mut(&mut self) -> &mut LimitedStage<FakeStage, Homed> {
        &mut self.stage
    }

    /// The shared physical state.
    pub fn state(&self) -> Shared<SimState> {
        Arc::clone(&self.state)
    }

    /// Lets the stage and servo move until `now` and updates the antenna.
    fn advance(&mut self, now: Duration) -> Result<()> {
        let dt = now.saturating_sub(self.advanced_to);
        self.advanced_to = self.advanced_to.max(now);
        self.stage.stage_mut().advance(dt);
        self.servo.advance(dt);
        let x_m = self.stage.stage_mut().exact_position_steps()
            / self.stage.geometry().steps_per_mm()
            * 1e-3;
        let base = self.mount_rad + self.servo.angle_rad()?;
        if self.solved_for != Some((x_m, base)) {
            let state = self.physics.update(x_m, base)?;
            self.solved_for = Some((x_m, base));
            *self
                .state
                .lock()
                .map_err(|_| anyhow!("simulated state lock poisoned"))? = state;
        }
        Ok(())
    }
}

impl Rig for SimRig {
    fn start_move_mm(
        &mut self,
        distance_mm: f64,
        speed_mm_per_s: f64,
        now: Duration,
    ) -> Result<()> {
        self.advance(now)?;
        self.stage.set_speed_mm_per_s(speed_mm_per_s)?;
        self.stage.start_relative_mm(distance_mm)?;
        Ok(())
    }

    fn stage_moving(&mut self, now: Duration) -> Result<bool> {
        self.advance(now)?;
        Ok(self.stage.stage_mut().is_moving())
    }

    fn stage_mm(&mut self, now: Duration) -> Result<f64> {
        self.advance(now)?;
        Ok(self.stage.position_mm()?)
    }

    fn set_base_angle_rad(&mut self, angle_rad: f64, now: Duration) -> Result<()> {
        self.advance(now)?;
        self.servo.set_angle_rad(angle_rad)?;
        Ok(())
    }

    fn base_angle_rad(&mut self, now: Duration) -> Result<f64> {
        self.advance(now)?;
        Ok(self.servo.angle_rad()?)
    }

    fn stop(&mut self, now: Duration) -> Result<()> {
        self.advance(now)?;
        Ok(self.stage.kill()?)
    }
}

/// The virtual bus of `config.bus`: one simulated segment per configured segment, each with
/// its own calibration.
pub fn sim_bus(config: &Config) -> SimBus {
    SimBus::new(
        config
            .bus
            .segments
            .iter()
            .map(|s| SimSegment::new(s.address, s.calibration()))
            .collect(),
    )
}

/// The polling thread's hook for the simulated rig: the segments sense the shared state and
/// run one sampling period of their firmware before each poll.
pub fn sense(state: Shared<SimState>) -> impl FnMut(&mut SimBus, Duration) + Send + 'static {
    let mut copy = SimState::default();
    move |bus, _| {
        if let Ok(shared) = state.lock() {
            copy.clone_from(&shared);
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

/// Options of [`run_sim_trial`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TrialOptions {
    /// Overrides the trial's duration (zero: until its moves are done).
    pub duration: Option<Duration>,
    /// Capacity of the event queue.
    pub queue: usize,
    /// Overrides `bus.spin_us`, the busy wait before each poll deadline.
    pub spin: Option<Duration>,
    /// Overrides `bus.realtime_priority` (0: normal scheduling).
    pub realtime_priority: Option<u8>,
}

impl Default for TrialOptions {
    fn default() -> Self {
        Self {
            duration: None,
            queue: 8192,
            spin: None,
            realtime_priority: None,
        }
    }
}

/// What a trial did.
#[derive(Debug, Clone, PartialEq)]
pub struct TrialSummary {
    /// Polls made.
    pub polls: u64,
    /// Poll deadlines skipped.
    pub skipped: u64,
    /// The latest poll wake-up.
    pub max_lateness: Duration,
    /// Health per segment.
    pub health: Vec<SegmentHealth>,
    /// Events dropped because the queue was full.
    pub dropped: u64,
    /// Stage moves started.
    pub moves_started: usize,
    /// Stage moves refused.
    pub moves_refused: usize,
    /// The trial's length.
    pub elapsed: Duration,
}

/// Runs `trial` on the simulated rig of `config`: the polling and motion threads on one
/// clock, every event handed to `on_event` on this thread as it arrives. Ends when the
/// duration has passed (the trial's, or `options.duration`; zero: when its moves are done)
/// or `stop` is set.
pub fn run_sim_trial(
    config: &Config,
    trial: &TrialConfig,
    options: TrialOptions,
    stop: Arc<AtomicBool>,
    mut on_event: impl FnMut(&AcquisitionEvent),
) -> Result<TrialSummary> {
    let state: Shared<SimState> = Arc::new(Mutex::new(SimState::default()));
    let rig = SimRig::new(config, Arc::clone(&state))?;
    let bus = sim_bus(config);
    let poller = Poller::new(bus, &config.bus.addresses());
    let (events, receiver) = event_channel(options.queue);
    let threads_stop = Arc::new(AtomicBool::new(false));
    let script_done = Arc::new(AtomicBool::new(false));
    let clock = TrialClock::start();
    let poll = spawn_poller(
        poller,
        clock,
        PollSettings {
            period: Duration::from_secs_f64(1.0 / config.bus.poll_hz),
            counter_check_every: config.bus.counter_check_every,
            spin: options
                .spin
                .unwrap_or(Duration::from_micros(config.bus.spin_us)),
            realtime_priority: options
                .realtime_priority
                .unwrap_or(config.bus.realtime_priority),
        },
        sense(state),
        events.clone(),
        Arc::clone(&threads_stop),
    )
    .context("starting the polling thread")?;
    let motion = spawn_motion(
        rig,
        trial.clone(),
        clock,
        MotionSettings {
            stage_period: Duration::from_secs_f64(1.0 / config.stage.sample_hz),
            base_period: Duration::from_secs_f64(1.0 / config.servo.sample_hz),
        },
        events.clone(),
        Arc::clone(&threads_stop),
        Arc::clone(&script_done),
    )
    .context("starting the motion thread")?;
    let duration = options
        .duration
        .unwrap_or(Duration::from_secs_f64(trial.duration_s));
    loop {
        let finished = if duration.is_zero() {
            script_done.load(Ordering::Relaxed)
        } else {
            clock.elapsed() >= duration
        };
        if finished || stop.load(Ordering::Relaxed) {
            break;
        }
        if let Ok(event) = receiver.recv_timeout(Duration::from_millis(20)) {
            on_event(&event);
            while let Ok(event) = receiver.try_recv() {
                on_event(&event);
            }
        }
    }
    let elapsed = clock.elapsed();
    threads_stop.store(true, Ordering::Relaxed);
    let poll: PollReport<SimBus> = poll
        .join()
        .map_err(|_| anyhow!("the polling thread panicked"))?;
    let motion = motion
        .join()
        .map_err(|_| anyhow!("the motion thread panicked"))?;
    while let Ok(event) = receiver.try_recv() {
        on_event(&event);
    }
    Ok(TrialSummary {
        polls: poll.polls,
        skipped: poll.skipped,
        max_lateness: poll.max_lateness,
        health: poll.health,
        dropped: events.dropped(),
        moves_started: motion.moves_started,
        moves_refused: motion.moves_refused,
        elapsed,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_antenna_bends_only_once_it_reaches_the_wall() {
        let config = Config::default();
        let mut physics = SimPhysics::new(&config).unwrap();
        let base = config.sim.antenna.base_angle_deg.to_radians();
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
}
