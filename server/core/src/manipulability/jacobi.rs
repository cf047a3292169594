//! One-sided Jacobi SVD (Hestenes 1958) for the small dense Jacobians of the analysis.
//!
//! Plane rotations are applied to pairs of vectors (the columns of J, or its rows when J is
//! wide) until every pair is orthogonal to working precision. The rotations accumulate into
//! the orthogonal factor on that side, the vector lengths are the singular values and the
//! normalised vectors are the other factor.
//!
//! # Why a hand-written SVD
//! The measures that matter near a singular posture — condition number σ₁/σₘ, isotropy,
//! Hong's index, force manipulability 1/Πσ, the rank and the null space — all hinge on the
//! *smallest* singular values, and those are what the library routes get wrong first:
//! * The eigenvalues of JJᵀ (the analysis's earlier route) carry an absolute error of about
//!   ε·σ₁², so every σ below √ε·σ₁ ≈ 10⁻⁸σ₁ is round-off — only a factor 10 under the rank
//!   tolerance of 1.5·10⁻⁷σ₁ (`measures::RANK_TOLERANCE`): the reported rank, condition
//!   number and force measures of a near-singular posture would be noise.
//! * A bidiagonalising SVD (Golub–Kahan, as nalgebra's) is backward stable: its error is
//!   about ε·σ₁ for every σ, so a σ near ε·σ₁ has no correct digit.
//! * One-sided Jacobi gives every σ with a small *relative* error whenever J is well
//!   conditioned up to a diagonal scaling of its vectors (Demmel & Veselić 1992, "Jacobi's
//!   method is more accurate than QR", SIAM J. Matrix Anal. Appl. 13(4), §4) — a Jacobian
//!   whose columns have very different scales (short and long levers, prismatic next to
//!   revolute joints), or one approaching a singularity along one direction.
//!   `tests/jacobi_svd.rs` checks it: for J = Q·D (Q orthogonal, D diagonal down to 2⁻⁶⁰)
//!   every σ to 10⁻¹³ of itself, however small, by both the columns and the rows route; for
//!   the planar 2R arm next to its stretched-out singularity (|q₂| down to 10⁻¹²) σ₂ to
//!   2ε·σ₁ of the closed form l₁l₂|sin q₂|/σ₁ (Lim eq. 2.27), where the eigenvalue route
//!   erred by about 10⁻⁸σ₁.
//!
//! It is also the fastest of the three at these sizes: no bidiagonalisation, no eigen solve,
//! no heap storage up to 7×7 (`benches/analysis.rs` times it against both nalgebra routes).
//!
//! # Mechanism
//! Rotation formulas: Golub & Van Loan, *Matrix Computations* (4th ed.) §8.5.2 (Algorithm
//! 8.5.1, symmetric Schur) and §8.6.3–8.6.4 (one-sided Jacobi, orderings); stopping rule,
//! sweep limit, norm updates with their safeguard and the early stop: LAPACK `dgesvj`
//! (Drmač & Veselić 2008). The pair orderings are chosen for instruction-level parallelism:
//! round-robin for an even number of vectors (Brent & Luk 1985), and independent problems
//! swept in lockstep. One sweep driver ([`sweep_until_quiet`]) and one rotation
//! ([`rotation`], [`updated_norm`]) serve two storage forms of the vectors:
//! * fixed-size, zero-padded lane arrays ([`Lanes`]) for the shapes of the 6- and 7-joint
//!   analysis ([`decompose_fixed`]), where every Jacobi step is straight-line code on packed
//!   pairs; and
//! * slices for every other shape ([`Slices`]).
//!
//! The fixed-size form was kept when one generic slice path measured too slow for the
//! analysis budget (≤ 5 µs for a 6-DOF arm): with vectors in zero-padded blocks of six, it
//! took 1.7× the instructions of the 6×6 `full_svd`, 1.9× those of the translational/
//! rotational pair and 1.57–1.58× those of the whole magnum and RX90 analyses (callgrind,
//! `examples/analysis_loop`), 1.3–1.5× the wall-clock time, taking the RX90's 4.2 µs of
//! then to about 5.5 µs. On the portable build the RX90 analysis now takes about 2.7 µs
//! (docs/speed.md), so the generic path alone would likely meet the budget: dropping the
//! fixed-size form is an open simplification, to be decided by `cargo bench --bench analysis`.
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
/// stored one after another in `a` (g = `sigma.len()`/`groups`; vector p is
/// `a[p·l..(p+1)·l]`). Each group is first scaled with [`scale_pow2`], then its vectors are
/// rotated until mutually orthogonal ([`sweep_until_quiet`]); on return `a` holds the
/// rotated (scaled) vectors. For group G and i < g, `sigma[G·g + i]` is the length of vector
/// G·g + `order[G·g + i]` of the rotated `a` (in the input's units), descending within the
/// group, and column i of the G-th g×g column-major block of `w` is the matching column of
/// that group's accumulated rotations.
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
    assert!(
        g * groups == k && a.len() == k * l && w.len() == groups * g * g,
        "jacobi::decompose: sizes"
    );
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
    with_scratch(groups * g * g + 2 * k + groups, |scratch: &mut [f64]| {
        let (rot, rest) = scratch.split_at_mut(groups * g * g);
        let (d, rest) = rest.split_at_mut(k);
        let (lengths, unscale) = rest.split_at_mut(k);
        for (u, block) in unscale.iter_mut().zip(a.chunks_exact_mut(g * l)) {
            *u = scale_pow2(block);
        }
        for (p, col) in rot.chunks_exact_mut(g).enumerate() {
            col[p % g] = 1.0;
        }
        let mut problem = Slices {
            a: &mut *a,
            l,
            w: rot,
            d,
            g,
        };
        sweep_until_quiet(&mut problem, l, g * g.saturating_sub(1) / 2, |n| {
            sweep_pair(g, n)
        });
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

/// Vectors to orthogonalise, in groups of g: [`sweep_until_quiet`] refreshes their squared
/// norms and rotates pairs (p, q) of every group.
trait Sweep {
    /// Recomputes every squared norm dₚ = ‖aₚ‖² from its vector.
    fn refresh_norms(&mut self);
    /// One Jacobi step ([`rotation`]) on vectors p < q of every group, in lockstep; whether
    /// any rotated.
    fn rotate_pairs(&mut self, p: usize, q: usize, tol2: f64) -> bool;
}

/// Rotates the vectors of `problem` (each of length l, scaled to at most about 1 in
/// magnitude by [`scale_pow2`] so that the squared norms can neither overflow nor underflow
/// needlessly), visiting the pairs of a sweep in the order `pair(0)`, …, `pair(n_pairs − 1)`,
/// until every pair within a group satisfies |aₚ·a_q| ≤ √l·ε·‖aₚ‖‖a_q‖ (`dgesvj`'s stopping
/// rule); the rotations accumulate as in [`decompose`]. Returns the number of sweeps run.
///
/// Several groups are swept in lockstep (pair (p, q) of every group, then the next pair) so
/// that their independent rotations overlap in the processor — the analysis's translational
/// and rotational rows are two 3-vector problems whose own pairs all depend on each other.
///
/// The stop need not wait for a sweep boundary: once every pair has been visited without a
/// rotation, no vector has changed since its pairs were found orthogonal (LAPACK dgesvj's
/// `notrot` count, Drmač & Veselić 2008, "New fast and accurate Jacobi SVD algorithm II",
/// SIAM J. Matrix Anal. Appl. 29(4), Algorithm 1), so the closing sweep is cut short at the
/// pair that last rotated. The squared norms are computed afresh only every other sweep: in
/// between, the updates α − tγ, β + tγ with their cancellation safeguard ([`updated_norm`])
/// carry them (dgesvj keeps its norms by such updates throughout; Drmač & Veselić 2008,
/// §3.2); they stay correct to about 10⁴ε relative, which is all the angle and the stopping
/// test need, and the σ themselves are taken from the final vectors.
fn sweep_until_quiet<S: Sweep>(
    problem: &mut S,
    l: usize,
    n_pairs: usize,
    pair: impl Fn(usize) -> (usize, usize),
) -> usize {
    // (√l·ε)², compared with γ²/(αβ) to avoid a square root per pair.
    let tol2 = (l as f64) * f64::EPSILON * f64::EPSILON;
    // Pair visits since the last rotation.
    let mut quiet = 0;
    for sweep in 1..=MAX_SWEEPS {
        if sweep % 2 == 1 {
            problem.refresh_norms();
        }
        for n in 0..n_pairs {
            let (p, q) = pair(n);
            quiet = if problem.rotate_pairs(p, q, tol2) {
                0
            } else {
                quiet + 1
            };
            if quiet == n_pairs {
                return sweep;
            }
        }
    }
    MAX_SWEEPS
}

/// The rotation of a Jacobi step on two vectors with squared norms α, β and product γ:
/// `None` when they already pass the stopping test γ² ≤ `tol2`·αβ (also for zero vectors,
/// γ = 0), else (c, s, t) = (cos θ, sin θ, tan θ).
///
/// θ diagonalises [[α, γ], [γ, β]] (GVL Algorithm 8.5.1): tan θ = t, the smaller root of
/// t² + 2ζt − 1 = 0 with ζ = (β − α)/2γ, so |θ| ≤ π/4. Written without ζ: with δ = β − α,
/// r = √(δ² + 4γ²), h = |δ| + r and g = 2γ·sign δ, t = g/h, cos θ = √(h/2r) and
/// sin θ = t·cos θ — one square root fewer on the critical path, and no overflow of ζ² when
/// γ ≪ |δ|.
fn rotation(alpha: f64, beta: f64, gamma: f64, tol2: f64) -> Option<(f64, f64, f64)> {
    if gamma * gamma <= tol2 * (alpha * beta) {
        return None;
    }
    let delta = beta - alpha;
    let r = (delta * delta + 4.0 * gamma * gamma).sqrt();
    if r == 0.0 {
        return None; // both vectors below the square root of the smallest normal
    }
    let h = delta.abs() + r;
    let t = 2.0 * gamma * 1f64.copysign(delta) / h;
    let c = (h / (2.0 * r)).sqrt();
    Some((c, t * c, t))
}

/// A squared norm `old` after the rotation, given its update `new` (α − tγ or β + tγ, exact
/// in exact arithmetic; GVL §8.6.4): `new`, or `fresh()` recomputed from the vector where
/// the update cancels (as LAPACK dgesvj does).
fn updated_norm(old: f64, new: f64, fresh: impl FnOnce() -> f64) -> f64 {
    if new < 1e-4 * old { fresh() } else { new }
}

/// The vectors in a slice (any shape): vector p is `a[p·l..(p+1)·l]`, the matching column of
/// the accumulated rotations `w[p·g..(p+1)·g]` (column p mod g of its group's g×g block), its
/// squared norm `d[p]`.
struct Slices<'a> {
    a: &'a mut [f64],
    l: usize,
    w: &'a mut [f64],
    d: &'a mut [f64],
    g: usize,
}

impl Sweep for Slices<'_> {
    fn refresh_norms(&mut self) {
        for (dp, v) in self.d.iter_mut().zip(self.a.chunks_exact(self.l)) {
            *dp = dot(v, v);
        }
    }

    fn rotate_pairs(&mut self, p: usize, q: usize, tol2: f64) -> bool {
        let (l, g) = (self.l, self.g);
        let mut rotated = false;
        for base in (0..self.d.len()).step_by(g) {
            let (p, q) = (base + p, base + q);
            let (head, tail) = self.a.split_at_mut(q * l);
            let (x, y) = (&mut head[p * l..(p + 1) * l], &mut tail[..l]);
            let (alpha, beta, gamma) = (self.d[p], self.d[q], dot(x, y));
            let Some((c, s, t)) = rotation(alpha, beta, gamma, tol2) else {
                continue;
            };
            rotate(x, y, c, s);
            let (wh, wt) = self.w.split_at_mut(q * g);
            rotate(&mut wh[p * g..(p + 1) * g], &mut wt[..g], c, s);
            self.d[p] = updated_norm(alpha, alpha - t * gamma, || dot(x, x));
            self.d[q] = updated_norm(beta, beta + t * gamma, || dot(y, y));
            rotated = true;
        }
        rotated
    }
}

