//! Valve-controlled hydraulic actuators, one per joint (Lim §3.4.3, eqs 3.48–3.54), with the
//! relief valves and cavitation floor the thesis lacked.
//!
//! * [`Linkage`]: the cylinder-to-joint geometry, x(q) and Ĵ(q) = dx/dq (eq. 3.53).
//! * [`ActuatorParams`], [`HydraulicParams`]: sizes and fluid data; [`HydraulicParams::magnum`]
//!   sizes them from Lim Table 1-1 with documented rules.
//! * [`valve_flow`]: turbulent orifice flow with the sign logic of eq. 3.48.
//! * [`update_chambers`]: one backward-Euler step of the chamber continuity equations
//!   (3.49–3.50, 3.56) including relief flow, piston leakage and the cavitation floor;
//!   `update_chambers_pair` does the same for both arms' actuator j in lockstep, bit for bit.
//! * [`JawParams`]: the jaw function (Table 1-1: 7.5 cm, 10.2 cm/s, 150 kgf), modelled as a
//!   flow-limited actuator (opening rate ∝ command) with a clamp force, not a chamber model.
//!
//! Pressures are gauge pressures relative to the return line (Pa); the return line is at
//! `return_pa` (0 by default). A chamber never goes below 0 Pa: below that the oil would
//! cavitate, and anti-cavitation check valves from the return line refill it (modelled as a
//! hard floor in the implicit update).

use crate::Error;
use crate::dynamics::Inertials;
use crate::kinematics::{KinData, jacobian};
use crate::linalg::Pair;
use crate::model::Model;

/// Number of joint actuators per arm.
pub const N_ACT: usize = 6;

/// How an actuator drives its joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Linkage {
    /// A linear cylinder pinned to the parent link at distance `r_a_m` from the joint axis and
    /// to the child link at `r_b_m`, both in the plane normal to the axis. The angle between
    /// the two pin radii is φ = `phi0_rad` + q, so the cylinder length is
    /// L(q) = √(r_a² + r_b² − 2 r_a r_b cos φ) and Ĵ(q) = dL/dq = r_a r_b sin φ / L: extending
    /// the cylinder increases q. φ stays in (0, π) over the joint range.
    Linear {
        /// Parent-side pin radius (m).
        r_a_m: f64,
        /// Child-side pin radius (m).
        r_b_m: f64,
        /// φ at q = 0 (rad).
        phi0_rad: f64,
    },
    /// A rotary actuator (vane, rack-and-pinion or motor): x = q, Ĵ = 1; "area" is the
    /// volumetric displacement (m³/rad).
    Rotary,
}

impl Linkage {
    /// Actuator coordinate x (m or rad) and Ĵ = dx/dq (m/rad or 1) at joint angle `q`.
    #[inline]
    pub fn coordinate(&self, q: f64) -> (f64, f64) {
        let sc = match *self {
            Linkage::Linear { phi0_rad, .. } => crate::trig::sin_cos(phi0_rad + q),
            Linkage::Rotary => (0.0, 1.0),
        };
        self.coordinate_sin_cos(q, sc)
    }

    /// [`Self::coordinate`] given (sin φ, cos φ) of the pin angle φ = φ₀ + q (ignored by a
    /// rotary actuator), for a caller that has them from the joint's trigonometry.
    #[inline]
    pub fn coordinate_sin_cos(&self, q: f64, (s, c): (f64, f64)) -> (f64, f64) {
        match *self {
            Linkage::Linear { r_a_m, r_b_m, .. } => {
                let l = (r_a_m * r_a_m + r_b_m * r_b_m - 2.0 * r_a_m * r_b_m * c)
                    .max(1e-12)
                    .sqrt();
                (l, r_a_m * r_b_m * s / l)
            }
            Linkage::Rotary => (q, 1.0),
        }
    }

    /// (sin, cos) of the pin angle at the joint angle whose (sin v, cos v) are `v_sin_cos`,
    /// where v = q + `offset` (the angle forward kinematics turns; [`KinData::joint_sin_cos`]),
    /// and `phase` = (sin, cos) of φ₀ − offset: φ = (φ₀ − offset) + v by angle addition.
    #[inline]
    pub fn pin_sin_cos(phase: (f64, f64), v_sin_cos: (f64, f64)) -> (f64, f64) {
        let ((sp, cp), (sv, cv)) = (phase, v_sin_cos);
        (sp * cv + cp * sv, cp * cv - sp * sv)
    }
}

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
    #[inline]
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

/// Payload at the jaw for the holding requirement, Lim Table 1-1 "lift 295 kg at full extension".
pub const MAGNUM_LIFT_KG: f64 = 295.0;
/// Margin of the holding side over the 295 kg requirement at supply pressure: 1.15.
pub const HOLD_MARGIN: f64 = 1.15;
/// Rod-side to bore-side area ratio of the linear cylinders (typical single-rod cylinder): 0.8.
pub const AREA_RATIO: f64 = 0.8;
/// Nominal joint speeds, Lim Table 1-1 (°/s): 20, 20, 30, 30, 30, 150.
pub const MAGNUM_SPEEDS_DEG_S: [f64; N_ACT] = [20.0, 20.0, 30.0, 30.0, 30.0, 150.0];

