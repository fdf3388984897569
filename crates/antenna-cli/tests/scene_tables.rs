//! The scene tables beyond docs/scene-format.md's core (`[antenna.hairs]`, `[[walls]]`,
//! `[[walls.zones]]`, `[sweep]`, `[start]`, `[contact]`, `[sensors]`): every error exits 2 with nothing on
//! stdout and names the file, the line and column, the key and the table, under both
//! `antenna solve` and `antenna sweep`; good tables reach sim-core as written.
#![allow(clippy::unwrap_used)]

mod common;

use antenna_scene::Scene;
use common::{WALL_SCENE, run, scratch, stderr, stdout};
use sim_core::contact::ContactSettings;
use sim_core::sweep::Placement;
use sim_core::{HairDirection, HairSide, Surface, WallShape, ZoneAxis};

/// Runs `text` (written to `name`) through `solve --json` and `sweep --jsonl`, checks the
/// bad-input contract of both, and returns the path and the message.
fn bad(name: &str, text: &str) -> (String, String) {
    let path = scratch(name, text);
    let mut message = String::new();
    for args in [
        vec!["solve", &path, "--json"],
        vec!["sweep", &path, "--jsonl"],
    ] {
        let out = run(&args);
        assert_eq!(
            out.status.code(),
            Some(2),
            "{name} {args:?}: {}",
            stderr(&out)
        );
        assert!(stdout(&out).is_empty(), "{name}: stdout {}", stdout(&out));
        message = stderr(&out);
    }
    (path, message)
}

fn expect(name: &str, text: &str, wanted: &str) {
    let (path, err) = bad(name, text);
    assert!(err.contains(&format!("{path}:{wanted}")), "{name}: {err}");
}

/// `WALL_SCENE` with `extra` appended.
fn with(extra: &str) -> String {
    format!("{WALL_SCENE}{extra}")
}

#[test]
fn the_wall_scene_parses_into_the_sweep_it_says() {
    let scene = Scene::parse(WALL_SCENE, "s.toml").unwrap();
    let sweep = scene.sweep_scene().unwrap();
    assert_eq!(sweep.walls.len(), 1);
    let WallShape::Line(line) = &sweep.walls[0].shape else {
        panic!("{:?}", sweep.walls[0].shape)
    };
    assert!((line.angle_rad() + 8f64.to_radians()).abs() < 1e-15);
    assert_eq!(line.point_m(), nalgebra::Vector2::new(0.0, 0.2));
    assert_eq!(sweep.walls[0].surfaces.first(), Surface::Smooth { mu: 0.3 });
    assert_eq!(sweep.motion.steps(), 20);
    assert_eq!(
        sweep.motion.velocity_m_per_s,
        nalgebra::Vector2::new(0.0167, 0.0)
    );
    assert!(matches!(
        sweep.placement,
        Placement::TipOnWall { wall: 0, ahead_m, .. } if ahead_m == 0.0
    ));
    assert_eq!(sweep.settings, ContactSettings::default());
    assert!(sweep.chain.hairs().iter().all(Option::is_none));
}

