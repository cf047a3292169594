//! `scenario`: switch to free play, a case-study set-up or an exercise (a fresh simulation
//! and a new attempt). Wire: the REST action `{"type": "scenario", "scenario"}`; every page
//! of the session then gets the `scenario` message. Not logged: the new attempt's `init`
//! names it.

use serde_json::json;

use super::{Command, CommandError};
use crate::catalogue::Scenario;
use crate::protocol::{SceneOut, ServerMessage};
use crate::sessions::{Live, Session};

impl Command {
    /// Parses a scenario switch: a live scenario's name or an exercise id.
    pub fn scenario(name: &str) -> Result<Command, CommandError> {
        Scenario::resolve(name)
            .map(Command::Scenario)
            .ok_or_else(|| CommandError::Invalid(format!("unknown scenario or exercise `{name}`")))
    }
}

/// Applies a switch.
pub(super) fn apply(
    live: &mut Live,
    scenario: &Scenario,
) -> Result<serde_json::Value, CommandError> {
    live.set_scenario(scenario.clone())
        .map_err(|e| CommandError::Invalid(format!("scenario: {e}")))?;
    Ok(json!({"scenario": scenario.name()}))
}

/// Tells every page of the session: redraw the scene and follow the new settings.
pub(super) fn announce(session: &Session, live: &Live) {
    let s = live.scenario();
    let msg = ServerMessage::Scenario {
        scenario: s.name().to_string(),
        exercise: s.exercise().cloned(),
        scene: Box::new(SceneOut::new(
            live.sim().params(),
            s.exercise().map(|e| &**e),
        )),
        settings: live.settings(),
    };
    let _ = session
        .notices
        .send(serde_json::to_string(&msg).unwrap_or_default().into());
}
