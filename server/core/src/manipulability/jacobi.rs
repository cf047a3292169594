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
//!
//! Rotation formulas: Golub & Van Loan, *Matrix Computations* (4th ed.) §8.5.2 (Algorithm
//! 8.5.1, symmetric Schur) and §8.6.3–8.6.4 (one-sided Jacobi, orderings); stopping rule,
//! sweep limit and the norm-update safeguard: LAPACK `dgesvj` (Drmač & Veselić 2008). The
//! pair orderings are chosen for instruction-level parallelism: round-robin for an even
//! number of vectors (Brent & Luk 1985), and independent problems swept in lockstep.
//!
//! Vectors shorter than about 10⁻⁶⁰ of the longest are beyond the reach of the squared
//! norms and products in the stopping test and count as zero (see `full_svd`).

/// Scratch capacity (entries) kept on the stack; larger problems use the heap. 64 covers
/// every shape up to 7×7 (k·l vectors; k² rotations plus k norms).
const STACK: usize = 64;

/// Runs `f` on `len` zeroed scratch entries: on the stack when `len` ≤ [`STACK`].
pub(crate) fn with_scratch<T: Copy + Default, R>(len: usize, f: impl FnOnce(&mut [T]) -> R) -> R {
    if len <= STACK {
        f(&mut [T::default(); STACK][..len])
    } else {
        f(&mut vec![T::default(); len])
    }
}

/// One-sided Jacobi SVD of `groups` independent problems of g vectors of length `l` each,
/// stored one after another in `a` (g = `sigma.len()`/`groups`; see [`orthogonalize`]; each
/// group is first scaled with [`scale_pow2`]). On return, for group G and i < g,
/// `sigma[G·g + i]` is the length of vector G·g + `order[G·g + i]` of the rotated `a` (in the
/// input's units), descending within the group, and column i of the G-th g×g column-major
/// block of `w` is the matching column of that group's accumulated rotations.
pub(crate) fn decompose(
    a: &mut [f64],
    l: usize,
    groups: usize,
    w: &mut [f64],
    sigma: &mut [f64],
    order: &mut [usize],
) {
    let k = sigma.len();
    let g = k / groups;
    assert!(g * groups == k && a.len() == k * l && w.len() == groups * g * g);
    // Fixed-size copies for the analysis's shapes (6×6 Jacobian columns, 3×6 row
    // selections alone or as the translational/rotational pair, and the same for 7 joints).
    match (g, l, groups) {
        (6, 6, 1) => return decompose_fixed::<6, 3, 6, 3, 1>(a, w, sigma, order, &ROUND_ROBIN_6),
        (6, 7, 1) => return decompose_fixed::<7, 4, 6, 3, 1>(a, w, sigma, order, &ROUND_ROBIN_6),
        (3, 6, 1) => return decompose_fixed::<6, 3, 3, 2, 1>(a, w, sigma, order, &CYCLIC_3),
        (3, 6, 2) => return decompose_fixed::<6, 3, 3, 2, 2>(a, w, sigma, order, &CYCLIC_3),
        (3, 7, 1) => return decompose_fixed::<7, 4, 3, 2, 1>(a, w, sigma, order, &CYCLIC_3),
        (3, 7, 2) => return decompose_fixed::<7, 4, 3, 2, 2>(a, w, sigma, order, &CYCLIC_3),
        _ => {}
    }
    let mut unscale = [1.0; 2];
    let mut unscale_heap;
    let unscale: &mut [f64] = if groups <= 2 {
        &mut unscale[..groups]
    } else {
        unscale_heap = vec![1.0; groups];
        &mut unscale_heap
    };
    for (u, block) in unscale.iter_mut().zip(a.chunks_exact_mut(g * l)) {
        *u = scale_pow2(block);
    }
    with_scratch(groups * g * g + k, |scratch: &mut [f64]| {
        let (rot, lengths) = scratch.split_at_mut(groups * g * g);
        for block in rot.chunks_exact_mut(g * g) {
            for i in 0..g {
                block[i * g + i] = 1.0;
            }
        }
        orthogonalize(a, l, groups, rot, k);
        for (n, v) in lengths.iter_mut().zip(a.chunks_exact(l)) {
            *n = dot(v, v).sqrt();
        }
        for grp in 0..groups {
            let len = &lengths[grp * g..(grp + 1) * g];
            let ord = &mut order[grp * g..(grp + 1) * g];
            order_descending(len, ord);
            let (src, dst) = (&rot[grp * g * g..], &mut w[grp * g * g..]);
            for (i, &o) in ord.iter().enumerate() {
                sigma[grp * g + i] = len[o] * unscale[grp];
                dst[i * g..(i + 1) * g].copy_from_slice(&src[o * g..(o + 1) * g]);
            }
        }
    });
}

