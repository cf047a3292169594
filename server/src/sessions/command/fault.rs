//! `fault` and `clear_faults`: the instructor injects a hydraulic fault on one arm (replacing
//! one of the same kind on the same actuator), or removes them all; a reset clears faults
//! that are not `persistent`. Wire: the REST actions
//! `{"type": "fault", "fault", "arm", "joint", "value", "silent", "persistent"}` and
//! `{"type": "clear_faults"}`. Logged as `{"c": "fault", "fault": {"arm": 0|1, "kind",
//! "joint", "value"}}` (a debrief shows silent faults too) and `{"c": "clear_faults"}`.

use serde_json::json;

use super::{Command, CommandError};
use crate::protocol::{ActiveFault, parse_arm};
use crate::sessions::Live;
use seaarms_core::hydraulics::{Fault, FaultKind};

impl Command {
    /// Parses a fault: its wire kind (`supply_drop`, `stuck_valve`, `leak`, `air`), arm
    /// (`left`, `right`), joint (per-joint kinds) and size, checked by [`Fault::new`].
    pub fn fault(
        kind: &str,
        arm: &str,
        joint: Option<usize>,
        value: f64,
        silent: bool,
        persistent: bool,
    ) -> Result<Command, CommandError> {
        let arm = parse_arm(arm).ok_or_else(|| {
            CommandError::Invalid(format!("arm must be `left` or `right`, got `{arm}`"))
        })?;
        let kind = FaultKind::parse(kind).ok_or_else(|| {
            CommandError::Invalid(format!(
                "unknown fault `{kind}` ({})",
                FaultKind::NAMES.join(", ")
            ))
        })?;
        let fault = Fault::new(kind, joint, value).map_err(CommandError::Invalid)?;
        Ok(Command::InjectFault {
            fault: ActiveFault {
                arm,
                fault,
                silent,
                persistent,
            },
        })
    }
}

/// Applies a fault.
pub(super) fn inject(live: &mut Live, fault: &ActiveFault) -> serde_json::Value {
    live.inject_fault(*fault);
    json!({"fault": fault, "silent": fault.silent, "persistent": fault.persistent})
}

/// Removes every fault.
pub(super) fn clear(live: &mut Live) -> serde_json::Value {
    live.clear_faults();
    json!({})
}

/// The log form of a fault (`#[serde(with = "log_form")]`): arm index, kind's wire name,
/// joint (per-joint kinds) and size. A logged fault reads back as not silent: a debrief shows
/// every fault.
pub mod log_form {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    use super::{ActiveFault, Fault, FaultKind};
    use seaarms_core::sim::Arm;

    /// A fault as logged (and in an attempt's `init.faults`).
    #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
    pub struct FaultEntry {
        /// 0 left, 1 right.
        pub arm: usize,
        /// Wire name of the kind (`supply_drop`, `stuck_valve`, `leak`, `air`).
        pub kind: String,
        /// Actuator, for per-joint kinds.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        pub joint: Option<usize>,
        /// Size (Pa, spool position, m³/(s·Pa) or bulk-modulus scale).
        pub value: f64,
    }

    impl From<&ActiveFault> for FaultEntry {
        fn from(f: &ActiveFault) -> FaultEntry {
            FaultEntry {
                arm: f.arm.index(),
                kind: f.fault.kind().name().to_string(),
                joint: f.fault.joint(),
                value: f.fault.value(),
            }
        }
    }

    impl TryFrom<&FaultEntry> for ActiveFault {
        type Error = String;

        fn try_from(e: &FaultEntry) -> Result<ActiveFault, String> {
            let kind =
                FaultKind::parse(&e.kind).ok_or_else(|| format!("unknown fault `{}`", e.kind))?;
            let arm = *Arm::BOTH
                .get(e.arm)
                .ok_or_else(|| format!("arm {}", e.arm))?;
            Ok(ActiveFault {
                arm,
                fault: Fault::new(kind, e.joint, e.value)?,
                silent: false,
                persistent: false,
            })
        }
    }

    /// Serializes `f` as a [`FaultEntry`].
    pub fn serialize<S: Serializer>(f: &ActiveFault, s: S) -> Result<S::Ok, S::Error> {
        FaultEntry::from(f).serialize(s)
    }

    /// Reads a [`FaultEntry`] back (checked like an injected fault).
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<ActiveFault, D::Error> {
        let e = FaultEntry::deserialize(d)?;
        ActiveFault::try_from(&e).map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use seaarms_core::sim::Arm;

    #[test]
    fn a_second_fault_of_the_same_kind_on_the_same_actuator_replaces_the_first() {
        let a = |arm, joint, v| ActiveFault {
            arm,
            fault: Fault::new(FaultKind::StuckValve, Some(joint), v).unwrap(),
            silent: false,
            persistent: false,
        };
        assert!(a(Arm::Left, 2, 0.5).same_slot(&a(Arm::Left, 2, -0.5)));
        assert!(!a(Arm::Left, 2, 0.5).same_slot(&a(Arm::Left, 3, 0.5)));
        assert!(!a(Arm::Left, 2, 0.5).same_slot(&a(Arm::Right, 2, 0.5)));
    }

    /// The log form is the one format 1 logs carry (`log.rs` tests decode it by hand-written lines).
    #[test]
    fn the_log_form_is_arm_index_kind_joint_value() {
        let c = Command::fault("leak", "right", Some(3), 1e-11, true, false).unwrap();
        let v = serde_json::to_value(&c).unwrap();
        assert_eq!(
            v,
            json!({"c": "fault", "fault": {"arm": 1, "kind": "leak", "joint": 3, "value": 1e-11}})
        );
        let Command::InjectFault { fault } = serde_json::from_value::<Command>(v).unwrap() else {
            panic!("a fault");
        };
        assert!(!fault.silent);
        assert_eq!(
            fault.fault,
            Fault::new(FaultKind::Leak, Some(3), 1e-11).unwrap()
        );
    }
}
