//! Session commands: one typed [`Command`] that both edges (the WebSocket in [`super::ws`],
//! REST in [`super::rest`]) parse their wire messages into, and one function, [`apply`], that
//! checks who may give it, applies it to the session and records it.
//!
//! Wire strings (`"left"`, `"supply_drop:left:3000000Pa"`, …) live in [`crate::protocol`];
//! here arms, faults and actors are enums.

use std::sync::atomic::Ordering;

use serde_json::json;

use super::record::RecordMsg;
use super::{Live, Scenario, Session, SessionManager};
use crate::auth::Actor;
use crate::protocol::{ControlMethod, ControlMode, EndReason, ServerMessage};
use crate::replay::log::{Applied, dequantize, quantize};

/// What a trainee's `resume` gets while the instructor has paused the session.
pub const PAUSED_BY_INSTRUCTOR: &str = "paused by the instructor; only the instructor can resume";
/// Largest instructor message to a trainee (characters).
pub const MAX_MESSAGE_CHARS: usize = 500;
/// How long `release` drives both jaws open (s): 7.5 cm at 10.2 cm/s takes 0.74 s (Lim
/// Table 1-1), so 1 s opens them fully whatever grip the sticks send meanwhile.
pub const RELEASE_DURATION_S: f64 = 1.0;
/// Actuators per arm (swing, shoulder, elbow, pitch, yaw, rotate).
pub const JOINTS: usize = 6;

pub use seaarms_core::hydraulics::{
    AIR_SCALE_RANGE, Fault, FaultKind, LEAK_RANGE_M3_S_PA, STUCK_SPOOL_RANGE, SUPPLY_DROP_RANGE_PA,
};
pub use seaarms_core::sim::Arm;
pub use seaarms_core::sim::water::{Current, MAX_CURRENT_M_S};

/// A fault active on one arm (shown to users through [`crate::protocol`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ActiveFault {
    /// Which arm.
    pub arm: Arm,
    /// What and how much.
    pub fault: Fault,
    /// Injected without telling the trainee (a diagnosis drill): it acts on the simulation
    /// like any fault but is left out of the state frames and of the trainee's summary; only
    /// the instructor's session summary lists it.
    pub silent: bool,
}

impl ActiveFault {
    /// Whether `other` replaces this one (same arm, kind and actuator).
    pub fn same_slot(&self, other: &ActiveFault) -> bool {
        self.arm == other.arm
            && self.fault.kind() == other.fault.kind()
            && self.fault.joint() == other.fault.joint()
    }
}

/// One arm's validated sticks: six axes and a grip, each in [−1, 1].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ArmSticks {
    /// Joint mode: valve commands; Cartesian mode: end-effector twist fractions.
    pub axes: [f64; 6],
    /// Jaw: +1 opens, −1 closes.
    pub grip: f64,
}

/// Validated stick input (an absent arm is all zero).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StickInput {
    /// Sequence number (≤ [`crate::protocol::MAX_INPUT_SEQ`]).
    pub seq: u64,
    /// Left and right.
    pub arms: [ArmSticks; 2],
    /// Closed loop: commanded object twist [vx, vy, vz, wx, wy, wz] (world frame) as
    /// fractions of the controller's maximum speeds, each in [−1, 1].
    pub object: [f64; 6],
}

impl StickInput {
    /// The input as applied: every value rounded to the input quantum
    /// ([`crate::replay::log::INPUT_QUANTUM`]), and its values in quanta (left axes and grip,
    /// right axes and grip, object twist) for the attempt's log.
    pub fn quantized(&self) -> (StickInput, Vec<i32>) {
        let mut quanta = Vec::with_capacity(crate::replay::log::INPUT_VALUES);
        for a in &self.arms {
            quanta.extend(a.axes.iter().map(|v| quantize(*v)));
            quanta.push(quantize(a.grip));
        }
        quanta.extend(self.object.iter().map(|v| quantize(*v)));
        let mut q = StickInput::from_quanta(&quanta);
        q.seq = self.seq;
        (q, quanta)
    }

