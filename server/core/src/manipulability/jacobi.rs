//! One-sided Jacobi SVD (Hestenes 1958) for the small dense Jacobians of the analysis.
//!
//! Plane rotations are applied to pairs of vectors (the columns of J, or its rows when J is
//! wide) until every pair is orthogonal to working precision. The rotations accumulate into
//! the orthogonal factor on that side, the vector lengths are the singular values and the
//! normalised vectors are the other factor. Unlike the eigenvalues of JᵀJ, which carry an
//! absolute error of order ε·σ₁², this gives every σ with a small *relative* error whenever
//! J is well conditioned up to a diagonal scaling of its vectors (Demmel & Veselić 1992,
//! "Jacobi's method is more accurate than QR", SIAM J. Matrix Anal. Appl. 13(4), §4), and it
//! needs no bidiagonalisation, no eigen solve and no heap storage for the sizes used here.
//! Rotation formulas: Golub & Van Loan, *Matrix Computations* (4th ed.) §8.6.3 and §8.6.4;
//! stopping rule and sweep limit: LAPACK `dgesvj` (Drmač & Veselić 2008).

/// Scratch capacity (entries) kept on the stack; larger problems use the heap.
pub(crate) const STACK: usize = 64;

/// Sweep limit (as `dgesvj`); a 6×6 Jacobian typically needs 5–7 sweeps.
const MAX_SWEEPS: usize = 30;

/// Rotates the `k` vectors of length `l` stored one after another in `a` (vector p is
/// `a[p·l..(p+1)·l]`) until every pair satisfies |aₚ·a_q| ≤ √l·ε·‖aₚ‖‖a_q‖ (`dgesvj`'s
/// stopping rule). The same rotations are applied to the columns of `w` (k×k column-major,
/// the identity on entry), so that A_in·W = A_out. Returns the number of sweeps run, the
/// last one being the sweep that found nothing left to rotate.
///
/// The entries of `a` should be scaled to at most about 1 in magnitude (see [`scale_pow2`])
/// so that the squared norms can neither overflow nor underflow needlessly.
pub(crate) fn orthogonalize(a: &mut [f64], l: usize, w: &mut [f64], k: usize) -> usize {
    assert!(a.len() == k * l && w.len() == k * k, "orthogonalize: sizes");
    // Monomorphised copies for the analysis's shapes (6×6 Jacobian, 3×6 row selections):
    // with the lengths known the loops unroll and vectorise.
    match (k, l) {
        (6, 6) => sweeps::<6>(a, 6, w),
        (3, 6) => sweeps::<3>(a, 6, w),
        (6, 7) => sweeps::<6>(a, 7, w),
        _ => sweeps_dyn(a, l, w, k),
    }
}

fn sweeps<const K: usize>(a: &mut [f64], l: usize, w: &mut [f64]) -> usize {
    match l {
        6 => sweeps_impl(&mut a[..K * 6], 6, &mut w[..K * K], K),
        7 => sweeps_impl(&mut a[..K * 7], 7, &mut w[..K * K], K),
        _ => sweeps_impl(a, l, w, K),
    }
}

fn sweeps_dyn(a: &mut [f64], l: usize, w: &mut [f64], k: usize) -> usize {
    sweeps_impl(a, l, w, k)
}

#[inline(always)]
fn sweeps_impl(a: &mut [f64], l: usize, w: &mut [f64], k: usize) -> usize {
    let tol = (l as f64).sqrt() * f64::EPSILON;
    // Squared norms dₚ = ‖aₚ‖², recomputed at the start of every sweep and updated through
    // a rotation as α − tγ, β + tγ (exact in exact arithmetic; GVL §8.6.4); recomputed
    // whenever that update cancels (as LAPACK dgesvj does), so each dₚ stays correct to
    // about 10⁴ε relative, which is all the angle and the stopping test need. The σ
    // themselves are taken from the final vectors by the caller.
    let mut d_stack = [0.0; 16];
    let mut d_heap;
    let d: &mut [f64] = if k <= 16 {
        &mut d_stack[..k]
    } else {
        d_heap = vec![0.0; k];
        &mut d_heap
    };
    for sweep in 1..=MAX_SWEEPS {
        let mut rotated = false;
        for (dp, v) in d.iter_mut().zip(a.chunks_exact(l)) {
            *dp = dot(v, v);
        }
        for q in 1..k {
            let (head, tail) = a.split_at_mut(q * l);
            let y = &mut tail[..l];
            for p in 0..q {
                let x = &mut head[p * l..(p + 1) * l];
                let (alpha, beta) = (d[p], d[q]);
                let gamma = dot(x, y);
                // Also skips zero vectors (γ = 0).
                if gamma.abs() <= tol * (alpha * beta).sqrt() {
                    continue;
                }
                rotated = true;
                // GVL Algorithm 8.5.1 (symmetric Schur 2×2) on [[α, γ], [γ, β]]: t is the
                // smaller root of t² + 2ζt − 1 = 0, so the rotation angle is ≤ π/4.
                let zeta = (beta - alpha) / (2.0 * gamma);
                let t = if zeta.abs() < 1e150 {
                    zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt())
                } else {
                    0.5 / zeta
                };
                let c = 1.0 / (1.0 + t * t).sqrt();
                let s = c * t;
                rotate(x, y, c, s);
                let (wh, wt) = w.split_at_mut(q * k);
                rotate(&mut wh[p * k..(p + 1) * k], &mut wt[..k], c, s);
                let (new_p, new_q) = (alpha - t * gamma, beta + t * gamma);
                d[p] = if new_p < 1e-4 * alpha {
                    dot(x, x)
                } else {
                    new_p
                };
                d[q] = if new_q < 1e-4 * beta {
                    dot(y, y)
                } else {
                    new_q
                };
            }
        }
        if !rotated {
            return sweep;
        }
    }
    MAX_SWEEPS
}

