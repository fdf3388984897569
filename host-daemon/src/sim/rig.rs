//! The simulated rig, used when no hardware is configured: a virtual I2C bus ([`SimBus`])
//! whose segments run `firmware-segment`'s own logic, and one simulated world ([`SimWorld`]):
//! joint angles from sim-core's equilibrium solver as the stage (simulated,
//! [`crate::sim::devices::SimStage`], or real) carries the antenna along a configured wall.
//!
//! # Contact
//! The physics is `antenna-sim-physics`' [`SimPhysics`] (shared with `antenna-monitor`'s
//! prediction): sim-core's quasi-static contact solver, every link and joint kept out of the
//! wall, Coulomb friction that sticks and slips (`mu` of `[sim.wall]`), snaps followed
//! downhill, a segment's touch switches closing where its link touches the wall.
//!
//! # Sensors
//! The segments' sensors are ideal unless `[sim.sensors]` says otherwise
//! ([`crate::config::SimSensorsConfig`]): each segment's Hall sensor then has its
//! joint's calibration offset and gain error and seeded noise on each of its ten-bit
//! conversions, which the firmware's own oversampling turns into the twelve-bit reading
//! ([`sim_bus`]), and a touch switch closes only for a contact pressing at least
//! `touch_threshold_n` ([`sim_physics`]). The touch debounce is the firmware's own, and the
//! sensors are sampled once per poll (`bus.poll_hz`).

use crate::config::{Config, SimFaultKind};
use crate::sim::bus::{SegmentFault, SimBus, SimSegment};
use antenna_bus::{HallErrors, HallSensor};
pub use antenna_sim_physics::{AntennaSpec, FlatWallSpec, SimPhysics, SimState};
use anyhow::{Context, Result};
use sim_core::Sensors;
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
pub fn sense(state: Arc<Mutex<SimState>>) -> impl FnMut(&mut SimBus, Duration) + Send + 'static {
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
/// [`sense`] hook. Solved again only when the stage or the base has moved.
#[derive(Debug)]
pub struct SimWorld {
    physics: SimPhysics,
    state: Arc<Mutex<SimState>>,
    /// The antenna's mount angle on the base, radians (`sim.antenna.base_angle_deg`).
    mount_rad: f64,
    solved_for: Option<(f64, f64)>,
}

impl SimWorld {
    /// The world of `config`'s `[sim]`, publishing its state to `state`.
    ///
    /// # Errors
    /// When the physics does not accept `[sim]` (a configuration that passed
    /// [`Config::from_toml_str`] always does).
    pub fn new(config: &Config, state: Arc<Mutex<SimState>>) -> Result<Self> {
        Ok(Self {
            physics: sim_physics(config)?,
            state,
            mount_rad: config.sim.antenna.base_angle_deg.to_radians(),
            solved_for: None,
        })
    }

    /// The stage at `stage_m` and the base servo at `base_rad`: the antenna settles there
    /// (if either moved since the last call) and the segments sense it from now on.
    ///
    /// # Errors
    /// When the contact solver fails.
    pub fn move_to(&mut self, stage_m: f64, base_rad: f64) -> Result<()> {
        let key = (stage_m, self.mount_rad + base_rad);
        if self.solved_for != Some(key) {
            let solved = self.physics.update(key.0, key.1)?;
            self.solved_for = Some(key);
            if let Ok(mut shared) = self.state.lock() {
                *shared = solved;
            }
        }
        Ok(())
    }
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
        let none = vec![Some(SegmentFault::None); 9];
        assert_eq!(faults(&mut bus, 0.5), none);
        let mut nack = none.clone();
        nack[2] = Some(SegmentFault::Nack);
        assert_eq!(faults(&mut bus, 1.0), nack);
        assert_eq!(faults(&mut bus, 1.999), nack);
        assert_eq!(faults(&mut bus, 2.0), none);
        assert_eq!(sensed.load(std::sync::atomic::Ordering::Relaxed), 4);
    }
}