#[test]
fn hairs_zones_and_contact_settings_reach_sim_core() {
    let text = WALL_SCENE
        .replace(
            "[[walls]]",
            "[antenna.hairs]\nlinks = [5, 7, 8]\ndirection = \"proximal\"\nside = \"right\"\n\
             length_m = 0.03\nopen_angle_deg = 40.0\nlateral_offset_m = 0.004\n\
             preload_n_m = 2e-4\nstiffness_n_m_per_rad = 1e-4\n\
             root_stiffness_n_m_per_rad = 0.02\n\n[[walls]]",
        )
        .replace(
            "solid = \"left\"",
            "solid = \"left\"\nzones_along = \"x\"\n[[walls.zones]]\nfrom_m = 0.3\n\
             surface = \"rough\"\nmu = 0.5\nhold_shear_n = 0.1\nhold_tension_n = 0.02\n\
             [[walls.zones]]\nfrom_m = 0.6\nmu = 0.2\n",
        );
    let text = format!(
        "{text}\n[contact]\ntolerance_m = 1e-11\nmax_iterations = 80\nmax_substep_depth = 8\n\
         jump_deg = 2.0\nmargin_m = 0.003\n"
    );
    let scene = Scene::parse(&text, "s.toml").unwrap();
    let hairs = scene.chain.hairs();
    let with_hair: Vec<usize> = (0..hairs.len()).filter(|&i| hairs[i].is_some()).collect();
    assert_eq!(with_hair, [5, 7, 8]);
    let hair = hairs[7].unwrap();
    assert_eq!(hair.direction, HairDirection::Proximal);
    assert_eq!(hair.side, HairSide::Right);
    assert_eq!(hair.length_m, 0.03);
    assert!((hair.open_angle_rad - 40f64.to_radians()).abs() < 1e-15);
    assert_eq!(
        hair.pivot_from_distal_end_m, 0.02,
        "default: the middle of the link"
    );
    assert_eq!(hair.lateral_offset_m, 0.004);
    assert_eq!(hair.preload_nm, 2e-4);
    assert_eq!(hair.stiffness_nm_per_rad, 1e-4);
    assert_eq!(hair.root_stiffness_nm_per_rad, Some(0.02));
    assert_eq!(
        Scene::parse(
            WALL_SCENE
                .replace("[[walls]]", "[antenna.hairs]\n\n[[walls]]")
                .as_str(),
            "s.toml"
        )
        .unwrap()
        .chain
        .hairs()[1]
            .unwrap()
            .root_stiffness_nm_per_rad,
        None,
        "absent: a rigid hair"
    );
    let surfaces = &scene.walls[0].surfaces;
    assert_eq!(surfaces.axis(), ZoneAxis::WorldX);
    assert_eq!(
        surfaces.boundaries(),
        [
            (
                0.3,
                Surface::Rough {
                    mu: 0.5,
                    hold_shear_n: 0.1,
                    hold_tension_n: 0.02
                }
            ),
            (0.6, Surface::Smooth { mu: 0.2 })
        ]
    );
    let c = scene.contact;
    assert_eq!(
        (
            c.tolerance_m,
            c.max_iterations,
            c.max_substep_depth,
            c.margin_m
        ),
        (1e-11, 80, 8, 0.003)
    );
    assert!((c.jump_rad - 2f64.to_radians()).abs() < 1e-15);
}

#[test]
fn polyline_sinusoid_and_placements_parse() {
    let poly = WALL_SCENE.replace(
        "shape = \"line\"\npoint_m = [0.0, 0.2]\nangle_deg = -8.0",
        "shape = \"polyline\"\nvertices_m = [[0.0, 0.2], [0.2, 0.15], [0.4, 0.15], [0.6, 0.2]]",
    );
    let scene = Scene::parse(&poly, "s.toml").unwrap();
    assert!(matches!(&scene.walls[0].shape, WallShape::Polyline(p) if p.vertices_m().len() == 4));
    let sine = WALL_SCENE.replace(
        "angle_deg = -8.0",
        "angle_deg = 0.0\namplitude_m = 0.02\nfrequency_per_m = 5.0\nphase_deg = 90.0",
    );
    let sine = sine.replacen("shape = \"line\"", "shape = \"sinusoid\"", 1);
    let scene = Scene::parse(&sine, "s.toml").unwrap();
    let WallShape::Sinusoid(s) = &scene.walls[0].shape else {
        panic!()
    };
    assert_eq!((s.amplitude_m(), s.frequency_per_m()), (0.02, 5.0));
    assert!((s.phase_rad() - std::f64::consts::FRAC_PI_2).abs() < 1e-15);

    let approach = WALL_SCENE.replace(
        "placement = \"tip-on-wall\"\nahead_m = 0.0\nshape = \"C\"",
        "placement = \"approach\"\ndistance_m = 0.05\nsteps = 20",
    );
    let scene = Scene::parse(&approach, "s.toml").unwrap();
    assert_eq!(
        scene.placement,
        Placement::Approach {
            wall: 0,
            distance_m: 0.05,
            along_m: 0.0,
            steps: 20
        }
    );
    let angles = WALL_SCENE.replace(
        "placement = \"tip-on-wall\"\nahead_m = 0.0\nshape = \"C\"",
        "placement = \"angles\"\nangles_deg = [10, 10, 10, 10, 10, 10, 10, 10]",
    );
    let scene = Scene::parse(&angles, "s.toml").unwrap();
    assert_eq!(
        scene.placement,
        Placement::Angles(vec![10f64.to_radians(); 8])
    );
    let rest = WALL_SCENE.replace(
        "placement = \"tip-on-wall\"\nahead_m = 0.0\nshape = \"C\"",
        "placement = \"rest\"",
    );
    assert_eq!(
        Scene::parse(&rest, "s.toml").unwrap().placement,
        Placement::Rest
    );
}

