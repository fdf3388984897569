//! What the server sends: one [`StreamMessage`] per line.

use serde::{Deserialize, Serialize};

/// The protocol version sent in [`StreamMessage::Hello`]; bumped on incompatible changes.
pub const PROTOCOL_VERSION: u32 = 1;

/// One line from the server to a client; the `type` field names the variant.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum StreamMessage {
    /// The first line on every connection.
    Hello {
        /// [`PROTOCOL_VERSION`].
        protocol_version: u32,
        /// The daemon's name and version, e.g. `"antennad 0.1.0"`.
        daemon: String,
        /// How many segments each [`StreamMessage::Samples`] describes.
        segment_count: usize,
        /// Their 7-bit I2C addresses, base to tip.
        segment_addresses: Vec<u8>,
        /// The antenna and the wall the daemon models, for clients that draw the chain or
        /// predict its posture (added in 0.1 without a version change; absent from older
        /// daemons' lines, read as `None`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        rig: Option<RigInfo>,
    },
    /// One poll of every segment, with the stage and base at that instant.
    Samples {
        /// Poll number, +1 per poll; a client sees gaps only after a [`StreamMessage::Lagged`].
        seq: u64,
        /// Monotonic time of the poll in nanoseconds since the daemon started.
        t_ns: u64,
        /// One entry per segment, in [`StreamMessage::Hello`]'s order.
        segments: Vec<SegmentSample>,
        /// Stage carriage position in metres, if a stage is present.
        stage_position_m: Option<f64>,
        /// Base servo angle in degrees, if a servo is present.
        base_angle_deg: Option<f64>,
    },
    /// The daemon's state, sent at a low rate and on every change.
    Status {
        /// Monotonic time in nanoseconds since the daemon started.
        t_ns: u64,
        /// The trial being recorded, if any.
        trial: Option<String>,
        /// Health counters per segment.
        segments: Vec<SegmentStatus>,
        /// Free text, e.g. `"stage moving"`.
        note: Option<String>,
        /// The polling thread as its watchdog sees it (added in 0.1 without a version
        /// change; absent from older daemons' lines, read as `None`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        polling: Option<PollingStatus>,
    },
    /// The wall as the antenna sees it: `antenna follow`'s estimator run by the daemon on
    /// the calibrated joint angles and touch bits (added in 0.1 under protocol 1's additive
    /// rule: older clients skip a type they do not know). Frame: origin at the base pivot, x
    /// along the stage's travel, y toward the wall (`[estimate] wall_side`).
    Estimate(EstimateMessage),
    /// Sent before the next message when messages were dropped for this (slow) client.
    Lagged {
        /// How many messages were dropped since the last one this client received.
        dropped: u64,
        /// How many of them were [`StreamMessage::Samples`]: the gap in `seq` the client
        /// sees next (added in 0.1; absent from older daemons' lines, read as 0).
        #[serde(default)]
        samples_dropped: u64,
    },
    /// The answer to one control request, sent only to the client that made it.
    Reply(ControlReply),
}

/// One live wall estimate ([`StreamMessage::Estimate`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EstimateMessage {
    /// The newest poll the estimate used: its [`StreamMessage::Samples`] `seq`.
    pub seq: u64,
    /// That poll's time, nanoseconds on the daemon's clock.
    pub t_ns: u64,
    /// When the estimate was made, nanoseconds on the daemon's clock (`estimated_ns - t_ns`
    /// is the estimator's own delay).
    pub estimated_ns: u64,
    /// `"contact-line"`, `"bend"` or `"ideal-preview"` (`[estimate] estimator`).
    pub estimator: String,
    /// The wall's distance from the x axis, metres, at `preview_m` along it; `None` when
    /// there is no estimate (`reason` says why).
    pub distance_m: Option<f64>,
    /// The wall's angle to the x axis, radians (the wall `y = distance_m + (x - preview_m)
    /// tan(angle_rad)`); `None` from the bend estimator or with no estimate.
    pub angle_rad: Option<f64>,
    /// Where along x the distance holds, metres ahead of the base pivot.
    pub preview_m: Option<f64>,
    /// Why there is no estimate, e.g. `"no contact in the window"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// The simulated rig only: the true wall's distance at `preview_m` (at the base pivot
    /// when there is no estimate) along the y axis, metres, from the pose the physics was
    /// solved at for that poll.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub true_distance_m: Option<f64>,
    /// The simulated rig only: the true wall's angle to the x axis there, radians.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub true_angle_rad: Option<f64>,
}