    /// An input from its values in quanta (the order of [`StickInput::quantized`]; missing
    /// values are 0).
    pub fn from_quanta(quanta: &[i32]) -> StickInput {
        let v = |i: usize| dequantize(quanta.get(i).copied().unwrap_or(0));
        StickInput {
            seq: 0,
            arms: [0, 7].map(|o| ArmSticks {
                axes: std::array::from_fn(|j| v(o + j)),
                grip: v(o + 6),
            }),
            object: std::array::from_fn(|j| v(14 + j)),
        }
    }
}

/// Settings changes (absent fields unchanged; `arm_speed` validated).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SettingsChange {
    /// Joint or Cartesian.
    pub control_mode: Option<ControlMode>,
    /// Open or closed loop.
    pub control_method: Option<ControlMethod>,
    /// Arm speed in (0, 1].
    pub arm_speed: Option<f64>,
}

/// Everything that can be done to a live session, from either edge.
#[derive(Debug, Clone)]
pub enum Command {
    /// New stick input.
    Input(StickInput),
    /// Change settings.
    Settings(SettingsChange),
    /// Back to the initial position (Lim §4.1).
    Reset,
    /// Pause the simulation clock.
    Pause,
    /// Resume it.
    Resume,
    /// Open both jaws for [`RELEASE_DURATION_S`].
    Release,
    /// Switch scenario (a fresh simulation): free play, a case-study set-up or an exercise.
    Scenario(Scenario),
    /// Name the fault of a diagnosis drill (one of the drill's answers).
    Diagnose(String),
    /// Inject a fault.
    InjectFault(ActiveFault),
    /// Remove every fault.
    ClearFaults,
    /// Set the water's current (instructor only; a subsea session).
    SetCurrent(Current),
    /// Show an instructor's message on every client of the session.
    Message(String),
    /// End the session.
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
    /// Builds a settings change, checking `arm_speed` ∈ (0, 1].
    pub fn settings(
        control_mode: Option<ControlMode>,
        control_method: Option<ControlMethod>,
        arm_speed: Option<f64>,
    ) -> Result<Command, CommandError> {
        if let Some(s) = arm_speed {
            if !(s.is_finite() && s > 0.0 && s <= 1.0) {
                return Err(CommandError::Invalid(format!(
                    "arm_speed must be in (0, 1], got {s}"
                )));
            }
        }
        Ok(Command::Settings(SettingsChange {
            control_mode,
            control_method,
            arm_speed,
        }))
    }

    /// Builds a scenario switch: a name of [`LIVE_SCENARIOS`] or an exercise id.
    pub fn scenario(name: &str) -> Result<Command, CommandError> {
        Scenario::resolve(name)
            .map(Command::Scenario)
            .ok_or_else(|| CommandError::Invalid(format!("unknown scenario or exercise `{name}`")))
    }

    /// Builds a current change, checking speed ∈ [0, [`MAX_CURRENT_M_S`]] m/s and a finite
    /// heading within ±360° ([`Current::new`]).
    pub fn current(speed_m_s: f64, heading_deg: f64) -> Result<Command, CommandError> {
        Current::new(speed_m_s, heading_deg)
            .map(Command::SetCurrent)
            .map_err(|e| CommandError::Invalid(e.to_string()))
    }

    /// Builds an instructor message, checking its length.
    pub fn message(text: &str) -> Result<Command, CommandError> {
        if text.chars().count() > MAX_MESSAGE_CHARS {
            return Err(CommandError::Invalid(format!(
                "message text is limited to {MAX_MESSAGE_CHARS} characters"
            )));
        }
        Ok(Command::Message(text.to_string()))
    }

