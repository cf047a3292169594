//! The grasp matrices of two grasp points on one object (Lim §3.4.2, eqs 3.39–3.47): the
//! blocks Wⁱ, W = [W¹ W²], the equal-load-sharing W⁺, the internal-force basis V, the
//! object mobility seen at the grasp points, and the split of contact wrenches into external
//! and internal parts.

use nalgebra::{Matrix3, Matrix6, SMatrix, SVector, Vector3, Vector6};

use crate::dynamics::skew;

/// Wⁱ (6×6, eq. 3.40 block): maps the wrench at grasp point i (at r from the object COM, base
/// frame) to the wrench at the COM: [f; m + r×f]. Its transpose maps the object twist to the
/// grasp point twist.
pub fn grasp_block(r: &Vector3<f64>) -> Matrix6<f64> {
    let mut w = Matrix6::identity();
    w.fixed_view_mut::<3, 3>(3, 0).copy_from(&skew(r));
    w
}

/// Wⁱᵀ·t: the velocity of grasp point i (at r from the COM) for the object twist
/// t = [v; ω]: [v + ω×r; ω] — [`grasp_block`] transposed, applied without forming it.
#[inline]
pub fn grasp_point_twist(r: &Vector3<f64>, t: &Vector6<f64>) -> Vector6<f64> {
    let w = Vector3::new(t[3], t[4], t[5]);
    let v = Vector3::new(t[0], t[1], t[2]) + w.cross(r);
    Vector6::new(v.x, v.y, v.z, w.x, w.y, w.z)
}

/// Wⁱ·F: the wrench at the COM of wrench F = [f; m] applied at grasp point i: [f; m + r×f] —
/// [`grasp_block`] applied without forming it.
#[inline]
pub fn wrench_at_com(r: &Vector3<f64>, f: &Vector6<f64>) -> Vector6<f64> {
    let fl = Vector3::new(f[0], f[1], f[2]);
    let m = Vector3::new(f[3], f[4], f[5]) + r.cross(&fl);
    Vector6::new(fl.x, fl.y, fl.z, m.x, m.y, m.z)
}

/// The moment-free share of an object wrench `fext` = [F; M] (at the COM, world) between
/// grasp points `r` (from the COM): contact wrenches [fⁱ; mⁱ] with W¹F¹ + W²F² = F_ext
/// (eq. 3.40) that carry the load by forces wherever two points can. With the midpoint
/// c = (r¹ + r²)/2, d = r¹ − r², M′ = M − c × F: fⁱ = F/2 ± g with g = (M′ × d)/|d|² (so
/// d × g is M′'s part across d), and mⁱ = ½·(M′·d)·d/|d|², the part about the line through
/// the grasp points, which forces there cannot make. Lim's equal share W⁺ (eq. 3.46) instead
/// gives mⁱ = M/2 − rⁱ × F/2: for a 50 kg box held by handles 0.3 m apart, ±37 N·m each
/// about the handles' line, an internal moment the jaws must hold against each other (the
/// "virtual linkage" of Williams & Khatib 1993 makes the same point about internal loads).
/// Coincident grasp points (|d| ≈ 0) split F and M′ equally.
pub fn moment_free_share(r: &[Vector3<f64>; 2], fext: &Vector6<f64>) -> [Vector6<f64>; 2] {
    let f = Vector3::new(fext[0], fext[1], fext[2]);
    let c = 0.5 * (r[0] + r[1]);
    let d = r[0] - r[1];
    let mp = Vector3::new(fext[3], fext[4], fext[5]) - c.cross(&f);
    let dd = d.norm_squared();
    let (g, m) = if dd > 1e-12 {
        (mp.cross(&d) / dd, d * (0.5 * mp.dot(&d) / dd))
    } else {
        (Vector3::zeros(), 0.5 * mp)
    };
    let one = |s: f64| {
        let fi = 0.5 * f + s * g;
        Vector6::new(fi.x, fi.y, fi.z, m.x, m.y, m.z)
    };
    [one(1.0), one(-1.0)]
}