/// Floor on the design torque of each joint (N·m), for joints the full-extension load does
/// not exercise: swing 2 000 (lateral loads of the order of the elbow's), shoulder/elbow/
/// pitch 0 (sized by the load), yaw 600, rotate 150 (typical wrist torques of 7-function
/// subsea arms; assumed).
pub const MAGNUM_TORQUE_FLOOR_NM: [f64; N_ACT] = [2000.0, 0.0, 0.0, 0.0, 600.0, 150.0];

/// The "full extension" posture of the Magnum model used for sizing and for the holding test:
/// all joints at 0 — upper arm, forearm and wrist in line and horizontal, reach 1.5 m.
pub const MAGNUM_FULL_EXTENSION: [f64; N_ACT] = [0.0; N_ACT];

impl HydraulicParams {
    /// Magnum hydraulics sized from Lim Table 1-1 by these rules:
    ///
    /// * Shoulder, elbow, pitch: linear cylinders (geometry below); swing, yaw: rotary
    ///   actuators; rotate: continuous hydraulic motor.
    /// * Design torque of joint j = max(1.15 × |G_j| at [`MAGNUM_FULL_EXTENSION`] with 295 kg at
    ///   the jaw (in air), [`MAGNUM_TORQUE_FLOOR_NM`]). The side of the actuator that holds
    ///   that load gets area = design torque / (Ĵ · supply); the other side is 0.8× (or
    ///   1/0.8×) for cylinders, equal for rotary actuators. So 295 kg is held below supply
    ///   pressure, and 590 kg needs ≈ 1.7× the relief setting: it cannot be held.
    /// * Flow gain so that full command moves the unloaded joint at its Table 1-1 speed at
    ///   mid-range: extend and retract speeds of a cylinder with area ratio α differ by √α,
    ///   so the gain puts their geometric mean on the nominal speed.
    /// * Cylinder pins (shoulder, elbow, pitch): r_a = 0.35/0.30/0.25 m, r_b = 0.10/0.09/0.06 m,
    ///   φ = 90° at mid-range (largest lever where the arm works most). Assumed; Lim prints none.
    /// * Dead volume 0.15 L per side (≈ 3 m of 3/8" hose); damping 5·10⁴ N·s/m for cylinders
    ///   (README range 10³–10⁵; the upper half, because a closed-centre valve adds no damping and
    ///   the cooperative loop needs the oil-column resonance damped), 200/50/5 N·m·s/rad for
    ///   swing/yaw/rotate.
    pub fn magnum(model: &Model, inertials: &Inertials) -> Result<HydraulicParams, Error> {
        if model.dof() != N_ACT {
            return Err(Error::InvalidModel {
                reason: "Magnum hydraulics need a 6-joint model".into(),
            });
        }
        let supply = 6.89e6;
        // Holding torques at full extension with the payload.
        let q = MAGNUM_FULL_EXTENSION;
        let mut kin = KinData::new(model);
        jacobian(model, &mut kin, &q);
        let mut dd = crate::dynamics::DynData::new(model);
        let mut g = [0.0; N_ACT];
        let g_vec = nalgebra::Vector3::new(0.0, 0.0, -9.81);
        crate::dynamics::rnea(
            model,
            inertials,
            &kin,
            &[0.0; N_ACT],
            &[0.0; N_ACT],
            &g_vec,
            0.0,
            &mut g,
            &mut dd,
        );
        // Payload weight at the tool: τ = −J_vᵀ·(m·g).
        for (j, gj) in g.iter_mut().enumerate() {
            let col = kin.jacobian.column(j);
            *gj -= col[2] * (-9.81 * MAGNUM_LIFT_KG);
        }
        let pins: [Option<(f64, f64)>; N_ACT] = [
            None,
            Some((0.35, 0.10)),
            Some((0.30, 0.09)),
            Some((0.25, 0.06)),
            None,
            None,
        ];
        let damping = [200.0, 5.0e4, 5.0e4, 5.0e4, 50.0, 5.0];
        let mut actuators = [ActuatorParams {
            linkage: Linkage::Rotary,
            area_in: 0.0,
            area_out: 0.0,
            x_min: 0.0,
            stroke: 0.0,
            dead_volume_in_m3: 1.5e-4,
            dead_volume_out_m3: 1.5e-4,
            flow_gain: 0.0,
            damping: 0.0,
            continuous: false,
            nominal_speed_rad_s: 0.0,
            design_torque_nm: 0.0,
        }; N_ACT];
        for j in 0..N_ACT {
            let joint = &model.joints[j];
            let (lo, hi) = if joint.is_limited() {
                (joint.limits[0], joint.limits[1])
            } else {
                (-std::f64::consts::PI, std::f64::consts::PI)
            };
            let mid = 0.5 * (lo + hi);
            let omega = MAGNUM_SPEEDS_DEG_S[j].to_radians();
            let torque = (HOLD_MARGIN * g[j].abs()).max(MAGNUM_TORQUE_FLOOR_NM[j]);
            let a = &mut actuators[j];
            a.damping = damping[j];
            a.nominal_speed_rad_s = omega;
            a.design_torque_nm = torque;
            match pins[j] {
                Some((ra, rb)) => {
                    let link = Linkage::Linear {
                        r_a_m: ra,
                        r_b_m: rb,
                        phi0_rad: std::f64::consts::FRAC_PI_2 - mid,
                    };
                    let (x_lo, _) = link.coordinate(lo);
                    let (x_hi, _) = link.coordinate(hi);
                    let (_, jh_q) = link.coordinate(q[j]);
                    let (_, jh_mid) = link.coordinate(mid);
                    let hold_area = torque / (jh_q * supply);
                    // τ_act = G holds the arm; G > 0 with Ĵ > 0 needs an extending force (inlet side).
                    let (ai, ao) = if g[j] >= 0.0 {
                        (hold_area, hold_area * AREA_RATIO)
                    } else {
                        (hold_area / AREA_RATIO, hold_area)
                    };
                    a.linkage = link;
                    a.area_in = ai;
                    a.area_out = ao;
                    a.x_min = x_lo;
                    a.stroke = x_hi - x_lo;
                    let alpha = ao / ai;
                    a.flow_gain = omega * jh_mid * ai * (1.0 + alpha.powi(3)).sqrt()
                        / (supply.sqrt() * alpha.powf(0.25));
                }
                None => {
                    let d = torque / supply;
                    a.linkage = Linkage::Rotary;
                    a.area_in = d;
                    a.area_out = d;
                    a.x_min = lo;
                    a.stroke = hi - lo;
                    a.continuous = !joint.is_limited();
                    a.flow_gain = omega * d * 2.0f64.sqrt() / supply.sqrt();
                }
            }
        }
        Ok(HydraulicParams {
            supply_pa: supply,
            return_pa: 0.0,
            relief_pa: 1.10 * supply,
            relief_gain: 1.0e-8,
            bulk_modulus_pa: 1.0e9,
            laminar_pa: 2.0e4,
            actuators,
            jaw: JawParams::default(),
        })
    }
}

