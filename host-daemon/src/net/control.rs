//! Control requests: parsing, validation and the [`ControlHandler`] the daemon implements.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::message::{ControlReply, ErrorCode};
use super::token::ControlToken;

/// One line from a client: `{"id": 1, "token": "...", "cmd": "stop_all", ...}`.
///
/// The command's own fields sit beside `id`, `token` and `cmd` at the top level.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ControlRequest {
    /// Chosen by the client, echoed in the reply.
    pub id: Option<u64>,
    /// The daemon's control token.
    pub token: String,
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
    /// Stop the stage, hold the servo and end any trial.
    StopAll {},
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

/// A validated control command, as handed to [`ControlHandler::handle`].
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

/// What the daemon does with control commands.
///
/// Called on the requesting client's reader thread, possibly from several clients at once,
/// only for requests that carried the right token. It should return promptly (e.g. by handing
/// the command to the daemon's own thread); while it runs, only that client waits.
pub trait ControlHandler: Send + Sync + 'static {
    /// Carries out `command`: `Ok` with a message for the client, or `Err` with the reason.
    ///
    /// # Errors
    /// The reason the command was refused or failed, sent to the client as
    /// [`ErrorCode::Rejected`].
    fn handle(&self, command: ControlCommand) -> Result<String, String>;
}

impl WireCommand {
    /// Checks the fields and turns the command into a [`ControlCommand`].
    ///
    /// # Errors
    /// A message naming the offending field.
    pub fn validate(self) -> Result<ControlCommand, String> {
        Ok(match self {
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
        })
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
pub const COMMAND_NAMES: [&str; 5] = [
    "start_trial",
    "stop_trial",
    "move_stage",
    "set_base_angle",
    "stop_all",
];

/// Parses one request line, checks the token, validates the command and, only if all of that
/// succeeds, calls `handler`. Always returns the reply to send.
pub fn serve_request(
    line: &[u8],
    token: &ControlToken,
    handler: &dyn ControlHandler,
) -> ControlReply {
    let Ok(text) = std::str::from_utf8(line) else {
        return ControlReply::error(None, ErrorCode::BadJson, "the line is not valid UTF-8");
    };
    let value: serde_json::Value = match serde_json::from_str(text) {
        Ok(v) => v,
        Err(e) => return ControlReply::error(None, ErrorCode::BadJson, format!("not JSON: {e}")),
    };
    let serde_json::Value::Object(mut map) = value else {
        return ControlReply::error(None, ErrorCode::BadJson, "a request must be a JSON object");
    };
    let id = match map.remove("id") {
        None | Some(serde_json::Value::Null) => None,
        Some(v) => match v.as_u64() {
            Some(id) => Some(id),
            None => {
                return ControlReply::error(
                    None,
                    ErrorCode::BadRequest,
                    "`id` must be an unsigned integer",
                );
            }
        },
    };
    let cmd_name = match map.get("cmd") {
        Some(serde_json::Value::String(s)) => s.clone(),
        Some(_) => {
            return ControlReply::error(id, ErrorCode::UnknownCommand, "`cmd` must be a string");
        }
        None => return ControlReply::error(id, ErrorCode::UnknownCommand, "missing `cmd`"),
    };
    if !COMMAND_NAMES.contains(&cmd_name.as_str()) {
        return ControlReply::error(
            id,
            ErrorCode::UnknownCommand,
            format!(
                "unknown command `{cmd_name}`; known: {}",
                COMMAND_NAMES.join(", ")
            ),
        );
    }
    let token_ok = match map.remove("token") {
        Some(serde_json::Value::String(s)) => token.matches(&s),
        _ => false,
    };
    if !token_ok {
        return ControlReply::error(id, ErrorCode::BadToken, "missing or wrong `token`");
    }
    let wire: WireCommand = match serde_json::from_value(serde_json::Value::Object(map)) {
        Ok(w) => w,
        Err(e) => {
            return ControlReply::error(id, ErrorCode::BadRequest, format!("{cmd_name}: {e}"));
        }
    };
    let command = match wire.validate() {
        Ok(c) => c,
        Err(e) => return ControlReply::error(id, ErrorCode::BadRequest, e),
    };
    match handler.handle(command) {
        Ok(message) => ControlReply::ok(id, message),
        Err(message) => ControlReply::error(id, ErrorCode::Rejected, message),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::RecordingHandler;
    use crate::net::framing::encode_line;
    use crate::net::message::StreamMessage;

    fn reply_line(request: &str) -> String {
        let token = ControlToken::new("s3cret").unwrap();
        let reply = serve_request(request.as_bytes(), &token, &RecordingHandler::new());
        let line = encode_line(&StreamMessage::Reply(reply)).unwrap();
        String::from_utf8(line).unwrap().trim_end().to_owned()
    }

    /// The error examples in docs/stream-protocol.md, byte for byte.
    #[test]
    fn documented_error_replies() {
        assert_eq!(
            reply_line(r#"{"id":9,"token":"s3cret","cmd":"move_stage","positon_m":0.3}"#),
            r#"{"type":"reply","id":9,"ok":false,"message":"move_stage: unknown field `positon_m`, expected one of `position_m`, `relative_m`, `speed_m_per_s`","error":"bad_request"}"#
        );
        assert_eq!(
            reply_line("hello?"),
            r#"{"type":"reply","id":null,"ok":false,"message":"not JSON: expected value at line 1 column 1","error":"bad_json"}"#
        );
        assert_eq!(
            reply_line(r#"{"id":10,"token":"s3cret","cmd":"self_destruct"}"#),
            r#"{"type":"reply","id":10,"ok":false,"message":"unknown command `self_destruct`; known: start_trial, stop_trial, move_stage, set_base_angle, stop_all","error":"unknown_command"}"#
        );
        assert_eq!(
            reply_line(r#"{"id":8,"token":"wrong","cmd":"stop_all"}"#),
            r#"{"type":"reply","id":8,"ok":false,"message":"missing or wrong `token`","error":"bad_token"}"#
        );
    }

    #[test]
    fn request_struct_encodes_the_documented_shape() {
        let request = ControlRequest {
            id: Some(4),
            token: "s3cret".into(),
            command: WireCommand::SetBaseAngle { angle_deg: 15.0 },
        };
        let text = serde_json::to_string(&request).unwrap();
        assert_eq!(
            serde_json::from_str::<ControlRequest>(&text).unwrap(),
            request
        );
        assert_eq!(
            text,
            r#"{"id":4,"token":"s3cret","cmd":"set_base_angle","angle_deg":15.0}"#
        );
        assert_eq!(
            reply_line(&text),
            r#"{"type":"reply","id":4,"ok":true,"message":"done: SetBaseAngle { angle_deg: 15.0 }"}"#
        );
    }
}