/// Wⁱᵀ·M⁻¹·Wᵏ (6×6) for the object mobility M⁻¹ = diag(1/m·I, Q) (Q = world inverse inertia,
/// symmetric),
/// in 3×3 blocks with Sⁱ = \[rⁱ\]×: [[1/m·I − SⁱQSᵏ, −SⁱQ], [QSᵏ, Q]].
pub fn mobility_block(
    ri: &Vector3<f64>,
    rk: &Vector3<f64>,
    inv_mass: f64,
    q: &Matrix3<f64>,
) -> Matrix6<f64> {
    // Products with a skew matrix as cross products, column by column: Sᵏ·Q has columns
    // rᵏ × Q_j, and Q·Sᵏ = −(Sᵏ·Q)ᵀ because Q is symmetric; Sⁱ·(Q·Sᵏ) has columns
    // rⁱ × (Q·Sᵏ)_j.
    let cross_cols = |r: &Vector3<f64>, m: &Matrix3<f64>| {
        Matrix3::from_columns(&[
            r.cross(&m.column(0).into_owned()),
            r.cross(&m.column(1).into_owned()),
            r.cross(&m.column(2).into_owned()),
        ])
    };
    let siq = cross_cols(ri, q);
    let qsk = if ri == rk {
        -siq.transpose()
    } else {
        -cross_cols(rk, q).transpose()
    };
    let si_qsk = cross_cols(ri, &qsk);
    let mut b = Matrix6::zeros();
    b.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(Matrix3::identity() * inv_mass - si_qsk));
    b.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-siq));
    b.fixed_view_mut::<3, 3>(3, 0).copy_from(&qsk);
    b.fixed_view_mut::<3, 3>(3, 3).copy_from(q);
    b
}

/// Wⁱᵀ·X·Wᵏ (6×6) for a general symmetric object mobility X = [[A, B], [Bᵀ, D]] (3×3
/// blocks; e.g. the inverse of the mass matrix with the seabed dashpots added), with
/// Sⁱ = \[rⁱ\]×: X·Wᵏ = [[A + B·Sᵏ, B], [Bᵀ + D·Sᵏ, D]], then Wⁱᵀ = [[I, −Sⁱ], [0, I]] on the
/// left. [`mobility_block`] is the case B = 0, A = I/m.
pub fn mobility_block_general(
    ri: &Vector3<f64>,
    rk: &Vector3<f64>,
    x: &Matrix6<f64>,
) -> Matrix6<f64> {
    mobility_general_impl(ri, rk, x, false)
}

/// Wᵀ·X·W for one grasp point (W = Wⁱ = Wᵏ, [`mobility_block_general`]), lower triangle
/// only: the part above the diagonal is left zero, as [`crate::linalg::gram_lower`] does
/// (the factorizations read no more). It skips the upper block B − S·D and three entries of
/// the upper left block.
pub fn mobility_block_general_lower(r: &Vector3<f64>, x: &Matrix6<f64>) -> Matrix6<f64> {
    mobility_general_impl(r, r, x, true)
}

