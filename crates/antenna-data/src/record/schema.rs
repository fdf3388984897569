//! Topic names and the JSON schemas embedded in every trial file (schema encoding
//! `jsonschema`, message encoding `json`: what Foxglove and PlotJuggler read). The Foxglove
//! channels ([`TRANSFORMS_TOPIC`], [`SCENE_TOPIC`]) carry Foxglove's own protobuf schemas
//! instead ([`crate::foxglove::ChannelSchema`]).

use serde_json::{Value, json};

/// Topic of [`super::SegmentsMessage`].
pub const SEGMENTS_TOPIC: &str = "/antenna/segments";
/// Topic of [`super::StageMessage`].
pub const STAGE_TOPIC: &str = "/antenna/stage";
/// Topic of [`super::ServoMessage`].
pub const SERVO_TOPIC: &str = "/antenna/servo";
/// Topic of [`super::PhysicsStepMessage`] (the simulated rig only).
pub const PHYSICS_TOPIC: &str = "/sim/physics";
/// Topic of [`super::EstimateMessage`].
pub const ESTIMATE_TOPIC: &str = "/antenna/estimate";
/// Topic of the chain's frames (`foxglove.FrameTransforms`, protobuf; see
/// [`crate::foxglove::frame_transforms`]).
pub const TRANSFORMS_TOPIC: &str = "/antenna/transforms";
/// Topic of the 3D scene (`foxglove.SceneUpdate`, protobuf; see
/// [`crate::foxglove::scene_update`]).
pub const SCENE_TOPIC: &str = "/antenna/scene";
/// Topic of [`super::LogMessage`].
pub const LOG_TOPIC: &str = "/trial/log";
/// Topic of [`super::TrialMetadata`].
pub const METADATA_TOPIC: &str = "/trial/metadata";

/// Schema encoding of every JSON channel.
pub const SCHEMA_ENCODING: &str = "jsonschema";
/// Message encoding of every JSON channel.
pub const MESSAGE_ENCODING: &str = "json";

fn nullable(kind: &str, description: &str) -> Value {
    json!({ "type": [kind, "null"], "description": description })
}

/// The schema of `/antenna/segments` (name `antenna.Segments`).
pub fn segments_schema() -> Value {
    json!({
        "title": "antenna.Segments",
        "description": "One poll of every segment",
        "type": "object",
        "properties": {
            "seq": { "type": "integer", "description": "poll number, +1 per poll deadline" },
            "t_s": { "type": "number", "description": "monotonic time since trial start, s" },
            "segments": {
                "type": "array",
                "items": {
                    "type": "object",
                    "properties": {
                        "address": { "type": "integer", "description": "7-bit I2C address" },
                        "angle_counts": nullable("integer", "raw angle, counts of 4096 per turn"),
                        "angle_rad": nullable("number", "joint angle, rad"),
                        "touch": nullable("integer", "touch bits, bit i = hair i"),
                        "ok": { "type": "boolean" },
                        "nack": { "type": "boolean" },
                        "pec_error": { "type": "boolean" },
                        "bus_error": { "type": "boolean" },
                        "stale": { "type": "boolean" }
                    },
                    "required": ["address", "angle_counts", "angle_rad", "touch", "ok", "nack",
                                 "pec_error", "bus_error", "stale"]
                }
            }
        },
        "required": ["t_s", "segments"]
    })
}

/// The schema of `/antenna/stage` (name `antenna.Stage`).
pub fn stage_schema() -> Value {
    json!({
        "title": "antenna.Stage",
        "type": "object",
        "properties": {
            "t_s": { "type": "number", "description": "monotonic time since trial start, s" },
            "position_m": { "type": "number", "description": "stage position, m" }
        },
        "required": ["t_s", "position_m"]
    })
}

/// The schema of `/antenna/servo` (name `antenna.Servo`).
pub fn servo_schema() -> Value {
    json!({
        "title": "antenna.Servo",
        "type": "object",
        "properties": {
            "t_s": { "type": "number", "description": "monotonic time since trial start, s" },
            "base_angle_rad": { "type": "number", "description": "base angle, rad" }
        },
        "required": ["t_s", "base_angle_rad"]
    })
}