/// x·y.
#[inline(always)]
fn dot(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).map(|(a, b)| a * b).sum()
}

/// x ← c·x − s·y, y ← s·x + c·y.
#[inline(always)]
fn rotate(x: &mut [f64], y: &mut [f64], c: f64, s: f64) {
    for (xi, yi) in x.iter_mut().zip(y.iter_mut()) {
        let (a, b) = (*xi, *yi);
        *xi = c * a - s * b;
        *yi = s * a + c * b;
    }
}

/// Multiplies `x` by a power of two 2ᵉ with 2ᵉ·max|x| in [0.5, 1) and returns 2⁻ᵉ, the
/// factor that undoes it (1 for an all-zero input; e is clamped for subnormal or
/// near-overflow maxima). Scaling by a power of two is exact, and it keeps the squared norms
/// of [`orthogonalize`] clear of overflow and underflow for every finite input.
pub(crate) fn scale_pow2(x: &mut [f64]) -> f64 {
    let max = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if max == 0.0 || !max.is_finite() {
        return 1.0;
    }
    // max = f·2^e with f in [1, 2); scale by 2^-(e+1), built from its bits.
    let e = (((max.to_bits() >> 52) & 0x7ff) as i64 - 1023).clamp(-1000, 1020);
    let scale = f64::from_bits(((1023 - (e + 1)) as u64) << 52);
    for v in x.iter_mut() {
        *v *= scale;
    }
    f64::from_bits(((1023 + (e + 1)) as u64) << 52)
}

/// Euclidean norms of the `k` vectors of length `l` in `a`, written to `out`.
pub(crate) fn norms(a: &[f64], l: usize, out: &mut [f64]) {
    for (o, v) in out.iter_mut().zip(a.chunks_exact(l)) {
        *o = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    }
}

/// Sorts `sigma` (k entries) descending, moving vector p of `a` (length l) and column p of
/// `w` (k×k) along with it. Selection sort: k is at most a handful.
pub(crate) fn sort_descending(sigma: &mut [f64], a: &mut [f64], l: usize, w: &mut [f64]) {
    let k = sigma.len();
    for p in 0..k {
        let mut best = p;
        for q in p + 1..k {
            if sigma[q] > sigma[best] {
                best = q;
            }
        }
        if best != p {
            sigma.swap(p, best);
            swap_blocks(a, l, p, best);
            swap_blocks(w, k, p, best);
        }
    }
}

/// Swaps blocks p < q of length `len` in `x`.
fn swap_blocks(x: &mut [f64], len: usize, p: usize, q: usize) {
    let (head, tail) = x.split_at_mut(q * len);
    head[p * len..(p + 1) * len].swap_with_slice(&mut tail[..len]);
}

/// Completes the `r` orthonormal leading columns of the l×l column-major `q` to an orthogonal
/// matrix by Gram–Schmidt on unit vectors. For each new column the unit vector eᵢ with the
/// largest residual (the row of the current basis with the smallest norm) is taken, so the
/// residual norm is at least √((l − c)/l) ≥ 1/√l before normalisation; the projection is done
/// twice ("twice is enough": Giraud, Langou & Rozložník 2005), which keeps QᵀQ = I to
/// working precision.
pub(crate) fn complete_columns(q: &mut [f64], l: usize, r: usize) {
    debug_assert_eq!(q.len(), l * l);
    for c in r..l {
        // Row norms² of the first c columns: ‖Qᵀeᵢ‖².
        let mut best = 0;
        let mut best_norm = f64::INFINITY;
        for i in 0..l {
            let s: f64 = (0..c).map(|j| q[j * l + i] * q[j * l + i]).sum();
            if s < best_norm {
                best_norm = s;
                best = i;
            }
        }
        let (done, rest) = q.split_at_mut(c * l);
        let x = &mut rest[..l];
        x.fill(0.0);
        x[best] = 1.0;
        for _ in 0..2 {
            for basis in done.chunks_exact(l) {
                let d: f64 = basis.iter().zip(x.iter()).map(|(b, v)| b * v).sum();
                for (v, b) in x.iter_mut().zip(basis) {
                    *v -= d * b;
                }
            }
        }
        let norm = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        for v in x.iter_mut() {
            *v /= norm;
        }
    }
}