/// [`mobility_block_general`], the lower triangle only if `lower`. Products with a skew
/// matrix as cross products: M·Sᵏ has rows mᵢ × rᵏ (mᵢᵀ·Sᵏ = (Sᵏᵀ·mᵢ)ᵀ = (mᵢ × rᵏ)ᵀ, for the
/// rows mᵢ of M) and Sⁱ·M columns rⁱ × m_j. Where the compiler inlines it with `lower` a
/// constant, the entries it does not store are never computed.
fn mobility_general_impl(
    ri: &Vector3<f64>,
    rk: &Vector3<f64>,
    x: &Matrix6<f64>,
    lower: bool,
) -> Matrix6<f64> {
    let a: Matrix3<f64> = x.fixed_view::<3, 3>(0, 0).into_owned();
    let b: Matrix3<f64> = x.fixed_view::<3, 3>(0, 3).into_owned();
    let d: Matrix3<f64> = x.fixed_view::<3, 3>(3, 3).into_owned();
    let times_sk = |m: &Matrix3<f64>| {
        Matrix3::from_rows(&[
            m.row(0).transpose().cross(rk).transpose(),
            m.row(1).transpose().cross(rk).transpose(),
            m.row(2).transpose().cross(rk).transpose(),
        ])
    };
    let si_times = |m: &Matrix3<f64>| {
        Matrix3::from_columns(&[
            ri.cross(&m.column(0)),
            ri.cross(&m.column(1)),
            ri.cross(&m.column(2)),
        ])
    };
    let bottom_left = b.transpose() + times_sk(&d);
    let top_left = a + times_sk(&b) - si_times(&bottom_left);
    let mut out = Matrix6::zeros();
    if lower {
        for j in 0..3 {
            for i in j..3 {
                out[(i, j)] = top_left[(i, j)];
                out[(i + 3, j + 3)] = d[(i, j)];
            }
        }
    } else {
        out.fixed_view_mut::<3, 3>(0, 0).copy_from(&top_left);
        out.fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&(b - si_times(&d)));
        out.fixed_view_mut::<3, 3>(3, 3).copy_from(&d);
    }
    out.fixed_view_mut::<3, 3>(3, 0).copy_from(&bottom_left);
    out
}

/// W = [W¹ W²] (6×12, eq. 3.40) for grasp points at r¹, r² from the COM.
pub fn grasp_matrix(r: &[Vector3<f64>; 2]) -> SMatrix<f64, 6, 12> {
    let mut w = SMatrix::<f64, 6, 12>::zeros();
    w.fixed_view_mut::<6, 6>(0, 0)
        .copy_from(&grasp_block(&r[0]));
    w.fixed_view_mut::<6, 6>(0, 6)
        .copy_from(&grasp_block(&r[1]));
    w
}

/// W⁺ for equal load sharing (12×6, eq. 3.46): ½[I 0; −Rⁱ I] per arm, Rⁱ = \[rⁱ\]×.
/// W·W⁺ = I.
pub fn grasp_pinv_equal_share(r: &[Vector3<f64>; 2]) -> SMatrix<f64, 12, 6> {
    arm_blocks(r, [0.5, 0.5])
}

/// V (12×6, eq. 3.47) with aⁱ = 2(−1)ⁱ/(N − (−1)ⁱ(1 − (−1)ᴺ)/2): for N = 2, a¹ = −1, a² = 1;
/// blocks aⁱ[I 0; −Rⁱ I]. W·V = 0.
pub fn internal_basis(r: &[Vector3<f64>; 2]) -> SMatrix<f64, 12, 6> {
    let n = 2.0_f64;
    let a = |i: i32| {
        let s = (-1.0_f64).powi(i);
        2.0 * s / (n - s * (1.0 - (-1.0_f64).powi(2)) / 2.0)
    };
    arm_blocks(r, [a(1), a(2)])
}

/// The 12×6 matrix of the two arms' blocks cⁱ[I 0; −Rⁱ I] (Rⁱ = \[rⁱ\]×) stacked, the shape
/// of both W⁺ (eq. 3.46) and V (eq. 3.47).
fn arm_blocks(r: &[Vector3<f64>; 2], c: [f64; 2]) -> SMatrix<f64, 12, 6> {
    let mut out = SMatrix::<f64, 12, 6>::zeros();
    for (k, (ri, ck)) in r.iter().zip(c).enumerate() {
        let mut b = Matrix6::identity();
        b.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-skew(ri)));
        out.fixed_view_mut::<6, 6>(6 * k, 0).copy_from(&(b * ck));
    }
    out
}

