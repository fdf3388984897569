//! [`scene_update`]: the links, their touch switches, the walls and the estimated wall as
//! Foxglove scene entities.

use foxglove::messages::{
    Color, LinePrimitive, Point3, Pose, SceneEntity, SceneEntityDeletion, SceneUpdate,
    SpherePrimitive, Vector3, line_primitive, scene_entity_deletion,
};

use super::model::{ChainModel, ChainPose, EstimatedWall};
use super::transforms::{CARRIAGE_FRAME, WORLD_FRAME, link_frame_id, rotation_z, timestamp};

/// Touch switches per segment, evenly along its link: switch `k` covers the quarter
/// `[k/4, (k+1)/4)` and is drawn at its middle.
pub const SWITCHES_PER_LINK: usize = 4;
/// The links' colour.
pub const LINK_COLOR: Color = rgba(0.15, 0.35, 0.75, 1.0);
/// A closed touch switch.
pub const SWITCH_CLOSED_COLOR: Color = rgba(0.9, 0.1, 0.1, 1.0);
/// An open touch switch.
pub const SWITCH_OPEN_COLOR: Color = rgba(0.6, 0.6, 0.6, 1.0);
/// A touch switch whose segment did not answer (its bits are missing).
pub const SWITCH_UNKNOWN_COLOR: Color = rgba(0.6, 0.6, 0.6, 0.25);
/// The walls (the scene's, on the simulated rig).
pub const WALL_COLOR: Color = rgba(0.35, 0.25, 0.15, 1.0);
/// The estimated wall.
pub const ESTIMATED_WALL_COLOR: Color = rgba(0.1, 0.7, 0.2, 1.0);
/// The length of the estimated wall as drawn, centred on its preview point, m.
pub const ESTIMATED_WALL_LENGTH_M: f64 = 0.3;
/// The id of the estimated wall's entity.
pub const ESTIMATED_WALL_ID: &str = "estimated_wall";

/// Line thickness of the links, m.
const LINK_THICKNESS_M: f64 = 0.002;
/// Line thickness of the walls, m.
const WALL_THICKNESS_M: f64 = 0.003;
/// Diameter of a touch switch's marker, m.
const SWITCH_DIAMETER_M: f64 = 0.005;

const fn rgba(r: f64, g: f64, b: f64, a: f64) -> Color {
    Color { r, g, b, a }
}

/// The id of link `k`'s entity (its line and, for `k >= 1`, its touch switches).
pub fn link_entity_id(k: usize) -> String {
    format!("link_{k}")
}

/// The id of wall `i`'s entity.
pub fn wall_entity_id(i: usize) -> String {
    format!("wall_{i}")
}

fn point([x, y]: [f64; 2]) -> Point3 {
    Point3 { x, y, z: 0.0 }
}

fn identity_pose() -> Pose {
    Pose {
        position: Some(Vector3::default()),
        orientation: Some(rotation_z(0.0)),
    }
}

fn line(points: Vec<Point3>, thickness_m: f64, color: Color) -> LinePrimitive {
    LinePrimitive {
        r#type: line_primitive::Type::LineStrip as i32,
        pose: Some(identity_pose()),
        thickness: thickness_m,
        scale_invariant: false,
        points,
        color: Some(color),
        colors: Vec::new(),
        indices: Vec::new(),
    }
}

fn entity(t_ns: u64, frame_id: &str, id: String, frame_locked: bool) -> SceneEntity {
    SceneEntity {
        timestamp: Some(timestamp(t_ns)),
        frame_id: frame_id.to_owned(),
        id,
        frame_locked,
        ..SceneEntity::default()
    }
}

/// The colour of switch `switch` for a segment's touch word.
pub fn switch_color(touch_bits: Option<u8>, switch: usize) -> Color {
    match touch_bits {
        Some(bits) if bits & (1 << switch) != 0 => SWITCH_CLOSED_COLOR,
        Some(_) => SWITCH_OPEN_COLOR,
        None => SWITCH_UNKNOWN_COLOR,
    }
}

