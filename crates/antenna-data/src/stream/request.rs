//! Control requests as a client writes them: parsing and validation, without the token check
//! (the server owns the token; see `host_daemon::net`).
//!
//! A request line is read in two steps, so that a server can check the token between them and
//! never look at a command's fields for a request it will refuse:
//! [`RequestEnvelope::parse`] reads `id`, `cmd` and `token`; [`RequestEnvelope::command`]
//! validates the command's own fields.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::message::{ControlReply, ErrorCode};

/// One line from a client: `{"id": 1, "token": "...", "cmd": "stop_all", ...}`.
///
/// The command's own fields sit beside `id`, `token` and `cmd` at the top level. `stop_all`
/// needs no token; `auth` and every other command do.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ControlRequest {
    /// Chosen by the client, echoed in the reply.
    pub id: Option<u64>,
    /// The daemon's control token (`None`: sent without one, enough for `stop_all`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub token: Option<String>,
    /// The command and its fields.
    #[serde(flatten)]
    pub command: WireCommand,
}

/// A command as it appears on the wire (before validation into [`ControlCommand`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "cmd", rename_all = "snake_case", deny_unknown_fields)]
pub enum WireCommand {
    /// Start recording a trial.
    StartTrial {
        /// Trial name (non-empty; used in the file name).
        name: String,
        /// Free-text metadata such as wall and hair layout.
        #[serde(default)]
        metadata: BTreeMap<String, String>,
    },
    /// Stop the current trial.
    StopTrial {},
    /// Move the stage: exactly one of `position_m` (absolute) and `relative_m`.
    MoveStage {
        /// Absolute target in metres.
        position_m: Option<f64>,
        /// Distance to move in metres (signed).
        relative_m: Option<f64>,
        /// Speed in metres per second (positive); the configured default if absent.
        speed_m_per_s: Option<f64>,
    },
    /// Turn the base servo.
    SetBaseAngle {
        /// Target angle in degrees.
        angle_deg: f64,
    },
    /// Stop the stage, hold the servo and end any trial. Needs no token.
    StopAll {},
    /// Prove the token without doing anything: the connection then counts as an operator's,
    /// which the server keeps when it is full.
    Auth {},
}

/// Where a stage move goes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StageTarget {
    /// To this absolute position, metres.
    Absolute {
        /// Target position in metres.
        position_m: f64,
    },
    /// By this signed distance, metres.
    Relative {
        /// Signed distance in metres.
        distance_m: f64,
    },
}

/// A validated control command, as a server hands it to the daemon.
///
/// Numbers are finite; the daemon still enforces its soft limits and calibration ranges.
#[derive(Debug, Clone, PartialEq)]
pub enum ControlCommand {
    /// Start recording a trial.
    StartTrial {
        /// Non-empty trial name.
        name: String,
        /// Free-text metadata.
        metadata: BTreeMap<String, String>,
    },
    /// Stop the current trial.
    StopTrial,
    /// Move the stage.
    MoveStage {
        /// Where to.
        target: StageTarget,
        /// Positive speed in metres per second, or the configured default.
        speed_m_per_s: Option<f64>,
    },
    /// Turn the base servo to `angle_deg` degrees.
    SetBaseAngle {
        /// Target angle in degrees.
        angle_deg: f64,
    },
    /// Stop everything.
    StopAll,
}

/// A validated request: `auth` (the server answers it itself) or a command for the daemon.
#[derive(Debug, Clone, PartialEq)]
pub enum Request {
    /// `auth`: the token was checked, nothing else to do.
    Auth,
    /// A command for the daemon.
    Control(ControlCommand),
}