/// The rig as configured, sent in [`StreamMessage::Hello`] and kept in every recording's
/// metadata: the scene the simulated rig runs (on hardware, the model of the antenna and the
/// walls a client predicts with), the stage's soft limits and the poll rate.
///
/// Lines and recordings from daemons before the scene (issue #46) carry no `scene_toml` but
/// the antenna's links and mounting angle (read here) and a flat `wall` with its stiffness
/// profile (ignored): a client draws their chain and predicts nothing.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RigInfo {
    /// Polls per second (`bus.poll_hz`).
    pub poll_hz: f64,
    /// The stage's soft limits, metres from home.
    pub stage_min_m: f64,
    /// See [`RigInfo::stage_min_m`].
    pub stage_max_m: f64,
    /// The scene's TOML text (`docs/scene-format.md`), every wall's `points_file` written in
    /// as its `vertices_m`, so a client rebuilds the same physics without any other file
    /// (antenna-scene reads it; stage position `s` puts the base at the scene's base position
    /// plus `s` along its direction of motion, the servo angle adds to its base angle).
    /// `None` from daemons before it existed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene_toml: Option<String>,
    /// Where the scene came from (its file, as antennad read it), for messages.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene_source: Option<String>,
    /// Every rigid link, the base link first: one more entry than there are segments, metres
    /// (also in the scene: here for clients that only draw the chain).
    #[serde(default)]
    pub link_lengths_m: Vec<f64>,
    /// The base link's angle from the stage's track with the servo at 0, degrees
    /// (counter-clockwise; the scene's `base_angle_deg`); the chain's base angle is this
    /// plus `base_angle_deg` of each sample.
    #[serde(default)]
    pub base_mount_angle_deg: f64,
    /// Which side of the stage's travel the live estimate's y axis points to, toward the
    /// wall (`[estimate] wall_side`: `"left"` or `"right"`); `None` from daemons before the
    /// estimate (a client then takes the side of the scene's nearest wall).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimate_wall_side: Option<String>,
}

/// One segment in one poll. A failed read has `error` set and no angle, contact or touch bits.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SegmentSample {
    /// 7-bit I2C address.
    pub address: u8,
    /// Joint angle in radians (calibrated).
    pub angle_rad: Option<f64>,
    /// Any of the segment's touch switches closed: `touch_bits != 0`.
    pub contact: Option<bool>,
    /// The segment's four touch switches as its sample word carries them, 0..=15: bit `i` is
    /// switch `i`, bit 0 the most proximal on the segment's link (`antenna_protocol::TouchBits`).
    /// Added in 0.1 beside `contact` (which it refines); absent from older daemons' lines,
    /// read as `None`.
    #[serde(default)]
    pub touch_bits: Option<u8>,
    /// The segment's own sample counter (stale if it stops advancing).
    pub counter: Option<u32>,
    /// Why the read failed, e.g. `"nack"` or `"pec"`.
    pub error: Option<String>,
    /// The segment's sample counter did not move at its last check: it answers, but with
    /// old news (added in 0.1; absent from older daemons' lines, read as `false`).
    #[serde(default)]
    pub stale: bool,
}

/// Health counters of one segment since the daemon started.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct SegmentStatus {
    /// 7-bit I2C address.
    pub address: u8,
    /// Good reads.
    pub ok: u64,
    /// Reads the segment did not acknowledge.
    pub nack: u64,
    /// Reads with a wrong PEC byte.
    pub pec_error: u64,
    /// Reads whose sample counter had not advanced.
    pub stale: u64,
    /// Reads that failed with another bus error (arbitration lost, a bus fault, a timeout).
    /// Added in 0.1; absent from older daemons' lines, read as 0.
    #[serde(default)]
    pub bus_error: u64,
    /// The segment's status register (0x02) as last read: bit 0 ADC fault, bit 1 a touch
    /// switch stuck closed, bit 2 address not assigned (`antenna_protocol::StatusFlags`);
    /// `None` until first read (a few seconds after start). Added in 0.1.
    #[serde(default)]
    pub status_flags: Option<u8>,
    /// The segment's firmware version (register 0x01) as last read, `"major.minor"`; `None`
    /// until first read. Added in 0.1.
    #[serde(default)]
    pub firmware_version: Option<String>,
}

/// The polling thread as the daemon's watchdog sees it, in [`StreamMessage::Status`].
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct PollingStatus {
    /// No poll has finished for longer than `stall_after_ms`: the polling thread is stuck
    /// (typically in an I2C transfer that does not return).
    pub stalled: bool,
    /// Milliseconds since the last poll finished.
    pub since_last_poll_ms: u64,
    /// The watchdog's bound, milliseconds.
    pub stall_after_ms: u64,
    /// Polls made since the daemon started.
    pub polls: u64,
    /// Poll deadlines missed since the daemon started (the thread was a whole period late).
    pub missed_deadlines: u64,
    /// Stalls seen since the daemon started, one going on included.
    pub stalls: u64,
}

