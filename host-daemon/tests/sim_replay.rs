//! The simulated rig of each `examples/rigs/` configuration (issue #46): antennad runs a
//! short trial in-process and records it; the recording's physics steps (`/sim/physics`:
//! each placement and step with its base pose) are replayed through sim-core's own stepper
//! (`sim_core::sweep::place_at`, `step_base_to`) from the scene the recording carries
//! (`rig.scene_toml`), and the replay must give the joint angles the rig recorded: each
//! step's, and every segment poll's (ideal sensors: within the 12-bit quantum). Friction
//! makes the posture depend on the path, so the replay takes the rig's path, step for step.
#![allow(clippy::unwrap_used)]

use antenna_data::record::{PhysicsStepKind, Trial, TrialReader};
use antenna_protocol::RAD_PER_COUNT;
use antenna_scene::Scene;
use host_daemon::service::config::Config;
use host_daemon::service::daemon::{Daemon, DaemonOptions};
use nalgebra::Vector2;
use sim_core::sweep::{BasePose, place_at, step_base_to};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Runs the first trial of `examples/rigs/<name>.toml` for `trial_s` seconds, recorded; the
/// configuration and the recording.
fn run_rig(name: &str, trial_s: f64) -> (Config, Trial) {
    let file = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../examples/rigs")
        .join(format!("{name}.toml"));
    let mut config = Config::from_file(&file).unwrap();
    let dir: PathBuf =
        std::env::temp_dir().join(format!("antennad-replay-{name}-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    config.data_dir = dir.clone();
    let options = DaemonOptions {
        first_trial: Some(None),
        first_trial_duration: Some(Duration::from_secs_f64(trial_s)),
        exit_after_trial: true,
        record: true,
        serve: false,
        ..DaemonOptions::default()
    };
    let summary = Daemon::start(config.clone(), options)
        .unwrap()
        .wait()
        .unwrap();
    assert_eq!(summary.dropped, 0, "{name}: events dropped");
    let trial = TrialReader::read(summary.trials[0].path.as_ref().unwrap()).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    (config, trial)
}

/// What a replay found.
#[derive(Debug)]
struct Replayed {
    /// Steps replayed (from the trial's placement on).
    steps: usize,
    /// Polls compared.
    polls: usize,
    /// The largest joint bend seen, degrees.
    max_bend_deg: f64,
    /// How far the stage carried the base, metres.
    travel_m: f64,
}

/// Replays `trial`'s physics steps through sim-core's stepper and checks every recorded
/// joint angle against the replay (see the module documentation).
fn replay(name: &str, config: &Config, trial: &Trial) -> Replayed {
    let rig = trial.metadata.as_ref().unwrap().rig.as_ref().unwrap();
    let scene = Scene::parse(rig.scene_toml.as_deref().unwrap(), "recorded")
        .unwrap()
        .sweep_scene()
        .unwrap();
    let first = trial
        .physics
        .iter()
        .position(|s| s.kind == PhysicsStepKind::Place)
        .unwrap_or_else(|| panic!("{name}: no placement recorded"));
    let steps = &trial.physics[first..];
    let mut sim = None;
    let mut replayed: Vec<(f64, Vec<f64>)> = Vec::with_capacity(steps.len());
    for step in steps {
        let pose = BasePose {
            base_m: Vector2::new(step.base_x_m, step.base_y_m),
            base_angle_rad: step.base_angle_rad,
        };
        match step.kind {
            PhysicsStepKind::Place => sim = Some(place_at(&scene, &pose).unwrap().0),
            PhysicsStepKind::Step => {
                step_base_to(sim.as_mut().unwrap(), &pose).unwrap();
            }
        }
        let angles = sim.as_ref().unwrap().theta_rad()[1..].to_vec();
        assert_eq!(angles.len(), step.joint_angles_rad.len());
        for (j, (a, r)) in angles.iter().zip(&step.joint_angles_rad).enumerate() {
            assert!(
                (a - r).abs() <= RAD_PER_COUNT,
                "{name}: step at t = {} s, joint {}: replayed {a}, recorded {r}",
                step.t_s,
                j + 1
            );
        }
        replayed.push((step.t_s, angles));
    }
    // Every poll after the placement reads the angles of a step near it in time: the one in
    // force when it was polled (the segments sense the state each step publishes, a step's
    // time being when it began), to one count of the 12-bit sensor.
    let calibrations = config.bus.calibrations();
    let placed_s = steps[0].t_s;
    let mut polls = 0;
    for poll in trial.segments.iter().filter(|p| p.t_s > placed_s + 0.01) {
        let read: Vec<f64> = poll
            .segments
            .iter()
            .zip(&calibrations)
            .map(|(s, c)| c.angle_rad(s.angle_counts.unwrap()))
            .collect();
        let k = replayed.partition_point(|(t, _)| *t <= poll.t_s).max(1) - 1;
        let matches = (k.saturating_sub(2)..(k + 2).min(replayed.len())).any(|j| {
            replayed[j]
                .1
                .iter()
                .zip(&read)
                .all(|(a, r)| (a - r).abs() <= RAD_PER_COUNT)
        });
        assert!(
            matches,
            "{name}: poll at t = {} s reads {read:?}; the steps around it: {:?}",
            poll.t_s,
            &replayed[k.saturating_sub(2)..(k + 2).min(replayed.len())]
        );
        polls += 1;
    }
    let max_bend_deg = replayed
        .iter()
        .flat_map(|(_, a)| a.iter())
        .fold(0f64, |m, a| m.max(a.abs()))
        .to_degrees();
    let travel_m = steps.iter().map(|s| s.stage_m).fold(0f64, f64::max) - steps[0].stage_m;
    Replayed {
        steps: steps.len(),
        polls,
        max_bend_deg,
        travel_m,
    }
}

fn check(name: &str, trial_s: f64) -> Replayed {
    let (config, trial) = run_rig(name, trial_s);
    let replayed = replay(name, &config, &trial);
    eprintln!("{name}: {replayed:?}");
    assert!(replayed.steps > 10, "{name}: {replayed:?}");
    assert!(replayed.polls > 100, "{name}: {replayed:?}");
    assert!(replayed.travel_m > 0.01, "{name}: {replayed:?}");
    replayed
}

#[test]
fn the_4_2_1_rig_replays_step_for_step_and_bends_by_tens_of_degrees() {
    let replayed = check("wall_following_4_2_1", 3.0);
    assert!(replayed.max_bend_deg > 20.0, "{replayed:?}");
}

#[test]
fn the_4_2_2_sinusoid_rig_replays_step_for_step() {
    check("sinusoid_4_2_2", 3.0);
}

#[test]
fn the_trapezoid_rig_replays_step_for_step() {
    check("trapezoid_4_2_2", 3.0);
}

#[test]
fn the_digitized_wall_rig_replays_step_for_step() {
    check("digitized", 3.0);
}

#[test]
fn the_distal_hairs_on_a_rough_wall_rig_replays_step_for_step() {
    check("hairs_distal_rough", 3.0);
}