#[test]
fn hairs_table_errors() {
    let hairs = |body: &str| {
        WALL_SCENE.replace(
            "[[walls]]",
            &format!("[antenna.hairs]\n{body}\n\n[[walls]]"),
        )
    };
    // [antenna.hairs] is line 11; its first key line 12.
    expect(
        "hairs_unknown.toml",
        &hairs("colour = 1"),
        "12:1: unknown key `colour` in [antenna.hairs]; allowed: links, direction, side, \
         length_m, open_angle_deg, pivot_from_distal_end_m, lateral_offset_m, preload_n_m, \
         stiffness_n_m_per_rad, root_stiffness_n_m_per_rad",
    );
    expect(
        "hairs_links.toml",
        &hairs("links = [1, 9]"),
        "12:9: `links` in [antenna.hairs]: link 9 is not a flagellar link (1..=8",
    );
    expect(
        "hairs_twice.toml",
        &hairs("links = [2, 2]"),
        "12:9: `links` in [antenna.hairs]: link 2 is listed twice",
    );
    expect(
        "hairs_direction.toml",
        &hairs("direction = \"up\""),
        "12:13: `direction` in [antenna.hairs]: \"up\" is not one of \"distal\", \"proximal\"",
    );
    expect(
        "hairs_side.toml",
        &hairs("side = \"top\""),
        "12:8: `side` in [antenna.hairs]: \"top\" is not one of \"left\", \"right\"",
    );
    expect(
        "hairs_length.toml",
        &hairs("length_m = 0.0"),
        "12:12: `length_m` in [antenna.hairs]: 0 must be > 0",
    );
    expect(
        "hairs_angle.toml",
        &hairs("open_angle_deg = 180.0"),
        "12:18: `open_angle_deg` in [antenna.hairs]: 180 must be below 180",
    );
    expect(
        "hairs_pivot.toml",
        &hairs("pivot_from_distal_end_m = 0.05"),
        "12:27: `pivot_from_distal_end_m` in [antenna.hairs]: 0.05 m is beyond the proximal end",
    );
    expect(
        "hairs_preload.toml",
        &hairs("preload_n_m = -1e-4"),
        "12:15: `preload_n_m` in [antenna.hairs]: -0.0001 must be >= 0",
    );
    expect(
        "hairs_root_zero.toml",
        &hairs("root_stiffness_n_m_per_rad = 0.0"),
        "12:30: `root_stiffness_n_m_per_rad` in [antenna.hairs]: 0 must be > 0",
    );
    expect(
        "hairs_root_negative.toml",
        &hairs("root_stiffness_n_m_per_rad = -0.01"),
        "12:30: `root_stiffness_n_m_per_rad` in [antenna.hairs]: -0.01 must be > 0",
    );
    expect(
        "hairs_root_nan.toml",
        &hairs("root_stiffness_n_m_per_rad = nan"),
        "12:30: `root_stiffness_n_m_per_rad` in [antenna.hairs]",
    );
}

