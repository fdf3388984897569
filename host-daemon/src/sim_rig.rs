//! The simulated rig, used when no hardware is configured: a virtual I2C bus ([`SimBus`])
//! whose segments run `firmware-segment`'s own logic, a [`FakeStage`] and a [`FakeServo`]
//! that move in real time at their set speeds, and joint angles from sim-core's equilibrium
//! solver as the stage carries the antenna along a configured wall.
//!
//! # Contact
//! The physics is `antenna-sim-physics`' [`SimPhysics`] (shared with `antenna-monitor`'s
//! prediction): sim-core's quasi-static contact solver, every link and joint kept out of the
//! wall, Coulomb friction that sticks and slips (`mu` of `[sim.wall]`), snaps followed
//! downhill, a segment's touch switches closing where its link touches the wall.

use crate::acquisition::{
    AcquisitionEvent, MotionSettings, PollReport, PollSettings, Rig, Shared, event_channel,
    spawn_motion, spawn_poller,
};
use crate::clock::TrialClock;
use crate::config::{Config, TrialConfig};
use crate::poll::{Poller, SegmentHealth};
use crate::sim_bus::{SimBus, SimSegment};
use crate::stage::{Homed, LimitedStage};
use crate::{FakeServo, FakeStage, Servo};
pub use antenna_sim_physics::{AntennaSpec, FlatWallSpec, SimPhysics, SimState};
use anyhow::{Context, Result, anyhow};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// The physics of `config`'s simulated antenna (`[sim.antenna]`) against its wall
/// (`[sim.wall]`).
pub fn sim_physics(config: &Config) -> Result<SimPhysics> {
    Ok(SimPhysics::new(&antenna_spec(config), &wall_spec(config))?)
}

/// `[sim.antenna]` as the physics takes it.
pub fn antenna_spec(config: &Config) -> AntennaSpec {
    let antenna = &config.sim.antenna;
    AntennaSpec {
        links: antenna.links,
        link_length_m: antenna.link_length_m,
        stiffness_profile: antenna.stiffness_profile.clone(),
        k_min_n_m_per_rad: antenna.k_min_n_m_per_rad,
        k_max_n_m_per_rad: antenna.k_max_n_m_per_rad,
        base_angle_deg: antenna.base_angle_deg,
    }
}

/// `[sim.wall]` as the physics takes it.
pub fn wall_spec(config: &Config) -> FlatWallSpec {
    let wall = &config.sim.wall;
    FlatWallSpec {
        distance_m: wall.distance_m,
        angle_deg: wall.angle_deg,
        mu: wall.mu,
    }
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
            physics: sim_physics(config)?,
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
    fn the_default_configuration_is_the_default_physics() {
        let config = Config::default();
        assert_eq!(antenna_spec(&config), AntennaSpec::default());
        assert_eq!(wall_spec(&config), FlatWallSpec::default());
    }
}