/// A vector of up to 2·H entries stored as H lanes of two (zero-padded): the layout of an
/// SSE2 register, so that dot products and rotations map onto packed instructions.
type Lanes<const H: usize> = [[f64; 2]; H];

/// [`decompose`] for `N` groups of `G` vectors of length `L` ≤ 2·`H`, with rotation
/// accumulators of `G` ≤ 2·`HG` entries, all known at compile time, and the pair order
/// `pairs` (every p < q < G once). The vectors are copied into fixed-size zero-padded lane
/// arrays ([`Fixed`]) so that each Jacobi step is straight-line code: one pass for γ, the
/// two rotations as whole-array updates in packed pairs, no bounds checks inside a vector;
/// the dot products are summed in two interleaved partial sums. The zero padding stays zero
/// under every rotation.
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
    let mut problem = Fixed::<H, G, HG, N> {
        a: [[[[0.0; 2]; H]; G]; N],
        w: [[[[0.0; 2]; HG]; G]; N],
        d: [[0.0; G]; N],
    };
    let mut unscale = [1.0; N];
    for (((grp, block), u), r) in problem
        .a
        .iter_mut()
        .zip(a.chunks_exact_mut(G * L))
        .zip(unscale.iter_mut())
        .zip(problem.w.iter_mut())
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
    sweep_until_quiet(&mut problem, L, pairs.len(), |n| pairs[n]);
    let (v, rot) = (&problem.a, &problem.w);
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

