//! Session commands, one file per command (tokio mini-redis's `src/cmd/` is the model). Each
//! command's file holds all of it:
//!
//! * its **wire parsing**: `Command::<name>(wire fields…)`, called by the WebSocket edge
//!   ([`Command::from_client`], from a [`ClientMessage`]) and the REST edge
//!   (`TryFrom<`[`Action`]`>`), which only route each wire variant to it;
//! * its **typed form** (a [`Command`] variant and its value types);
//! * its **application** to the live state (`apply`, called by [`Live::apply`]), and for the
//!   commands that concern the session rather than its simulation (`message`, `end`) the
//!   session's part, called by [`apply`];
//! * its **log form**: the attempt's input log ([`log`]) records the applied [`Command`]s
//!   themselves, serialized by the serde attributes on their types (`{"c": name, …}`).
//!
//! | file | command | wire (`type`) | who | logged (`c`) |
//! | --- | --- | --- | --- | --- |
//! | [`input`] | [`Command::Input`] | WS `input` | trainee | `input` (quanta) |
//! | [`jog`] | [`Command::Jog`] | WS `jog` | trainee | `jog` |
//! | [`settings`] | [`Command::Settings`] | WS `settings` | trainee | `settings` |
//! | [`ready`] | [`Command::Ready`] | WS `ready` | trainee | — (no steps pass while waiting) |
//! | [`reset`] | [`Command::Reset`] | WS, REST `reset` | trainee | — (a new attempt) |
//! | [`pause`] | [`Command::Pause`], [`Command::Resume`] | WS, REST `pause`, `resume` | trainee | — (no steps pass) |
//! | [`release`] | [`Command::Release`] | WS, REST `release` | trainee | `release` |
//! | [`scenario`] | [`Command::Scenario`] | REST `scenario` | instructor | — (a new attempt) |
//! | [`diagnose`] | [`Command::Diagnose`] | WS `diagnose` | trainee | `diagnose` |
//! | [`fault`] | [`Command::InjectFault`], [`Command::ClearFaults`] | REST `fault`, `clear_faults` | instructor | `fault`, `clear_faults` |
//! | [`current`] | [`Command::SetCurrent`] | REST `set_current` | instructor | `current` |
//! | [`visibility`] | [`Command::SetVisibility`] | REST `set_visibility` | instructor | — (drawing only) |
//! | [`message`] | [`Command::Message`] | REST `message` | instructor | — |
//! | [`end`] | [`Command::End`] | `DELETE /api/sessions/{id}` | trainee | — |
//!
//! "Who" is the least actor that may give it (the instructor may give every command; an
//! observer none). Wire names and shapes are in [`crate::protocol`]; here arms, faults and
//! actors are enums.

pub mod current;
pub mod diagnose;
pub mod end;
pub mod fault;
pub mod input;
pub mod jog;
pub mod log;
pub mod message;
pub mod pause;
pub mod ready;
pub mod release;
pub mod reset;
pub mod scenario;
pub mod settings;
pub mod visibility;

use std::sync::atomic::Ordering;

use serde::{Deserialize, Serialize};
use serde_json::json;

use super::record::RecordMsg;
use super::{Live, Session, SessionManager};
use crate::auth::Actor;
use crate::catalogue::Scenario;
use crate::protocol::{Action, ClientMessage};

pub use crate::protocol::ActiveFault;
pub use current::MAX_CURRENT_M_S;
pub use input::{ArmSticks, JOINTS, StickInput};
pub use message::MAX_MESSAGE_CHARS;
pub use pause::PAUSED_BY_INSTRUCTOR;
pub use release::RELEASE_DURATION_S;
pub use seaarms_core::hydraulics::{
    AIR_SCALE_RANGE, Fault, FaultKind, LEAK_RANGE_M3_S_PA, STUCK_SPOOL_RANGE, SUPPLY_DROP_RANGE_PA,
};
pub use seaarms_core::sim::Arm;
pub use seaarms_core::sim::water::Current;
pub use settings::SettingsChange;