/// Sweep limit (as `dgesvj`); a 6×6 Jacobian typically needs 5–7 sweeps.
const MAX_SWEEPS: usize = 30;

/// Rotates the `k` vectors of length `l` stored one after another in `a` (vector p is
/// `a[p·l..(p+1)·l]`), which form `groups` independent problems of g = k/`groups`
/// consecutive vectors, until every pair within a group satisfies
/// |aₚ·a_q| ≤ √l·ε·‖aₚ‖‖a_q‖ (`dgesvj`'s stopping rule). The same rotations are applied to
/// the columns of `w` (`groups` g×g column-major blocks, identities on entry), so that
/// A_in·W = A_out group by group. Returns the number of sweeps run, the last one being the
/// sweep that found nothing left to rotate.
///
/// Several groups are swept in lockstep (pair (p, q) of every group, then the next pair) so
/// that their independent rotations overlap in the processor — the analysis's translational
/// and rotational rows are two 3-vector problems whose own pairs all depend on each other.
///
/// The entries of `a` should be scaled to at most about 1 in magnitude (see [`scale_pow2`])
/// so that the squared norms can neither overflow nor underflow needlessly.
pub(crate) fn orthogonalize(
    a: &mut [f64],
    l: usize,
    groups: usize,
    w: &mut [f64],
    k: usize,
) -> usize {
    let g = k / groups;
    assert!(
        g * groups == k && a.len() == k * l && w.len() == groups * g * g,
        "orthogonalize: sizes"
    );
    // (The analysis's shapes take the fixed-size route of `decompose_fixed` instead.)
    sweeps_impl(a, l, groups, w, g)
}

/// [`orthogonalize`] for `groups` groups of `g` vectors.
fn sweeps_impl(a: &mut [f64], l: usize, groups: usize, w: &mut [f64], g: usize) -> usize {
    let k = groups * g;
    // (√l·ε)², compared with γ²/(αβ) to avoid a square root per pair.
    let tol2 = (l as f64) * f64::EPSILON * f64::EPSILON;
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
        if g == 6 {
            // The 6-vector tournament from a table (the seat arithmetic below, at compile time).
            for &(p, q) in &ROUND_ROBIN_6 {
                rotated |= step(a, l, groups, w, g, d, tol2, p, q);
            }
        } else if g % 2 == 0 {
            // Round-robin ("tournament") ordering (Brent & Luk 1985; GVL §8.6.4, parallel
            // ordering): each round rotates g/2 disjoint pairs, whose work is independent,
            // so the processor overlaps the long square-root/division chain of one rotation
            // with the next. Every pair once per sweep; it converges as the cyclic order.
            for round in 0..g - 1 {
                for seat in 0..g / 2 {
                    let (i, j) = (
                        tournament_seat(seat, round, g),
                        tournament_seat(g - 1 - seat, round, g),
                    );
                    rotated |= step(a, l, groups, w, g, d, tol2, i.min(j), i.max(j));
                }
            }
        } else {
            // Odd g (3 rows): every pair shares a vector with the previous one anyway.
            for q in 1..g {
                for p in 0..q {
                    rotated |= step(a, l, groups, w, g, d, tol2, p, q);
                }
            }
        }
        if !rotated {
            return sweep;
        }
    }
    MAX_SWEEPS
}

/// Pair (p, q), p < q, of every group (see [`sweeps_impl`]); whether any rotated.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn step(
    a: &mut [f64],
    l: usize,
    groups: usize,
    w: &mut [f64],
    g: usize,
    d: &mut [f64],
    tol2: f64,
    p: usize,
    q: usize,
) -> bool {
    let mut rotated = false;
    for grp in 0..groups {
        let base = grp * g;
        let (head, tail) = a.split_at_mut((base + q) * l);
        let y = &mut tail[..l];
        let x = &mut head[(base + p) * l..(base + p + 1) * l];
        let block = &mut w[grp * g * g..(grp + 1) * g * g];
        let (wh, wt) = block.split_at_mut(q * g);
        let (wx, wy) = (&mut wh[p * g..(p + 1) * g], &mut wt[..g]);
        let (dh, dt) = d.split_at_mut(base + q);
        rotated |= rotate_pair(x, y, wx, wy, &mut dh[base + p], &mut dt[0], tol2);
    }
    rotated
}

