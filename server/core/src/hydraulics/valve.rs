//! The proportional valve's orifice law (Lim eq. 3.48), with a laminar band near ΔP = 0.

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