/// Everything that can be done to a live session, from either edge. Serialized, it is the
/// log form of the commands that change the simulation (`{"c": "input", "v": […]}`, …); the
/// others are never logged (`#[serde(skip)]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "c", rename_all = "snake_case")]
pub enum Command {
    /// New stick input ([`input`]).
    Input(StickInput),
    /// A keyboard tap: move a bounded amount and stop ([`jog`]).
    Jog(jog::Jog),
    /// Change settings ([`settings`]).
    Settings(SettingsChange),
    /// Back to the initial position, Lim §4.1 ([`reset`]).
    #[serde(skip)]
    Reset,
    /// Pause the simulation clock ([`pause`]).
    #[serde(skip)]
    Pause,
    /// Resume it ([`pause`]).
    #[serde(skip)]
    Resume,
    /// Open both jaws for [`RELEASE_DURATION_S`] ([`release`]).
    Release,
    /// The trainee has read the goal: the attempt's clock starts ([`ready`]).
    #[serde(skip)]
    Ready,
    /// Switch scenario (a fresh simulation): free play, a case-study set-up or an exercise
    /// ([`scenario`]).
    #[serde(skip)]
    Scenario(Scenario),
    /// Name the fault of a diagnosis drill: one of the drill's answers ([`diagnose`]).
    Diagnose {
        /// The answer.
        answer: String,
    },
    /// Inject a fault ([`fault`]).
    #[serde(rename = "fault")]
    InjectFault {
        /// The fault (logged as arm index, kind, joint, value).
        #[serde(with = "fault::log_form")]
        fault: ActiveFault,
    },
    /// Remove every fault ([`fault`]).
    ClearFaults,
    /// Set the water's current: instructor only, a subsea session ([`current`]).
    #[serde(rename = "current")]
    SetCurrent(Current),
    /// Set the water's visibility for every page: instructor only ([`visibility`]).
    #[serde(skip)]
    SetVisibility(f64),
    /// Show an instructor's message on every client of the session ([`message`]).
    #[serde(skip)]
    Message(String),
    /// End the session ([`end`]).
    #[serde(skip)]
    End,
}

/// Why a command was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CommandError {
    /// The actor may not give this command.
    #[error("{0}")]
    Forbidden(String),
    /// The command's values are invalid.
    #[error("{0}")]
    Invalid(String),
}

