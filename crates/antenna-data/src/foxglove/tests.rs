//! The frames against forward kinematics computed independently, the scene's switches against
//! the touch bits, and the encoding's round trip.
#![allow(clippy::unwrap_used)]

use std::collections::BTreeMap;

use foxglove::Decode;
use foxglove::messages::{FrameTransform, FrameTransforms, SceneUpdate};

use super::*;

/// A 2-D rigid transform: `(x, y, angle)`.
type Rigid = (f64, f64, f64);

fn rigid(t: &FrameTransform) -> Rigid {
    let v = t.translation.unwrap();
    let q = t.rotation.unwrap();
    assert_eq!((v.z, q.x, q.y), (0.0, 0.0, 0.0), "a planar transform");
    (v.x, v.y, 2.0 * q.z.atan2(q.w))
}

fn compose((x, y, a): Rigid, (cx, cy, ca): Rigid) -> Rigid {
    let (s, c) = a.sin_cos();
    (x + c * cx - s * cy, y + s * cx + c * cy, a + ca)
}

/// The pose of `frame` in `world`, by walking its parents in `transforms`.
fn in_world(transforms: &FrameTransforms, frame: &str) -> Rigid {
    let by_child: BTreeMap<&str, &FrameTransform> = transforms
        .transforms
        .iter()
        .map(|t| (t.child_frame_id.as_str(), t))
        .collect();
    let mut chain = Vec::new();
    let mut at = frame;
    while at != WORLD_FRAME {
        let t = by_child[at];
        chain.push(rigid(t));
        at = t.parent_frame_id.as_str();
    }
    chain
        .iter()
        .rev()
        .fold((0.0, 0.0, 0.0), |acc, &t| compose(acc, t))
}

fn model() -> ChainModel {
    ChainModel {
        link_lengths_m: vec![0.05, 0.04, 0.035, 0.03, 0.025],
        base_mount_angle_rad: 0.5,
        origin_m: [0.2, -0.1],
        travel_angle_rad: 0.3,
        walls_m: vec![vec![[0.0, 0.2], [1.0, 0.25], [2.0, 0.2]], vec![[0.0, 0.0]]],
    }
}

#[test]
fn the_last_link_ends_where_forward_kinematics_puts_the_tip() {
    let model = model();
    let joints = [Some(0.2), Some(-0.35), Some(0.1), Some(0.6)];
    let (stage_m, servo_rad) = (0.37, -0.15);
    let pose = ChainPose {
        t_ns: 1_795_000_000_250_000_000,
        stage_m: Some(stage_m),
        servo_rad: Some(servo_rad),
        joint_angles_rad: &joints,
        touch_bits: &[None; 4],
    };
    let transforms = frame_transforms(&model, &pose);
    assert_eq!(transforms.transforms.len(), 6);

    // Independently: phi_k = travel + mount + servo + theta_1 + ... + theta_k.
    let mut phi = model.travel_angle_rad + model.base_mount_angle_rad + servo_rad;
    let mut tip = [
        model.origin_m[0] + stage_m * model.travel_angle_rad.cos(),
        model.origin_m[1] + stage_m * model.travel_angle_rad.sin(),
    ];
    for (k, &length_m) in model.link_lengths_m.iter().enumerate() {
        if k >= 1 {
            phi += joints[k - 1].unwrap();
        }
        tip[0] += length_m * phi.cos();
        tip[1] += length_m * phi.sin();
    }
    let n = model.link_lengths_m.len() - 1;
    let end = compose(
        in_world(&transforms, &link_frame_id(n)),
        (model.link_lengths_m[n], 0.0, 0.0),
    );
    assert!((end.0 - tip[0]).abs() < 1e-12, "{end:?} vs {tip:?}");
    assert!((end.1 - tip[1]).abs() < 1e-12, "{end:?} vs {tip:?}");
    assert!((end.2 - phi).abs() < 1e-12);
    for t in &transforms.transforms {
        let stamp = t.timestamp.unwrap();
        assert_eq!((stamp.sec(), stamp.nsec()), (1_795_000_000, 250_000_000));
    }
}

#[test]
fn a_missing_reading_leaves_out_only_its_own_transform() {
    let model = model();
    let joints = [Some(0.2), None, Some(0.1), Some(f64::NAN)];
    let pose = ChainPose {
        t_ns: 5,
        stage_m: None,
        servo_rad: Some(0.0),
        joint_angles_rad: &joints,
        touch_bits: &[],
    };
    let children: Vec<String> = frame_transforms(&model, &pose)
        .transforms
        .into_iter()
        .map(|t| t.child_frame_id)
        .collect();
    assert_eq!(children, ["link_0", "link_1", "link_3"]);
}

