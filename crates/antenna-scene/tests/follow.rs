//! Follow scenes (issue #47): `[robot]`, `[controller]`, `[follow]`, their defaults, the
//! sweep parts of a follow scene, and every bad input located at its key.

use std::path::Path;

use antenna_scene::{Location, Scene, SceneErrorKind};
use nalgebra::Vector2;
use sim_core::follow::{BodyModel, Estimator, FollowConfig, FollowError, WallSide};
use sim_core::sweep::{Placement, Sweep};

/// The antenna and the wall of a follow scene, without the follow tables.
const ANTENNA: &str = r#"[antenna]
links = 9
link_length_m = 0.04

[antenna.stiffness]
profile = "fast-exponential"
min_n_m_per_rad = 0.004
max_n_m_per_rad = 0.082

[[walls]]
shape = "line"
point_m = [0.0, 0.2]
solid = "left"
"#;

/// The issue's example tables (line 15 is `[robot]`).
const TABLES: &str = r#"[robot]
speed_m_per_s = 0.3
inertia_kg_m2 = 2.0e-4
damping_n_m_s_per_rad = 4.0e-3
footprint_m = [0.12, 0.06]
mount_m = [0.04, 0.02]
mount_angle_deg = 30.0
[controller]
estimator = "contact-line"
setpoint_m = 0.10
kp_n = 0.05
kd_n_s = 0.002
delay_s = 0.0
[follow]
duration_s = 10.0
step_s = 0.01
pose_m = [0.0, 0.12]
heading_deg = 0.0
"#;

fn scene(text: &str) -> Scene {
    match Scene::parse(text, "f.toml") {
        Ok(scene) => scene,
        Err(e) => panic!("{e}\n{text}"),
    }
}