/// Per-arm fault injection, plain mutable parameters (all "no fault" by default). Any value is
/// accepted; non-finite or out-of-range values are clamped by the simulation at use.
#[derive(Debug, Clone, Copy, PartialEq)]
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

/// Signed square root with a linear (laminar) region below `lam` Pa, continuous in value.
#[inline]
fn signed_root(dp: f64, lam: f64) -> (f64, f64) {
    let a = dp.abs();
    if a >= lam {
        let r = a.sqrt();
        (dp.signum() * r, 0.5 / r)
    } else {
        let k = 1.0 / lam.sqrt();
        (dp * k, k)
    }
}

/// Valve flow into a chamber (m³/s) and its derivative with respect to the chamber pressure,
/// eq. 3.48: with a spool opening `s` ∈ [−1, 1] towards this chamber (s > 0 connects it to
/// supply, s < 0 to return), q = K·s·√(P_s − P) or K·s·√(P − P_e). The flow reverses sign
/// (signed root) if the pressure difference does.
#[inline]
pub fn valve_flow(gain: f64, s: f64, p: f64, supply: f64, ret: f64, lam: f64) -> (f64, f64) {
    if s >= 0.0 {
        let (r, dr) = signed_root(supply - p, lam);
        (gain * s * r, -gain * s * dr)
    } else {
        let (r, dr) = signed_root(p - ret, lam);
        (gain * s * r, gain * s * dr)
    }
}

/// Fixed inputs of one chamber update.
#[derive(Debug, Clone, Copy)]
struct Chamber {
    p0: f64,
    c: f64,
    gain: f64,
    s: f64,
    other: f64,
    leak: f64,
    piston: f64,
}

/// Net flow into a chamber at pressure `p` and its derivative with respect to `p`: valve
/// flow − leakage to the other chamber − relief flow − piston flow (eqs 3.48–3.50).
#[inline]
fn chamber_inflow(ch: &Chamber, hp: &HydraulicParams, supply: f64, p: f64) -> (f64, f64) {
    let (qv, dqv) = valve_flow(ch.gain, ch.s, p, supply, hp.return_pa, hp.laminar_pa);
    let over = p - hp.relief_pa;
    let (qr, dqr) = if over > 0.0 {
        (hp.relief_gain * over, hp.relief_gain)
    } else {
        (0.0, 0.0)
    };
    (
        qv - ch.leak * (p - ch.other) - qr - ch.piston,
        dqv - ch.leak - dqr,
    )
}