#[test]
fn walls_table_errors() {
    expect(
        "wall_unknown.toml",
        &WALL_SCENE.replace("solid = \"left\"", "solid = \"left\"\nradius_m = 1.0"),
        "16:1: unknown key `radius_m` in [[walls]] (wall 0); allowed: shape, solid, point_m, \
         angle_deg, vertices_m, points_file, amplitude_m, frequency_per_m, phase_deg, surface, \
         mu, hold_shear_n, hold_tension_n, zones_along, zones",
    );
    expect(
        "wall_shape.toml",
        &WALL_SCENE.replace("shape = \"line\"", "shape = \"circle\""),
        "12:9: `shape` in [[walls]] (wall 0): \"circle\" is not one of \"line\", \"polyline\", \
         \"sinusoid\"",
    );
    expect(
        "wall_solid.toml",
        &WALL_SCENE.replace("solid = \"left\"", "solid = \"up\""),
        "15:9: `solid` in [[walls]] (wall 0): \"up\" is not one of \"left\", \"right\"",
    );
    expect(
        "wall_missing_solid.toml",
        &WALL_SCENE.replace("solid = \"left\"\n", ""),
        "11:1: missing key `solid` in [[walls]] (wall 0)",
    );
    expect(
        "wall_wrong_shape_key.toml",
        &WALL_SCENE.replace("angle_deg = -8.0", "amplitude_m = 0.01"),
        "14:15: `amplitude_m` in [[walls]] (wall 0): not a key of a line wall (it takes \
         point_m, angle_deg)",
    );
    expect(
        "wall_point.toml",
        &WALL_SCENE.replace("point_m = [0.0, 0.2]", "point_m = [0.0]"),
        "13:11: `point_m` in [[walls]] (wall 0): has 1 value(s); expected 2",
    );
    // A second wall is wall 1 in the messages.
    let second = WALL_SCENE.replace(
        "\n[sweep]",
        "\n[[walls]]\nshape = \"polyline\"\nvertices_m = [[0.0, 0.5], [0.1, 0.5], [0.0, 0.5]]\n\
         solid = \"left\"\n\n[sweep]",
    );
    expect(
        "wall_polyline.toml",
        &second,
        "19:14: `vertices_m` in [[walls]] (wall 1): polyline doubles back on itself at vertex 1",
    );
    expect(
        "wall_sinusoid.toml",
        &WALL_SCENE
            .replace("shape = \"line\"", "shape = \"sinusoid\"")
            .replace(
                "angle_deg = -8.0",
                "amplitude_m = 0.01\nfrequency_per_m = 0.0",
            ),
        "15:19: `frequency_per_m` in [[walls]] (wall 0): 0 must be > 0",
    );
    expect(
        "wall_rough.toml",
        &WALL_SCENE.replace(
            "solid = \"left\"",
            "solid = \"left\"\nsurface = \"rough\"\nhold_shear_n = 0.1",
        ),
        "11:1: missing key `hold_tension_n` in [[walls]] (wall 0)",
    );
    expect(
        "wall_smooth_hold.toml",
        &WALL_SCENE.replace("solid = \"left\"", "solid = \"left\"\nhold_shear_n = 0.1"),
        "16:16: `hold_shear_n` in [[walls]] (wall 0): not a key of a smooth surface",
    );
    expect(
        "wall_mu.toml",
        &WALL_SCENE.replace("solid = \"left\"", "solid = \"left\"\nmu = -0.1"),
        "16:6: `mu` in [[walls]] (wall 0): -0.1 must be >= 0",
    );
    expect(
        "wall_and_pin.toml",
        &with("\n[tip_pin]\nposition_m = [0.1, 0.2]\n"),
        "27:1: `tip_pin` and `walls` in the top level exclude each other",
    );
    expect(
        "wall_and_solver.toml",
        &with("\n[solver]\ninitial = \"C\"\n"),
        "27:1: `solver` in the top level: [solver] sets the equilibrium solver of scenes \
         without walls",
    );
}

