//! The JSON schemas of the plottable channels: each channel carries the stream message's own
//! JSON line (docs/stream-protocol.md, without its newline), described here so that
//! Foxglove's plot and raw-message panels offer its fields.

use serde_json::{Value, json};

/// `/antenna/samples`: every poll (`type` `"samples"`).
pub const SAMPLES_TOPIC: &str = "/antenna/samples";
/// `/antenna/status`: the daemon's health, once a second and on every change (`type`
/// `"status"`).
pub const STATUS_TOPIC: &str = "/antenna/status";
/// `/antenna/estimate`: the live wall estimate (`type` `"estimate"`).
pub const ESTIMATE_TOPIC: &str = "/antenna/estimate";
/// `/antenna/transforms`: `foxglove.FrameTransforms`, `world` to the last link.
pub const TRANSFORMS_TOPIC: &str = "/antenna/transforms";
/// `/antenna/scene`: `foxglove.SceneUpdate`, the links, their touch switches and the walls.
pub const SCENE_TOPIC: &str = "/antenna/scene";

/// The schema's name on the samples channel.
pub const SAMPLES_SCHEMA: &str = "antenna.stream.Samples";
/// The schema's name on the status channel.
pub const STATUS_SCHEMA: &str = "antenna.stream.Status";
/// The schema's name on the estimate channel.
pub const ESTIMATE_SCHEMA: &str = "antenna.stream.Estimate";

fn nullable(kind: &str, description: &str) -> Value {
    json!({ "type": [kind, "null"], "description": description })
}

fn object(title: &str, description: &str, properties: Value) -> Value {
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": title,
        "description": description,
        "type": "object",
        "properties": properties,
    })
}

/// The samples line's JSON schema.
pub fn samples_schema() -> Value {
    object(
        SAMPLES_SCHEMA,
        "One poll of every segment, with the stage and the servo (docs/stream-protocol.md)",
        json!({
            "type": { "const": "samples" },
            "seq": { "type": "integer", "description": "poll number, +1 per poll" },
            "t_ns": { "type": "integer", "description": "time of the poll, ns since the daemon started" },
            "segments": {
                "type": "array",
                "description": "one entry per segment, base first",
                "items": {
                    "type": "object",
                    "properties": {
                        "address": { "type": "integer", "description": "7-bit I2C address" },
                        "angle_rad": nullable("number", "calibrated joint angle, rad"),
                        "contact": nullable("boolean", "any touch switch closed"),
                        "touch_bits": nullable("integer", "the four touch switches, bit 0 the most proximal"),
                        "counter": nullable("integer", "the segment's sample counter"),
                        "error": nullable("string", "why the read failed"),
                        "stale": { "type": "boolean", "description": "the counter did not move at its last check" },
                    },
                },
            },
            "stage_position_m": nullable("number", "stage carriage position, m"),
            "base_angle_deg": nullable("number", "base servo angle, deg"),
        }),
    )
}

/// The status line's JSON schema.
pub fn status_schema() -> Value {
    let count = |description: &str| json!({ "type": "integer", "description": description });
    object(
        STATUS_SCHEMA,
        "The daemon's health: per-segment counters and the polling thread (docs/stream-protocol.md)",
        json!({
            "type": { "const": "status" },
            "t_ns": { "type": "integer", "description": "ns since the daemon started" },
            "trial": nullable("string", "the trial being recorded"),
            "segments": {
                "type": "array",
                "items": {
                    "type": "object",
                    "properties": {
                        "address": count("7-bit I2C address"),
                        "ok": count("good reads"),
                        "nack": count("reads not acknowledged"),
                        "pec_error": count("reads with a bad checksum"),
                        "stale": count("polls with the counter stopped"),
                        "bus_error": count("bus errors"),
                        "status_flags": nullable("integer", "the firmware's status register"),
                        "firmware_version": nullable("string", "the firmware's version"),
                    },
                },
            },
            "note": nullable("string", "what changed"),
            "polling": {
                "type": ["object", "null"],
                "properties": {
                    "stalled": { "type": "boolean" },
                    "since_last_poll_ms": count("ms since the last poll"),
                    "stall_after_ms": count("the watchdog's bound, ms"),
                    "polls": count("polls made"),
                    "missed_deadlines": count("poll deadlines missed"),
                    "stalls": count("stalls seen"),
                },
            },
        }),
    )
}

/// The estimate line's JSON schema.
pub fn estimate_schema() -> Value {
    object(
        ESTIMATE_SCHEMA,
        "The live wall estimate; frame: origin at the base pivot, x along the stage's travel, \
         y toward the wall (docs/stream-protocol.md)",
        json!({
            "type": { "const": "estimate" },
            "seq": { "type": "integer", "description": "the newest poll the estimate used" },
            "t_ns": { "type": "integer", "description": "that poll's time, ns" },
            "estimated_ns": { "type": "integer", "description": "when the estimate was made, ns" },
            "estimator": { "type": "string" },
            "distance_m": nullable("number", "the wall's distance at preview_m, m"),
            "angle_rad": nullable("number", "the wall's angle to the travel, rad"),
            "preview_m": nullable("number", "where along x the distance holds, m"),
            "reason": nullable("string", "why there is no estimate"),
            "true_distance_m": nullable("number", "simulated rig: the true distance, m"),
            "true_angle_rad": nullable("number", "simulated rig: the true angle, rad"),
        }),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use antenna_data::stream::{EstimateMessage, SegmentSample, StreamMessage};

    /// Every field of a message is described, and nothing else.
    fn assert_describes(schema: &Value, message: &StreamMessage) {
        let line: Value = serde_json::to_value(message).unwrap();
        let properties = schema["properties"].as_object().unwrap();
        for key in line.as_object().unwrap().keys() {
            assert!(
                properties.contains_key(key),
                "{key} not in {}",
                schema["title"]
            );
        }
    }

    #[test]
    fn the_schemas_describe_the_stream_s_lines() {
        let samples = StreamMessage::Samples {
            seq: 1,
            t_ns: 2,
            segments: vec![SegmentSample {
                address: 0x20,
                angle_rad: Some(0.1),
                contact: Some(true),
                touch_bits: Some(1),
                counter: Some(3),
                error: None,
                stale: false,
            }],
            stage_position_m: Some(0.1),
            base_angle_deg: Some(0.0),
        };
        assert_describes(&samples_schema(), &samples);
        let items = &samples_schema()["properties"]["segments"]["items"]["properties"];
        let line = serde_json::to_value(&samples).unwrap();
        for key in line["segments"][0].as_object().unwrap().keys() {
            assert!(items.get(key).is_some(), "{key}");
        }
        let estimate = StreamMessage::Estimate(EstimateMessage {
            seq: 1,
            t_ns: 2,
            estimated_ns: 3,
            estimator: "contact-line".to_owned(),
            distance_m: Some(0.2),
            angle_rad: Some(0.1),
            preview_m: Some(0.0),
            reason: Some("x".to_owned()),
            true_distance_m: Some(0.2),
            true_angle_rad: Some(0.1),
        });
        assert_describes(&estimate_schema(), &estimate);
        let status = StreamMessage::Status {
            t_ns: 1,
            trial: None,
            segments: Vec::new(),
            note: None,
            polling: None,
        };
        assert_describes(&status_schema(), &status);
    }
}
