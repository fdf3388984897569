//! The scene's `[sensors]` on the simulated rig (issue #18; `[sim.sensors]` before issue #46):
//! without the table, or with an explicitly ideal one, the polled words are exactly those of
//! ideal segments; noise, calibration errors and the touch threshold change them,
//! reproducibly for a seed.
//!
//! A trial on the rig runs in real time (its polls fall where the clock says), so two trials
//! are never word for word alike; these tests drive the rig's own parts (the physics of
//! `sim_physics`, the bus of `sim_bus`, the polling thread's `sense` hook and the `Poller`)
//! through one scripted sweep of the stage instead, poll by poll.
#![allow(clippy::unwrap_used)]

use antenna_protocol::RAD_PER_COUNT;
use host_daemon::service::acquisition::Shared;
use host_daemon::service::config::Config;
use host_daemon::service::config::scene::BUILT_IN_SCENE;
use host_daemon::sim::rig::{SimPhysics, SimState, sense, sim_bus, sim_physics};
use host_daemon::{Poller, SegmentReading, SimBus, SimSegment};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// Polls of the scripted sweep: the stage forward 160 mm and back, 1 mm a poll.
const POLLS: usize = 320;

fn stage_m(poll: usize) -> f64 {
    let mm = if poll <= POLLS / 2 {
        poll
    } else {
        POLLS - poll
    };
    mm as f64 * 1e-3
}

/// Every poll's readings over the sweep, with this physics and bus.
fn sweep(config: &Config, mut physics: SimPhysics, bus: SimBus) -> Vec<Vec<SegmentReading>> {
    let state: Shared<SimState> = Arc::new(Mutex::new(SimState::default()));
    let mut sense = sense(Arc::clone(&state));
    let mut poller = Poller::new(bus, &config.bus.addresses());
    (0..POLLS)
        .map(|poll| {
            *state.lock().unwrap() = physics.update(stage_m(poll), 0.0).unwrap();
            sense(poller.bus_mut(), Duration::from_millis(poll as u64));
            poller.poll_all()
        })
        .collect()
}

/// The sweep on the rig `config` describes.
fn rig_sweep(config: &Config) -> Vec<Vec<SegmentReading>> {
    sweep(
        config,
        sim_physics(config).unwrap(),
        sim_bus(config).unwrap(),
    )
}

/// The sweep on the rig with ideal sensors: the physics without a threshold, plain segments.
fn todays_sweep(config: &Config) -> Vec<Vec<SegmentReading>> {
    let physics = SimPhysics::new(config.sim.rig.sweep_scene().unwrap()).unwrap();
    let bus = SimBus::new(
        config
            .bus
            .segments
            .iter()
            .map(|s| SimSegment::new(s.address, s.calibration()))
            .collect(),
    );
    sweep(config, physics, bus)
}

/// The rig running `scene` (a scene file's text), configured by `config` besides.
fn rig_of(scene: &str, config: &str) -> Config {
    static FILES: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let k = FILES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("sim-sensors-{}-{k}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    let config = Config::from_toml_str(
        &format!("{config}\n[sim]\nscene = \"scene.toml\"\n"),
        &dir.join("rig.toml").display().to_string(),
    )
    .unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    config
}

/// The built-in rig with the scene's `[sensors]` table `sensors` (its body).
fn config(sensors: &str) -> Config {
    rig_of(&format!("{BUILT_IN_SCENE}\n[sensors]\n{sensors}"), "")
}

/// The words' angle counts of segment `k` over the sweep.
fn counts(readings: &[Vec<SegmentReading>], k: usize) -> Vec<u16> {
    readings
        .iter()
        .map(|r| r[k].result.unwrap().angle_counts())
        .collect()
}

fn touch_bits(readings: &[Vec<SegmentReading>]) -> u32 {
    readings
        .iter()
        .flatten()
        .map(|r| r.result.unwrap().touch().bits().count_ones())
        .sum()
}

#[test]
fn ideal_sensors_are_todays_words_exactly() {
    let absent = Config::default();
    let explicit = config(
        "angle_noise_counts = 0.0\noffset_counts = 0.0\ngain_error = 0\n\
         touch_threshold_n = 0.0\ntouch_debounce_samples = 3\nseed = 12345\n",
    );
    let listed = config(&format!(
        "offset_counts = [{zeros}]\ngain_error = [{zeros}]\nseed = 9\n",
        zeros = ["0.0"; 8].join(", ")
    ));
    let today = todays_sweep(&absent);
    // The sweep reaches the wall: the angles and the touch bits move.
    assert!(touch_bits(&today) > 0);
    assert!(
        counts(&today, 7)
            .iter()
            .any(|&c| c != today[0][7].result.unwrap().angle_counts())
    );
    assert_eq!(rig_sweep(&absent), today);
    assert_eq!(rig_sweep(&explicit), today);
    assert_eq!(rig_sweep(&listed), today);
}

