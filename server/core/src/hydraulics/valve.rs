//! The proportional valve's orifice law (Lim eq. 3.48), with a laminar band near ΔP = 0, and
//! its steady-state inverse (the opening for a speed against a load).

use super::ActuatorParams;

/// Signed square root with a linear (laminar) region below `lam` Pa, continuous in value.
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
pub fn valve_flow(gain: f64, s: f64, p: f64, supply: f64, ret: f64, lam: f64) -> (f64, f64) {
    if s >= 0.0 {
        let (r, dr) = signed_root(supply - p, lam);
        (gain * s * r, -gain * s * dr)
    } else {
        let (r, dr) = signed_root(p - ret, lam);
        (gain * s * r, gain * s * dr)
    }
}

/// The spool opening u ∈ [−1, 1] that moves actuator `act` at the steady speed `x_dot`
/// (m/s; rad/s for a motor) while it delivers the load force `force_n` (N; N·m),
/// i.e. A_I·P_I − A_O·P_O − K_damp·ẋ = F (eq. 3.52), with supply `supply_pa` and return
/// `return_pa`. Steady state of eqs 3.48–3.49 (constant pressures: each chamber's valve flow
/// is its piston flow): extending (ẋ ≥ 0), K·u·√(P_s − P_I) = A_I·ẋ and
/// K·u·√(P_O − P_e) = A_O·ẋ, so with F' = F + K_damp·ẋ
///
/// u = ẋ·√(A_I³ + A_O³) / (K·√(A_I·P_s − A_O·P_e − F')),
///
/// and retracting, with the chambers' roles swapped,
/// u = ẋ·√(A_I³ + A_O³) / (K·√(A_O·P_s − A_I·P_e + F')). A load the supply cannot move at
/// that speed (radicand ≤ 0) gets the full opening. Zero for ẋ = 0.
pub fn steady_opening(
    act: &ActuatorParams,
    supply_pa: f64,
    return_pa: f64,
    x_dot: f64,
    force_n: f64,
) -> f64 {
    if x_dot == 0.0 || act.flow_gain <= 0.0 {
        return 0.0;
    }
    let (ai, ao) = (act.area_in, act.area_out);
    let f = force_n + act.damping * x_dot;
    let drive = if x_dot > 0.0 {
        ai * supply_pa - ao * return_pa - f
    } else {
        ao * supply_pa - ai * return_pa + f
    };
    if drive <= 0.0 {
        return x_dot.signum();
    }
    let u = x_dot * (ai * ai * ai + ao * ao * ao).sqrt() / (act.flow_gain * drive.sqrt());
    if u.is_finite() {
        u.clamp(-1.0, 1.0)
    } else {
        0.0
    }
}

/// Time constant of the proportional valves' spool (s): 0.025. Lim eq. 3.51 takes the spool as
/// instantaneous ("due to very small rise time"); with that, a full step of command slams
/// supply pressure onto the oil columns and the joints overshoot their steady speed by 35–40 %
/// at start (a lightly damped oil-column resonance: the valve adds no damping at full opening,
/// and the joint's inertia rides the compressed oil). A first-order spool with τ = 25 ms
/// (a 0–90 % step in 58 ms: the step response of direct-operated proportional directional
/// valves, whose catalogue 0–100 % step times are of the order of 30–80 ms; an assumption,
/// Lim prints none) ramps the flow in over several resonance periods, so the start-up peak
/// stays within 10 % of the steady speed (tests/joint_speed_sweep.rs).
pub const SPOOL_TIME_CONSTANT_S: f64 = 0.025;

/// The spool position after a step of `dt_s` toward the commanded opening `target` from
/// `spool`: the exact solution of the first-order lag τ·ṡ = target − s over the step (so it
/// cannot overshoot the target for any step length).
pub fn spool_response(spool: f64, target: f64, dt_s: f64) -> f64 {
    let k = 1.0 - (-dt_s / SPOOL_TIME_CONSTANT_S).exp();
    spool + k * (target - spool)
}
