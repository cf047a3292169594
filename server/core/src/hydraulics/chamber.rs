//! One backward-Euler step of an actuator's two chamber pressures (Lim eqs 3.49–3.50, 3.56)
//! with relief flow, piston leakage and the cavitation floor: each chamber solved exactly in
//! its own pressure (closed forms where the orifice is turbulent, safeguarded Newton in the
//! laminar band and above relief).

use super::valve::valve_flow;
use super::{ActuatorParams, HydraulicParams};

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

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::hydraulics::{JawParams, Linkage, N_ACT};

    /// A hydraulic system with six identical rotary actuators (test data).
    pub(in crate::hydraulics) fn params() -> HydraulicParams {
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
}
