//! The [`ControlHandler`] the daemon implements, and [`serve_request`]: one request line in,
//! one reply out, the token checked before the command's fields are looked at.

use antenna_data::stream::{ControlCommand, ControlReply, ErrorCode, Request, RequestEnvelope};

use super::token::ControlToken;

/// What the daemon does with control commands.
///
/// Called on the requesting client's reader thread, possibly from several clients at once,
/// only for requests that carried the right token (or needed none: `stop_all`). It should
/// return promptly (e.g. by handing the command to the daemon's own thread); while it runs,
/// only that client waits.
pub trait ControlHandler: Send + Sync + 'static {
    /// Carries out `command`: `Ok` with a message for the client, or `Err` with the reason.
    ///
    /// # Errors
    /// The reason the command was refused or failed, sent to the client as
    /// [`ErrorCode::Rejected`].
    fn handle(&self, command: ControlCommand) -> Result<String, String>;
}

/// Parses one request line, checks the token, validates the command and, only if all of that
/// succeeds, calls `handler`. Always returns the reply to send.
pub fn serve_request(
    line: &[u8],
    token: &ControlToken,
    handler: &dyn ControlHandler,
) -> ControlReply {
    let envelope = match RequestEnvelope::parse(line) {
        Ok(envelope) => envelope,
        Err(reply) => return reply,
    };
    let id = envelope.id();
    if !envelope.token().is_some_and(|t| token.matches(t)) {
        return ControlReply::error(id, ErrorCode::BadToken, "missing or wrong `token`");
    }
    match envelope.command() {
        Ok(Request::Auth) => ControlReply::ok(id, "authenticated"),
        Ok(Request::Control(command)) => match handler.handle(command) {
            Ok(message) => ControlReply::ok(id, message),
            Err(message) => ControlReply::error(id, ErrorCode::Rejected, message),
        },
        Err(reply) => reply,
    }
}