#[test]
fn zones_table_errors() {
    let zones = |body: &str| {
        WALL_SCENE.replace(
            "solid = \"left\"",
            &format!("solid = \"left\"\n[[walls.zones]]\nfrom_m = 0.3\n{body}"),
        )
    };
    // [[walls.zones]] is line 16; from_m line 17; the body from line 18.
    expect(
        "zone_unknown.toml",
        &zones("to_m = 0.5"),
        "18:1: unknown key `to_m` in [[walls.zones]] (wall 0, zone 0); allowed: from_m, surface, \
         mu, hold_shear_n, hold_tension_n",
    );
    expect(
        "zone_surface.toml",
        &zones("surface = \"felt\""),
        "18:11: `surface` in [[walls.zones]] (wall 0, zone 0): \"felt\" is not one of \
         \"smooth\", \"rough\"",
    );
    expect(
        "zone_order.toml",
        &zones("[[walls.zones]]\nfrom_m = 0.1"),
        "19:10: `from_m` in [[walls.zones]] (wall 0, zone 1): 0.1 does not exceed the previous \
         zone's from_m (0.3)",
    );
    expect(
        "zone_missing.toml",
        &WALL_SCENE.replace(
            "solid = \"left\"",
            "solid = \"left\"\n[[walls.zones]]\nmu = 0.5",
        ),
        "16:1: missing key `from_m` in [[walls.zones]] (wall 0, zone 0)",
    );
    expect(
        "zone_axis.toml",
        &WALL_SCENE.replace("solid = \"left\"", "solid = \"left\"\nzones_along = \"y\""),
        "16:15: `zones_along` in [[walls]] (wall 0): \"y\" is not one of \"arclength\", \"x\"",
    );
}

#[test]
fn sweep_table_errors() {
    expect(
        "sweep_unknown.toml",
        &WALL_SCENE.replace("step_s = 0.01", "step_s = 0.01\nspeed = 1"),
        "21:1: unknown key `speed` in [sweep]; allowed: velocity_m_per_s, duration_s, step_s",
    );
    expect(
        "sweep_velocity.toml",
        &WALL_SCENE.replace("[0.0167, 0.0]", "[0.0167]"),
        "18:20: `velocity_m_per_s` in [sweep]: has 1 value(s); expected 2",
    );
    expect(
        "sweep_step.toml",
        &WALL_SCENE.replace("step_s = 0.01", "step_s = 0.0"),
        "20:10: `step_s` in [sweep]: 0 must be > 0",
    );
    expect(
        "sweep_duration.toml",
        &WALL_SCENE.replace("duration_s = 0.2", "duration_s = -1.0"),
        "19:14: `duration_s` in [sweep]: -1 must be >= 0",
    );
    expect(
        "sweep_steps.toml",
        &WALL_SCENE.replace("step_s = 0.01", "step_s = 1e-9"),
        "20:10: `step_s` in [sweep]: duration_s / step_s = 200000000 steps; at most 10000000",
    );
}