/// One Jacobi step on the vectors x, y with squared norms `dx`, `dy` (updated), applying
/// the rotation also to the accumulator columns `wx`, `wy`; returns whether it rotated.
#[inline(always)]
fn rotate_pair(
    x: &mut [f64],
    y: &mut [f64],
    wx: &mut [f64],
    wy: &mut [f64],
    dx: &mut f64,
    dy: &mut f64,
    tol2: f64,
) -> bool {
    let (alpha, beta) = (*dx, *dy);
    let gamma = dot(x, y);
    // Also skips zero vectors (γ = 0).
    if gamma * gamma <= tol2 * (alpha * beta) {
        return false;
    }
    // The rotation diagonalising [[α, γ], [γ, β]] (GVL Algorithm 8.5.1): tan θ = t, the
    // smaller root of t² + 2ζt − 1 = 0 with ζ = (β − α)/2γ, so |θ| ≤ π/4. Written without ζ:
    // with δ = β − α, r = √(δ² + 4γ²), h = |δ| + r and g = 2γ·sign δ, t = g/h,
    // cos θ = √(h/2r) and sin θ = t·cos θ — one square root fewer on the critical path, and
    // no overflow of ζ² when γ ≪ |δ|.
    let delta = beta - alpha;
    let r = (delta * delta + 4.0 * gamma * gamma).sqrt();
    if r == 0.0 {
        return false; // both vectors below the square root of the smallest normal
    }
    let h = delta.abs() + r;
    let t = 2.0 * gamma * 1f64.copysign(delta) / h;
    let c = (h / (2.0 * r)).sqrt();
    let s = t * c;
    rotate(x, y, c, s);
    rotate(wx, wy, c, s);
    let (new_x, new_y) = (alpha - t * gamma, beta + t * gamma);
    *dx = if new_x < 1e-4 * alpha {
        dot(x, x)
    } else {
        new_x
    };
    *dy = if new_y < 1e-4 * beta {
        dot(y, y)
    } else {
        new_y
    };
    true
}

/// A vector of up to 2·H entries stored as H lanes of two (zero-padded): the layout of an
/// SSE2 register, so that dot products and rotations map onto packed instructions.
type Lanes<const H: usize> = [[f64; 2]; H];

/// [`decompose`] for `N` groups of `G` vectors of length `L` ≤ 2·`H`, with rotation
/// accumulators of `G` ≤ 2·`HG` entries, all known at compile time, and the pair order
/// `pairs` (every p < q < G once). The vectors are copied into fixed-size zero-padded lane
/// arrays ([`Lanes`]) so that each Jacobi step ([`pair_fixed`]) is straight-line code: one
/// pass for γ, the two rotations as whole-array updates in packed pairs, no bounds checks
/// inside a vector. Same rotations, pair test and norm updates as [`sweeps_impl`], except
/// that [`sweeps_fixed`] stops mid-sweep once every pair has passed the test in a row and
/// refreshes the squared norms only every other sweep; the dot products are summed in two
/// interleaved partial sums. The zero padding stays zero under every rotation.
fn decompose_fixed<
    const L: usize,
    const H: usize,
    const G: usize,
    const HG: usize,
    const N: usize,
>(
    a: &mut [f64],
    w: &mut [f64],
    sigma: &mut [f64],
    order: &mut [usize],
    pairs: &[(usize, usize)],
) {
    debug_assert!(L <= 2 * H && G <= 2 * HG);
    let mut v = [[[[0.0; 2]; H]; G]; N];
    let mut rot = [[[[0.0; 2]; HG]; G]; N];
    let mut unscale = [1.0; N];
    for (((grp, block), u), r) in v
        .iter_mut()
        .zip(a.chunks_exact_mut(G * L))
        .zip(unscale.iter_mut())
        .zip(rot.iter_mut())
    {
        *u = scale_pow2(block);
        for (col, src) in grp.iter_mut().zip(block.chunks_exact(L)) {
            for (i, &x) in src.iter().enumerate() {
                col[i / 2][i % 2] = x;
            }
        }
        for (i, c) in r.iter_mut().enumerate() {
            c[i / 2][i % 2] = 1.0;
        }
    }
    sweeps_fixed::<L, H, G, HG, N>(&mut v, &mut rot, pairs);
    for grp in 0..N {
        let mut len = [0.0; G];
        for (n, x) in len.iter_mut().zip(&v[grp]) {
            *n = dot_lanes(x, x).sqrt();
        }
        let ord = &mut order[grp * G..(grp + 1) * G];
        order_descending(&len, ord);
        let dst = &mut w[grp * G * G..(grp + 1) * G * G];
        for ((i, &o), d) in ord.iter().enumerate().zip(dst.chunks_exact_mut(G)) {
            sigma[grp * G + i] = len[o] * unscale[grp];
            for (k, x) in d.iter_mut().enumerate() {
                *x = rot[grp][o][k / 2][k % 2];
            }
        }
        for (dst, src) in a[grp * G * L..(grp + 1) * G * L]
            .chunks_exact_mut(L)
            .zip(&v[grp])
        {
            for (i, x) in dst.iter_mut().enumerate() {
                *x = src[i / 2][i % 2];
            }
        }
    }
}

