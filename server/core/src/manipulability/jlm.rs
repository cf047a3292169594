//! Joint-limit measure (Jun 2008 eqs 11–16) and its gradient.

use crate::model::Model;

/// Normalised joint coordinate xᵢ = Dᵢqᵢ + xᵢ⁰ ∈ [−1, 1] (Jun eqs 12–15); `None` for an
/// unlimited joint, which does not enter the measure.
pub fn normalized(lo: f64, hi: f64, q: f64) -> Option<f64> {
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    let d = 2.0 / (hi - lo); // eq. 13
    let x0 = -(hi + lo) / (hi - lo); // eq. 14
    Some(d * q + x0)
}

/// JLM p = Π(1 − xᵢ²) (Jun eq. 16). Each factor is clamped at 0, so a joint at or beyond its
/// limit gives 0 (the paper's reading: "goes to zero when one of the joints approaches its
/// limit"). Unlimited joints contribute a factor 1.
pub fn jlm(model: &Model, q: &[f64]) -> f64 {
    model
        .joints
        .iter()
        .zip(q)
        .filter_map(|(j, &qi)| normalized(j.limits[0], j.limits[1], qi))
        .map(|x| (1.0 - x * x).max(0.0))
        .product()
}

/// Factor 1 − xᵢ² of joint i in the JLM, clamped at 0 (1 for an unlimited joint).
fn factor(lo: f64, hi: f64, q: f64) -> f64 {
    normalized(lo, hi, q).map_or(1.0, |x| (1.0 - x * x).max(0.0))
}

/// ∂p/∂q (length n), written into `grad`: ∂p/∂qᵢ = −2xᵢDᵢ·Π_{j≠i}(1 − xⱼ²), computed without
/// division so it stays finite at the limits (the products of the other factors from a
/// prefix and a suffix pass: O(n)).
pub fn jlm_gradient(model: &Model, q: &[f64], grad: &mut [f64]) {
    let n = model.dof();
    // First pass: grad[i] = Π_{j>i} fⱼ.
    let mut suffix = 1.0;
    for i in (0..n).rev() {
        grad[i] = suffix;
        let [lo, hi] = model.joints[i].limits;
        suffix *= factor(lo, hi, q[i]);
    }
    // Second pass: times Π_{j<i} fⱼ, times −2xᵢDᵢ.
    let mut prefix = 1.0;
    for i in 0..n {
        let [lo, hi] = model.joints[i].limits;
        let others = prefix * grad[i];
        grad[i] = match normalized(lo, hi, q[i]) {
            // Clamped factor: flat outside the limits.
            Some(xi) if 1.0 - xi * xi > 0.0 => -2.0 * xi * (2.0 / (hi - lo)) * others,
            _ => 0.0, // unlimited, or at/beyond a limit
        };
        prefix *= factor(lo, hi, q[i]);
    }
}
