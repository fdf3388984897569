//! The closed loop (sim-core's `follow`): the template with an ideal preview settles on the
//! setpoint; a right-wall run is the mirror image of a left-wall run; the antenna's sensors
//! do not see the body's heading (a scene turned rigidly gives the same estimates); the
//! contact-line and bend estimators follow a straight wall with the thesis's antenna.

#![allow(clippy::unwrap_used)]

use nalgebra::{Rotation2, Vector2};
use sim_core::follow::{Estimator, Follow, FollowConfig, FollowError, FollowStep, WallSide};
use sim_core::sweep::{Placement, SweepScene};
use sim_core::{Chain, JointLimit, Line, SensorSettings, SolidSide, StiffnessProfile, Wall};

fn straight_wall(y_m: f64) -> Wall {
    Wall::smooth(Line::new(Vector2::new(0.0, y_m), 0.0, SolidSide::Left).unwrap())
}

fn ideal_config(speed_m_per_s: f64) -> FollowConfig {
    let mut c = FollowConfig::default();
    c.robot.speed_m_per_s = speed_m_per_s;
    c.controller.estimator = Estimator::IdealPreview { preview_m: 0.05 };
    c.controller.kd_n_s = 0.002;
    c.settings.duration_s = 15.0;
    c.settings.pose_m = Vector2::new(0.0, 0.08);
    c
}

fn run_all(mut run: Follow) -> (Vec<FollowStep>, sim_core::follow::FollowSummary) {
    let mut steps = Vec::new();
    while let Some(step) = run.next_step() {
        match step {
            Ok(s) => steps.push(s),
            Err(e) => panic!("{e}"),
        }
    }
    (steps, run.summary())
}

/// The thesis's 4.2.1 antenna: 9 links of 40 mm, fast-exponential stiffness 0.004-0.082
/// N m/rad, the base link at the mount angle.
fn antenna_scene(walls: Vec<Wall>, mount_angle_rad: f64) -> SweepScene {
    let k = StiffnessProfile::FastExponential
        .stiffness_n_m_per_rad(&[0.04; 9], 0.004, 0.082)
        .unwrap();
    let chain = Chain::builder(8)
        .link_length_m(0.04)
        .base_angle_rad(mount_angle_rad)
        .joint_limit(JointLimit::new(-1.5, 1.5))
        .stiffnesses_nm_per_rad(k)
        .build()
        .unwrap();
    SweepScene {
        placement: Placement::Approach {
            wall: 0,
            distance_m: 0.36,
            along_m: 0.0,
            steps: 180,
        },
        ..SweepScene::new(chain, walls)
    }
}

#[test]
fn the_template_with_an_ideal_preview_settles_on_the_setpoint() {
    let config = ideal_config(0.3);
    let run = Follow::without_antenna(vec![straight_wall(0.2)], &config).unwrap();
    let (steps, summary) = run_all(run);
    assert_eq!(summary.status.name(), "ok");
    assert_eq!(steps.len(), 1500);
    let last = steps.last().unwrap();
    // Started 0.12 m from the wall, it ends at the setpoint (0.10 m) within a millimetre.
    assert!(
        (last.wall_distance_m.unwrap() - 0.10).abs() < 1e-3,
        "{last:?}"
    );
    assert!(summary.settling_distance_m.is_some());
    assert_eq!(summary.collisions, 0);
    assert_eq!(summary.estimate_rms_error_m, Some(0.0));
}

#[test]
fn a_right_wall_run_is_the_mirror_image_of_a_left_wall_run() {
    let left = ideal_config(0.5);
    let mut right = left;
    right.robot.wall_side = WallSide::Right;
    right.settings.pose_m = Vector2::new(0.0, -0.08);
    let wall_right =
        Wall::smooth(Line::new(Vector2::new(0.0, -0.2), 0.0, SolidSide::Right).unwrap());
    let (a, _) = run_all(Follow::without_antenna(vec![straight_wall(0.2)], &left).unwrap());
    let (b, _) = run_all(Follow::without_antenna(vec![wall_right], &right).unwrap());
    assert_eq!(a.len(), b.len());
    for (a, b) in a.iter().zip(&b) {
        assert!((a.pose_m.x - b.pose_m.x).abs() < 1e-12);
        assert!((a.pose_m.y + b.pose_m.y).abs() < 1e-12);
        assert!((a.heading_rad + b.heading_rad).abs() < 1e-12);
        assert!((a.omega_rad_per_s - b.omega_rad_per_s).abs() < 1e-12);
    }
}

#[test]
fn a_footprint_in_a_wall_at_the_start_is_refused() {
    let mut config = ideal_config(0.3);
    config.settings.pose_m = Vector2::new(0.0, 0.18);
    match Follow::without_antenna(vec![straight_wall(0.2)], &config) {
        Err(FollowError::StartsInWall { wall: 0, depth_m }) => {
            assert!((depth_m - 0.01).abs() < 1e-9, "{depth_m}")
        }
        other => panic!("{:?}", other.err()),
    }
}

#[test]
fn the_contact_line_estimator_follows_a_straight_wall_with_the_thesis_antenna() {
    let mut config = FollowConfig::default();
    config.settings.duration_s = 3.0;
    config.settings.pose_m = Vector2::new(0.0, 0.10);
    let scene = antenna_scene(vec![straight_wall(0.2)], config.robot.mount_angle_rad);
    let run = Follow::new(&scene, &SensorSettings::IDEAL, &config).unwrap();
    let (steps, summary) = run_all(run);
    assert_eq!(summary.status.name(), "ok", "{summary:?}");
    assert!(summary.estimate_share > 0.9, "{summary:?}");
    assert!(summary.contact_share > 0.9, "{summary:?}");
    // The estimate of d at its preview is within 5 mm of the truth (the switches' spacing
    // and the fitted line).
    assert!(summary.estimate_rms_error_m.unwrap() < 5e-3, "{summary:?}");
    assert!(summary.max_error_m.unwrap() < 0.03, "{summary:?}");
    assert_eq!(steps.last().unwrap().theta_rad.len(), 9);
}

