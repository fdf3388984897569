//! The simulated rig, used when no hardware is configured: a virtual I2C bus ([`SimBus`])
//! whose segments run `firmware-segment`'s own logic, a [`FakeStage`] and a [`FakeServo`]
//! that move in real time at their set speeds, and joint angles from sim-core's equilibrium
//! solver as the stage carries the antenna along a configured wall.
//!
//! # Contact: a stand-in
//! sim-core's contact solver does not exist yet. Until it lands, contact is a **tip-only
//! penalty**: the wall pushes on the tip along its normal with `f = k_wall * penetration`,
//! and the posture is the equilibrium under that load ([`sim_core::solve_equilibrium`],
//! warm-started from the previous posture). The force is the root of
//! `penetration(f) - f / k_wall`, found by safeguarded secant steps on `f >= 0`. Frictionless;
//! links other than the tip may pass through the wall. A segment's touch switches close
//! while the end of its link is within [`TOUCH_DISTANCE_M`] of the wall.

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
use sim_core::{Chain, EquilibriumProblem, InitialGuess, SolveOptions, solve_equilibrium};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// How close to the wall (metres) the end of a link must be for its touch switches to close.
pub const TOUCH_DISTANCE_M: f64 = 0.002;

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
#[derive(Debug, Clone)]
pub struct SimPhysics {
    chain: Chain,
    wall: WallConfig,
    theta: Vec<f64>,
    force_n: f64,
}

impl SimPhysics {
    /// The antenna of `config.sim.antenna` (one link per segment) in front of its wall.
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
        Ok(Self {
            theta: chain.rest_theta(),
            chain,
            wall: config.sim.wall.clone(),
            force_n: 0.0,
        })
    }

    /// The wall's unit normal, pointing into the wall.
    fn normal(&self) -> Vector2<f64> {
        let (s, c) = self.wall.angle_deg.to_radians().sin_cos();
        Vector2::new(s, c)
    }

    /// How far `point` (metres, track frame) is inside the wall (negative: in front of it).
    fn penetration_m(&self, point: Vector2<f64>) -> f64 {
        (point - Vector2::new(0.0, self.wall.distance_m)).dot(&self.normal())
    }

    /// The equilibrium under a wall force `f` on the tip, from the current posture; returns
    /// the angles and the tip's penetration with the base at `base_x_m`.
    fn solve(&self, chain: &Chain, f: f64, base_x_m: f64) -> Result<(Vec<f64>, f64)> {
        let problem = EquilibriumProblem::new(chain).with_tip_force_n(-f * self.normal());
        let guess = InitialGuess::Angles(self.theta[1..].to_vec());
        let eq = solve_equilibrium(&problem, &guess, &SolveOptions::default())
            .context("equilibrium solve")?;
        let tip = sim_core::tip_pose(chain, &eq.theta_rad).context("tip pose")?;
        let pen = self.penetration_m(tip.position_m + Vector2::new(base_x_m, 0.0));
        Ok((eq.theta_rad, pen))
    }

    /// The posture with the base at `base_x_m` along the track and the base link at
    /// `base_angle_rad`, warm-started from the last one.
    pub fn update(&mut self, base_x_m: f64, base_angle_rad: f64) -> Result<SimState> {
        let chain = self
            .chain
            .with_base_angle_rad(base_angle_rad)
            .context("base angle")?;
        let k_wall = self.wall.stiffness_n_per_m;
        let residual = |pen: f64, f: f64| pen - f / k_wall;
        let (theta0, pen0) = self.solve(&chain, 0.0, base_x_m)?;
        let (theta, force) = if pen0 <= 0.0 {
            (theta0, 0.0)
        } else {
            // g(f) = pen(f) - f / k decreases from g(0) > 0 to g(k pen0) <= 0.
            let (mut lo, mut g_lo) = (0.0, pen0);
            let mut hi = k_wall * pen0;
            let (theta_hi, pen_hi) = self.solve(&chain, hi, base_x_m)?;
            let mut g_hi = residual(pen_hi, hi);
            let mut f = self.force_n.clamp(lo, hi);
            let mut best = (theta_hi, hi);
            for _ in 0..60 {
                if hi - lo <= 1e-9 * hi.max(1e-9) {
                    break;
                }
                let (theta_f, pen_f) = self.solve(&chain, f, base_x_m)?;
                let g = residual(pen_f, f);
                best = (theta_f, f);
                if g.abs() <= 1e-7 {
                    break;
                }
                if g > 0.0 {
                    (lo, g_lo) = (f, g);
                } else {
                    (hi, g_hi) = (f, g);
                }
                // Secant inside the bracket, bisection if it would leave it.
                let secant = lo - g_lo * (hi - lo) / (g_hi - g_lo);
                f = if secant.is_finite() && secant > lo && secant < hi {
                    secant
                } else {
                    0.5 * (lo + hi)
                };
            }
            best
        };
        self.theta = theta;
        self.force_n = force;
        let poses =
            sim_core::frame_poses(&chain, &self.theta, sim_core::Frame::GROUND).context("poses")?;
        let n = chain.n();
        let touch = (1..=n)
            .map(|j| {
                let end = poses
                    .position_m(sim_core::Frame::link(j))
                    .unwrap_or_default()
                    + Vector2::new(base_x_m, 0.0);
                let near = self.penetration_m(end) > -TOUCH_DISTANCE_M;
                let bits = match (near, j == n && force > 0.0) {
                    (_, true) => 0b1100,
                    (true, false) => 0b1000,
                    (false, false) => 0,
                };
                TouchBits::from_bits_truncate(bits)
            })
            .collect();
        Ok(SimState {
            joint_angles_rad: self.theta[1..].to_vec(),
            touch,
            tip_force_n: force,
        })
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
