//! `message`: the instructor's message, shown on every page of the session. Wire: the REST
//! action `{"type": "message", "text"}`; pages get `{"type": "message", "from", "text"}`.
//! Not logged (it changes nothing in the simulation); recorded as an event.

use serde_json::json;

use super::{Command, CommandError};
use crate::auth::Actor;
use crate::protocol::ServerMessage;
use crate::sessions::Session;

/// Largest instructor message to a trainee (characters).
pub const MAX_MESSAGE_CHARS: usize = 500;

impl Command {
    /// Parses a message, checking its length.
    pub fn message(text: &str) -> Result<Command, CommandError> {
        if text.chars().count() > MAX_MESSAGE_CHARS {
            return Err(CommandError::Invalid(format!(
                "message text is limited to {MAX_MESSAGE_CHARS} characters"
            )));
        }
        Ok(Command::Message(text.to_string()))
    }
}

/// Sends the message to every client of the session; returns the record's detail.
pub(super) fn announce(session: &Session, from: Actor, text: &str) -> serde_json::Value {
    let msg = ServerMessage::Message {
        from: from.as_str().into(),
        text: text.to_string(),
    };
    let _ = session
        .notices
        .send(serde_json::to_string(&msg).unwrap_or_default().into());
    json!({"text": text})
}