#[test]
fn start_table_errors() {
    let start = |body: &str| {
        WALL_SCENE.replace(
            "placement = \"tip-on-wall\"\nahead_m = 0.0\nshape = \"C\"",
            body,
        )
    };
    // [start] is line 22; its first key line 23.
    expect(
        "start_unknown.toml",
        &start("placement = \"rest\"\nhow = 1"),
        "24:1: unknown key `how` in [start]; allowed: placement, angles_deg, wall, distance_m, \
         along_m, steps, ahead_m, shape",
    );
    expect(
        "start_placement.toml",
        &start("placement = \"drop\""),
        "23:13: `placement` in [start]: \"drop\" is not one of \"rest\", \"angles\", \
         \"approach\", \"tip-on-wall\"",
    );
    expect(
        "start_wall.toml",
        &start("placement = \"approach\"\nwall = 3\ndistance_m = 0.05"),
        "24:8: `wall` in [start]: placement \"approach\" needs wall 3, but the scene has 1 \
         [[walls]] table(s)",
    );
    expect(
        "start_distance.toml",
        &start("placement = \"approach\""),
        "22:1: missing key `distance_m` in [start]",
    );
    expect(
        "start_steps.toml",
        &start("placement = \"approach\"\ndistance_m = 0.05\nsteps = 0"),
        "25:9: `steps` in [start]: 0 is out of range 1..=1000000",
    );
    expect(
        "start_foreign_key.toml",
        &start("placement = \"approach\"\ndistance_m = 0.05\nahead_m = 0.1"),
        "25:11: `ahead_m` in [start]: not a key of placement \"approach\" (it takes wall, \
         distance_m, along_m, steps)",
    );
    expect(
        "start_shape.toml",
        &start("placement = \"tip-on-wall\"\nshape = \"U\""),
        "24:9: `shape` in [start]: \"U\" is not one of \"straight\", \"C\", \"S\", \"mirror-C\", \
         \"mirror-S\"",
    );
    expect(
        "start_angles.toml",
        &start("placement = \"angles\"\nangles_deg = [1, 2]"),
        "24:14: `angles_deg` in [start]: has 2 value(s); expected 8",
    );
    expect(
        "start_angles_limits.toml",
        &start("placement = \"angles\"\nangles_deg = [0, 0, 0, 95, 0, 0, 0, 0]"),
        "24:14: `angles_deg` in [start]: angle #4 = 95 deg is outside the joint limits",
    );
    // A placement on a wall in a scene without walls.
    let no_walls = WALL_SCENE.replace(
        "[[walls]]\nshape = \"line\"\npoint_m = [0.0, 0.2]\nangle_deg = -8.0\nsolid = \"left\"\n",
        "",
    );
    let (path, err) = bad("start_no_walls.toml", &no_walls);
    assert!(
        err.contains(&format!(
            "{path}:18:13: `placement` in [start]: placement \"tip-on-wall\" needs wall 0, but \
             the scene has 0 [[walls]] table(s)"
        )),
        "{err}"
    );
}

#[test]
fn contact_table_errors() {
    expect(
        "contact_unknown.toml",
        &with("\n[contact]\ntolerance = 1e-9\n"),
        "28:1: unknown key `tolerance` in [contact]; allowed: tolerance_m, max_iterations, \
         max_substep_depth, jump_deg, margin_m",
    );
    expect(
        "contact_tolerance.toml",
        &with("\n[contact]\ntolerance_m = 0.0\n"),
        "28:15: `tolerance_m` in [contact]: 0 must be > 0",
    );
    expect(
        "contact_depth.toml",
        &with("\n[contact]\nmax_substep_depth = 41\n"),
        "28:21: `max_substep_depth` in [contact]: 41 is out of range 0..=40",
    );
    expect(
        "contact_iterations.toml",
        &with("\n[contact]\nmax_iterations = 0\n"),
        "28:18: `max_iterations` in [contact]: 0 is out of range 1..=1000000",
    );
    expect(
        "contact_jump.toml",
        &with("\n[contact]\njump_deg = -1.0\n"),
        "28:12: `jump_deg` in [contact]: -1 must be > 0",
    );
    expect(
        "contact_type.toml",
        &with("\n[contact]\nmargin_m = \"wide\"\n"),
        "28:12: `margin_m` in [contact]:",
    );
}

