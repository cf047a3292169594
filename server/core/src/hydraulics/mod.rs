//! Valve-controlled hydraulic actuators, one per joint (Lim §3.4.3, eqs 3.48–3.54), with the
//! relief valves and cavitation floor the thesis lacked.
//!
//! * [`Linkage`] (`linkage.rs`): the cylinder-to-joint geometry, x(q) and Ĵ(q) = dx/dq
//!   (eq. 3.53).
//! * [`ActuatorParams`], [`HydraulicParams`], [`JawParams`] (here): sizes and fluid data;
//!   [`HydraulicParams::magnum`] (`sizing.rs`) sizes them from Lim Table 1-1 with documented
//!   rules.
//! * [`Faults`] (`faults.rs`): fault injection and the clamped values the step uses.
//! * [`valve_flow`] (`valve.rs`): turbulent orifice flow with the sign logic of eq. 3.48.
//! * [`update_chambers`] (`chamber.rs`): one backward-Euler step of the chamber continuity
//!   equations (3.49–3.50, 3.56) including relief flow, piston leakage and the cavitation floor.
//! * [`JawParams`]: the jaw function (Table 1-1: 7.5 cm, 10.2 cm/s, 150 kgf), modelled as a
//!   flow-limited actuator (opening rate ∝ command) with a clamp force, not a chamber model.
//!
//! Pressures are gauge pressures relative to the return line (Pa); the return line is at
//! `return_pa` (0 by default). A chamber never goes below 0 Pa: below that the oil would
//! cavitate, and anti-cavitation check valves from the return line refill it (modelled as a
//! hard floor in the implicit update).

mod chamber;
mod faults;
mod linkage;
mod sizing;
mod valve;

pub use chamber::{ChamberFlags, update_chambers};
pub use faults::{
    AIR_SCALE_RANGE, Fault, FaultKind, Faults, LEAK_RANGE_M3_S_PA, STUCK_SPOOL_RANGE,
    SUPPLY_DROP_RANGE_PA,
};
pub use linkage::{Linkage, four_bar_transmission};
pub use sizing::{
    AREA_RATIO, FOUR_BAR_DESIGNS, HOLD_MARGIN, MAGNUM_FULL_EXTENSION, MAGNUM_LIFT_KG,
    MAGNUM_SPEEDS_DEG_S, MAGNUM_TORQUE_FLOOR_NM, MEAN_LEVER_M, magnum_four_bar,
};
pub use valve::{SPOOL_TIME_CONSTANT_S, spool_response, steady_opening, valve_flow};

/// Number of joint actuators per arm.
pub const N_ACT: usize = 6;

/// One joint actuator with its proportional valve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ActuatorParams {
    /// Cylinder-to-joint geometry.
    pub linkage: Linkage,
    /// Piston area of the inlet (extend) chamber A_I (m²; m³/rad for rotary).
    pub area_in: f64,
    /// Piston area of the outlet chamber A_O (m²; m³/rad for rotary).
    pub area_out: f64,
    /// Actuator coordinate at the joint's lower limit (m or rad): the fully retracted end.
    pub x_min: f64,
    /// Usable stroke (m or rad) from `x_min`.
    pub stroke: f64,
    /// Dead volume of the inlet side (hoses, end clearance) V̄_I (m³).
    pub dead_volume_in_m3: f64,
    /// Dead volume of the outlet side V̄_O (m³).
    pub dead_volume_out_m3: f64,
    /// Flow gain K·K_sp of eq. 3.48/3.51 (m³/s per √Pa) at full command u = ±1.
    pub flow_gain: f64,
    /// Equivalent viscous damping K_damp of eq. 3.52 (N·s/m; N·m·s/rad for rotary).
    pub damping: f64,
    /// Continuous rotation (hydraulic motor): chamber volumes do not change with x.
    pub continuous: bool,
    /// Nominal joint speed at full command, Lim Table 1-1 (rad/s); used by the servo.
    pub nominal_speed_rad_s: f64,
    /// Design torque used for sizing (N·m), for reference.
    pub design_torque_nm: f64,
}

impl ActuatorParams {
    /// Chamber volumes (V_I, V_O) (m³) at actuator coordinate `x` (eq. 3.50).
    pub fn volumes(&self, x: f64) -> (f64, f64) {
        if self.continuous {
            return (self.dead_volume_in_m3, self.dead_volume_out_m3);
        }
        let s = (x - self.x_min).clamp(0.0, self.stroke);
        (
            self.dead_volume_in_m3 + self.area_in * s,
            self.dead_volume_out_m3 + self.area_out * (self.stroke - s),
        )
    }
}

/// The jaw function (Lim Table 1-1: "7.5 cm opening; 10.2 cm per second; clamp force 150 kg").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JawParams {
    /// Full opening (m): 0.075.
    pub max_opening_m: f64,
    /// Opening/closing speed at full command (m/s): 0.102.
    pub speed_m_s: f64,
    /// Clamp force at full closing command (N): 150 kgf = 1 471 N.
    pub clamp_force_n: f64,
}

impl Default for JawParams {
    fn default() -> Self {
        JawParams {
            max_opening_m: 0.075,
            speed_m_s: 0.102,
            clamp_force_n: 150.0 * 9.80665,
        }
    }
}

/// Hydraulic system of one arm.
#[derive(Debug, Clone, PartialEq)]
pub struct HydraulicParams {
    /// Pump (supply) pressure P_i (Pa): 6.89 MPa, Lim Table 1-1 "operating pressure 6,890 kPa".
    pub supply_pa: f64,
    /// Exit (return) pressure P_e (Pa): 0 (gauge; README: tank ≈ 0–0.1 MPa).
    pub return_pa: f64,
    /// Relief valve cracking pressure (Pa): 1.10 × supply = 7.58 MPa ("usually set a little
    /// above supply", README); the thesis had none and saw 12 MPa.
    pub relief_pa: f64,
    /// Relief valve flow gain above cracking (m³/s per Pa): 1e-8, i.e. 1 L/s at 0.1 MPa
    /// override — far more than any actuator's full valve flow, so the line stays near the setting.
    pub relief_gain: f64,
    /// Effective bulk modulus β (Pa): 1.0 GPa (README: 0.7–1.5 GPa in practice with hoses).
    pub bulk_modulus_pa: f64,
    /// Pressure drop below which orifice flow is taken as laminar (linear) (Pa): 2e4. Keeps
    /// dq/dP finite at ΔP → 0 (numerical regularization; flows there are tiny).
    pub laminar_pa: f64,
    /// The six joint actuators.
    pub actuators: [ActuatorParams; N_ACT],
    /// The jaw.
    pub jaw: JawParams,
}

/// Actuator force (eq. 3.52), N (N·m for rotary): A_I P_I − A_O P_O − K_damp ẋ.
pub fn actuator_force(act: &ActuatorParams, p_in: f64, p_out: f64, xdot: f64) -> f64 {
    act.area_in * p_in - act.area_out * p_out - act.damping * xdot
}