/// Backward-Euler pressure of one chamber: solves P − P0 − c·g(P) = 0 with
/// g = valve flow − leak·(P − P_other) − relief − piston flow; g decreases with P, so the
/// residual increases strictly and the root in [0, ∞) is unique. Closed forms for a shut
/// valve and for an open turbulent one ([`open_valve_root`]); safeguarded Newton otherwise.
#[inline(always)]
fn solve_chamber(ch: &Chamber, hp: &HydraulicParams, supply: f64) -> (f64, bool) {
    let g = |p: f64| chamber_inflow(ch, hp, supply, p);
    // Closed valve: g is linear (piston, leakage and relief only): closed form.
    if ch.s == 0.0 {
        let k = ch.c * ch.leak;
        let mut p = (ch.p0 + ch.c * (ch.leak * ch.other - ch.piston)) / (1.0 + k);
        if p > hp.relief_pa {
            let kr = ch.c * hp.relief_gain;
            p = (ch.p0 + ch.c * (ch.leak * ch.other - ch.piston) + kr * hp.relief_pa)
                / (1.0 + k + kr);
        }
        let p = p.max(0.0);
        return (p, p > hp.relief_pa);
    }
    if let Some(p) = open_valve_root(ch, hp, supply) {
        return (p, false);
    }
    solve_chamber_bracketed(ch, hp, g)
}

/// The root of the backward-Euler residual of a chamber with an open valve, in closed form,
/// where the orifice is turbulent and the relief valve shut — nearly always. `None` when the
/// root lies in the orifice's laminar band or above the relief setting: the caller then
/// solves numerically.
///
/// With a = 1 + c·leak and E = P0 + c·(leak·P_other − piston), the residual is
/// R(P) = a·P − E − c·K·s·√±(P_s − P) for s > 0 (eq. 3.48, `signed_root`), and
/// R(P) = a·P − E + c·K·|s|·√±(P − P_e) for s < 0. Writing P = P_r ∓ m² about the
/// valve's reference pressure P_r (supply or return) turns R = 0 into
/// a·m² + k·m − |D| = 0 with k = c·K·|s| and D = ±(a·P_r − E), whose positive root is
/// m = 2|D| / (k + √(k² + 4a|D|)) (the cancellation-free form). The sign of D says which
/// way the oil flows. A root below 0 Pa means the chamber cavitates: the floor holds it at 0,
/// as in the bracketed solver (R increases, so R(0) > 0 there).
#[inline]
fn open_valve_root(ch: &Chamber, hp: &HydraulicParams, supply: f64) -> Option<f64> {
    let a = 1.0 + ch.c * ch.leak;
    let e = ch.p0 + ch.c * (ch.leak * ch.other - ch.piston);
    let k = ch.c * ch.gain * ch.s.abs();
    // σ = +1 for a valve opened to supply (reference P_s), −1 to return (reference P_e).
    let (p_ref, sigma) = if ch.s > 0.0 {
        (supply, 1.0)
    } else {
        (hp.return_pa, -1.0)
    };
    let d = sigma * (a * p_ref - e);
    let m = 2.0 * d.abs() / (k + (k * k + 4.0 * a * d.abs()).sqrt());
    let m2 = m * m;
    // P = P_r − σ·sign(D)·m²: below P_s when supply flows in, above P_e when oil flows out.
    let p = if (d > 0.0) == (sigma > 0.0) {
        p_ref - m2
    } else {
        p_ref + m2
    };
    if m2 >= hp.laminar_pa && p <= hp.relief_pa && m2.is_finite() {
        Some(p.max(0.0))
    } else {
        None
    }
}

/// [`solve_chamber`] where the closed form does not apply: safeguarded Newton on the
/// residual P − P0 − c·g(P), bracketing the root so it stays safe where the orifice law bends.
#[inline(never)]
fn solve_chamber_bracketed(
    ch: &Chamber,
    hp: &HydraulicParams,
    g: impl Fn(f64) -> (f64, f64),
) -> (f64, bool) {
    let mut lo = 0.0;
    let mut hi = f64::INFINITY;
    let mut p = ch.p0.max(0.0);
    for _ in 0..60 {
        let (gp, dg) = g(p);
        let r = p - ch.p0 - ch.c * gp;
        if r.abs() < 0.1 {
            break;
        }
        if r > 0.0 {
            hi = p;
        } else {
            lo = p;
        }
        let mut next = p - r / (1.0 - ch.c * dg);
        if next <= 0.0 && lo == 0.0 {
            // The root may lie below zero: then the chamber cavitates (floor at 0).
            let (g0, _) = g(0.0);
            if -ch.p0 - ch.c * g0 >= 0.0 {
                return (0.0, false);
            }
        }
        if !(next > lo && next < hi) {
            next = if hi.is_finite() {
                0.5 * (lo + hi)
            } else {
                2.0 * p.max(1.0e3)
            };
        }
        p = next;
        if hi - lo < 0.1 {
            break;
        }
    }
    (p, p > hp.relief_pa)
}

