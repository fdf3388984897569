//! [`frame_transforms`]: the chain's frames, `world` to the last link.

use foxglove::messages::{FrameTransform, FrameTransforms, Quaternion, Timestamp, Vector3};

use super::model::{ChainModel, ChainPose};

/// The scene frame: the scene's (the simulator's) ground frame, fixed.
pub const WORLD_FRAME: &str = "world";
/// The carriage: the base pivot, moved by the stage; `x` along the stage's travel.
pub const CARRIAGE_FRAME: &str = "carriage";

/// The frame of link `k` (`link_0` the base link): origin at its proximal joint, `x` along the
/// link.
pub fn link_frame_id(k: usize) -> String {
    format!("link_{k}")
}

/// A Foxglove time stamp for `t_ns` nanoseconds (saturating past the year 2106).
pub fn timestamp(t_ns: u64) -> Timestamp {
    let nsec = (t_ns % 1_000_000_000) as u32;
    u32::try_from(t_ns / 1_000_000_000)
        .ok()
        .and_then(|sec| Timestamp::new_checked(sec, nsec))
        .unwrap_or(Timestamp::MAX)
}

/// The rotation by `angle_rad` about `z`.
pub(super) fn rotation_z(angle_rad: f64) -> Quaternion {
    let half = 0.5 * angle_rad;
    Quaternion {
        x: 0.0,
        y: 0.0,
        z: half.sin(),
        w: half.cos(),
    }
}

fn transform(
    t_ns: u64,
    parent: &str,
    child: String,
    [x, y]: [f64; 2],
    angle_rad: f64,
) -> FrameTransform {
    FrameTransform {
        timestamp: Some(timestamp(t_ns)),
        parent_frame_id: parent.to_owned(),
        child_frame_id: child,
        translation: Some(Vector3 { x, y, z: 0.0 }),
        rotation: Some(rotation_z(angle_rad)),
    }
}

/// The chain's frames at `pose` (see the module documentation): `world` -> `carriage` (at
/// `origin_m` plus `stage_m` along the travel, turned by `travel_angle_rad`) -> `link_0`
/// (turned by `base_mount_angle_rad + servo_rad`) -> `link_1` (at `link_0`'s length along
/// its `x`, turned by segment 0's joint angle) -> ... -> `link_n`, all stamped `pose.t_ns`.
///
/// A transform whose reading is missing (a `None` stage, servo or joint angle, or a value
/// that is not finite) is left out, so a viewer keeps the last one it was given; the others
/// are still there (each is relative to its parent). Links beyond the model's, or joint
/// angles beyond the pose's, are not placed.
pub fn frame_transforms(model: &ChainModel, pose: &ChainPose<'_>) -> FrameTransforms {
    let t_ns = pose.t_ns;
    let finite = |v: Option<f64>| v.filter(|v| v.is_finite());
    let mut transforms = Vec::with_capacity(model.link_lengths_m.len() + 1);
    if let Some(stage_m) = finite(pose.stage_m) {
        let (sin, cos) = model.travel_angle_rad.sin_cos();
        let at = [
            model.origin_m[0] + stage_m * cos,
            model.origin_m[1] + stage_m * sin,
        ];
        transforms.push(transform(
            t_ns,
            WORLD_FRAME,
            CARRIAGE_FRAME.to_owned(),
            at,
            model.travel_angle_rad,
        ));
    }
    if model.link_lengths_m.is_empty() {
        return FrameTransforms { transforms };
    }
    if let Some(servo_rad) = finite(pose.servo_rad) {
        transforms.push(transform(
            t_ns,
            CARRIAGE_FRAME,
            link_frame_id(0),
            [0.0, 0.0],
            model.base_mount_angle_rad + servo_rad,
        ));
    }
    let parents = model.link_lengths_m.iter().take(model.segments());
    for (k, (&length_m, &angle_rad)) in parents.zip(pose.joint_angles_rad).enumerate() {
        if let Some(angle_rad) = finite(angle_rad) {
            transforms.push(transform(
                t_ns,
                &link_frame_id(k),
                link_frame_id(k + 1),
                [length_m, 0.0],
                angle_rad,
            ));
        }
    }
    FrameTransforms { transforms }
}