#[test]
fn sensors_table_reaches_the_settings() {
    use sim_core::{CalibrationError, SensorSettings};
    let scene = Scene::parse(WALL_SCENE, "s.toml").unwrap();
    assert_eq!(scene.sensors, SensorSettings::IDEAL);
    let scene = Scene::parse(
        &with(
            "\n[sensors]\nangle_noise_counts = 1\noffset_counts = 4.0\n\
             gain_error = [0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -0.02]\n\
             touch_threshold_n = 0.002\ntouch_debounce_samples = 3\nsample_rate_hz = 50\n\
             seed = 9\nhair_tip_points = true\n",
        ),
        "s.toml",
    )
    .unwrap();
    assert_eq!(
        scene.sensors,
        SensorSettings {
            angle_noise_counts: 1.0,
            offset_counts: CalibrationError::Spread(4.0),
            gain_error: CalibrationError::PerJoint(vec![0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -0.02]),
            touch_threshold_n: 0.002,
            touch_debounce_samples: 3,
            sample_rate_hz: Some(50.0),
            seed: 9,
            hair_tip_points: true,
        }
    );
    // An empty table is the ideal sensors.
    let scene = Scene::parse(&with("\n[sensors]\n"), "s.toml").unwrap();
    assert!(scene.sensors.is_ideal());
}

/// Issue #18: every bad `[sensors]` value is a located error at the value naming the key,
/// exit 2 from `solve` and `sweep` (and `study`, whose scene it is).
#[test]
fn sensors_table_errors() {
    expect(
        "sensors_unknown.toml",
        &with("\n[sensors]\nnoise_counts = 1.0\n"),
        "28:1: unknown key `noise_counts` in [sensors]; allowed: angle_noise_counts, \
         offset_counts, gain_error, touch_threshold_n, touch_debounce_samples, sample_rate_hz, \
         seed, hair_tip_points",
    );
    expect(
        "sensors_noise.toml",
        &with("\n[sensors]\nangle_noise_counts = -1.0\n"),
        "28:22: `angle_noise_counts` in [sensors]: -1 must be finite and at least 0",
    );
    expect(
        "sensors_noise_nan.toml",
        &with("\n[sensors]\nangle_noise_counts = nan\n"),
        "28:22: `angle_noise_counts` in [sensors]: NaN must be finite and at least 0",
    );
    expect(
        "sensors_threshold.toml",
        &with("\n[sensors]\nseed = 3\ntouch_threshold_n = -0.01\n"),
        "29:21: `touch_threshold_n` in [sensors]: -0.01 must be finite and at least 0",
    );
    expect(
        "sensors_debounce.toml",
        &with("\n[sensors]\ntouch_debounce_samples = 0\n"),
        "28:26: `touch_debounce_samples` in [sensors]: 0 is out of range 1..=1000000",
    );
    expect(
        "sensors_rate.toml",
        &with("\n[sensors]\nsample_rate_hz = 0\n"),
        "28:18: `sample_rate_hz` in [sensors]: 0 must be finite and above 0",
    );
    expect(
        "sensors_offset_length.toml",
        &with("\n[sensors]\noffset_counts = [1.0, -2.0]\n"),
        "28:17: `offset_counts` in [sensors]: has 2 value(s); expected 8 (one per flexible \
         joint, links - 1)",
    );
    expect(
        "sensors_offset_spread.toml",
        &with("\n[sensors]\noffset_counts = -4\n"),
        "28:17: `offset_counts` in [sensors]: -4 must be finite and at least 0",
    );
    expect(
        "sensors_gain.toml",
        &with("\n[sensors]\ngain_error = [0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0]\n"),
        "28:14: `gain_error` in [sensors]: has -1; every entry must be above -1",
    );
    expect(
        "sensors_gain_type.toml",
        &with("\n[sensors]\ngain_error = \"small\"\n"),
        "28:14: `gain_error` in [sensors]:",
    );
    expect(
        "sensors_seed.toml",
        &with("\n[sensors]\nseed = -3\n"),
        "28:8: `seed` in [sensors]: -3 must be >= 0",
    );
    expect(
        "sensors_seed_type.toml",
        &with("\n[sensors]\nseed = 1.5\n"),
        "28:8: `seed` in [sensors]:",
    );
}