/// The schema of `/sim/physics` (name `antenna.PhysicsStep`).
pub fn physics_schema() -> Value {
    json!({
        "title": "antenna.PhysicsStep",
        "description": "One placement or step of the simulated rig's physics: the base pose it was for and the joint angles it gave",
        "type": "object",
        "properties": {
            "t_s": { "type": "number", "description": "monotonic time since trial start, s" },
            "kind": {
                "type": "string",
                "enum": ["place", "step"],
                "description": "place: the scene's placement done afresh at this pose; step: one quasi-static step from the previous posture"
            },
            "stage_m": { "type": "number", "description": "stage position, m (fractional, as the physics took it)" },
            "base_x_m": { "type": "number", "description": "base pivot x, ground frame, m" },
            "base_y_m": { "type": "number", "description": "base pivot y, ground frame, m" },
            "base_angle_rad": { "type": "number", "description": "base link angle from the ground x-axis, rad" },
            "joint_angles_rad": {
                "type": "array",
                "items": { "type": "number" },
                "description": "joint angles theta_1..theta_n it gave, rad"
            }
        },
        "required": ["t_s", "kind", "stage_m", "base_x_m", "base_y_m", "base_angle_rad", "joint_angles_rad"]
    })
}

/// The schema of `/antenna/estimate` (name `antenna.Estimate`).
pub fn estimate_schema() -> Value {
    json!({
        "title": "antenna.Estimate",
        "description": "One wall estimate, in the carriage frame: origin at the base pivot, x along the stage's travel, y toward the wall; the wall is y = distance_m + (x - preview_m) tan(angle_rad)",
        "type": "object",
        "properties": {
            "t_s": { "type": "number", "description": "monotonic time since trial start, s (the newest poll's)" },
            "seq": { "type": "integer", "description": "the newest poll's seq" },
            "estimator": { "type": "string", "description": "contact-line, bend or ideal-preview" },
            "distance_m": nullable("number", "wall distance from the travel at x = preview_m, m"),
            "angle_rad": nullable("number", "wall angle to the travel, rad (null for bend)"),
            "preview_m": nullable("number", "where along the travel the distance is, m"),
            "reason": { "type": "string", "description": "why there is no estimate" },
            "true_distance_m": { "type": "number", "description": "the true distance (simulated rig), m" },
            "true_angle_rad": { "type": "number", "description": "the true angle (simulated rig), rad" }
        },
        "required": ["t_s", "seq", "estimator", "distance_m", "angle_rad", "preview_m"]
    })
}

/// The schema of `/trial/log` (name `antenna.Log`).
pub fn log_schema() -> Value {
    json!({
        "title": "antenna.Log",
        "type": "object",
        "properties": {
            "t_s": { "type": "number", "description": "monotonic time since trial start, s" },
            "text": { "type": "string", "description": "what the daemon said" }
        },
        "required": ["t_s", "text"]
    })
}

/// The schema of `/trial/metadata` (name `antenna.TrialMetadata`).
pub fn metadata_schema() -> Value {
    json!({
        "title": "antenna.TrialMetadata",
        "type": "object",
        "properties": {
            "trial": { "type": "string" },
            "started_unix_s": { "type": "number", "description": "wall-clock start, Unix s" },
            "started_unix_ns": {
                "type": "integer",
                "description": "the same, Unix ns: each message's log time is this plus its t_s"
            },
            "config": { "type": "string", "description": "the configuration, TOML text" },
            "notes": {
                "type": "object",
                "additionalProperties": { "type": "string" },
                "description": "free-text notes such as wall and hairs"
            },
            "rig": {
                "type": "object",
                "description": "the rig's geometry, as the stream's hello carries it"
            }
        },
        "required": ["trial", "started_unix_s", "config", "notes"]
    })
}