/// [`sweeps_impl`] on fixed-size storage: `a[grp][p]` is vector p of group grp, `w[grp][p]`
/// the matching column of its accumulated rotations. Returns the number of sweeps run.
fn sweeps_fixed<const L: usize, const H: usize, const G: usize, const HG: usize, const N: usize>(
    a: &mut [[Lanes<H>; G]; N],
    w: &mut [[Lanes<HG>; G]; N],
    pairs: &[(usize, usize)],
) -> usize {
    // (√l·ε)², compared with γ²/(αβ) (dgesvj's stopping rule, as `sweeps_impl`).
    let tol2 = (L as f64) * f64::EPSILON * f64::EPSILON;
    let mut d = [[0.0; G]; N];
    // Pair visits since the last rotation: once every pair has been visited without a
    // rotation, no vector has changed since its pairs were found orthogonal, so the stop
    // need not wait for a sweep boundary (LAPACK dgesvj's `notrot` count, Drmač & Veselić
    // 2008, "New fast and accurate Jacobi SVD algorithm II", SIAM J. Matrix Anal. Appl.
    // 29(4), Algorithm 1): the closing sweep is cut short at the pair that last rotated.
    let mut quiet = 0;
    for sweep in 1..=MAX_SWEEPS {
        // Squared norms afresh only every other sweep: in between, the updates α − tγ,
        // β + tγ with their cancellation safeguard carry them (dgesvj keeps its norms by
        // such updates throughout; Drmač & Veselić 2008, §3.2).
        if sweep % 2 == 1 {
            for (dg, ag) in d.iter_mut().zip(a.iter()) {
                for (dp, x) in dg.iter_mut().zip(ag) {
                    *dp = dot_lanes(x, x);
                }
            }
        }
        for &(p, q) in pairs {
            // Lockstep over the groups (see `orthogonalize`).
            let mut rotated = false;
            for ((ag, wg), dg) in a.iter_mut().zip(w.iter_mut()).zip(d.iter_mut()) {
                rotated |= pair_fixed(ag, wg, dg, p, q, tol2);
            }
            quiet = if rotated { 0 } else { quiet + 1 };
            if quiet == pairs.len() {
                return sweep;
            }
        }
    }
    MAX_SWEEPS
}

/// [`rotate_pair`] on vectors p < q of fixed-size storage: the vectors and their
/// accumulator columns are copied out, rotated in registers and stored back.
#[inline(always)]
fn pair_fixed<const H: usize, const G: usize, const HG: usize>(
    a: &mut [Lanes<H>; G],
    w: &mut [Lanes<HG>; G],
    d: &mut [f64; G],
    p: usize,
    q: usize,
    tol2: f64,
) -> bool {
    let (mut x, mut y) = (a[p], a[q]);
    let (alpha, beta) = (d[p], d[q]);
    let gamma = dot_lanes(&x, &y);
    // Also skips zero vectors (γ = 0).
    if gamma * gamma <= tol2 * (alpha * beta) {
        return false;
    }
    // The rotation diagonalising [[α, γ], [γ, β]] (GVL Algorithm 8.5.1), as `rotate_pair`.
    let delta = beta - alpha;
    let r = (delta * delta + 4.0 * gamma * gamma).sqrt();
    if r == 0.0 {
        return false;
    }
    let h = delta.abs() + r;
    let t = 2.0 * gamma * 1f64.copysign(delta) / h;
    let c = (h / (2.0 * r)).sqrt();
    let s = t * c;
    rotate_lanes(&mut x, &mut y, c, s);
    a[p] = x;
    a[q] = y;
    let (mut wx, mut wy) = (w[p], w[q]);
    rotate_lanes(&mut wx, &mut wy, c, s);
    w[p] = wx;
    w[q] = wy;
    // Norm updates α − tγ, β + tγ, recomputed where they cancel (dgesvj; see `sweeps_impl`).
    let (new_x, new_y) = (alpha - t * gamma, beta + t * gamma);
    d[p] = if new_x < 1e-4 * alpha {
        dot_lanes(&x, &x)
    } else {
        new_x
    };
    d[q] = if new_y < 1e-4 * beta {
        dot_lanes(&y, &y)
    } else {
        new_y
    };
    true
}