/// Result of one chamber update.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ChamberFlags {
    /// A relief valve of this actuator is open at the end of the update.
    pub relief_open: bool,
}

/// One backward-Euler step of length `h_s` of both chamber pressures of an actuator
/// (eqs 3.48–3.50, 3.56 with relief, leakage and cavitation floor). `spool` ∈ [−1, 1] is the
/// valve opening (eq. 3.51 with K_sp folded into the flow gain), `x` and `xdot` the actuator
/// coordinate and rate at the start of the step. Each chamber is solved implicitly in its own
/// pressure (the stiff orifice/relief terms); the coupling through leakage uses the other
/// chamber's latest value (Gauss–Seidel).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn update_chambers(
    act: &ActuatorParams,
    hp: &HydraulicParams,
    supply_pa: f64,
    beta_pa: f64,
    leak: f64,
    spool: f64,
    x: f64,
    xdot: f64,
    h_s: f64,
    p_in: &mut f64,
    p_out: &mut f64,
) -> ChamberFlags {
    let (v_in, v_out) = act.volumes(x);
    let a = Chamber {
        p0: *p_in,
        c: h_s * beta_pa / v_in,
        gain: act.flow_gain,
        s: spool,
        other: *p_out,
        leak,
        piston: act.area_in * xdot,
    };
    let (pi, ri) = solve_chamber(&a, hp, supply_pa);
    let b = Chamber {
        p0: *p_out,
        c: h_s * beta_pa / v_out,
        gain: act.flow_gain,
        s: -spool,
        other: pi,
        leak,
        piston: -act.area_out * xdot,
    };
    let (po, ro) = solve_chamber(&b, hp, supply_pa);
    *p_in = pi;
    *p_out = po;
    ChamberFlags {
        relief_open: ri || ro,
    }
}

/// Fixed inputs of one chamber update for both arms in lockstep (arm i in lane i): the
/// fields of [`Chamber`], one [`Pair`] each.
#[derive(Debug, Clone, Copy)]
struct ChamberPair {
    p0: Pair,
    c: Pair,
    gain: Pair,
    s: Pair,
    other: Pair,
    leak: Pair,
    piston: Pair,
}

impl ChamberPair {
    /// The scalar chamber of lane `l`.
    #[inline(always)]
    fn lane(&self, l: usize) -> Chamber {
        Chamber {
            p0: self.p0.0[l],
            c: self.c.0[l],
            gain: self.gain.0[l],
            s: self.s.0[l],
            other: self.other.0[l],
            leak: self.leak.0[l],
            piston: self.piston.0[l],
        }
    }
}

/// Both arms' hydraulic constants for [`update_chambers_pair`] (arm i in lane i), the same
/// for every actuator and sub-step, so gathered once per step.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PairSystem {
    /// Fault-adjusted supply pressure P_s (Pa).
    supply: Pair,
    /// Return pressure P_e (Pa).
    ret: Pair,
    /// Relief cracking pressure (Pa).
    relief: Pair,
    /// Laminar band of the orifice law (Pa).
    laminar: Pair,
    /// h·β, the numerator of c = h·β/V (eq. 3.56 in backward Euler).
    h_beta: Pair,
}

impl PairSystem {
    /// From the arms' parameters, fault-adjusted supply pressure and bulk modulus, and the
    /// step length `h_s` (s).
    #[inline]
    pub(crate) fn new(
        hps: [&HydraulicParams; 2],
        supply_pa: Pair,
        beta_pa: Pair,
        h_s: f64,
    ) -> PairSystem {
        PairSystem {
            supply: supply_pa,
            ret: Pair([hps[0].return_pa, hps[1].return_pa]),
            relief: Pair([hps[0].relief_pa, hps[1].relief_pa]),
            laminar: Pair([hps[0].laminar_pa, hps[1].laminar_pa]),
            h_beta: Pair::splat(h_s) * beta_pa,
        }
    }
}

/// Per lane: `a` where `take_a`, else `b` (a select, no branch).
#[inline(always)]
fn select(take_a: [bool; 2], a: Pair, b: Pair) -> Pair {
    Pair([
        if take_a[0] { a.0[0] } else { b.0[0] },
        if take_a[1] { a.0[1] } else { b.0[1] },
    ])
}

/// Per-lane function of a pair.
#[inline(always)]
fn map(x: Pair, f: impl Fn(f64) -> f64) -> Pair {
    Pair([f(x.0[0]), f(x.0[1])])
}