impl WireCommand {
    /// Checks the fields and turns the command into a [`Request`].
    ///
    /// # Errors
    /// A message naming the offending field.
    pub fn validate(self) -> Result<Request, String> {
        Ok(Request::Control(match self {
            Self::StartTrial { name, metadata } => {
                if name.trim().is_empty() {
                    return Err("start_trial: `name` must not be empty".into());
                }
                ControlCommand::StartTrial { name, metadata }
            }
            Self::StopTrial {} => ControlCommand::StopTrial,
            Self::MoveStage {
                position_m,
                relative_m,
                speed_m_per_s,
            } => {
                let target = match (position_m, relative_m) {
                    (Some(p), None) => StageTarget::Absolute {
                        position_m: finite("position_m", p)?,
                    },
                    (None, Some(d)) => StageTarget::Relative {
                        distance_m: finite("relative_m", d)?,
                    },
                    _ => {
                        return Err(
                            "move_stage: give exactly one of `position_m` and `relative_m`".into(),
                        );
                    }
                };
                if let Some(v) = speed_m_per_s
                    && !(v.is_finite() && v > 0.0)
                {
                    return Err(format!("move_stage: `speed_m_per_s` must be > 0, got {v}"));
                }
                ControlCommand::MoveStage {
                    target,
                    speed_m_per_s,
                }
            }
            Self::SetBaseAngle { angle_deg } => ControlCommand::SetBaseAngle {
                angle_deg: finite("angle_deg", angle_deg)?,
            },
            Self::StopAll {} => ControlCommand::StopAll,
            Self::Auth {} => return Ok(Request::Auth),
        }))
    }
}

fn finite(field: &str, v: f64) -> Result<f64, String> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("`{field}` must be a finite number"))
    }
}

/// The command names [`WireCommand`] accepts.
pub const COMMAND_NAMES: [&str; 6] = [
    "start_trial",
    "stop_trial",
    "move_stage",
    "set_base_angle",
    "stop_all",
    "auth",
];

/// The command that needs no token.
pub const STOP_ALL: &str = "stop_all";

/// A request line read as far as its `id`, `cmd` and `token` (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct RequestEnvelope {
    id: Option<u64>,
    cmd: String,
    token: Option<String>,
    fields: serde_json::Map<String, serde_json::Value>,
}

impl RequestEnvelope {
    /// Reads `id`, `cmd` (one of [`COMMAND_NAMES`]) and `token` from one request line.
    ///
    /// # Errors
    /// The reply to send: `bad_json` for a line that is not a UTF-8 JSON object,
    /// `bad_request` for a bad `id`, `unknown_command` for a missing or unknown `cmd`.
    pub fn parse(line: &[u8]) -> Result<Self, ControlReply> {
        let Ok(text) = std::str::from_utf8(line) else {
            return Err(ControlReply::error(
                None,
                ErrorCode::BadJson,
                "the line is not valid UTF-8",
            ));
        };
        let value: serde_json::Value = serde_json::from_str(text)
            .map_err(|e| ControlReply::error(None, ErrorCode::BadJson, format!("not JSON: {e}")))?;
        let serde_json::Value::Object(mut fields) = value else {
            return Err(ControlReply::error(
                None,
                ErrorCode::BadJson,
                "a request must be a JSON object",
            ));
        };
        let id = match fields.remove("id") {
            None | Some(serde_json::Value::Null) => None,
            Some(v) => match v.as_u64() {
                Some(id) => Some(id),
                None => {
                    return Err(ControlReply::error(
                        None,
                        ErrorCode::BadRequest,
                        "`id` must be an unsigned integer",
                    ));
                }
            },
        };
        let cmd = match fields.get("cmd") {
            Some(serde_json::Value::String(s)) => s.clone(),
            Some(_) => {
                return Err(ControlReply::error(
                    id,
                    ErrorCode::UnknownCommand,
                    "`cmd` must be a string",
                ));
            }
            None => {
                return Err(ControlReply::error(
                    id,
                    ErrorCode::UnknownCommand,
                    "missing `cmd`",
                ));
            }
        };
        if !COMMAND_NAMES.contains(&cmd.as_str()) {
            return Err(ControlReply::error(
                id,
                ErrorCode::UnknownCommand,
                format!(
                    "unknown command `{cmd}`; known: {}",
                    COMMAND_NAMES.join(", ")
                ),
            ));
        }
        // Whatever the token field holds, it is not a command field.
        let token = match fields.remove("token") {
            Some(serde_json::Value::String(s)) => Some(s),
            _ => None,
        };
        Ok(Self {
            id,
            cmd,
            token,
            fields,
        })
    }