/// Each link as a line from `(0, 0, 0)` to `(L, 0, 0)` in its own frame, locked to it; link
/// `k >= 1` (segment `k - 1`'s) with its [`SWITCHES_PER_LINK`] touch switches as spheres at
/// `(j + 1/2)/4` of its length, coloured by the segment's touch bits. The base link carries
/// no switches (the segments' switches are on the links distal of their joints, as
/// `sim_core::touch_bits_from_contacts` numbers them).
fn link_entities(model: &ChainModel, pose: &ChainPose<'_>) -> Vec<SceneEntity> {
    model
        .link_lengths_m
        .iter()
        .enumerate()
        .map(|(k, &length_m)| {
            let mut e = entity(pose.t_ns, &link_frame_id(k), link_entity_id(k), true);
            e.lines.push(line(
                vec![point([0.0, 0.0]), point([length_m, 0.0])],
                LINK_THICKNESS_M,
                LINK_COLOR,
            ));
            if k >= 1 {
                let bits = pose.touch_bits.get(k - 1).copied().flatten();
                e.spheres = (0..SWITCHES_PER_LINK)
                    .map(|j| SpherePrimitive {
                        pose: Some(Pose {
                            position: Some(Vector3 {
                                x: length_m * (j as f64 + 0.5) / SWITCHES_PER_LINK as f64,
                                y: 0.0,
                                z: 0.0,
                            }),
                            orientation: Some(rotation_z(0.0)),
                        }),
                        size: Some(Vector3 {
                            x: SWITCH_DIAMETER_M,
                            y: SWITCH_DIAMETER_M,
                            z: SWITCH_DIAMETER_M,
                        }),
                        color: Some(switch_color(bits, j)),
                    })
                    .collect();
            }
            e
        })
        .collect()
}

fn wall_entities(model: &ChainModel, t_ns: u64) -> Vec<SceneEntity> {
    model
        .walls_m
        .iter()
        .enumerate()
        .filter(|(_, polyline)| polyline.len() >= 2)
        .map(|(i, polyline)| {
            let mut e = entity(t_ns, WORLD_FRAME, wall_entity_id(i), false);
            e.lines.push(line(
                polyline.iter().copied().map(point).collect(),
                WALL_THICKNESS_M,
                WALL_COLOR,
            ));
            e
        })
        .collect()
}

/// The estimated wall as an entity, or (`None`, or a distance that is not finite) the
/// deletion of the one drawn before.
fn add_estimate(update: &mut SceneUpdate, t_ns: u64, estimate: Option<&EstimatedWall>) {
    let finite = estimate.filter(|e| {
        e.distance_m.is_finite()
            && e.preview_m.is_finite()
            && e.wall_angle_rad.is_none_or(f64::is_finite)
    });
    match finite {
        Some(estimate) => {
            let half = 0.5 * ESTIMATED_WALL_LENGTH_M;
            let mut e = entity(t_ns, CARRIAGE_FRAME, ESTIMATED_WALL_ID.to_owned(), true);
            e.lines.push(line(
                vec![
                    point(estimate.point_at(estimate.preview_m - half)),
                    point(estimate.point_at(estimate.preview_m + half)),
                ],
                WALL_THICKNESS_M,
                ESTIMATED_WALL_COLOR,
            ));
            update.entities.push(e);
        }
        None => update.deletions.push(SceneEntityDeletion {
            timestamp: Some(timestamp(t_ns)),
            r#type: scene_entity_deletion::Type::MatchingId as i32,
            id: ESTIMATED_WALL_ID.to_owned(),
        }),
    }
}

/// The whole scene at `pose`: the links with their touch switches ([`link_entity_id`], in the
/// links' frames), the walls ([`wall_entity_id`], line strips in `world`) and the estimated
/// wall ([`ESTIMATED_WALL_ID`], a [`ESTIMATED_WALL_LENGTH_M`] segment centred on its preview
/// point, in `carriage`; `None` deletes the one drawn before). Every entity has a stable id,
/// so each update replaces the last.
pub fn scene_update(
    model: &ChainModel,
    pose: &ChainPose<'_>,
    estimate: Option<&EstimatedWall>,
) -> SceneUpdate {
    let mut update = chain_scene_update(model, pose, estimate);
    update.entities.extend(wall_entities(model, pose.t_ns));
    update
}

/// [`scene_update`] without the walls, for updates between [`walls_scene_update`]s (the
/// walls do not move: entities stay until replaced).
pub fn chain_scene_update(
    model: &ChainModel,
    pose: &ChainPose<'_>,
    estimate: Option<&EstimatedWall>,
) -> SceneUpdate {
    let mut update = SceneUpdate {
        deletions: Vec::new(),
        entities: link_entities(model, pose),
    };
    add_estimate(&mut update, pose.t_ns, estimate);
    update
}

/// The walls alone, stamped `t_ns`.
pub fn walls_scene_update(model: &ChainModel, t_ns: u64) -> SceneUpdate {
    SceneUpdate {
        deletions: Vec::new(),
        entities: wall_entities(model, t_ns),
    }
}