fn err(text: &str) -> String {
    match Scene::parse(text, "f.toml") {
        Ok(_) => panic!("parsed:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// The 1-based line and column where `needle` starts in `text`.
fn at(text: &str, needle: &str) -> String {
    let offset = text
        .find(needle)
        .unwrap_or_else(|| panic!("{needle:?} not in the text"));
    let l = Location::of_offset(text, offset);
    format!("f.toml:{}:{}:", l.line, l.column)
}

fn full() -> String {
    format!("{ANTENNA}{TABLES}")
}

/// `full()` with `old` replaced by `new` (which must occur).
fn with(old: &str, new: &str) -> String {
    let text = full();
    assert!(text.contains(old), "{old:?}");
    text.replacen(old, new, 1)
}

#[test]
fn the_issues_example_reads_into_the_follow_config() {
    let s = scene(&full());
    let f = s.follow.as_ref().expect("a follow scene");
    let c = &f.config;
    assert_eq!(c.robot.speed_m_per_s, 0.3);
    assert_eq!(
        c.robot.body,
        BodyModel::Template {
            inertia_kg_m2: 2.0e-4,
            damping_n_m_s_per_rad: 4.0e-3
        }
    );
    assert_eq!(c.robot.footprint_m, [0.12, 0.06]);
    assert_eq!(c.robot.mount_m, Vector2::new(0.04, 0.02));
    assert!((c.robot.mount_angle_rad - 30f64.to_radians()).abs() < 1e-15);
    assert_eq!(c.robot.wall_side, WallSide::Left);
    assert_eq!(
        c.controller.estimator,
        Estimator::ContactLine { window_s: 0.5 }
    );
    assert_eq!(c.settings.pose_m, Vector2::new(0.0, 0.12));
    assert_eq!(c.validate(), Ok(()));
    // The chain's base angle is the mount angle; the base starts at the mount.
    assert!((s.chain.base_angle_rad() - 30f64.to_radians()).abs() < 1e-15);
    assert!((s.base_position_m - Vector2::new(0.04, 0.14)).norm() < 1e-15);
    // Where the keys are.
    let text = full();
    let pose = f.locations.keys.get("follow.pose_m").copied();
    let expected = Location::of_offset(&text, text.find("[0.0, 0.12]").unwrap_or(0));
    assert_eq!(pose, Some(expected));
}

#[test]
fn any_one_follow_table_makes_a_follow_scene_with_defaults() {
    for table in ["[robot]\n", "[controller]\n", "[follow]\n"] {
        let s = scene(&format!("{ANTENNA}{table}"));
        let f = s.follow.as_ref().expect("a follow scene");
        assert_eq!(f.config, FollowConfig::default(), "{table}");
        let (sweep, config, sensors) = s.follow_parts().expect("follow parts");
        assert_eq!(config, FollowConfig::default());
        assert_eq!(sensors, sim_core::SensorSettings::IDEAL);
        assert_eq!(sweep.walls.len(), 1);
        // The default placement: an approach onto wall 0 from as far back as the antenna
        // is long, at most antenna_step_m (2 mm) per step.
        assert_eq!(
            sweep.placement,
            Placement::Approach {
                wall: 0,
                distance_m: s.chain.total_length_m(),
                along_m: 0.0,
                steps: 180,
            }
        );
        // The open-loop motion: the robot's speed along its heading, for the run.
        assert_eq!(sweep.motion.velocity_m_per_s, Vector2::new(0.3, 0.0));
        assert_eq!(sweep.motion.steps(), 1000);
    }
    // Without any of them: not a follow scene.
    let s = scene(ANTENNA);
    assert!(s.follow.is_none());
    let e = s.follow_parts().expect_err("not a follow scene");
    assert_eq!(
        e.to_string(),
        "f.toml: no [follow] table: not a follow scene"
    );
}

#[test]
fn a_follow_scene_sweeps_from_its_default_approach() {
    let s = scene(&full());
    let (sweep_scene, _, _) = s.follow_parts().expect("follow parts");
    let sweep = Sweep::new(sweep_scene).expect("the default approach places the antenna");
    assert!(
        !sweep.sim().contacts().is_empty(),
        "the approach brings the antenna onto the wall"
    );
}

#[test]
fn a_written_start_is_kept() {
    let text = format!("{}[start]\nplacement = \"tip-on-wall\"\n", full());
    let s = scene(&text);
    assert!(matches!(s.placement, Placement::TipOnWall { wall: 0, .. }));
}

#[test]
fn the_wheeled_body_and_the_other_estimators() {
    let text = with(
        "inertia_kg_m2 = 2.0e-4\ndamping_n_m_s_per_rad = 4.0e-3\n",
        "body = \"wheeled\"\nmax_turn_rate_deg_per_s = 90.0\nwall_side = \"right\"\n",
    )
    .replace(
        "kp_n = 0.05\nkd_n_s = 0.002\n",
        "kp_rad_per_s_per_m = 30.0\nkd_rad_per_m = 1.5\n",
    )
    .replace("\"contact-line\"", "\"ideal-preview\"\npreview_m = 0.05");
    let s = scene(&text);
    let c = s.follow.as_ref().expect("follow").config;
    assert_eq!(
        c.robot.body,
        BodyModel::Wheeled {
            max_turn_rate_rad_per_s: 90f64.to_radians(),
            max_turn_accel_rad_per_s2: 720f64.to_radians(),
        }
    );
    assert_eq!(c.robot.wall_side, WallSide::Right);
    assert_eq!(c.controller.kp_rad_per_s_per_m, 30.0);
    assert_eq!(c.controller.kd_rad_per_m, 1.5);
    assert_eq!(
        c.controller.estimator,
        Estimator::IdealPreview { preview_m: 0.05 }
    );
    // The mount is toward the wall: on the right, -y.
    assert!((s.base_position_m - Vector2::new(0.04, 0.10)).norm() < 1e-15);
    let bend = scene(&with("\"contact-line\"", "\"bend\""));
    assert_eq!(
        bend.follow
            .as_ref()
            .expect("follow")
            .config
            .controller
            .estimator,
        Estimator::Bend
    );
}

#[test]
fn the_example_scene_parses() {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/follow/straight_wall.toml");
    let s = Scene::from_path(&path).unwrap_or_else(|e| panic!("{e}"));
    let (sweep, config, sensors) = s.follow_parts().unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.n(), 8);
    assert_eq!(sweep.walls.len(), 1);
    assert_eq!(config.robot.speed_m_per_s, 0.3);
    assert_eq!(config.settings.pose_m, Vector2::new(0.0, 0.12));
    assert_eq!(config.controller.setpoint_m, 0.10);
    assert_eq!(sensors.sample_rate_hz, Some(100.0));
    assert!((s.chain.base_angle_rad() - 30f64.to_radians()).abs() < 1e-15);
}

// ---------------------------------------------------------------------------------------
// Bad input, each at its key.

#[test]
fn negative_speed_and_inertia() {
    let text = with("speed_m_per_s = 0.3", "speed_m_per_s = -0.3");
    let e = err(&text);
    let want = format!(
        "{} `speed_m_per_s` in [robot]: -0.3 must be > 0",
        at(&text, "-0.3")
    );
    assert_eq!(e, want);
    let text = with("inertia_kg_m2 = 2.0e-4", "inertia_kg_m2 = -2.0e-4");
    let e = err(&text);
    assert!(
        e.starts_with(&format!(
            "{} `inertia_kg_m2` in [robot]:",
            at(&text, "-2.0e-4")
        )),
        "{e}"
    );
}

#[test]
fn nan_gains() {
    for key in ["kp_n", "kd_n_s"] {
        let text = full().replace(&format!("{key} = "), &format!("{key} = nan #"));
        let e = err(&text);
        let want = format!(
            "{} `{key}` in [controller]: NaN is not a finite number",
            at(&text, "nan #")
        );
        assert_eq!(e, want);
    }
}

#[test]
fn negative_delay() {
    let text = with("delay_s = 0.0", "delay_s = -0.01");
    let e = err(&text);
    assert_eq!(
        e,
        format!(
            "{} `delay_s` in [controller]: -0.01 must be >= 0",
            at(&text, "-0.01")
        )
    );
}

#[test]
fn an_unknown_estimator_lists_the_names() {
    let text = with("\"contact-line\"", "\"whiskers\"");
    let e = err(&text);
    assert_eq!(
        e,
        format!(
            "{} `estimator` in [controller]: \"whiskers\" is not one of \"contact-line\", \
             \"bend\", \"ideal-preview\"",
            at(&text, "\"whiskers\"")
        )
    );
}

#[test]
fn estimator_keys_of_another_estimator() {
    let text = with("setpoint_m = 0.10", "preview_m = 0.05\nsetpoint_m = 0.10");
    let e = err(&text);
    assert_eq!(
        e,
        format!(
            "{} `preview_m` in [controller]: only estimator \"ideal-preview\" takes preview_m; \
             this is estimator \"contact-line\" (it takes window_s)",
            at(&text, "0.05\nsetpoint")
        )
    );
    let text = with("\"contact-line\"", "\"bend\"\nwindow_s = 0.3");
    let e = err(&text);
    assert_eq!(
        e,
        format!(
            "{} `window_s` in [controller]: only estimator \"contact-line\" takes window_s; \
             this is estimator \"bend\" (it takes neither window_s nor preview_m)",
            at(&text, "0.3\nsetpoint")
        )
    );
    let text = with("\"contact-line\"", "\"ideal-preview\"");
    let e = err(&text);
    assert!(
        e.starts_with(&format!(
            "{} `preview_m` in [controller]: estimator \"ideal-preview\" needs preview_m",
            at(&text, "\"ideal-preview\"")
        )),
        "{e}"
    );
}

#[test]
fn body_keys_of_the_other_body() {
    let text = with(
        "speed_m_per_s = 0.3",
        "speed_m_per_s = 0.3\nbody = \"wheeled\"",
    );
    let e = err(&text);
    assert_eq!(
        e,
        format!(
            "{} `inertia_kg_m2` in [robot]: not a key of body \"wheeled\" (it takes \
             max_turn_rate_deg_per_s, max_turn_accel_deg_per_s2)",
            at(&text, "2.0e-4")
        )
    );
    let text = with(
        "mount_angle_deg = 30.0",
        "mount_angle_deg = 30.0\nmax_turn_accel_deg_per_s2 = 100.0",
    );
    let e = err(&text);
    assert_eq!(
        e,
        format!(
            "{} `max_turn_accel_deg_per_s2` in [robot]: not a key of body \"template\" (it \
             takes inertia_kg_m2, damping_n_m_s_per_rad)",
            at(&text, "100.0")
        )
    );
    let e = err(&with(
        "speed_m_per_s = 0.3",
        "speed_m_per_s = 0.3\nbody = \"tank\"",
    ));
    assert!(
        e.contains("`body` in [robot]: \"tank\" is not one of \"template\", \"wheeled\""),
        "{e}"
    );
}

#[test]
fn gains_of_the_other_body() {
    let text = with(
        "kd_n_s = 0.002",
        "kd_n_s = 0.002\nkp_rad_per_s_per_m = 40.0",
    );
    let e = err(&text);
    assert_eq!(
        e,
        format!(
            "{} `kp_rad_per_s_per_m` in [controller]: the wheeled body's gain (a turning \
             rate); [robot] body = \"template\" takes the gains kp_n, kd_n_s",
            at(&text, "40.0")
        )
    );
    let text = with(
        "inertia_kg_m2 = 2.0e-4\ndamping_n_m_s_per_rad = 4.0e-3\n",
        "body = \"wheeled\"\n",
    );
    let e = err(&text);
    assert_eq!(
        e,
        format!(
            "{} `kp_n` in [controller]: the template body's gain (a moment); [robot] body = \
             \"wheeled\" takes the gains kp_rad_per_s_per_m, kd_rad_per_m",
            at(&text, "0.05\nkd_n_s")
        )
    );
}

#[test]
fn tables_a_follow_scene_refuses_say_why() {
    let text = format!("{}[sweep]\nduration_s = 1.0\n", full());
    let e = err(&text);
    assert!(
        e.starts_with(&format!(
            "{} `sweep` in the top level: refused in a follow scene ([robot], [controller], \
             [follow]): a follow scene's robot moves by itself",
            at(&text, "[sweep]")
        )),
        "{e}"
    );
    let text = format!("{}[base]\nposition_m = [0.0, 0.0]\n", full());
    let e = err(&text);
    assert!(
        e.starts_with(&format!(
            "{} `base` in the top level: refused in a follow scene",
            at(&text, "[base]")
        )) && e
            .contains("[robot] mount_m puts it on the body and [follow] pose_m places the robot"),
        "{e}"
    );
    let text = format!("{}[tip_pin]\nposition_m = [0.2, 0.1]\n", full());
    let e = err(&text);
    assert!(
        e.starts_with(&format!(
            "{} `tip_pin` in the top level: refused in a follow scene",
            at(&text, "[tip_pin]")
        )),
        "{e}"
    );
    let text = full().replace("links = 9\n", "links = 9\nbase_angle_deg = 30.0\n");
    let e = err(&text);
    assert!(
        e.starts_with(&format!(
            "{} `base_angle_deg` in [antenna]: refused in a follow scene ([robot], \
             [controller], [follow]): [robot] mount_angle_deg sets the base angle",
            at(&text, "30.0\nlink_length_m")
        )),
        "{e}"
    );
    // Without the follow tables the same tables are fine.
    scene(&format!(
        "{ANTENNA}[sweep]\nduration_s = 1.0\n[base]\nposition_m = [0.0, 0.0]\n"
    ));
}

#[test]
fn a_follow_scene_needs_a_wall() {
    let text = format!(
        "{}{TABLES}",
        ANTENNA.split("[[walls]]").next().unwrap_or_default()
    );
    let e = err(&text);
    assert!(
        e.starts_with(&format!(
            "{} `walls` in the top level: a follow scene ([robot], [controller], [follow]) \
             needs at least one [[walls]] table",
            at(&text, "[robot]")
        )),
        "{e}"
    );
}

#[test]
fn unknown_keys_list_the_tables_keys() {
    let text = with(
        "heading_deg = 0.0",
        "heading_deg = 0.0\nspeed_m_per_s = 1.0",
    );
    let e = err(&text);
    assert_eq!(
        e,
        format!(
            "{} unknown key `speed_m_per_s` in [follow]; allowed: duration_s, step_s, pose_m, \
             heading_deg, lost_after_s, lost_beyond_m, settling_window_m, settling_band_m, \
             antenna_step_m",
            at(&text, "speed_m_per_s = 1.0")
        )
    );
    let text = with("kp_n = 0.05", "kp = 0.05");
    let e = err(&text);
    assert!(
        e.starts_with(&format!(
            "{} unknown key `kp` in [controller]; allowed: estimator, window_s, preview_m,",
            at(&text, "kp = ")
        )),
        "{e}"
    );
    let text = with("mount_m", "mount_at_m");
    let e = err(&text);
    assert!(
        e.contains("unknown key `mount_at_m` in [robot]; allowed: speed_m_per_s, body,"),
        "{e}"
    );
}

#[test]
fn other_values_at_their_keys() {
    for (old, new, key, table, value) in [
        (
            "pose_m = [0.0, 0.12]",
            "pose_m = [0.0]",
            "pose_m",
            "[follow]",
            "[0.0]",
        ),
        (
            "step_s = 0.01",
            "step_s = 0.0001",
            "step_s",
            "[follow]",
            "0.0001",
        ),
        (
            "duration_s = 10.0",
            "duration_s = 0.0",
            "duration_s",
            "[follow]",
            "0.0\nstep_s",
        ),
        (
            "footprint_m = [0.12, 0.06]",
            "footprint_m = [0.12, -0.06]",
            "footprint_m",
            "[robot]",
            "[0.12, -0.06]",
        ),
        (
            "mount_angle_deg = 30.0",
            "mount_angle_deg = 200.0",
            "mount_angle_deg",
            "[robot]",
            "200.0",
        ),
        (
            "setpoint_m = 0.10",
            "setpoint_m = 0.0",
            "setpoint_m",
            "[controller]",
            "0.0\nkp_n",
        ),
        (
            "heading_deg = 0.0",
            "heading_deg = inf",
            "heading_deg",
            "[follow]",
            "inf",
        ),
    ] {
        let text = with(old, new);
        let e = err(&text);
        assert!(
            e.starts_with(&format!("{} `{key}` in {table}:", at(&text, value))),
            "{new}: {e}"
        );
    }
    // step_s's range is sim-core's (FollowConfig::validate), put at the key.
    let e = err(&with("step_s = 0.01", "step_s = 0.0001"));
    assert!(
        e.contains("must be within 0.0005 to 0.05 s, not 0.0001"),
        "{e}"
    );
    let e = err(&with(
        "mount_angle_deg = 30.0",
        "mount_angle_deg = 30.0\nwall_side = \"up\"",
    ));
    assert!(
        e.contains("`wall_side` in [robot]: \"up\" is not one of \"left\", \"right\""),
        "{e}"
    );
}

#[test]
fn run_errors_are_put_at_their_keys() {
    let text = full();
    let s = scene(&text);
    let f = s.follow.as_ref().expect("follow");
    // A footprint in a wall at the start: at [follow] pose_m.
    let e = f.locate(&FollowError::StartsInWall {
        wall: 0,
        depth_m: 0.01,
    });
    assert_eq!(
        e.location,
        Some(Location::of_offset(
            &text,
            text.find("[0.0, 0.12]").unwrap_or(0)
        ))
    );
    let message = e.to_string();
    assert!(
        message.starts_with(&format!(
            "{} `pose_m` in [follow]: the robot's footprint overlaps wall 0",
            at(&text, "[0.0, 0.12]")
        )),
        "{message}"
    );
    // A value sim-core refuses: at its key, or its table where the key is not written.
    let e = f.locate(&FollowError::Invalid {
        table: "controller",
        key: "kd_n_s",
        reason: "too big".to_string(),
    });
    assert_eq!(
        e.to_string(),
        format!("{} `kd_n_s` in [controller]: too big", at(&text, "0.002"))
    );
    let e = f.locate(&FollowError::Invalid {
        table: "follow",
        key: "lost_after_s",
        reason: "too small".to_string(),
    });
    assert_eq!(
        e.to_string(),
        format!(
            "{} `lost_after_s` in [follow]: too small",
            at(&text, "[follow]")
        )
    );
    // A step the solver refused has no key.
    let e = f.locate(&FollowError::Sensors("broken".to_string()));
    assert!(matches!(*e.kind, SceneErrorKind::Run { .. }));
    assert_eq!(e.to_string(), "f.toml: the sensors: broken");
}

#[test]
fn a_failed_placement_is_put_at_start_or_at_the_pose() {
    let error =
        FollowError::Placement(sim_core::sweep::SweepError::Placement("jammed".to_string()));
    // The default approach: at [follow] pose_m, saying it was the default.
    let text = full();
    let s = scene(&text);
    let e = s
        .follow
        .as_ref()
        .expect("follow")
        .locate(&error)
        .to_string();
    assert!(
        e.starts_with(&format!(
            "{} `pose_m` in [follow]: the default placement of a follow scene (an approach \
             onto wall 0) failed:",
            at(&text, "[0.0, 0.12]")
        )),
        "{e}"
    );
    // A written [start]: at its placement.
    let text = format!("{}[start]\nplacement = \"tip-on-wall\"\n", full());
    let s = scene(&text);
    let e = s
        .follow
        .as_ref()
        .expect("follow")
        .locate(&error)
        .to_string();
    assert!(
        e.starts_with(&format!(
            "{} `placement` in [start]:",
            at(&text, "\"tip-on-wall\"")
        )),
        "{e}"
    );
}

#[test]
fn the_mount_turns_with_the_heading_and_the_wall_side() {
    let text = with("heading_deg = 0.0", "heading_deg = 90.0");
    let s = scene(&text);
    // Heading +y: ahead is +y, the wall's side (left) is -x.
    assert!((s.base_position_m - Vector2::new(-0.02, 0.12 + 0.04)).norm() < 1e-12);
    let f = s.follow.as_ref().expect("follow");
    assert!((f.open_loop_motion().velocity_m_per_s - Vector2::new(0.0, 0.3)).norm() < 1e-12);
    let s = scene(&text.replace(
        "mount_angle_deg = 30.0",
        "mount_angle_deg = 30.0\nwall_side = \"right\"",
    ));
    assert!((s.base_position_m - Vector2::new(0.02, 0.12 + 0.04)).norm() < 1e-12);
    // The chain's base angle is the mount angle whatever the heading.
    assert!((s.chain.base_angle_rad() - 30f64.to_radians()).abs() < 1e-15);
}
