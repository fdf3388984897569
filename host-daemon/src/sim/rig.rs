//! The simulated rig, used when no hardware is configured: a virtual I2C bus ([`SimBus`])
//! whose segments run `firmware-segment`'s own logic, a [`crate::FakeStage`] (homed against
//! its limit switch like the VXM) and a [`crate::FakeServo`] that move in real time at their
//! set speeds, and joint angles from sim-core's equilibrium solver as the stage carries the
//! antenna along a configured wall.
//!
//! # Contact
//! The physics is `antenna-sim-physics`' [`SimPhysics`] (shared with `antenna-monitor`'s
//! prediction): sim-core's quasi-static contact solver, every link and joint kept out of the
//! wall, Coulomb friction that sticks and slips (`mu` of `[sim.wall]`), snaps followed
//! downhill, a segment's touch switches closing where its link touches the wall.
//!
//! # Sensors
//! The segments' sensors are ideal unless `[sim.sensors]` says otherwise
//! ([`crate::service::config::SimSensorsConfig`]): each segment's Hall sensor then has its
//! joint's calibration offset and gain error and seeded noise on each of its ten-bit
//! conversions, which the firmware's own oversampling turns into the twelve-bit reading
//! ([`sim_bus`]), and a touch switch closes only for a contact pressing at least
//! `touch_threshold_n` ([`sim_physics`]). The touch debounce is the firmware's own, and the
//! sensors are sampled once per poll (`bus.poll_hz`).

use crate::hardware::poll::{Poller, SegmentHealth};
use crate::service::acquisition::{
    AcquisitionEvent, PollReport, PollSettings, Shared, event_channel, spawn_poller,
};
use crate::service::clock::TrialClock;
use crate::service::config::{Config, TrialConfig};
use crate::service::motion::{MotionCommand, MotionShared, RigStatus, spawn_motion};
use crate::service::rig::DaemonRig;
use crate::service::trial_script::ScriptEnds;
use crate::sim::bus::{SimBus, SimSegment};
use antenna_bus::{HallErrors, HallSensor};
pub use antenna_sim_physics::{AntennaSpec, FlatWallSpec, SimPhysics, SimState};
use anyhow::{Context, Result, anyhow};
use sim_core::Sensors;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::channel;
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// The physics of `config`'s simulated antenna (`[sim.antenna]`) against its wall
/// (`[sim.wall]`), its touch switches closed by contacts of at least
/// `sim.sensors.touch_threshold_n`.
pub fn sim_physics(config: &Config) -> Result<SimPhysics> {
    let mut physics = SimPhysics::new(&antenna_spec(config), &wall_spec(config))?;
    physics
        .set_touch_threshold_n(config.sim.sensors.touch_threshold_n)
        .context("`sim.sensors.touch_threshold_n`")?;
    Ok(physics)
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

/// The virtual bus of `config.bus`: one simulated segment per configured segment, each with
/// its own calibration and its Hall sensor as `[sim.sensors]` says: segment `k` (base to tip)
/// senses joint `k + 1`, with that joint's calibration offset and gain error (given, or drawn
/// from the seed by sim-core's [`Sensors`]) and its own noise stream of the seed, `k + 1`
/// (stream 0 is the calibration draw's), so that its noise does not depend on the others'.
///
/// # Errors
/// When `[sim.sensors]` does not fit the bus (a configuration that passed
/// [`Config::from_toml_str`] always does).
pub fn sim_bus(config: &Config) -> Result<SimBus> {
    let settings = config.sensor_settings();
    let segments = &config.bus.segments;
    let sensors = Sensors::new(&settings, segments.len()).context("`sim.sensors`")?;
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
                .with_context(|| format!("`sim.sensors` for bus.segments[{k}]"))?;
            Ok(SimSegment::new(s.address, s.calibration()).with_hall_sensor(hall))
        })
        .collect::<Result<Vec<_>>>()
        .map(SimBus::new)
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

/// Runs `trial` on the simulated rig of `config`: the polling thread and the daemon's own
/// motion thread (`crate::service::motion`, homing the simulated stage first, as antennad does) on
/// one clock, every event handed to `on_event` on this thread as it arrives. Ends when the
/// duration has passed (the trial's, or `options.duration`; zero: when its moves are done)
/// or `stop` is set. The stage, servo and bus of `config` are simulated whatever it says.
pub fn run_sim_trial(
    config: &Config,
    trial: &TrialConfig,
    options: TrialOptions,
    stop: Arc<AtomicBool>,
    mut on_event: impl FnMut(&AcquisitionEvent),
) -> Result<TrialSummary> {
    let state: Shared<SimState> = Arc::new(Mutex::new(SimState::default()));
    let mut sim_config = config.clone();
    sim_config.stage.port = "sim".to_owned();
    sim_config.servo.port = "sim".to_owned();
    let rig = DaemonRig::open(&sim_config, Some(Arc::clone(&state)))?;
    let bus = sim_bus(config)?;
    let poller = Poller::new(bus, &config.bus.addresses());
    let (events, receiver) = event_channel(options.queue);
    let threads_stop = Arc::new(AtomicBool::new(false));
    let script_ends = Arc::new(ScriptEnds::default());
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
    let (commands, motion_commands) = channel();
    commands
        .send(MotionCommand::RunScript {
            id: 1,
            trial: Box::new(trial.clone()),
        })
        .map_err(|_| anyhow!("the motion thread's queue is closed"))?;
    let motion = spawn_motion(
        rig,
        clock,
        (
            Duration::from_secs_f64(1.0 / config.stage.sample_hz),
            Duration::from_secs_f64(1.0 / config.servo.sample_hz),
        ),
        events.clone(),
        MotionShared {
            commands: motion_commands,
            stop_pending: Arc::new(AtomicBool::new(false)),
            stop: Arc::clone(&threads_stop),
            status: Arc::new(RigStatus::default()),
            script_ends: Arc::clone(&script_ends),
        },
    )
    .context("starting the motion thread")?;
    let duration = options
        .duration
        .unwrap_or(Duration::from_secs_f64(trial.duration_s));
    loop {
        let finished = if duration.is_zero() {
            script_ends.is_done(1) || script_ends.failure(1).is_some()
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
        moves_started: motion.moves.started,
        moves_refused: motion.moves.refused,
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