/// The vectors in fixed-size storage: `a[grp][p]` is vector p of group grp, `w[grp][p]` the
/// matching column of its accumulated rotations, `d[grp][p]` its squared norm.
struct Fixed<const H: usize, const G: usize, const HG: usize, const N: usize> {
    a: [[Lanes<H>; G]; N],
    w: [[Lanes<HG>; G]; N],
    d: [[f64; G]; N],
}

impl<const H: usize, const G: usize, const HG: usize, const N: usize> Sweep for Fixed<H, G, HG, N> {
    fn refresh_norms(&mut self) {
        for (dg, ag) in self.d.iter_mut().zip(self.a.iter()) {
            for (dp, x) in dg.iter_mut().zip(ag) {
                *dp = dot_lanes(x, x);
            }
        }
    }

    /// The vectors and their accumulator columns are copied out, rotated in registers and
    /// stored back.
    fn rotate_pairs(&mut self, p: usize, q: usize, tol2: f64) -> bool {
        let mut rotated = false;
        for ((a, w), d) in self
            .a
            .iter_mut()
            .zip(self.w.iter_mut())
            .zip(self.d.iter_mut())
        {
            let (mut x, mut y) = (a[p], a[q]);
            let (alpha, beta, gamma) = (d[p], d[q], dot_lanes(&x, &y));
            let Some((c, s, t)) = rotation(alpha, beta, gamma, tol2) else {
                continue;
            };
            rotate_lanes(&mut x, &mut y, c, s);
            a[p] = x;
            a[q] = y;
            let (mut wx, mut wy) = (w[p], w[q]);
            rotate_lanes(&mut wx, &mut wy, c, s);
            w[p] = wx;
            w[q] = wy;
            d[p] = updated_norm(alpha, alpha - t * gamma, || dot_lanes(&x, &x));
            d[q] = updated_norm(beta, beta + t * gamma, || dot_lanes(&y, &y));
            rotated = true;
        }
        rotated
    }
}

