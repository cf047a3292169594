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

/// ∂p/∂q (length n), written into `grad`: ∂p/∂qᵢ = −2xᵢDᵢ·Π_{j≠i}(1 − xⱼ²), computed without
/// division so it stays finite at the limits.
pub fn jlm_gradient(model: &Model, q: &[f64], grad: &mut [f64]) {
    let n = model.dof();
    for i in 0..n {
        let ji = &model.joints[i];
        let Some(xi) = normalized(ji.limits[0], ji.limits[1], q[i]) else {
            grad[i] = 0.0;
            continue;
        };
        if 1.0 - xi * xi <= 0.0 {
            grad[i] = 0.0; // clamped factor: flat outside the limits
            continue;
        }
        let di = 2.0 / (ji.limits[1] - ji.limits[0]);
        let others: f64 = (0..n)
            .filter(|&k| k != i)
            .filter_map(|k| normalized(model.joints[k].limits[0], model.joints[k].limits[1], q[k]))
            .map(|x| (1.0 - x * x).max(0.0))
            .product();
        grad[i] = -2.0 * xi * di * others;
    }
}