#[test]
fn touch_switches_are_coloured_exactly_where_the_bits_are_set() {
    let model = model();
    let touch = [Some(0b0000), Some(0b1001), None, Some(0b0110)];
    let pose = ChainPose {
        t_ns: 7,
        stage_m: Some(0.0),
        servo_rad: Some(0.0),
        joint_angles_rad: &[Some(0.0); 4],
        touch_bits: &touch,
    };
    let estimate = EstimatedWall {
        distance_m: 0.1,
        wall_angle_rad: Some(0.2),
        preview_m: 0.05,
        wall_on_left: false,
    };
    let update = scene_update(&model, &pose, Some(&estimate));
    assert!(update.deletions.is_empty());
    let by_id: BTreeMap<&str, _> = update.entities.iter().map(|e| (e.id.as_str(), e)).collect();
    let mut ids: Vec<&str> = by_id.keys().copied().collect();
    ids.sort_unstable();
    assert_eq!(
        ids,
        [
            "estimated_wall",
            "link_0",
            "link_1",
            "link_2",
            "link_3",
            "link_4",
            "wall_0"
        ]
    );
    assert!(
        by_id["link_0"].spheres.is_empty(),
        "the base link has no switches"
    );
    for (k, &length_m) in model.link_lengths_m.iter().enumerate() {
        let e = by_id[link_entity_id(k).as_str()];
        assert_eq!(e.frame_id, link_frame_id(k));
        assert!(e.frame_locked);
        let ends: Vec<(f64, f64)> = e.lines[0].points.iter().map(|p| (p.x, p.y)).collect();
        assert_eq!(ends, [(0.0, 0.0), (length_m, 0.0)]);
        if k == 0 {
            continue;
        }
        assert_eq!(e.spheres.len(), 4);
        for (j, sphere) in e.spheres.iter().enumerate() {
            let at = sphere.pose.unwrap().position.unwrap();
            assert!((at.x - length_m * (2 * j + 1) as f64 / 8.0).abs() < 1e-15);
            let want = match touch[k - 1] {
                None => SWITCH_UNKNOWN_COLOR,
                Some(bits) if (bits >> j) & 1 == 1 => SWITCH_CLOSED_COLOR,
                Some(_) => SWITCH_OPEN_COLOR,
            };
            assert_eq!(sphere.color.unwrap(), want, "link {k} switch {j}");
        }
    }
    // The wall of fewer than two points is not drawn; the other is in world.
    assert_eq!(by_id["wall_0"].frame_id, WORLD_FRAME);
    assert_eq!(by_id["wall_0"].lines[0].points.len(), 3);
    // The estimate, on the right: y = -(d + (x - preview) tan a) in the carriage frame.
    let wall = by_id[ESTIMATED_WALL_ID];
    assert_eq!(wall.frame_id, CARRIAGE_FRAME);
    let points = &wall.lines[0].points;
    assert_eq!(points.len(), 2);
    for p in points {
        let want = -(0.1 + (p.x - 0.05) * 0.2f64.tan());
        assert!((p.y - want).abs() < 1e-15);
    }
    assert!((points[1].x - points[0].x - ESTIMATED_WALL_LENGTH_M).abs() < 1e-15);
    assert!((points[0].x + points[1].x - 0.1).abs() < 1e-15);
}

#[test]
fn no_estimate_deletes_the_last_one_and_walls_come_apart_on_request() {
    let model = model();
    let pose = ChainPose {
        t_ns: 9,
        joint_angles_rad: &[Some(0.0); 4],
        touch_bits: &[Some(0); 4],
        ..ChainPose::default()
    };
    let update = chain_scene_update(&model, &pose, None);
    assert_eq!(update.deletions.len(), 1);
    assert_eq!(update.deletions[0].id, ESTIMATED_WALL_ID);
    assert_eq!(update.entities.len(), 5);
    let walls = walls_scene_update(&model, 9);
    assert_eq!(walls.entities.len(), 1);
    assert_eq!(walls.entities[0].id, wall_entity_id(0));
}

#[test]
fn messages_round_trip_through_their_protobuf_bytes() {
    let model = model();
    let pose = ChainPose {
        t_ns: 11,
        stage_m: Some(0.1),
        servo_rad: Some(0.2),
        joint_angles_rad: &[Some(0.3); 4],
        touch_bits: &[Some(1); 4],
    };
    let transforms = frame_transforms(&model, &pose);
    let bytes = encode(&transforms).unwrap();
    assert_eq!(
        FrameTransforms::decode(bytes.as_slice()).unwrap(),
        transforms
    );
    let scene = scene_update(&model, &pose, None);
    let mut buf = vec![1, 2];
    encode_into(&scene, &mut buf).unwrap();
    assert_eq!(SceneUpdate::decode(&buf[2..]).unwrap(), scene);
    let schema = ChannelSchema::of::<SceneUpdate>().unwrap();
    assert_eq!(schema.name, "foxglove.SceneUpdate");
    assert_eq!(schema.encoding, "protobuf");
    assert_eq!(schema.message_encoding, "protobuf");
    assert!(!schema.data.is_empty());
}

#[test]
fn a_model_comes_from_the_rig_info() {
    let rig: crate::stream::RigInfo = serde_json::from_str(
        r#"{"poll_hz":1000.0,"link_lengths_m":[0.04,0.03],"base_mount_angle_deg":30.0,
            "stage_min_m":0.0,"stage_max_m":0.3}"#,
    )
    .unwrap();
    let model = ChainModel::from_rig(&rig).unwrap();
    assert_eq!(model.link_lengths_m, [0.04, 0.03]);
    assert!((model.base_mount_angle_rad - 30f64.to_radians()).abs() < 1e-15);
    assert_eq!(model.segments(), 1);
    let no_links = crate::stream::RigInfo {
        link_lengths_m: Vec::new(),
        ..rig
    };
    assert_eq!(ChainModel::from_rig(&no_links), None);
}

#[test]
fn time_stamps_split_into_seconds_and_nanoseconds() {
    let t = timestamp(12_345_678_901);
    assert_eq!((t.sec(), t.nsec()), (12, 345_678_901));
    let far = timestamp(u64::MAX);
    assert_eq!(far, foxglove::messages::Timestamp::MAX);
}