/// [`solve_chamber`] for both arms' chamber in lockstep, giving bit for bit the scalar
/// results: each lane evaluates the scalar closed forms with the same operations in the same
/// order, and selects instead of branching —
///
/// * shut valve (s = 0): P = E/a, the root of the linear residual R(P) = a·P − E with
///   a = 1 + c·leak, E = P0 + c·(leak·P_other − piston) (eqs 3.49–3.50, 3.56);
/// * open valve: the turbulent-orifice root of [`open_valve_root`] (eq. 3.48), with the
///   valve direction (reference pressure P_r and σ) selected per lane.
///
/// A lane that needs more — relief open, the orifice's laminar band, a non-finite value —
/// is solved by the scalar [`solve_chamber`] (rare). `both_shut`: s = 0 in both lanes (the
/// caller knows it from the spools, once for both chambers).
#[inline(always)]
fn solve_chamber_pair(
    ch: &ChamberPair,
    hps: [&HydraulicParams; 2],
    sys: &PairSystem,
    both_shut: bool,
) -> (Pair, [bool; 2]) {
    let (supply, ret, relief) = (sys.supply, sys.ret, sys.relief);
    let a = Pair::splat(1.0) + ch.c * ch.leak;
    let e = ch.p0 + ch.c * (ch.leak * ch.other - ch.piston);
    // Shut valve.
    let p_shut = e / a;
    let shut = [ch.s.0[0] == 0.0, ch.s.0[1] == 0.0];
    // Both valves shut (an arm holding still): the linear root alone.
    if both_shut && (p_shut.0[0] <= relief.0[0]) & (p_shut.0[1] <= relief.0[1]) {
        return (map(p_shut, |v| v.max(0.0)), [false, false]);
    }
    // Open valve (open_valve_root): σ = +1 towards supply, −1 towards return; σ·t = ±t.
    let k = ch.c * ch.gain * map(ch.s, f64::abs);
    let up = [ch.s.0[0] > 0.0, ch.s.0[1] > 0.0];
    let p_ref = select(up, supply, ret);
    let t = a * p_ref - e;
    let d = select(up, t, -t);
    let d_abs = map(d, f64::abs);
    let m = Pair::splat(2.0) * d_abs / (k + map(k * k + Pair::splat(4.0) * a * d_abs, f64::sqrt));
    let m2 = m * m;
    let below = [(d.0[0] > 0.0) == up[0], (d.0[1] > 0.0) == up[1]];
    let p_open = select(below, p_ref - m2, p_ref + m2);
    let p = select(shut, p_shut, p_open);
    // Non-short-circuit `&`/`|` so the lane tests compile to compares, not branches;
    // m² ≥ 0 or NaN, so m² < ∞ is its finiteness test.
    let lam = sys.laminar;
    let ok = |l: usize| {
        (p.0[l] <= relief.0[l]) & (shut[l] | ((m2.0[l] >= lam.0[l]) & (m2.0[l] < f64::INFINITY)))
    };
    let (ok0, ok1) = (ok(0), ok(1));
    // Relief flags are false on this path, as in the scalar closed forms: P ≤ P_relief and
    // P_relief ≥ 0 (the initial pressures are clamped to [0, P_relief]), so max(P, 0) is too.
    if ok0 & ok1 {
        return (map(p, |v| v.max(0.0)), [false, false]);
    }
    let mut out = map(p, |v| v.max(0.0));
    let mut relief_open = [false, false];
    for (l, good) in [ok0, ok1].into_iter().enumerate() {
        if !good {
            (out.0[l], relief_open[l]) = solve_chamber(&ch.lane(l), hps[l], supply.0[l]);
        }
    }
    (out, relief_open)
}

/// [`update_chambers`] for actuator j of both arms in lockstep (arm i in lane i, each lane
/// with its own arm's actuator and hydraulic parameters), bit for bit the same results
/// (see [`solve_chamber_pair`]). The pressures are read and written as pairs.
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn update_chambers_pair(
    acts: [&ActuatorParams; 2],
    hps: [&HydraulicParams; 2],
    sys: &PairSystem,
    leak: Pair,
    spool: Pair,
    x: Pair,
    xdot: Pair,
    p_in: &mut Pair,
    p_out: &mut Pair,
) -> [ChamberFlags; 2] {
    let (vi0, vo0) = acts[0].volumes(x.0[0]);
    let (vi1, vo1) = acts[1].volumes(x.0[1]);
    let field = |f: fn(&ActuatorParams) -> f64| Pair([f(acts[0]), f(acts[1])]);
    let hb = sys.h_beta;
    // Both spools shut: both chambers of both lanes have s = 0 (tested once here).
    let both_shut = (spool.0[0] == 0.0) & (spool.0[1] == 0.0);
    let gain = field(|a| a.flow_gain);
    let a = ChamberPair {
        p0: *p_in,
        c: hb / Pair([vi0, vi1]),
        gain,
        s: spool,
        other: *p_out,
        leak,
        piston: field(|a| a.area_in) * xdot,
    };
    let (pi, ri) = solve_chamber_pair(&a, hps, sys, both_shut);
    let b = ChamberPair {
        p0: *p_out,
        c: hb / Pair([vo0, vo1]),
        gain,
        s: -spool,
        other: pi,
        leak,
        piston: -field(|a| a.area_out) * xdot,
    };
    let (po, ro) = solve_chamber_pair(&b, hps, sys, both_shut);
    *p_in = pi;
    *p_out = po;
    [
        ChamberFlags {
            relief_open: ri[0] || ro[0],
        },
        ChamberFlags {
            relief_open: ri[1] || ro[1],
        },
    ]
}