#[test]
fn the_sensors_do_not_see_the_heading_a_turned_scene_gives_the_same_estimates() {
    let angle = 0.7_f64;
    let mut config = FollowConfig::default();
    config.settings.duration_s = 1.0;
    config.settings.pose_m = Vector2::new(0.0, 0.10);
    let wall = straight_wall(0.2);
    let scene = antenna_scene(vec![wall], config.robot.mount_angle_rad);
    let turn = Rotation2::new(angle);
    let turned_wall =
        Wall::smooth(Line::new(turn * Vector2::new(0.0, 0.2), angle, SolidSide::Left).unwrap());
    let turned_scene = antenna_scene(vec![turned_wall], config.robot.mount_angle_rad);
    let mut turned = config;
    turned.settings.pose_m = turn * config.settings.pose_m;
    turned.settings.heading_rad = angle;
    let (a, _) = run_all(Follow::new(&scene, &SensorSettings::IDEAL, &config).unwrap());
    let (b, _) = run_all(Follow::new(&turned_scene, &SensorSettings::IDEAL, &turned).unwrap());
    assert_eq!(a.len(), b.len());
    let mut compared = 0;
    for (a, b) in a.iter().zip(&b) {
        assert_eq!(a.touch, b.touch, "t = {}", a.t_s);
        if let (Some(ea), Some(eb)) = (a.estimate, b.estimate) {
            assert!(
                (ea.distance_m - eb.distance_m).abs() < 1e-6,
                "t = {}",
                a.t_s
            );
            compared += 1;
        }
        assert!((b.heading_rad - a.heading_rad - angle).abs() < 1e-6);
    }
    assert!(compared > a.len() / 2, "{compared} of {}", a.len());
}

#[test]
fn the_bend_estimator_has_a_calibration_table_that_grows_with_distance() {
    let mut config = FollowConfig::default();
    config.controller.estimator = Estimator::Bend;
    config.settings.duration_s = 0.5;
    config.settings.pose_m = Vector2::new(0.0, 0.10);
    let scene = antenna_scene(vec![straight_wall(0.2)], config.robot.mount_angle_rad);
    let run = Follow::new(&scene, &SensorSettings::IDEAL, &config).unwrap();
    let table = run.bend_table().unwrap().clone();
    assert!(table.rows.len() >= 5, "{table:?}");
    let (_, summary) = run_all(run);
    assert!(summary.estimate_share > 0.5, "{summary:?}");
}

#[test]
fn a_robot_drifting_away_is_lost_beyond_three_setpoints_though_it_still_has_an_estimate() {
    let mut config = ideal_config(1.0);
    config.controller.kp_n = 0.0;
    config.controller.kd_n_s = 0.0;
    config.settings.heading_rad = -0.3;
    let (steps, summary) =
        run_all(Follow::without_antenna(vec![straight_wall(0.2)], &config).unwrap());
    assert_eq!(summary.status.name(), "lost");
    let last = steps.last().unwrap();
    assert!(last.estimate.is_some());
    assert!(last.wall_distance_m.unwrap() > 0.3);
    // It ended at the first step past 0.3 m: the one before was within.
    assert!(steps[steps.len() - 2].wall_distance_m.unwrap() <= 0.3);
    assert!(summary.duration_s < config.settings.lost_after_s);
}

#[test]
fn a_loop_unstable_at_its_step_ends_unstable_before_the_body_spins() {
    // The derivative term held over a step: Kd l h / J = 5 is beyond what a held command
    // can take, and the turning rate doubles from step to step.
    let mut config = ideal_config(0.5);
    config.controller.kd_n_s = 2.0;
    config.settings.step_s = 0.01;
    let (steps, summary) =
        run_all(Follow::without_antenna(vec![straight_wall(0.2)], &config).unwrap());
    assert_eq!(summary.status.name(), "unstable");
    assert!(steps.len() < 1500);
    assert!(
        steps
            .windows(2)
            .all(|w| (w[1].heading_rad - w[0].heading_rad).abs()
                <= sim_core::follow::MAX_TURN_PER_STEP_RAD)
    );
}

#[test]
fn with_antenna_loads_body_the_antennas_moment_turns_the_body() {
    let mut config = FollowConfig::default();
    config.settings.duration_s = 1.0;
    config.settings.pose_m = Vector2::new(0.0, 0.10);
    let scene = antenna_scene(vec![straight_wall(0.2)], config.robot.mount_angle_rad);
    let (free, _) = run_all(Follow::new(&scene, &SensorSettings::IDEAL, &config).unwrap());
    let mut loaded_config = config;
    loaded_config.robot.antenna_loads_body = true;
    let (loaded, _) = run_all(Follow::new(&scene, &SensorSettings::IDEAL, &loaded_config).unwrap());
    // The wall pushes the antenna back and away: about the point of rotation, a moment
    // that turns the body away from the wall (positive), reported either way.
    let moment = free[0].antenna_moment_n_m;
    assert!(moment > 0.0, "{moment}");
    assert_eq!(loaded[0].antenna_moment_n_m, moment);
    // Only the loaded body turns by it: the same first command, then different paths.
    assert_eq!(free[0].command, loaded[0].command);
    assert!(loaded[1].omega_rad_per_s > free[1].omega_rad_per_s);
}