impl Command {
    /// Name in records (the event's `kind`).
    pub fn name(&self) -> &'static str {
        match self {
            Command::Input(_) => "input",
            Command::Jog(_) => "jog",
            Command::Settings(_) => "settings",
            Command::Reset => "reset",
            Command::Pause => "pause",
            Command::Resume => "resume",
            Command::Release => "release",
            Command::Ready => "ready",
            Command::Scenario(_) => "scenario",
            Command::Diagnose { .. } => "diagnose",
            Command::InjectFault { .. } => "fault",
            Command::ClearFaults => "clear_faults",
            Command::SetCurrent(_) => "set_current",
            Command::SetVisibility(_) => "set_visibility",
            Command::Message(_) => "message",
            Command::End => "end",
        }
    }

    /// Whether `actor` may give this command.
    pub fn permitted(&self, actor: Actor) -> bool {
        match actor {
            Actor::Instructor => true,
            Actor::Trainee => matches!(
                self,
                Command::Input(_)
                    | Command::Jog(_)
                    | Command::Settings(_)
                    | Command::Reset
                    | Command::Pause
                    | Command::Resume
                    | Command::Release
                    | Command::Ready
                    | Command::Diagnose { .. }
                    | Command::End
            ),
            Actor::Observer => false,
        }
    }

    /// The WebSocket edge: a client message to a typed command, through each command's own
    /// parsing (values validated, clamping reported in `notes`). `ping` is answered by the
    /// connection itself and is no command.
    pub fn from_client(msg: ClientMessage, notes: &mut Vec<String>) -> Result<Command, String> {
        Ok(match msg {
            ClientMessage::Input { seq, arms, object } => {
                Command::input(seq, &arms, object.as_deref(), notes)?
            }
            ClientMessage::Jog { arm, axes } => {
                Command::jog(&arm, &axes, notes).map_err(|e| e.to_string())?
            }
            ClientMessage::Settings {
                control_mode,
                control_method,
                arm_speed,
                hold_orientation,
            } => Command::settings(control_mode, control_method, arm_speed, hold_orientation)
                .map_err(|e| e.to_string())?,
            ClientMessage::Reset => Command::Reset,
            ClientMessage::Pause => Command::Pause,
            ClientMessage::Resume => Command::Resume,
            ClientMessage::Release => Command::Release,
            ClientMessage::Ready => Command::Ready,
            ClientMessage::Diagnose { answer } => Command::Diagnose { answer },
            ClientMessage::Ping { .. } => return Err("ping is not a command".into()),
        })
    }

    /// The command as it is applied and logged: stick input rounded to the input quantum
    /// ([`log::INPUT_QUANTUM`]), everything else as given.
    fn applied_form(&self) -> Command {
        match self {
            Command::Input(input) => Command::Input(input.quantized()),
            other => other.clone(),
        }
    }

    /// Whether the attempt's log records this command (it changes what the next steps do;
    /// a reset or a scenario switch starts a new attempt instead, and pauses take no steps).
    fn logged(&self) -> bool {
        matches!(
            self,
            Command::Input(_)
                | Command::Jog(_)
                | Command::Settings(_)
                | Command::Release
                | Command::Diagnose { .. }
                | Command::InjectFault { .. }
                | Command::ClearFaults
                | Command::SetCurrent(_)
        )
    }
}

impl TryFrom<Action> for Command {
    type Error = CommandError;

    /// The REST edge: an action's wire fields to a typed command, through each command's own
    /// parsing.
    fn try_from(action: Action) -> Result<Command, CommandError> {
        Ok(match action {
            Action::Reset => Command::Reset,
            Action::Pause => Command::Pause,
            Action::Resume => Command::Resume,
            Action::Release => Command::Release,
            Action::Scenario { scenario } => Command::scenario(&scenario)?,
            Action::Fault {
                fault,
                arm,
                joint,
                value,
                silent,
                persistent,
            } => Command::fault(&fault, &arm, joint, value, silent, persistent)?,
            Action::ClearFaults => Command::ClearFaults,
            Action::SetCurrent {
                speed_m_s,
                heading_deg,
            } => Command::current(speed_m_s, heading_deg)?,
            Action::SetVisibility { visibility_m } => Command::visibility(visibility_m)?,
            Action::Message { text } => Command::message(&text)?,
        })
    }
}

/// Applies `command` to `session` on behalf of `actor`: the one place where commands take
/// effect, whichever edge they came from. Every command but stick input is recorded as an
/// event `{"t", "event", "by", …}`.
pub fn apply(
    manager: &SessionManager,
    session: &Session,
    actor: Actor,
    command: Command,
) -> Result<(), CommandError> {
    if !command.permitted(actor) {
        return Err(CommandError::Forbidden(match actor {
            Actor::Observer => "observers cannot control this session".to_string(),
            _ => format!("instructor token required for `{}`", command.name()),
        }));
    }
    if session.ended.load(Ordering::Relaxed) {
        return Err(CommandError::Invalid("the session has ended".into()));
    }
    // Trainee activity keeps a session from idling out; an instructor's does not.
    if actor == Actor::Trainee {
        session.touch();
    }
    let detail = match &command {
        Command::End => {
            record(manager, session, actor, &command, json!({}));
            end::apply(manager, session, actor);
            return Ok(());
        }
        Command::Message(text) => message::announce(session, actor, text),
        _ => {
            let mut live = session.live();
            if actor == Actor::Instructor {
                live.note_intervention(&command);
            }
            let detail = match &command {
                Command::Pause => pause::apply(&mut live, actor, true),
                Command::Resume => pause::apply(&mut live, actor, false),
                _ => live.apply(&command),
            };
            // A reset or switch ended an attempt and started one: records go out in order,
            // before this command's event.
            for msg in live.take_records(false) {
                manager.recorder.send(msg);
            }
            let detail = detail?;
            if let Command::Scenario(_) = &command {
                scenario::announce(session, &live);
            }
            if let Command::Input(_) | Command::Jog(_) = &command {
                return Ok(());
            }
            detail
        }
    };
    record(manager, session, actor, &command, detail);
    Ok(())
}