/// Actuator force (eq. 3.52), N (N·m for rotary): A_I P_I − A_O P_O − K_damp ẋ.
#[inline]
pub fn actuator_force(act: &ActuatorParams, p_in: f64, p_out: f64, xdot: f64) -> f64 {
    act.area_in * p_in - act.area_out * p_out - act.damping * xdot
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> HydraulicParams {
        HydraulicParams {
            supply_pa: 6.89e6,
            return_pa: 0.0,
            relief_pa: 1.1 * 6.89e6,
            relief_gain: 1.0e-8,
            bulk_modulus_pa: 1.0e9,
            laminar_pa: 2.0e4,
            actuators: [ActuatorParams {
                linkage: Linkage::Rotary,
                area_in: 1e-3,
                area_out: 1e-3,
                x_min: 0.0,
                stroke: 1.0,
                dead_volume_in_m3: 1.5e-4,
                dead_volume_out_m3: 1.5e-4,
                flow_gain: 1e-7,
                damping: 0.0,
                continuous: false,
                nominal_speed_rad_s: 1.0,
                design_torque_nm: 0.0,
            }; N_ACT],
            jaw: JawParams::default(),
        }
    }

    /// The linkage coordinate from the joint's sin/cos by angle addition
    /// ([`Linkage::pin_sin_cos`]) equals the direct one (closed form L(q), Ĵ(q)) to round-off,
    /// with and without a DH offset.
    #[test]
    fn linkage_from_joint_trigonometry() {
        let link = Linkage::Linear {
            r_a_m: 0.35,
            r_b_m: 0.10,
            phi0_rad: 1.9,
        };
        for k in 0..400 {
            let q = -2.0 + 0.01 * k as f64;
            for offset in [0.0, 0.3, -1.2] {
                let phase = crate::trig::sin_cos(1.9 - offset);
                let sc = Linkage::pin_sin_cos(phase, (q + offset).sin_cos());
                let (x, jh) = link.coordinate_sin_cos(q, sc);
                let (x_ref, jh_ref) = link.coordinate(q);
                assert!(
                    (x - x_ref).abs() < 1e-15 && (jh - jh_ref).abs() < 1e-15,
                    "{q} {offset}"
                );
            }
        }
        assert_eq!(
            Linkage::Rotary.coordinate_sin_cos(0.7, (0.3, 0.1)),
            (0.7, 1.0)
        );
    }

    /// A reproducible uniform number in [0, 1).
    fn uniform(s: &mut u64) -> f64 {
        *s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*s >> 11) as f64 / (1u64 << 53) as f64
    }

    /// The closed-form open-valve root ([`open_valve_root`]) against the bracketed Newton
    /// solver on the same residual (an independent numerical method), over random chambers
    /// spanning both valve directions, both flow directions, leakage, cavitation and
    /// pressures near relief; where the closed form declines, the solver must find the root
    /// in the laminar band or above relief.
    #[test]
    fn closed_form_root_agrees_with_bracketed_newton() {
        let hp = params();
        let mut seed = 7;
        let (mut closed, mut declined) = (0, 0);
        for _ in 0..20_000 {
            let ch = Chamber {
                p0: uniform(&mut seed) * 1.2 * hp.relief_pa,
                // h·β/V for V from 0.05 to 2 L at h = 1 ms.
                c: 1e-3 * hp.bulk_modulus_pa / (5e-5 + uniform(&mut seed) * 2e-3),
                gain: 1e-7 * (0.5 + uniform(&mut seed)),
                s: if uniform(&mut seed) < 0.02 {
                    1e-4
                } else {
                    2.0 * uniform(&mut seed) - 1.0
                },
                other: uniform(&mut seed) * hp.relief_pa,
                leak: if uniform(&mut seed) < 0.5 {
                    0.0
                } else {
                    uniform(&mut seed) * 1e-11
                },
                // Piston flow up to ±2 L/s·(A v).
                piston: (2.0 * uniform(&mut seed) - 1.0) * 2e-3,
            };
            if ch.s == 0.0 {
                continue;
            }
            let g = |p: f64| chamber_inflow(&ch, &hp, hp.supply_pa, p);
            let (reference, _) = solve_chamber_bracketed(&ch, &hp, g);
            match open_valve_root(&ch, &hp, hp.supply_pa) {
                Some(p) => {
                    closed += 1;
                    // The bracketed solver stops within 0.1 Pa of the residual's root.
                    let slope = 1.0 - ch.c * g(p.max(1.0)).1;
                    assert!(
                        (p - reference).abs() <= 0.1 / slope.min(1.0) + 1e-9 * reference,
                        "{ch:?}: closed {p}, bracketed {reference}"
                    );
                    if p > 0.0 {
                        let r = p - ch.p0 - ch.c * g(p).0;
                        assert!(r.abs() < 1e-6 * (ch.p0 + 1.0) * slope, "residual {r}");
                    }
                }
                None => {
                    declined += 1;
                    let laminar = (reference - hp.supply_pa).abs() < hp.laminar_pa
                        || (reference - hp.return_pa).abs() < hp.laminar_pa;
                    assert!(laminar || reference > hp.relief_pa, "{ch:?}: {reference}");
                }
            }
        }
        // Both branches were exercised.
        assert!(closed > 15_000 && declined > 10, "{closed} {declined}");
    }
    /// [`update_chambers_pair`] against two calls of the scalar [`update_chambers`] (the
    /// reference it must reproduce bit for bit), with different parameters per lane, over
    /// random states mixing shut valves (in one lane or both), both valve and flow
    /// directions, leakage, cavitation, the laminar band and relief.
    #[test]
    fn pair_update_is_bitwise_the_scalar_update() {
        let mut hp1 = params();
        hp1.supply_pa = 5.0e6;
        hp1.relief_pa = 6.0e6;
        hp1.return_pa = 1.0e5;
        hp1.laminar_pa = 3.0e4;
        hp1.actuators[0].flow_gain = 2e-7;
        hp1.actuators[0].area_out = 0.8e-3;
        hp1.actuators[0].continuous = true;
        let hps = [params(), hp1];
        let mut seed = 5;
        let (mut fallbacks, mut shut_both, mut shut_one) = (0, 0, 0);
        for n in 0..20_000 {
            let mut lane_in = [0.0; 2];
            // Per lane: supply, β, leak, spool, x, ẋ, P_I, P_O.
            let mut lane_args = [[0.0; 8]; 2];
            for l in 0..2 {
                let spool = match uniform(&mut seed) {
                    u if u < 0.3 => 0.0,
                    u if u < 0.35 => 1e-4 * (2.0 * uniform(&mut seed) - 1.0),
                    _ => 2.0 * uniform(&mut seed) - 1.0,
                };
                lane_args[l] = [
                    hps[l].supply_pa * (1.0 - 0.3 * uniform(&mut seed)),
                    hps[l].bulk_modulus_pa * (0.2 + 0.8 * uniform(&mut seed)),
                    if uniform(&mut seed) < 0.5 {
                        0.0
                    } else {
                        uniform(&mut seed) * 1e-11
                    },
                    spool,
                    1.2 * uniform(&mut seed) - 0.1,
                    (2.0 * uniform(&mut seed) - 1.0) * 2.0,
                    uniform(&mut seed) * 1.2 * hps[l].relief_pa,
                    uniform(&mut seed) * 1.2 * hps[l].relief_pa,
                ];
                lane_in[l] = spool;
            }
            if lane_in[0] == 0.0 && lane_in[1] == 0.0 {
                shut_both += 1;
            } else if lane_in[0] == 0.0 || lane_in[1] == 0.0 {
                shut_one += 1;
            }
            let h = if n % 2 == 0 { 1e-3 } else { 2.5e-4 };
            let acts = [&hps[0].actuators[0], &hps[1].actuators[0]];
            let pick = |k: usize| Pair([lane_args[0][k], lane_args[1][k]]);
            let mut p_in = pick(6);
            let mut p_out = pick(7);
            let sys = PairSystem::new([&hps[0], &hps[1]], pick(0), pick(1), h);
            let flags = update_chambers_pair(
                acts,
                [&hps[0], &hps[1]],
                &sys,
                pick(2),
                pick(3),
                pick(4),
                pick(5),
                &mut p_in,
                &mut p_out,
            );
            for l in 0..2 {
                let [supply, beta, leak, spool, x, xd, mut pi, mut po] = lane_args[l];
                let reference = update_chambers(
                    acts[l], &hps[l], supply, beta, leak, spool, x, xd, h, &mut pi, &mut po,
                );
                assert_eq!(
                    (p_in.0[l].to_bits(), p_out.0[l].to_bits(), flags[l]),
                    (pi.to_bits(), po.to_bits(), reference),
                    "lane {l}: {:?}",
                    lane_args[l]
                );
                if reference.relief_open {
                    fallbacks += 1;
                }
            }
        }
        assert!(fallbacks > 100 && shut_both > 1000 && shut_one > 1000);
    }
}