    /// The request's `id`.
    pub fn id(&self) -> Option<u64> {
        self.id
    }

    /// The command's name, one of [`COMMAND_NAMES`].
    pub fn cmd(&self) -> &str {
        &self.cmd
    }

    /// Whether the command needs the token (every one but `stop_all`).
    pub fn needs_token(&self) -> bool {
        self.cmd != STOP_ALL
    }

    /// The token sent, if it was a string.
    pub fn token(&self) -> Option<&str> {
        self.token.as_deref()
    }

    /// Validates the command's fields.
    ///
    /// # Errors
    /// A `bad_request` reply naming the field.
    pub fn command(self) -> Result<Request, ControlReply> {
        let id = self.id;
        let mut fields = self.fields;
        // `cmd` is the tag; every other field belongs to the command.
        fields.insert(
            "cmd".to_owned(),
            serde_json::Value::String(self.cmd.clone()),
        );
        let wire: WireCommand =
            serde_json::from_value(serde_json::Value::Object(fields)).map_err(|e| {
                ControlReply::error(id, ErrorCode::BadRequest, format!("{}: {e}", self.cmd))
            })?;
        wire.validate()
            .map_err(|e| ControlReply::error(id, ErrorCode::BadRequest, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn command(line: &str) -> Result<Request, ControlReply> {
        RequestEnvelope::parse(line.as_bytes())?.command()
    }

    #[test]
    fn request_struct_encodes_the_documented_shape() {
        let request = ControlRequest {
            id: Some(4),
            token: Some("s3cret-s3cret-s3cret".into()),
            command: WireCommand::SetBaseAngle { angle_deg: 15.0 },
        };
        let text = serde_json::to_string(&request).unwrap_or_default();
        assert_eq!(
            serde_json::from_str::<ControlRequest>(&text).ok(),
            Some(request)
        );
        assert_eq!(
            text,
            r#"{"id":4,"token":"s3cret-s3cret-s3cret","cmd":"set_base_angle","angle_deg":15.0}"#
        );
        let stop = ControlRequest {
            id: Some(6),
            token: None,
            command: WireCommand::StopAll {},
        };
        assert_eq!(
            serde_json::to_string(&stop).unwrap_or_default(),
            r#"{"id":6,"cmd":"stop_all"}"#
        );
    }

    #[test]
    fn envelopes_read_id_cmd_and_token_then_the_fields() {
        let envelope =
            RequestEnvelope::parse(br#"{"id":3,"token":"t","cmd":"move_stage","relative_m":1}"#)
                .expect("parses");
        assert_eq!(
            (envelope.id(), envelope.cmd(), envelope.token()),
            (Some(3), "move_stage", Some("t"))
        );
        assert!(envelope.needs_token());
        assert_eq!(
            envelope.command(),
            Ok(Request::Control(ControlCommand::MoveStage {
                target: StageTarget::Relative { distance_m: 1.0 },
                speed_m_per_s: None
            }))
        );
        let stop = RequestEnvelope::parse(br#"{"cmd":"stop_all","token":42}"#).expect("parses");
        assert!(!stop.needs_token());
        assert_eq!(stop.token(), None);
        assert_eq!(command(r#"{"cmd":"auth"}"#), Ok(Request::Auth));
        let bad = command(r#"{"id":2,"cmd":"set_base_angle","angle_deg":"x"}"#).unwrap_err();
        assert_eq!(bad.error, Some(ErrorCode::BadRequest));
        assert_eq!(bad.id, Some(2));
        let unknown = command(r#"{"id":2,"cmd":"fly"}"#).unwrap_err();
        assert_eq!(unknown.error, Some(ErrorCode::UnknownCommand));
    }
}