    /// Name in records.
    pub fn name(&self) -> &'static str {
        match self {
            Command::Input(_) => "input",
            Command::Settings(_) => "settings",
            Command::Reset => "reset",
            Command::Pause => "pause",
            Command::Resume => "resume",
            Command::Release => "release",
            Command::Scenario(_) => "scenario",
            Command::Diagnose(_) => "diagnose",
            Command::InjectFault(_) => "fault",
            Command::ClearFaults => "clear_faults",
            Command::SetCurrent(_) => "set_current",
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
                    | Command::Settings(_)
                    | Command::Reset
                    | Command::Pause
                    | Command::Resume
                    | Command::Release
                    | Command::Diagnose(_)
                    | Command::End
            ),
            Actor::Observer => false,
        }
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
    if matches!(command, Command::End) {
        record(manager, session, actor, &command, json!({}));
        // `permitted` lets only instructors and trainees end a session.
        let reason = match actor {
            Actor::Instructor => EndReason::Instructor,
            Actor::Trainee | Actor::Observer => EndReason::Trainee,
        };
        manager.end(&session.id, reason);
        return Ok(());
    }
    let detail = match &command {
        Command::Message(text) => {
            let msg = ServerMessage::Message {
                from: actor.as_str().into(),
                text: text.clone(),
            };
            let _ = session
                .notices
                .send(serde_json::to_string(&msg).unwrap_or_default().into());
            json!({"text": text})
        }
        _ => {
            let mut live = session.live();
            if actor == Actor::Instructor {
                live.note_intervention(&command);
            }
            let detail = match &command {
                Command::Pause => live.pause_as(actor, true),
                Command::Resume => live.pause_as(actor, false),
                _ => live.apply(&command),
            };
            // A reset or switch ended an attempt and started one: records go out in order,
            // before this command's event.
            for msg in live.take_records(false) {
                manager.recorder.send(msg);
            }
            let detail = detail?;
            if let Command::Scenario(s) = &command {
                session.set_scenario(s.name());
                // Every page redraws the scene and follows the new settings.
                let msg = ServerMessage::Scenario {
                    scenario: s.name().to_string(),
                    exercise: s.exercise().cloned(),
                    scene: Box::new(crate::protocol::SceneOut::new(
                        live.sim().params(),
                        s.exercise().map(|e| &**e),
                    )),
                    settings: live.settings(),
                };
                let _ = session
                    .notices
                    .send(serde_json::to_string(&msg).unwrap_or_default().into());
            }
            match command {
                Command::Input(_) => return Ok(()),
                _ => detail,
            }
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
    /// Applies a command to the live state (the part of [`apply`] that both sessions and
    /// headless attempts share); returns the record's detail. `End` and `Message` are the
    /// session's business and do nothing here.
    pub fn apply(&mut self, command: &Command) -> Result<serde_json::Value, CommandError> {
        Ok(match command {
            Command::Input(input) => {
                let (input, quanta) = input.quantized();
                self.log(Applied::Input { v: quanta });
                self.apply_input(&input);
                json!({})
            }
            Command::Settings(change) => {
                self.log(Applied::Settings {
                    mode: change.control_mode,
                    method: change.control_method,
                    speed: change.arm_speed,
                });
                self.apply_settings(change);
                json!({"settings": self.settings()})
            }
            Command::Reset => {
                self.reset();
                json!({})
            }
            // Without an actor (headless attempts), pause and resume act as the trainee's.
            Command::Pause => self.pause_as(Actor::Trainee, true)?,
            Command::Resume => self.pause_as(Actor::Trainee, false)?,
            Command::Release => {
                self.log(Applied::Release);
                self.release(RELEASE_DURATION_S);
                json!({})
            }
            Command::Scenario(scenario) => {
                self.set_scenario(scenario.clone())
                    .map_err(|e| CommandError::Invalid(format!("scenario: {e}")))?;
                json!({"scenario": scenario.name()})
            }
            Command::Diagnose(answer) => {
                let run = self
                    .exercise
                    .as_mut()
                    .ok_or_else(|| CommandError::Invalid("no exercise is running".to_string()))?;
                run.diagnose(answer).map_err(CommandError::Invalid)?;
                self.log(Applied::Diagnose {
                    answer: answer.clone(),
                });
                json!({"answer": answer})
            }
            Command::InjectFault(f) => {
                self.log(Applied::Fault {
                    fault: crate::replay::fault_entry(f),
                });
                self.inject_fault(*f);
                json!({"fault": f, "silent": f.silent})
            }
            Command::ClearFaults => {
                self.log(Applied::ClearFaults);
                self.clear_faults();
                json!({})
            }
            Command::SetCurrent(c) => {
                self.sim
                    .set_current(*c)
                    .map_err(|e| CommandError::Invalid(e.to_string()))?;
                self.log(Applied::Current {
                    speed_m_s: c.speed_m_s,
                    heading_deg: c.heading_deg,
                });
                json!({"current": c})
            }
            Command::Message(_) | Command::End => json!({}),
        })
    }

    /// Pauses (`pause`) or resumes the clock on behalf of `by`. An instructor's pause is
    /// lifted only by the instructor: the trainee's `resume` is refused
    /// ([`PAUSED_BY_INSTRUCTOR`]) and the trainee's `pause` leaves it the instructor's. The
    /// instructor's pause takes over a trainee's; the instructor's resume lifts any pause.
    /// Returns the record's detail (who holds the pause now).
    pub fn pause_as(&mut self, by: Actor, pause: bool) -> Result<serde_json::Value, CommandError> {
        let instructors = self.paused_by() == Some(Actor::Instructor);
        match (pause, by) {
            (false, Actor::Trainee) if instructors => {
                return Err(CommandError::Forbidden(PAUSED_BY_INSTRUCTOR.to_string()));
            }
            (true, Actor::Trainee) if instructors => {}
            (true, _) => self.set_paused(Some(by)),
            (false, _) => self.set_paused(None),
        }
        Ok(json!({"paused_by": self.paused_by()}))
    }

    /// Counts an instructor's command as an intervention in the running attempt (stick
    /// input and messages do not count, nor silent faults: they set up a diagnosis drill,
    /// and a count the trainee's assessment shows would give them away).
    fn note_intervention(&mut self, command: &Command) {
        let silent = matches!(command, Command::InjectFault(f) if f.silent);
        if !silent
            && !matches!(
                command,
                // The current is the exercise's conditions, not help given to the trainee.
                Command::Input(_) | Command::Message(_) | Command::End | Command::SetCurrent(_)
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
    fn a_second_fault_of_the_same_kind_on_the_same_actuator_replaces_the_first() {
        let a = |arm, joint, v| ActiveFault {
            arm,
            fault: Fault::new(FaultKind::StuckValve, Some(joint), v).unwrap(),
            silent: false,
        };
        assert!(a(Arm::Left, 2, 0.5).same_slot(&a(Arm::Left, 2, -0.5)));
        assert!(!a(Arm::Left, 2, 0.5).same_slot(&a(Arm::Left, 3, 0.5)));
        assert!(!a(Arm::Left, 2, 0.5).same_slot(&a(Arm::Right, 2, 0.5)));
    }

    #[test]
    fn permissions() {
        for c in [Command::Reset, Command::Pause, Command::End] {
            assert!(c.permitted(Actor::Trainee));
            assert!(c.permitted(Actor::Instructor));
            assert!(!c.permitted(Actor::Observer));
        }
        assert!(!Command::ClearFaults.permitted(Actor::Trainee));
        assert!(!Command::Message("x".into()).permitted(Actor::Trainee));
        assert!(Command::settings(None, None, Some(0.0)).is_err());
        assert!(Command::settings(None, None, Some(1.0)).is_ok());
        assert!(Command::scenario("nope").is_err());
    }
}