/// The reply to a control request.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ControlReply {
    /// The request's `id`, or `null` if the request had none or could not be parsed.
    pub id: Option<u64>,
    /// Whether the command was carried out.
    pub ok: bool,
    /// What happened (on success) or why not (on failure), for humans.
    pub message: String,
    /// On failure, the machine-readable reason.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub error: Option<ErrorCode>,
}

/// Why a request failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorCode {
    /// The line was not UTF-8 JSON, or not a JSON object.
    BadJson,
    /// The line exceeded [`super::MAX_LINE_BYTES`]; the connection is then closed.
    LineTooLong,
    /// `cmd` was missing or not one of the known commands.
    UnknownCommand,
    /// The command's fields were missing, misspelt or out of range.
    BadRequest,
    /// `token` was missing or wrong; nothing was done. The reply comes after a delay that
    /// grows with the failures from the same address.
    BadToken,
    /// The daemon refused or failed to carry out a valid command.
    Rejected,
    /// The server already has its maximum number of clients (or this address its maximum of
    /// connections) and none can be dropped for this one; the connection is then closed.
    TooManyClients,
    /// The connection made too many failed authentications; it is then closed.
    TooManyFailures,
    /// The server was full and dropped this connection, the oldest one that never proved the
    /// token, to make room for a new client; it is then closed.
    Evicted,
}

impl ControlReply {
    /// A success reply.
    pub fn ok(id: Option<u64>, message: impl Into<String>) -> Self {
        Self {
            id,
            ok: true,
            message: message.into(),
            error: None,
        }
    }

