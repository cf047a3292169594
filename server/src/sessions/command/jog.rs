//! `jog`: a keyboard tap — the arm moves a bounded, repeatable amount and stops, whatever the
//! tap's length (`seaarms_core::sim::Operator::jog`: 2° of a joint in joint mode, 1 cm along
//! or 2° about a world axis at the jaw in Cartesian mode, times the axis and the arm speed).
//! Wire: the WebSocket's `{"type": "jog", "arm": "left" | "right", "axes": [6 values in
//! [−1, 1]]}` (in Cartesian mode the page has turned them into the world frame, as the
//! sticks'). Applied from the next step, the axes rounded to the input quantum; logged as
//! `{"c": "jog", "arm": 0 | 1, "v": [6 values in quanta]}`. Not recorded as an event (like
//! stick input).

use serde::{Deserialize, Serialize};
use serde_json::json;

use super::log::{dequantize, quantize};
use super::{Command, CommandError};
use crate::sessions::Live;
use seaarms_core::sim::Arm;

/// A validated jog: the arm and its six axes (each in [−1, 1], whole quanta).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(into = "JogLog", try_from = "JogLog")]
pub struct Jog {
    /// The arm.
    pub arm: Arm,
    /// Joint mode: per joint; Cartesian mode: [vx vy vz wx wy wz] directions (world).
    pub axes: [f64; 6],
}

/// The log form of a jog.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JogLog {
    /// Arm index (0 left, 1 right).
    pub arm: u8,
    /// The axes in quanta.
    pub v: [i32; 6],
}

impl From<Jog> for JogLog {
    fn from(j: Jog) -> JogLog {
        JogLog {
            arm: j.arm.index() as u8,
            v: j.axes.map(quantize),
        }
    }
}

impl TryFrom<JogLog> for Jog {
    type Error = String;

    fn try_from(l: JogLog) -> Result<Jog, String> {
        let arm = *Arm::BOTH
            .get(usize::from(l.arm))
            .ok_or_else(|| format!("jog arm {}", l.arm))?;
        Ok(Jog {
            arm,
            axes: l.v.map(dequantize),
        })
    }
}

impl Command {
    /// Parses a jog: `arm` is `left` or `right`; `axes` six finite values, each clamped to
    /// [−1, 1] (a clamp is reported in `notes`) and rounded to the input quantum; all zero
    /// is refused (a jog that moves nothing).
    pub fn jog(arm: &str, axes: &[f64], notes: &mut Vec<String>) -> Result<Command, CommandError> {
        let arm = match arm {
            "left" => Arm::Left,
            "right" => Arm::Right,
            other => {
                return Err(CommandError::Invalid(format!(
                    "jog arm must be left or right, got {other:?}"
                )));
            }
        };
        if axes.len() != 6 {
            return Err(CommandError::Invalid(format!(
                "jog axes must have 6 values, got {}",
                axes.len()
            )));
        }
        if axes.iter().any(|v| !v.is_finite()) {
            return Err(CommandError::Invalid("jog axes must be finite".into()));
        }
        if axes.iter().any(|v| v.abs() > 1.0) {
            notes.push("jog axes clamped to [-1, 1]".into());
        }
        let axes: [f64; 6] =
            std::array::from_fn(|k| dequantize(quantize(axes[k].clamp(-1.0, 1.0))));
        if axes.iter().all(|v| *v == 0.0) {
            return Err(CommandError::Invalid("a jog needs a non-zero axis".into()));
        }
        Ok(Command::Jog(Jog { arm, axes }))
    }
}

/// Applies a jog.
pub(super) fn apply(live: &mut Live, jog: &Jog) -> serde_json::Value {
    live.jog(jog.arm, &jog.axes);
    json!({})
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_jog_is_validated_and_logged_in_quanta() {
        let mut notes = Vec::new();
        let c = Command::jog("right", &[0.0, 0.0, 0.0, 1.5, 0.0, -0.25], &mut notes).unwrap();
        assert_eq!(notes.len(), 1, "the clamp is reported");
        let v = serde_json::to_value(&c).unwrap();
        assert_eq!(
            v,
            json!({"c": "jog", "arm": 1, "v": [0, 0, 0, 1000, 0, -250]})
        );
        assert_eq!(serde_json::from_value::<Command>(v).unwrap(), c);
        for bad in [
            Command::jog("middle", &[1.0; 6], &mut notes),
            Command::jog("left", &[1.0; 5], &mut notes),
            Command::jog("left", &[f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0], &mut notes),
            Command::jog("left", &[0.0; 6], &mut notes),
        ] {
            assert!(matches!(bad, Err(CommandError::Invalid(_))), "{bad:?}");
        }
    }
}
