//! `settings`: control mode, control method, arm speed and the orientation hold. Wire: the
//! WebSocket's `{"type": "settings", "control_mode", "control_method", "arm_speed",
//! "hold_orientation"}` (absent fields unchanged). Logged as `{"c": "settings", "mode",
//! "method", "speed", "hold"}` (absent ones left out).

use serde::{Deserialize, Serialize};
use serde_json::json;

use super::{Command, CommandError};
use crate::protocol::{ControlMethod, ControlMode};
use crate::sessions::Live;

/// Settings changes (absent fields unchanged; `arm_speed` validated).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct SettingsChange {
    /// Joint or Cartesian.
    #[serde(rename = "mode", default, skip_serializing_if = "Option::is_none")]
    pub control_mode: Option<ControlMode>,
    /// Open or closed loop.
    #[serde(rename = "method", default, skip_serializing_if = "Option::is_none")]
    pub control_method: Option<ControlMethod>,
    /// Arm speed in (0, 1].
    #[serde(rename = "speed", default, skip_serializing_if = "Option::is_none")]
    pub arm_speed: Option<f64>,
    /// Cartesian translation holds the jaw's orientation (`sim::Operator::hold_orientation`).
    #[serde(rename = "hold", default, skip_serializing_if = "Option::is_none")]
    pub hold_orientation: Option<bool>,
}

impl Command {
    /// Parses a settings change, checking `arm_speed` ∈ (0, 1].
    pub fn settings(
        control_mode: Option<ControlMode>,
        control_method: Option<ControlMethod>,
        arm_speed: Option<f64>,
        hold_orientation: Option<bool>,
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
            hold_orientation,
        }))
    }
}

/// Applies a settings change (a mode change stops every stick command).
pub(super) fn apply(live: &mut Live, change: &SettingsChange) -> serde_json::Value {
    live.apply_settings(change);
    json!({"settings": live.settings()})
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_log_form_names_only_what_changed() {
        let c = Command::settings(Some(ControlMode::Cartesian), None, Some(0.5), None).unwrap();
        let v = serde_json::to_value(&c).unwrap();
        assert_eq!(
            v,
            json!({"c": "settings", "mode": "cartesian", "speed": 0.5})
        );
        assert_eq!(serde_json::from_value::<Command>(v).unwrap(), c);
        let c = Command::settings(None, None, None, Some(false)).unwrap();
        let v = serde_json::to_value(&c).unwrap();
        assert_eq!(v, json!({"c": "settings", "hold": false}));
        assert_eq!(serde_json::from_value::<Command>(v).unwrap(), c);
    }
}
