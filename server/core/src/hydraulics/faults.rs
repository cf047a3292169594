//! Fault injection per arm (supply drop, stuck valves, leakage, entrained air) and the
//! clamped values the step uses.

use super::{HydraulicParams, N_ACT};
use crate::finite_or;

/// Per-arm fault injection, plain mutable parameters (all "no fault" by default). Any value is
/// accepted; non-finite or out-of-range values are clamped by the simulation at use.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Faults {
    /// Supply pressure drop (Pa), subtracted from the supply, clamped to [0, supply].
    pub supply_drop_pa: f64,
    /// Stuck valve per actuator: `Some(u)` holds the spool at u ∈ [−1, 1] whatever the command.
    pub stuck_valve: [Option<f64>; N_ACT],
    /// Cross-piston leakage coefficient per actuator (m³/s per Pa), ≥ 0; e.g. 1e-11 is a worn seal.
    pub leak_m3_s_pa: [f64; N_ACT],
    /// Entrained air: multiplies the bulk modulus, clamped to [0.01, 1] (e.g. 0.2 with 1–2 % air).
    pub bulk_modulus_scale: f64,
}

impl Default for Faults {
    fn default() -> Self {
        Faults {
            supply_drop_pa: 0.0,
            stuck_valve: [None; N_ACT],
            leak_m3_s_pa: [0.0; N_ACT],
            bulk_modulus_scale: 1.0,
        }
    }
}

impl Faults {
    /// Supply pressure after the drop (Pa): the drop clamped to [0, supply], non-finite → 0.
    pub fn supply_pa(&self, hp: &HydraulicParams) -> f64 {
        hp.supply_pa - finite_or(self.supply_drop_pa, 0.0).clamp(0.0, hp.supply_pa)
    }

    /// Bulk modulus with entrained air (Pa): the scale clamped to [0.01, 1], non-finite → 1.
    pub fn bulk_modulus_pa(&self, hp: &HydraulicParams) -> f64 {
        hp.bulk_modulus_pa * finite_or(self.bulk_modulus_scale, 1.0).clamp(0.01, 1.0)
    }

    /// Cross-piston leakage of actuator `j` (m³/s per Pa): clamped to [0, 10⁻⁸], non-finite → 0.
    pub fn leak_m3_s_pa(&self, j: usize) -> f64 {
        finite_or(self.leak_m3_s_pa[j], 0.0).clamp(0.0, 1e-8)
    }

    /// The spool of actuator `j` given the commanded one: a stuck valve's position (clamped
    /// to [−1, 1], non-finite → 0) or `commanded`.
    pub fn spool(&self, j: usize, commanded: f64) -> f64 {
        match self.stuck_valve[j] {
            Some(u) => finite_or(u, 0.0).clamp(-1.0, 1.0),
            None => commanded,
        }
    }
}

/// Supply-pressure drop range (Pa): up to the full supply of 6.89 MPa (Lim Table 1-1).
pub const SUPPLY_DROP_RANGE_PA: (f64, f64) = (0.0, 6.89e6);
/// Stuck-valve spool position range.
pub const STUCK_SPOOL_RANGE: (f64, f64) = (-1.0, 1.0);
/// Cross-piston leakage coefficient range (m³/(s·Pa)).
pub const LEAK_RANGE_M3_S_PA: (f64, f64) = (0.0, 1e-9);
/// Entrained-air bulk-modulus scale range.
pub const AIR_SCALE_RANGE: (f64, f64) = (0.01, 1.0);

/// One fault to inject on one arm: what instructors inject and what a fault drill draws
/// (exercise files name it as `{"kind": "stuck_valve", "joint": 2, "spool": 0.4}`). It
/// writes itself into the arm's [`Faults`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Fault {
    /// The supply pressure drops by this much (Pa).
    SupplyDrop {
        /// Drop (Pa), in [`SUPPLY_DROP_RANGE_PA`].
        drop_pa: f64,
    },
    /// A valve's spool sticks at a position whatever the command.
    StuckValve {
        /// Actuator 0..5.
        joint: usize,
        /// Spool position in [−1, 1].
        spool: f64,
    },
    /// Cross-piston leakage in one actuator.
    Leak {
        /// Actuator 0..5.
        joint: usize,
        /// Leakage coefficient (m³/(s·Pa)), in [`LEAK_RANGE_M3_S_PA`].
        coefficient_m3_s_pa: f64,
    },
    /// Entrained air: the bulk modulus is scaled down.
    Air {
        /// Bulk-modulus scale, in [`AIR_SCALE_RANGE`].
        bulk_modulus_scale: f64,
    },
}

/// The kinds of [`Fault`]: one entry per (arm, kind, joint), and the fault drill's answers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaultKind {
    /// [`Fault::SupplyDrop`].
    SupplyDrop,
    /// [`Fault::StuckValve`].
    StuckValve,
    /// [`Fault::Leak`].
    Leak,
    /// [`Fault::Air`].
    Air,
}

impl FaultKind {
    /// Every kind.
    pub const ALL: [FaultKind; 4] = [
        FaultKind::SupplyDrop,
        FaultKind::StuckValve,
        FaultKind::Leak,
        FaultKind::Air,
    ];

    /// Every name, in [`FaultKind::ALL`] order (the drill's answers).
    pub const NAMES: [&'static str; 4] = ["supply_drop", "stuck_valve", "leak", "air"];

    /// Its name: the wire's `fault` field, fault labels, exercise files and drill answers.
    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }

    /// A kind from its name.
    pub fn parse(name: &str) -> Option<FaultKind> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }
}