    /// A failure reply.
    pub fn error(id: Option<u64>, code: ErrorCode, message: impl Into<String>) -> Self {
        Self {
            id,
            ok: false,
            message: message.into(),
            error: Some(code),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reply_round_trips_with_type_tag() {
        let m = StreamMessage::Reply(ControlReply::error(Some(3), ErrorCode::BadToken, "no"));
        let text = serde_json::to_string(&m).unwrap();
        assert_eq!(
            text,
            r#"{"type":"reply","id":3,"ok":false,"message":"no","error":"bad_token"}"#
        );
        assert_eq!(serde_json::from_str::<StreamMessage>(&text).unwrap(), m);
    }

    /// The `hello` examples in docs/stream-protocol.md: each reads, and one with the rig's
    /// scene goes back byte for byte.
    #[test]
    fn documented_hello_lines_read() {
        let doc = include_str!("../../../../docs/stream-protocol.md");
        let lines: Vec<&str> = doc
            .lines()
            .filter(|l| l.starts_with(r#"{"type":"hello""#))
            .collect();
        assert!(!lines.is_empty());
        for line in &lines {
            let message: StreamMessage = serde_json::from_str(line).unwrap();
            if line.contains("scene_toml") || !line.contains("\"rig\"") {
                assert_eq!(serde_json::to_string(&message).unwrap(), *line);
            }
        }
    }

    /// A `hello` without `rig` (the oldest daemons) and one with the rig as daemons sent it
    /// before the scene (issue #46: links, a flat wall, a stiffness profile) still read: the
    /// links and the mounting angle are kept, the rest is ignored, no scene.
    #[test]
    fn hello_lines_of_older_daemons_still_read() {
        let bare = r#"{"type":"hello","protocol_version":1,"daemon":"antennad 0.1.0","segment_count":3,"segment_addresses":[33,34,35]}"#;
        let StreamMessage::Hello { rig, .. } = serde_json::from_str(bare).unwrap() else {
            panic!("not hello");
        };
        assert!(rig.is_none());
        let old = r#"{"type":"hello","protocol_version":1,"daemon":"antennad 0.1.0","segment_count":3,"segment_addresses":[33,34,35],"rig":{"poll_hz":1000.0,"link_lengths_m":[0.04,0.04,0.04,0.04],"base_mount_angle_deg":30.0,"stiffness_profile":"linear","k_min_n_m_per_rad":0.01,"k_max_n_m_per_rad":0.05,"stiffness_n_m_per_rad":[0.05,0.03,0.01],"wall":{"distance_m":0.42,"angle_deg":30.0,"stiffness_n_per_m":200.0},"stage_min_m":0.0,"stage_max_m":0.3}}"#;
        let StreamMessage::Hello { rig, .. } = serde_json::from_str(old).unwrap() else {
            panic!("not hello");
        };
        let rig = rig.unwrap();
        assert_eq!(rig.link_lengths_m, vec![0.04; 4]);
        assert_eq!(rig.base_mount_angle_deg, 30.0);
        assert_eq!((rig.stage_min_m, rig.stage_max_m), (0.0, 0.3));
        assert_eq!(rig.scene_toml, None);
        // A new one goes back as it came.
        let new = RigInfo {
            scene_toml: Some("[antenna]\nlinks = 4\n".to_owned()),
            scene_source: Some("rig.toml".to_owned()),
            ..rig
        };
        let line = serde_json::to_string(&new).unwrap();
        assert_eq!(serde_json::from_str::<RigInfo>(&line).unwrap(), new);
    }

    /// The `samples` example in docs/stream-protocol.md, byte for byte; a line from a daemon
    /// that did not send `stale` or `touch_bits` still reads, as not stale and without bits.
    #[test]
    fn documented_samples_line_and_stale_compatibility() {
        let doc = include_str!("../../../../docs/stream-protocol.md");
        let line = doc
            .lines()
            .find(|l| l.starts_with(r#"{"type":"samples""#))
            .unwrap();
        let message: StreamMessage = serde_json::from_str(line).unwrap();
        assert_eq!(serde_json::to_string(&message).unwrap(), line);
        let StreamMessage::Samples { segments, .. } = &message else {
            panic!("not samples: {message:?}");
        };
        assert_eq!(
            segments.iter().map(|s| s.stale).collect::<Vec<_>>(),
            [false, false, true]
        );
        // `contact` is any touch bit; a failed read has neither.
        assert_eq!(
            segments
                .iter()
                .map(|s| (s.contact, s.touch_bits))
                .collect::<Vec<_>>(),
            [
                (Some(false), Some(0)),
                (None, None),
                (Some(true), Some(0b0100))
            ]
        );
        let old = r#"{"address":33,"angle_rad":0.5,"contact":true,"counter":17,"error":null}"#;
        let sample: SegmentSample = serde_json::from_str(old).unwrap();
        assert!(!sample.stale);
        assert_eq!((sample.contact, sample.touch_bits), (Some(true), None));
    }

    /// The `estimate` and `lagged` examples in docs/stream-protocol.md, byte for byte; a
    /// `lagged` line from a daemon before `samples_dropped` still reads.
    #[test]
    fn documented_estimate_and_lagged_lines() {
        let doc = include_str!("../../../../docs/stream-protocol.md");
        let lines: Vec<&str> = doc
            .lines()
            .filter(|l| l.starts_with(r#"{"type":"estimate""#))
            .collect();
        assert_eq!(lines.len(), 2);
        for line in &lines {
            let message: StreamMessage = serde_json::from_str(line).unwrap();
            assert_eq!(serde_json::to_string(&message).unwrap(), *line);
            let StreamMessage::Estimate(e) = message else {
                panic!("not an estimate: {line}");
            };
            // An estimate has no reason; no estimate has one and no distance.
            assert_eq!(e.distance_m.is_some(), e.reason.is_none());
            assert!(e.estimated_ns >= e.t_ns);
        }
        let line = doc
            .lines()
            .find(|l| l.starts_with(r#"{"type":"lagged""#))
            .unwrap();
        let message: StreamMessage = serde_json::from_str(line).unwrap();
        assert_eq!(serde_json::to_string(&message).unwrap(), line);
        let old: StreamMessage = serde_json::from_str(r#"{"type":"lagged","dropped":3}"#).unwrap();
        assert_eq!(
            old,
            StreamMessage::Lagged {
                dropped: 3,
                samples_dropped: 0
            }
        );
    }

    /// The `status` example in docs/stream-protocol.md, byte for byte; a line from a daemon
    /// without the bus fields (bus errors, firmware, the watchdog) still reads.
    #[test]
    fn documented_status_line_and_older_status_lines() {
        let doc = include_str!("../../../../docs/stream-protocol.md");
        let line = doc
            .lines()
            .find(|l| l.starts_with(r#"{"type":"status""#))
            .unwrap();
        let message: StreamMessage = serde_json::from_str(line).unwrap();
        assert_eq!(serde_json::to_string(&message).unwrap(), line);
        let StreamMessage::Status {
            segments, polling, ..
        } = &message
        else {
            panic!("not status: {message:?}");
        };
        assert_eq!(segments[0].firmware_version.as_deref(), Some("1.0"));
        assert_eq!(polling.as_ref().map(|p| p.stall_after_ms), Some(100));
        let old = r#"{"type":"status","t_ns":5,"trial":null,"segments":[{"address":33,"ok":4990,"nack":10,"pec_error":0,"stale":0}],"note":null}"#;
        let StreamMessage::Status {
            segments, polling, ..
        } = serde_json::from_str(old).unwrap()
        else {
            panic!("not status");
        };
        assert_eq!(polling, None);
        assert_eq!(
            (
                segments[0].bus_error,
                segments[0].status_flags,
                segments[0].firmware_version.clone()
            ),
            (0, None, None)
        );
    }
}
