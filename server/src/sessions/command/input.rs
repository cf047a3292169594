//! `input`: the trainee's sticks. Wire: the WebSocket's `{"type": "input", "seq", "arms",
//! "object"}` ([`crate::protocol::ClientMessage::Input`]), sent at the page's 50 Hz. Applied
//! from the next step on, rounded to the input quantum; logged as `{"c": "input", "v": [20
//! values in quanta]}` (on disk, the compact `[dk, i, d, …]` lines of [`super::log`]).

use serde::{Deserialize, Serialize};
use serde_json::json;

use super::Command;
use super::log::{INPUT_VALUES, dequantize, quantize};
use crate::protocol::{ArmAxes, ArmsAxes, MAX_INPUT_SEQ, arm_name};
use crate::sessions::Live;
use seaarms_core::sim::Arm;

/// Actuators per arm (swing, shoulder, elbow, pitch, yaw, rotate).
pub const JOINTS: usize = 6;

/// One arm's validated sticks: six axes and a grip, each in [−1, 1].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ArmSticks {
    /// Joint mode: valve commands; Cartesian mode: end-effector twist fractions.
    pub axes: [f64; 6],
    /// Jaw: +1 opens, −1 closes.
    pub grip: f64,
}

/// Validated stick input (an absent arm is all zero). Its log form is its values in quanta,
/// `{"v": […]}` (the sequence number is not logged).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(into = "Quanta", try_from = "Quanta")]
pub struct StickInput {
    /// Sequence number (≤ [`crate::protocol::MAX_INPUT_SEQ`]).
    pub seq: u64,
    /// Left and right.
    pub arms: [ArmSticks; 2],
    /// Closed loop: commanded object twist [vx, vy, vz, wx, wy, wz] (world frame) as
    /// fractions of the controller's maximum speeds, each in [−1, 1].
    pub object: [f64; 6],
}

/// The log form of a stick input: its [`INPUT_VALUES`] values in quanta.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Quanta {
    /// Left axes and grip, right axes and grip, object twist.
    pub v: Vec<i32>,
}

impl From<StickInput> for Quanta {
    fn from(input: StickInput) -> Quanta {
        Quanta { v: input.quanta() }
    }
}

impl TryFrom<Quanta> for StickInput {
    type Error = String;

    fn try_from(q: Quanta) -> Result<StickInput, String> {
        if q.v.len() != INPUT_VALUES {
            return Err(format!("input of {} values", q.v.len()));
        }
        Ok(StickInput::from_quanta(&q.v))
    }
}

impl StickInput {
    /// Its values in quanta, in the log's order: left axes and grip, right axes and grip,
    /// object twist.
    pub fn quanta(&self) -> Vec<i32> {
        let mut quanta = Vec::with_capacity(INPUT_VALUES);
        for a in &self.arms {
            quanta.extend(a.axes.iter().map(|v| quantize(*v)));
            quanta.push(quantize(a.grip));
        }
        quanta.extend(self.object.iter().map(|v| quantize(*v)));
        quanta
    }

    /// The input as applied: every value rounded to the input quantum
    /// ([`super::log::INPUT_QUANTUM`]); the same sequence number.
    pub fn quantized(&self) -> StickInput {
        StickInput {
            seq: self.seq,
            ..StickInput::from_quanta(&self.quanta())
        }
    }

    /// An input from its values in quanta (the order of [`StickInput::quanta`]; missing
    /// values are 0; sequence number 0).
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

impl Command {
    /// Parses an `input` message: `seq` ≤ 2⁵³ − 1, six axes per arm (an empty list means all
    /// zero) and six object values, each clamped to [−1, 1] (clamping reported in `notes`).
    pub fn input(
        seq: u64,
        arms: &ArmsAxes,
        object: Option<&[f64]>,
        notes: &mut Vec<String>,
    ) -> Result<Command, String> {
        if seq > MAX_INPUT_SEQ {
            return Err(format!(
                "seq must be at most 2^53 - 1 = {MAX_INPUT_SEQ} (exact in JavaScript), got {seq}; input ignored"
            ));
        }
        let mut input = StickInput {
            seq,
            ..StickInput::default()
        };
        for (arm, a) in [(Arm::Left, &arms.left), (Arm::Right, &arms.right)] {
            if let Some(a) = a {
                input.arms[arm.index()] = arm_sticks(arm_name(arm), a, notes)?;
            }
        }
        if let Some(o) = object {
            if o.len() != 6 {
                return Err(format!("object must have 6 values, got {}", o.len()));
            }
            for (i, v) in o.iter().enumerate() {
                input.object[i] = clamp_unit(*v, &format!("object[{i}]"), notes);
            }
        }
        Ok(Command::Input(input))
    }
}

/// Validates one arm's axes: six values (an empty list means all zero), each clamped to
/// [−1, 1]; clamping is reported.
fn arm_sticks(name: &str, a: &ArmAxes, notes: &mut Vec<String>) -> Result<ArmSticks, String> {
    let mut axes = [0.0; 6];
    if !a.axes.is_empty() && a.axes.len() != 6 {
        return Err(format!(
            "arms.{name}.axes must have 6 values, got {}",
            a.axes.len()
        ));
    }
    for (i, v) in a.axes.iter().enumerate() {
        axes[i] = clamp_unit(*v, &format!("arms.{name}.axes[{i}]"), notes);
    }
    let grip = clamp_unit(a.grip, &format!("arms.{name}.grip"), notes);
    Ok(ArmSticks { axes, grip })
}

fn clamp_unit(v: f64, what: &str, notes: &mut Vec<String>) -> f64 {
    if !v.is_finite() {
        notes.push(format!("{what} is not finite; used 0"));
        return 0.0;
    }
    if v.abs() > 1.0 {
        notes.push(format!("{what} = {v} clamped to {}", v.signum()));
        return v.signum();
    }
    v
}

/// Applies an (already quantized) input.
pub(super) fn apply(live: &mut Live, input: &StickInput) -> serde_json::Value {
    live.apply_input(input);
    json!({})
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_log_form_is_the_quanta_and_reads_back_the_applied_input() {
        let mut input = StickInput {
            seq: 7,
            ..StickInput::default()
        };
        input.arms[1].axes[2] = 0.12345;
        input.object[5] = -1.0;
        let applied = input.quantized();
        let v = serde_json::to_value(Command::Input(applied)).unwrap();
        let mut quanta = vec![0; INPUT_VALUES];
        quanta[7 + 2] = 123;
        quanta[19] = -1000;
        assert_eq!(v, json!({"c": "input", "v": quanta}));
        let back: Command = serde_json::from_value(v).unwrap();
        // The sequence number is not logged; every value is, bit for bit.
        assert_eq!(back, Command::Input(StickInput { seq: 0, ..applied }));
        assert!(serde_json::from_value::<Command>(json!({"c": "input", "v": [1, 2]})).is_err());
    }
}
