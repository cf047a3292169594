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