/// x·y summed lane by lane (even and odd entries), then the two lanes.
#[inline(always)]
fn dot_lanes<const H: usize>(x: &Lanes<H>, y: &Lanes<H>) -> f64 {
    let mut s = [0.0; 2];
    for (a, b) in x.iter().zip(y) {
        s[0] += a[0] * b[0];
        s[1] += a[1] * b[1];
    }
    s[0] + s[1]
}

/// x ← c·x − s·y, y ← s·x + c·y, lane by lane.
#[inline(always)]
fn rotate_lanes<const H: usize>(x: &mut Lanes<H>, y: &mut Lanes<H>, c: f64, s: f64) {
    for (a, b) in x.iter_mut().zip(y.iter_mut()) {
        let (a0, a1, b0, b1) = (a[0], a[1], b[0], b[1]);
        *a = [c * a0 - s * b0, c * a1 - s * b1];
        *b = [s * a0 + c * b0, s * a1 + c * b1];
    }
}

/// The cyclic order for 3 vectors (every pair shares a vector with the previous one).
const CYCLIC_3: [(usize, usize); 3] = [(0, 1), (0, 2), (1, 2)];

/// The 15 pairs (p < q) of the round-robin order for 6 vectors, round by round.
const ROUND_ROBIN_6: [(usize, usize); 15] = {
    let mut pairs = [(0, 0); 15];
    let mut n = 0;
    let mut round = 0;
    while round < 5 {
        let mut seat = 0;
        while seat < 3 {
            let (i, j) = (
                tournament_seat(seat, round, 6),
                tournament_seat(5 - seat, round, 6),
            );
            pairs[n] = if i < j { (i, j) } else { (j, i) };
            n += 1;
            seat += 1;
        }
        round += 1;
    }
    pairs
};

/// The player at seat `seat` in round `round` of a round-robin tournament of `players`
/// (even): player 0 stays at seat 0, the others move one seat along per round; seats s and
/// players − 1 − s play each other.
#[inline(always)]
const fn tournament_seat(seat: usize, round: usize, players: usize) -> usize {
    if seat == 0 {
        0
    } else {
        1 + (seat - 1 + players - 1 - round) % (players - 1)
    }
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

/// `ord` = the indices 0..len.len() ordered by decreasing `len` (stable insertion sort;
/// a group holds a handful of columns).
fn order_descending(len: &[f64], ord: &mut [usize]) {
    for i in 0..len.len() {
        let mut j = i;
        while j > 0 && len[ord[j - 1]] < len[i] {
            ord[j] = ord[j - 1];
            j -= 1;
        }
        ord[j] = i;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every sweep order visits each pair p < q exactly once, and a round-robin round's
    /// pairs are disjoint (Brent & Luk 1985).
    #[test]
    fn round_robin_visits_every_pair_once_in_disjoint_rounds() {
        for players in [2usize, 4, 6, 8] {
            let mut seen = vec![false; players * players];
            for round in 0..players - 1 {
                let mut busy = vec![false; players];
                for seat in 0..players / 2 {
                    let (i, j) = (
                        tournament_seat(seat, round, players),
                        tournament_seat(players - 1 - seat, round, players),
                    );
                    let (p, q) = (i.min(j), i.max(j));
                    assert!(p < q && q < players);
                    assert!(!busy[p] && !busy[q], "round {round} not disjoint");
                    busy[p] = true;
                    busy[q] = true;
                    assert!(!seen[p * players + q], "pair ({p}, {q}) twice");
                    seen[p * players + q] = true;
                }
            }
            let pairs = seen.iter().filter(|&&x| x).count();
            assert_eq!(pairs, players * (players - 1) / 2);
        }
        let mut seen = [false; 36];
        for (n, &(p, q)) in ROUND_ROBIN_6.iter().enumerate() {
            assert!(p < q && q < 6 && !seen[p * 6 + q]);
            seen[p * 6 + q] = true;
            // Rounds of three disjoint pairs.
            let round = &ROUND_ROBIN_6[n / 3 * 3..n / 3 * 3 + 3];
            let count = round
                .iter()
                .filter(|&&(a, b)| a == p || b == p || a == q || b == q);
            assert_eq!(count.count(), 1);
        }
    }
}
