//! The [`ControlHandler`] the daemon implements, and [`serve_request`]: one request line in,
//! one reply out, the token checked before the command's fields are looked at.
//!
//! `stop_all` needs no token and no valid fields: any line whose `cmd` is `stop_all` stops
//! everything. Every other command, and `auth`, needs the token.

use antenna_data::stream::{ControlCommand, ControlReply, ErrorCode, Request, RequestEnvelope};

use crate::config::token::ControlToken;

/// What the daemon does with control commands.
///
/// Called on the requesting client's reader thread, possibly from several clients at once,
/// only for requests that carried the right token (or needed none: `stop_all`). It should
/// return promptly (e.g. by handing the command to the daemon's own thread); while it runs,
/// only that client waits. `stop_all` should be carried out ahead of any other work.
pub trait ControlHandler: Send + Sync + 'static {
    /// Carries out `command`: `Ok` with a message for the client, or `Err` with the reason.
    ///
    /// # Errors
    /// The reason the command was refused or failed, sent to the client as
    /// [`ErrorCode::Rejected`].
    fn handle(&self, command: ControlCommand) -> Result<String, String>;
}

/// What a request did about the token.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AuthOutcome {
    /// It needed none (`stop_all`), or was refused before the token was looked at.
    NotAsked,
    /// It carried the right token.
    Proved,
    /// It needed the token and did not carry the right one: nothing was done.
    Failed,
}

/// One request served.
#[derive(Debug, Clone, PartialEq)]
pub struct Served {
    /// The reply to send.
    pub reply: ControlReply,
    /// What the request did about the token.
    pub auth: AuthOutcome,
    /// The request was a `stop_all`.
    pub stop_all: bool,
}

/// Parses one request line, checks the token (except for `stop_all`), validates the command
/// and, only if all of that succeeds, calls `handler`.
pub fn serve_request(line: &[u8], token: &ControlToken, handler: &dyn ControlHandler) -> Served {
    let refused = |reply| Served {
        reply,
        auth: AuthOutcome::NotAsked,
        stop_all: false,
    };
    let envelope = match RequestEnvelope::parse(line) {
        Ok(envelope) => envelope,
        Err(reply) => return refused(reply),
    };
    let id = envelope.id();
    if !envelope.needs_token() {
        // Stopping is always allowed: no token, and stray fields do not hold it back.
        return Served {
            reply: answer(id, handler.handle(ControlCommand::StopAll)),
            auth: AuthOutcome::NotAsked,
            stop_all: true,
        };
    }
    if !envelope.token().is_some_and(|t| token.matches(t)) {
        return Served {
            reply: ControlReply::error(id, ErrorCode::BadToken, "missing or wrong `token`"),
            auth: AuthOutcome::Failed,
            stop_all: false,
        };
    }
    let reply = match envelope.command() {
        Ok(Request::Auth) => ControlReply::ok(
            id,
            "authenticated: this connection is an operator's, kept when the server is full",
        ),
        Ok(Request::Control(command)) => answer(id, handler.handle(command)),
        Err(reply) => reply,
    };
    Served {
        reply,
        auth: AuthOutcome::Proved,
        stop_all: false,
    }
}

fn answer(id: Option<u64>, result: Result<String, String>) -> ControlReply {
    match result {
        Ok(message) => ControlReply::ok(id, message),
        Err(message) => ControlReply::error(id, ErrorCode::Rejected, message),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::RecordingHandler;
    use antenna_data::stream::{StreamMessage, encode_line};

    const TOKEN: &str = "s3cret-s3cret-s3cret";

    fn served(request: &str) -> (String, AuthOutcome, Vec<ControlCommand>) {
        let token = ControlToken::new(TOKEN).unwrap();
        let handler = RecordingHandler::new();
        let served = serve_request(request.as_bytes(), &token, &handler);
        let line = encode_line(&StreamMessage::Reply(served.reply)).unwrap();
        (
            String::from_utf8(line).unwrap().trim_end().to_owned(),
            served.auth,
            handler.calls(),
        )
    }

    /// The error examples in docs/stream-protocol.md, byte for byte.
    #[test]
    fn documented_error_replies() {
        let doc = include_str!("../../../docs/stream-protocol.md");
        let lines: Vec<&str> = doc.lines().collect();
        let mut checked = 0;
        for pair in lines.windows(2) {
            if let (Some(request), Some(reply)) =
                (pair[0].strip_prefix("-> "), pair[1].strip_prefix("<- "))
            {
                assert_eq!(served(request).0, reply, "{request}");
                checked += 1;
            }
        }
        assert!(checked >= 4, "{checked} documented examples");
    }

    #[test]
    fn stop_all_needs_no_token_and_the_rest_do() {
        for request in [
            r#"{"id":1,"cmd":"stop_all"}"#,
            r#"{"id":1,"token":"wrong","cmd":"stop_all"}"#,
            r#"{"id":1,"cmd":"stop_all","please":true}"#,
        ] {
            let (reply, auth, calls) = served(request);
            assert!(reply.contains(r#""ok":true"#), "{reply}");
            assert_eq!(auth, AuthOutcome::NotAsked);
            assert_eq!(calls, [ControlCommand::StopAll]);
        }
        let (reply, auth, calls) = served(r#"{"id":2,"cmd":"stop_trial"}"#);
        assert!(reply.contains("bad_token"), "{reply}");
        assert_eq!(auth, AuthOutcome::Failed);
        assert!(calls.is_empty());
        let (reply, auth, calls) = served(&format!(r#"{{"id":3,"token":"{TOKEN}","cmd":"auth"}}"#));
        assert!(reply.contains(r#""ok":true"#), "{reply}");
        assert_eq!(auth, AuthOutcome::Proved);
        assert!(calls.is_empty());
        // The reply never echoes the token.
        assert!(!reply.contains(TOKEN));
    }
}