/// External wrench W·F_c (6) and internal wrench F_int (6) with F_c = W⁺F_ext + V·F_int
/// (eq. 3.41), F_int = V⁺(I − W⁺W)F_c (least squares; exact since (I − W⁺W)F_c lies in the
/// range of V).
pub fn decompose(r: &[Vector3<f64>; 2], fc: &SVector<f64, 12>) -> (Vector6<f64>, Vector6<f64>) {
    let w = grasp_matrix(r);
    let wp = grasp_pinv_equal_share(r);
    let v = internal_basis(r);
    let fext = w * fc;
    let rest = fc - wp * fext;
    let vtv = v.transpose() * v;
    let fint = match crate::linalg::Ldlt::factor(&vtv) {
        Some(ch) => ch.solve(&(v.transpose() * rest)),
        None => Vector6::zeros(),
    };
    (fext, fint)
}

/// F_int of [`decompose`] for two grasps without forming W, W⁺ or V (the step computes it every
/// millisecond). With ρ = (I − W⁺W)F_c, ρⁱ = aⁱBⁱF_int for V's blocks aⁱBⁱ (eq. 3.47:
/// a¹ = −1, a² = 1, Bⁱ = [I 0; −Rⁱ I], Bⁱ⁻¹ = [I 0; Rⁱ I]); ρ lies in the range of V, so
/// F_int = ½(B²⁻¹ρ² − B¹⁻¹ρ¹) exactly, the mean of the two arms' readings.
pub fn internal_wrench(r: &[Vector3<f64>; 2], fc: &[Vector6<f64>; 2]) -> Vector6<f64> {
    let f = |i: usize| Vector3::new(fc[i][0], fc[i][1], fc[i][2]);
    let m = |i: usize| Vector3::new(fc[i][3], fc[i][4], fc[i][5]);
    // External wrench at the COM (eq. 3.40) and each arm's equal share of it (eq. 3.46).
    let fe = f(0) + f(1);
    let me = m(0) + m(1) + r[0].cross(&f(0)) + r[1].cross(&f(1));
    let mut out = Vector6::zeros();
    for (i, sign) in [(0, -0.5), (1, 0.5)] {
        let rho_f = f(i) - fe * 0.5;
        let rho_m = m(i) - (me - r[i].cross(&fe)) * 0.5;
        let b_inv_m = rho_m + r[i].cross(&rho_f);
        out += Vector6::new(rho_f.x, rho_f.y, rho_f.z, b_inv_m.x, b_inv_m.y, b_inv_m.z) * sign;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The moment-free share reproduces the object wrench through W (eq. 3.40), leaves the
    /// jaws only the moment about the grasp points' line, and carries a weight hung midway
    /// between two handles by equal vertical forces alone (where Lim's W⁺, eq. 3.46, puts
    /// ∓r × F/2 on each jaw).
    #[test]
    fn moment_free_share_balances_and_keeps_moments_on_the_line() {
        let r = [
            Vector3::new(0.02, 0.15, 0.13),
            Vector3::new(-0.01, -0.15, 0.12),
        ];
        let fext = Vector6::new(30.0, -20.0, 490.0, 12.0, -7.0, 5.0);
        let s = moment_free_share(&r, &fext);
        let back = wrench_at_com(&r[0], &s[0]) + wrench_at_com(&r[1], &s[1]);
        assert!((back - fext).norm() < 1e-9, "{back} vs {fext}");
        let d = r[0] - r[1];
        for si in &s {
            let m = Vector3::new(si[3], si[4], si[5]);
            assert!(
                m.cross(&d).norm() < 1e-9 * (1.0 + m.norm()),
                "moment off the line: {m}"
            );
        }
        // A weight midway below two handles: 245 N up each, no moments.
        let r = [
            Vector3::new(0.0, 0.15, 0.13),
            Vector3::new(0.0, -0.15, 0.13),
        ];
        let s = moment_free_share(&r, &Vector6::new(0.0, 0.0, 490.0, 0.0, 0.0, 0.0));
        for si in &s {
            assert!((si - Vector6::new(0.0, 0.0, 245.0, 0.0, 0.0, 0.0)).norm() < 1e-9);
        }
        let w = grasp_pinv_equal_share(&r) * Vector6::new(0.0, 0.0, 490.0, 0.0, 0.0, 0.0);
        assert!((w[3].abs() - 0.15 * 245.0).abs() < 1e-9, "W⁺ gives {w}");
    }
}