/// x·y summed lane by lane (even and odd entries), then the two lanes.
fn dot_lanes<const H: usize>(x: &Lanes<H>, y: &Lanes<H>) -> f64 {
    let mut s = [0.0; 2];
    for (a, b) in x.iter().zip(y) {
        s[0] += a[0] * b[0];
        s[1] += a[1] * b[1];
    }
    s[0] + s[1]
}

/// x ← c·x − s·y, y ← s·x + c·y, lane by lane.
fn rotate_lanes<const H: usize>(x: &mut Lanes<H>, y: &mut Lanes<H>, c: f64, s: f64) {
    for (a, b) in x.iter_mut().zip(y.iter_mut()) {
        let (a0, a1, b0, b1) = (a[0], a[1], b[0], b[1]);
        *a = [c * a0 - s * b0, c * a1 - s * b1];
        *b = [s * a0 + c * b0, s * a1 + c * b1];
    }
}

/// The cyclic order for 3 vectors (every pair shares a vector with the previous one).
const CYCLIC_3: [(usize, usize); 3] = pair_table(3);

/// The 15 pairs (p < q) of the round-robin order for 6 vectors, round by round.
const ROUND_ROBIN_6: [(usize, usize); 15] = pair_table(6);

/// The first `P` pairs of [`sweep_pair`] for `g` vectors.
const fn pair_table<const P: usize>(g: usize) -> [(usize, usize); P] {
    let mut pairs = [(0, 0); P];
    let mut n = 0;
    while n < P {
        pairs[n] = sweep_pair(g, n);
        n += 1;
    }
    pairs
}