impl Fault {
    /// Builds a fault from its kind, joint and size, checking ranges (messages name the field).
    pub fn new(kind: FaultKind, joint: Option<usize>, value: f64) -> Result<Fault, String> {
        let in_range = |(lo, hi): (f64, f64)| -> Result<f64, String> {
            if value.is_finite() && value >= lo && value <= hi {
                Ok(value)
            } else {
                Err(format!(
                    "`value` for {} must be in [{lo}, {hi}], got {value}",
                    kind.name()
                ))
            }
        };
        let joint = || match joint {
            Some(j) if j < N_ACT => Ok(j),
            _ => Err(format!("this fault needs `joint` in 0..={}", N_ACT - 1)),
        };
        Ok(match kind {
            FaultKind::SupplyDrop => Fault::SupplyDrop {
                drop_pa: in_range(SUPPLY_DROP_RANGE_PA)?,
            },
            FaultKind::StuckValve => Fault::StuckValve {
                joint: joint()?,
                spool: in_range(STUCK_SPOOL_RANGE)?,
            },
            FaultKind::Leak => Fault::Leak {
                joint: joint()?,
                coefficient_m3_s_pa: in_range(LEAK_RANGE_M3_S_PA)?,
            },
            FaultKind::Air => Fault::Air {
                bulk_modulus_scale: in_range(AIR_SCALE_RANGE)?,
            },
        })
    }

    /// Its kind.
    pub fn kind(&self) -> FaultKind {
        match self {
            Fault::SupplyDrop { .. } => FaultKind::SupplyDrop,
            Fault::StuckValve { .. } => FaultKind::StuckValve,
            Fault::Leak { .. } => FaultKind::Leak,
            Fault::Air { .. } => FaultKind::Air,
        }
    }

    /// The actuator it acts on, for per-joint faults.
    pub fn joint(&self) -> Option<usize> {
        match self {
            Fault::StuckValve { joint, .. } | Fault::Leak { joint, .. } => Some(*joint),
            Fault::SupplyDrop { .. } | Fault::Air { .. } => None,
        }
    }

    /// Its size (Pa, spool position, m³/(s·Pa) or bulk-modulus scale).
    pub fn value(&self) -> f64 {
        match *self {
            Fault::SupplyDrop { drop_pa } => drop_pa,
            Fault::StuckValve { spool, .. } => spool,
            Fault::Leak {
                coefficient_m3_s_pa,
                ..
            } => coefficient_m3_s_pa,
            Fault::Air { bulk_modulus_scale } => bulk_modulus_scale,
        }
    }

    /// Writes the fault into an arm's fault set (a joint out of range changes nothing).
    pub fn apply_to(&self, faults: &mut Faults) {
        match *self {
            Fault::SupplyDrop { drop_pa } => faults.supply_drop_pa = drop_pa,
            Fault::StuckValve { joint, spool } => {
                if let Some(s) = faults.stuck_valve.get_mut(joint) {
                    *s = Some(spool);
                }
            }
            Fault::Leak {
                joint,
                coefficient_m3_s_pa,
            } => {
                if let Some(l) = faults.leak_m3_s_pa.get_mut(joint) {
                    *l = coefficient_m3_s_pa;
                }
            }
            Fault::Air { bulk_modulus_scale } => faults.bulk_modulus_scale = bulk_modulus_scale,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Out-of-range and non-finite fault values are clamped as documented on [`Faults`].
    #[test]
    fn fault_values_are_clamped() {
        let hp = crate::hydraulics::chamber::tests::params();
        let mut f = Faults::default();
        assert_eq!(f.supply_pa(&hp), hp.supply_pa);
        assert_eq!(f.bulk_modulus_pa(&hp), hp.bulk_modulus_pa);
        assert_eq!((f.leak_m3_s_pa(0), f.spool(0, 0.3)), (0.0, 0.3));
        f.supply_drop_pa = 2.0 * hp.supply_pa;
        f.bulk_modulus_scale = f64::NAN;
        f.leak_m3_s_pa[2] = 1.0;
        f.stuck_valve[1] = Some(-7.0);
        f.stuck_valve[3] = Some(f64::INFINITY);
        assert_eq!(f.supply_pa(&hp), 0.0);
        assert_eq!(f.bulk_modulus_pa(&hp), hp.bulk_modulus_pa);
        assert_eq!(f.leak_m3_s_pa(2), 1e-8);
        assert_eq!((f.spool(1, 0.5), f.spool(3, 0.5)), (-1.0, 0.0));
        f.bulk_modulus_scale = 0.0;
        assert_eq!(f.bulk_modulus_pa(&hp), 0.01 * hp.bulk_modulus_pa);
    }
}

#[cfg(test)]
mod fault_tests {
    use super::*;

    #[test]
    fn fault_ranges_are_checked_and_name_the_field() {
        assert!(Fault::new(FaultKind::SupplyDrop, None, 3e6).is_ok());
        assert!(Fault::new(FaultKind::SupplyDrop, None, 7e6).is_err());
        assert!(Fault::new(FaultKind::Air, None, f64::NAN).is_err());
        let e = Fault::new(FaultKind::StuckValve, None, 0.5).unwrap_err();
        assert!(e.contains("joint"), "{e}");
        assert!(Fault::new(FaultKind::Leak, Some(6), 1e-10).is_err());
        assert_eq!(
            Fault::new(FaultKind::Leak, Some(5), 1e-10),
            Ok(Fault::Leak {
                joint: 5,
                coefficient_m3_s_pa: 1e-10
            })
        );
        for k in FaultKind::ALL {
            assert_eq!(FaultKind::parse(k.name()), Some(k));
        }
    }
}