fn record(
    manager: &SessionManager,
    session: &Session,
    actor: Actor,
    command: &Command,
    detail: serde_json::Value,
) {
    let mut event = session.live().event(command.name(), detail);
    event.actor = Some(actor.as_str());
    manager.recorder.send(RecordMsg::Event(event));
}

impl Live {
    /// Applies a command to the live state (the part of [`apply`] that sessions, headless
    /// attempts and replay share) and logs it in the running attempt when it changes the
    /// simulation; returns the record's detail. `End` and `Message` are the session's
    /// business and do nothing here.
    pub fn apply(&mut self, command: &Command) -> Result<serde_json::Value, CommandError> {
        let command = command.applied_form();
        let detail = match &command {
            Command::Input(input) => input::apply(self, input),
            Command::Jog(j) => jog::apply(self, j),
            Command::Settings(change) => settings::apply(self, change),
            Command::Reset => reset::apply(self),
            // Without an actor (headless attempts), pause and resume act as the trainee's.
            Command::Pause => pause::apply(self, Actor::Trainee, true)?,
            Command::Resume => pause::apply(self, Actor::Trainee, false)?,
            Command::Release => release::apply(self),
            Command::Scenario(scenario) => scenario::apply(self, scenario)?,
            Command::Diagnose { answer } => diagnose::apply(self, answer)?,
            Command::InjectFault { fault } => fault::inject(self, fault),
            Command::ClearFaults => fault::clear(self),
            Command::SetCurrent(current) => current::apply(self, current)?,
            Command::SetVisibility(v) => visibility::apply(self, *v),
            Command::Ready => ready::apply(self),
            Command::Message(_) | Command::End => json!({}),
        };
        if command.logged() {
            self.log(log::Logged::Command(command));
        }
        Ok(detail)
    }

    /// Counts an instructor's command as an intervention in the running attempt (stick
    /// input and messages do not count, nor silent faults: they set up a diagnosis drill,
    /// and a count the trainee's assessment shows would give them away).
    fn note_intervention(&mut self, command: &Command) {
        let silent = matches!(command, Command::InjectFault { fault } if fault.silent);
        if !silent
            && !matches!(
                command,
                // The current is the exercise's conditions, not help given to the trainee.
                Command::Input(_)
                    | Command::Message(_)
                    | Command::End
                    | Command::SetCurrent(_)
                    | Command::SetVisibility(_)
                    | Command::Ready
            )
        {
            self.intervene();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permissions() {
        for c in [Command::Reset, Command::Pause, Command::End] {
            assert!(c.permitted(Actor::Trainee));
            assert!(c.permitted(Actor::Instructor));
            assert!(!c.permitted(Actor::Observer));
        }
        assert!(!Command::ClearFaults.permitted(Actor::Trainee));
        assert!(!Command::Message("x".into()).permitted(Actor::Trainee));
        assert!(Command::settings(None, None, Some(0.0), None).is_err());
        assert!(Command::settings(None, None, Some(1.0), None).is_ok());
        assert!(Command::scenario("nope").is_err());
    }
}