#[test]
fn noise_on_the_rig_is_seeded_per_segment() {
    let noisy = |seed: u64| config(&format!("angle_noise_counts = 2.0\nseed = {seed}\n"));
    let today = todays_sweep(&Config::default());
    let a = rig_sweep(&noisy(1));
    assert_eq!(rig_sweep(&noisy(1)), a);
    assert_ne!(rig_sweep(&noisy(2)), a);
    assert_ne!(a, today);
    // Noise, not a shift: each segment's counts scatter about today's.
    for k in 0..8 {
        let (noisy, ideal) = (counts(&a, k), counts(&today, k));
        let differences: Vec<f64> = noisy
            .iter()
            .zip(&ideal)
            .map(|(&n, &i)| f64::from(n) - f64::from(i))
            .collect();
        let mean = differences.iter().sum::<f64>() / differences.len() as f64;
        assert!(mean.abs() < 1.0, "segment {k}: mean difference {mean}");
        assert!(differences.iter().any(|&d| d != 0.0));
    }
    // Segment 0's noise is its own: a bus of two segments gives it the same words (an
    // antenna of two joints, at rest clear of the wall).
    let short_scene = |sensors: &str| {
        let text = BUILT_IN_SCENE.replace("links = 9", "links = 3");
        let text = &text[..text.find("[start]").unwrap()];
        rig_of(
            &format!("{text}\n[sensors]\n{sensors}"),
            "[[bus.segments]]\naddress = 0x20\nzero_counts = 1500\ndirection = \"ccw\"\n\
             [[bus.segments]]\naddress = 0x21\nzero_counts = 1597\ndirection = \"cw\"\n",
        )
    };
    let two = rig_sweep(&short_scene("angle_noise_counts = 2.0\nseed = 1\n"));
    let quiet = rig_sweep(&short_scene("seed = 1\n"));
    // (The two-segment antenna bends differently, so compare the noise, not the words.)
    let noise = |rig: &[Vec<SegmentReading>], ideal: &[Vec<SegmentReading>]| -> Vec<i32> {
        counts(rig, 0)
            .iter()
            .zip(counts(ideal, 0))
            .map(|(&n, i)| i32::from(n) - i32::from(i))
            .collect()
    };
    let nine_quiet = rig_sweep(&config("seed = 1\n"));
    assert_eq!(noise(&two, &quiet), noise(&a, &nine_quiet));
}

#[test]
fn per_segment_offsets_and_gains_move_each_segments_counts() {
    let offsets = [10.0, -20.0, 0.0, 0.0, 0.0, 0.0, 0.0, 5.0];
    let text = format!(
        "offset_counts = [{}]\ngain_error = [0, 0, 0.1, 0, 0, 0, 0, 0]\n",
        offsets.map(|o| o.to_string()).join(", ")
    );
    let moved = config(&text);
    let base = Config::default();
    let (rig, today) = (rig_sweep(&moved), todays_sweep(&base));
    let calibrations = base.bus.calibrations();
    for poll in 0..POLLS {
        for k in [0, 1, 7] {
            let angle = |r: &[Vec<SegmentReading>]| {
                calibrations[k].angle_rad(r[poll][k].result.unwrap().angle_counts())
            };
            let shift = (angle(&rig) - angle(&today)) / RAD_PER_COUNT;
            assert!((shift - offsets[k]).abs() < 1e-6, "segment {k}: {shift}");
        }
        // The gain: theta (1 + 0.1), to a count.
        let ideal_rad = calibrations[2].angle_rad(today[poll][2].result.unwrap().angle_counts());
        let rig_rad = calibrations[2].angle_rad(rig[poll][2].result.unwrap().angle_counts());
        assert!(
            (rig_rad - 1.1 * ideal_rad).abs()
                <= 1.1 * RAD_PER_COUNT / 2.0 + RAD_PER_COUNT / 2.0 + 1e-12,
            "poll {poll}: {rig_rad} vs {ideal_rad}"
        );
        // Untouched segments read as today.
        assert_eq!(rig[poll][4], today[poll][4]);
    }
    // Drawn offsets: the bus's sensors carry sim-core's draw for the seed.
    let drawn = config("offset_counts = 4.0\ngain_error = 0.01\nseed = 3\n");
    let sensors = sim_core::Sensors::new(&drawn.sensor_settings(), 8).unwrap();
    let bus = sim_bus(&drawn).unwrap();
    for (k, segment) in bus.segments().iter().enumerate() {
        let errors = segment.hall_sensor().errors();
        assert_eq!(errors.offset_counts, sensors.offset_counts()[k + 1]);
        assert_eq!(errors.gain_error, sensors.gain_error()[k + 1]);
        assert_eq!(errors.noise_counts, 0.0);
    }
    assert!(
        bus.segments()
            .iter()
            .any(|s| s.hall_sensor().errors().offset_counts != 0.0)
    );
}

#[test]
fn a_touch_threshold_opens_the_switches_of_light_contacts() {
    let today = todays_sweep(&Config::default());
    // The default antenna is soft: its contacts press with millinewtons.
    let light = rig_sweep(&config("touch_threshold_n = 0.01\n"));
    let firm = rig_sweep(&config("touch_threshold_n = 1000.0\n"));
    let (all, some, none) = (touch_bits(&today), touch_bits(&light), touch_bits(&firm));
    assert!(all > 0);
    assert!(0 < some && some < all, "{some} of {all}");
    assert_eq!(none, 0);
    // The angles are the same: only the switches change.
    for k in 0..8 {
        assert_eq!(counts(&firm, k), counts(&today, k));
    }
}