/// Pair n (p < q) of the sweep order for `g` vectors, n < g(g − 1)/2. For even g the
/// round-robin ("tournament") ordering (Brent & Luk 1985; GVL §8.6.4, parallel ordering):
/// each round of g/2 disjoint pairs has independent work, so the processor overlaps the long
/// square-root/division chain of one rotation with the next; every pair once per sweep, and
/// it converges as the cyclic order. For odd g (3 rows) the cyclic order by columns — every
/// pair shares a vector with the previous one anyway.
const fn sweep_pair(g: usize, n: usize) -> (usize, usize) {
    if g % 2 == 0 {
        let (round, seat) = (n / (g / 2), n % (g / 2));
        let (i, j) = (
            tournament_seat(seat, round, g),
            tournament_seat(g - 1 - seat, round, g),
        );
        if i < j { (i, j) } else { (j, i) }
    } else {
        // Column q holds the pairs q(q − 1)/2 … q(q + 1)/2 − 1.
        let mut q = 1;
        while q * (q + 1) / 2 <= n {
            q += 1;
        }
        (n - q * (q - 1) / 2, q)
    }
}

/// The player at seat `seat` in round `round` of a round-robin tournament of `players`
/// (even): player 0 stays at seat 0, the others move one seat along per round; seats s and
/// players − 1 − s play each other.
const fn tournament_seat(seat: usize, round: usize, players: usize) -> usize {
    if seat == 0 {
        0
    } else {
        1 + (seat - 1 + players - 1 - round) % (players - 1)
    }
}

/// x·y.
fn dot(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).map(|(a, b)| a * b).sum()
}

/// x ← c·x − s·y, y ← s·x + c·y.
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

    /// The sweep order visits each pair p < q exactly once per sweep; for an even number of
    /// vectors the pairs come in rounds of disjoint pairs (Brent & Luk 1985), for an odd one
    /// in the cyclic order by columns; the fixed tables are the same order.
    #[test]
    fn sweep_order_visits_every_pair_once_in_disjoint_rounds() {
        for g in 2usize..=9 {
            let pairs: Vec<(usize, usize)> =
                (0..g * (g - 1) / 2).map(|n| sweep_pair(g, n)).collect();
            let mut seen = vec![false; g * g];
            for &(p, q) in &pairs {
                assert!(p < q && q < g, "{g}: ({p}, {q})");
                assert!(!seen[p * g + q], "{g}: pair ({p}, {q}) twice");
                seen[p * g + q] = true;
            }
            if g % 2 == 0 {
                for round in pairs.chunks_exact(g / 2) {
                    let mut busy = vec![false; g];
                    for &(p, q) in round {
                        assert!(!busy[p] && !busy[q], "{g}: round {round:?} not disjoint");
                        busy[p] = true;
                        busy[q] = true;
                    }
                }
            } else {
                let cyclic: Vec<(usize, usize)> =
                    (1..g).flat_map(|q| (0..q).map(move |p| (p, q))).collect();
                assert_eq!(pairs, cyclic);
            }
            if g == 3 {
                assert_eq!(pairs, CYCLIC_3);
            }
            if g == 6 {
                assert_eq!(pairs, ROUND_ROBIN_6);
            }
        }
    }
}
