//! The object, its contact with the seabed, grasp detection and the grasp matrices
//! (Lim §3.4.2, eqs 3.39–3.47).
//!
//! Wrench convention: a contact wrench F_c^i = [f; m] (6: force N, moment N·m, base frame) is
//! what end-effector i exerts on the object at its grasp point. The object twist is
//! [v; ω] of its centre of mass, base frame.
//!
//! * [`ObjectParams`]: the 50 kg box with two handles, its seabed contact.
//! * [`grasp_block`], [`grasp_matrix`], [`grasp_pinv_equal_share`], [`internal_basis`]:
//!   W = [W¹ W²] (eq. 3.40), the equal-load-sharing W⁺ (eq. 3.46) and V (eq. 3.47).
//! * [`decompose`]: external and internal force/torque of a pair of contact wrenches.
//! * [`GraspState`]: the colour code of Lim §4.1.

use nalgebra::{Isometry3, Matrix3, Matrix6, SMatrix, SVector, Vector3, Vector6};
use serde::{Deserialize, Serialize};

use crate::dynamics::skew;

/// The object and its environment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectParams {
    /// Mass (kg): 50 (Lim §4.2.2, "an object which is 50 kg").
    pub mass_kg: f64,
    /// Box size x, y, z (m): 0.30 × 0.40 × 0.20 (assumed; mean density ≈ 2 080 kg/m³).
    pub size_m: Vector3<f64>,
    /// Handle grasp points in the object frame (m): bars 3 cm above the top face at y = ±0.15
    /// that the jaws close on, one per arm (index 0: left arm at +y, 1: right arm). Assumed.
    pub handles_m: [Vector3<f64>; 2],
    /// Handle bar thickness the jaw closes on (m): 0.04 (< 7.5 cm jaw opening).
    pub handle_width_m: f64,
    /// Contact (capture) radius (m) around a handle within which the tool point touches it:
    /// 0.04. Stands in for the thesis's collision detection of jaw and object meshes.
    pub capture_radius_m: f64,
    /// Seabed height (m, base frame z).
    pub seabed_z_m: f64,
    /// Initial pose of the object frame (at its centre of mass), resting on the seabed.
    pub initial_pose: Isometry3<f64>,
    /// Seabed contact stiffness per bottom corner (N/m): 2·10⁶ (stiff sediment-free rock/
    /// steel plate; settles 0.06 mm under 50 kg).
    pub contact_stiffness_n_m: f64,
    /// Seabed contact damping per corner (N·s/m): 2·10⁴ (about critical for 50 kg on 4 corners).
    pub contact_damping_n_s_m: f64,
    /// Seabed Coulomb friction coefficient: 0.5.
    pub friction: f64,
    /// Friction regularization speed (m/s): 0.01 (μN·v/√(v²+ε²)).
    pub friction_speed_m_s: f64,
}

impl ObjectParams {
    /// The case-study object: 50 kg box centred at (x, y), resting on the seabed at `seabed_z`.
    pub fn case_study_box(x: f64, y: f64, seabed_z: f64) -> ObjectParams {
        let size = Vector3::new(0.30, 0.40, 0.20);
        ObjectParams {
            mass_kg: 50.0,
            size_m: size,
            handles_m: [
                Vector3::new(0.0, 0.15, 0.5 * size.z + 0.03),
                Vector3::new(0.0, -0.15, 0.5 * size.z + 0.03),
            ],
            handle_width_m: 0.04,
            capture_radius_m: 0.04,
            seabed_z_m: seabed_z,
            initial_pose: Isometry3::translation(x, y, seabed_z + 0.5 * size.z),
            contact_stiffness_n_m: 2.0e6,
            contact_damping_n_s_m: 2.0e4,
            friction: 0.5,
            friction_speed_m_s: 0.01,
        }
    }

    /// Inertia about the centre of mass, object axes (kg·m²): solid box.
    pub fn inertia_body(&self) -> Matrix3<f64> {
        Matrix3::from_diagonal(&self.principal_inertia())
    }

    /// The principal moments of inertia about the centre of mass (kg·m²), along the object
    /// axes: the diagonal of [`Self::inertia_body`] (a box's axes are its principal axes).
    pub fn principal_inertia(&self) -> Vector3<f64> {
        let (x, y, z) = (self.size_m.x, self.size_m.y, self.size_m.z);
        let k = self.mass_kg / 12.0;
        Vector3::new(
            k * (y * y + z * z),
            k * (x * x + z * z),
            k * (x * x + y * y),
        )
    }

    /// The eight box corners in the object frame.
    pub fn corners(&self) -> [Vector3<f64>; 8] {
        let h = self.size_m * 0.5;
        let mut out = [Vector3::zeros(); 8];
        for (k, c) in out.iter_mut().enumerate() {
            *c = Vector3::new(
                if k & 1 == 0 { -h.x } else { h.x },
                if k & 2 == 0 { -h.y } else { h.y },
                if k & 4 == 0 { -h.z } else { h.z },
            );
        }
        out
    }
}

/// The seabed's push on the object at one instant (see [`seabed_contact`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeabedContact {
    /// Wrench on the object (force; moment about the COM), world frame.
    pub wrench: Vector6<f64>,
    /// Total normal force (N).
    pub normal_n: f64,
    /// The wrench's damping matrix C (6×6, symmetric positive semidefinite): the wrench
    /// falls by C·δt for a change δt = [δv; δω] of the object twist — the dashpots of the
    /// touching corners, normal and (regularized) friction. `None` when nothing touches.
    pub damping: Option<Matrix6<f64>>,
}

/// Seabed contact wrench on the object (6: force, moment about the COM; base frame) from
/// penalty springs at the box corners that are below the seabed, with regularized Coulomb
/// friction. Returns the wrench and the total normal force (N).
pub fn seabed_wrench(
    p: &ObjectParams,
    pose: &Isometry3<f64>,
    v: &Vector3<f64>,
    w: &Vector3<f64>,
) -> (Vector6<f64>, f64) {
    let c = seabed_contact_impl(p, pose, v, w, false);
    (c.wrench, c.normal_n)
}

/// [`seabed_wrench`] with its damping matrix, for an integrator that treats the dashpots
/// implicitly. A corner's velocity along a direction d is a_dᵀ·[v; ω] with a_d = [d; r × d]
/// (r from the COM), and a force f·d there is the wrench a_d·f, so a dashpot of coefficient
/// c adds c·a_d·a_dᵀ. The normal dashpot is the contact damping while the corner pushes
/// (f_n > 0); friction −μ·f_n·v_t/√(|v_t|²+ε²) is a dashpot of coefficient μ·f_n/√(|v_t|²+ε²)
/// along both seabed axes (its secant, exact at v_t = 0).
pub fn seabed_contact(
    p: &ObjectParams,
    pose: &Isometry3<f64>,
    v: &Vector3<f64>,
    w: &Vector3<f64>,
) -> SeabedContact {
    seabed_contact_impl(p, pose, v, w, true)
}

/// The running sums of the seabed dashpots' damping matrix C = Σ_corners Σ_d c_d·a_d·a_dᵀ
/// (a_d = [d; r × d], d = x, y with the friction coefficient c_t and z with the normal one
/// c_n; see [`seabed_contact`]) in closed form. With D = diag(c_t, c_t, c_n) and S = [r]×
/// (r × d = S·d), one corner adds [[D, D·Sᵀ], [S·D, S·D·Sᵀ]]: S·D has columns c_d·(r × d),
/// i.e. [[0, −c_t·r_z, c_n·r_y], [c_t·r_z, 0, −c_n·r_x], [−c_t·r_y, c_t·r_x, 0]], and
/// S·D·Sᵀ = Σ_d c_d·(r × d)(r × d)ᵀ has the diagonal (c_t·r_z² + c_n·r_y²,
/// c_t·r_z² + c_n·r_x², c_t·(r_x² + r_y²)) and below it −c_n·r_x·r_y, −c_t·r_x·r_z,
/// −c_t·r_y·r_z. Only these sums are kept (14 numbers) instead of three rank-one updates of
/// the 6×6 matrix per corner; C is symmetric and assembled once.
#[derive(Debug, Clone, Copy, Default)]
struct DashpotSums {
    /// Σ c_t and Σ c_n.
    c_t: f64,
    c_n: f64,
    /// Σ c_t·r and Σ c_n·r.
    ct_r: Vector3<f64>,
    cn_r: Vector3<f64>,
    /// Σ c_t·r_z², Σ c_n·r_y², Σ c_n·r_x², Σ c_t·(r_x² + r_y²).
    ct_zz: f64,
    cn_yy: f64,
    cn_xx: f64,
    ct_xx_yy: f64,
    /// Σ c_n·r_x·r_y, Σ c_t·r_x·r_z, Σ c_t·r_y·r_z.
    cn_xy: f64,
    ct_xz: f64,
    ct_yz: f64,
}

impl DashpotSums {
    /// Adds the dashpots of one corner at r from the COM: c_t along the seabed's x and y,
    /// c_n along z.
    #[inline(always)]
    fn add(&mut self, r: &Vector3<f64>, c_t: f64, c_n: f64) {
        let tr = r * c_t;
        let nr = r * c_n;
        self.c_t += c_t;
        self.c_n += c_n;
        self.ct_r += tr;
        self.cn_r += nr;
        self.ct_zz += tr.z * r.z;
        self.cn_yy += nr.y * r.y;
        self.cn_xx += nr.x * r.x;
        self.ct_xx_yy += tr.x * r.x + tr.y * r.y;
        self.cn_xy += nr.x * r.y;
        self.ct_xz += tr.x * r.z;
        self.ct_yz += tr.y * r.z;
    }

    /// C = [[D, (S·D)ᵀ], [S·D, S·D·Sᵀ]] summed over the corners (both triangles).
    fn matrix(&self) -> Matrix6<f64> {
        let (t, n) = (&self.ct_r, &self.cn_r);
        let mut c = Matrix6::zeros();
        c[(0, 0)] = self.c_t;
        c[(1, 1)] = self.c_t;
        c[(2, 2)] = self.c_n;
        // Σ S·D (rows 3–5, columns 0–2) and its transpose.
        let sd = Matrix3::new(0.0, -t.z, n.y, t.z, 0.0, -n.x, -t.y, t.x, 0.0);
        c.fixed_view_mut::<3, 3>(3, 0).copy_from(&sd);
        c.fixed_view_mut::<3, 3>(0, 3).copy_from(&sd.transpose());
        // Σ S·D·Sᵀ.
        c[(3, 3)] = self.ct_zz + self.cn_yy;
        c[(4, 4)] = self.ct_zz + self.cn_xx;
        c[(5, 5)] = self.ct_xx_yy;
        for (i, j, x) in [
            (4, 3, -self.cn_xy),
            (5, 3, -self.ct_xz),
            (5, 4, -self.ct_yz),
        ] {
            c[(i, j)] = x;
            c[(j, i)] = x;
        }
        c
    }
}

#[inline]
fn seabed_contact_impl(
    p: &ObjectParams,
    pose: &Isometry3<f64>,
    v: &Vector3<f64>,
    w: &Vector3<f64>,
    with_damping: bool,
) -> SeabedContact {
    let mut f = Vector3::zeros();
    let mut m = Vector3::zeros();
    let mut normal = 0.0;
    // The box's half edges in the world frame, u_j = h_j·R_j (R's columns): the corner
    // (±h_x, ±h_y, ±h_z) of the object frame is at r = ±u_0 ± u_1 ± u_2 from the COM.
    let rot = pose.rotation.to_rotation_matrix();
    let h = p.size_m * 0.5;
    let u = [
        rot.matrix().column(0) * h.x,
        rot.matrix().column(1) * h.y,
        rot.matrix().column(2) * h.z,
    ];
    let z0 = pose.translation.vector.z;
    // Quick reject: the lowest corner, z_0 − Σ_j |u_j,z| (each sign chosen to go down), is
    // above the seabed — exactly the test of the loop below for every corner, so nothing
    // touches.
    if z0 - (u[0].z.abs() + u[1].z.abs() + u[2].z.abs()) > p.seabed_z_m {
        return SeabedContact {
            wrench: Vector6::zeros(),
            normal_n: 0.0,
            damping: None,
        };
    }
    let mut sums = DashpotSums::default();
    let mut touching = false;
    // The corners in the order of `ObjectParams::corners` (bit j of k set: +h_j).
    for k in 0..8 {
        let pick = |j: usize| if k & (1 << j) == 0 { -u[j] } else { u[j] };
        let r = pick(0) + pick(1) + pick(2);
        let pen = p.seabed_z_m - (z0 + r.z);
        if pen <= 0.0 {
            continue;
        }
        let vc = v + w.cross(&r);
        let fn_ = (p.contact_stiffness_n_m * pen - p.contact_damping_n_s_m * vc.z).max(0.0);
        let vt = Vector3::new(vc.x, vc.y, 0.0);
        let s = (vt.norm_squared() + p.friction_speed_m_s * p.friction_speed_m_s).sqrt();
        let c_t = p.friction * fn_ / s;
        let ft = -vt * c_t;
        let fc = Vector3::new(ft.x, ft.y, fn_);
        f += fc;
        m += r.cross(&fc);
        normal += fn_;
        if with_damping && fn_ > 0.0 {
            touching = true;
            sums.add(&r, c_t, p.contact_damping_n_s_m);
        }
    }
    SeabedContact {
        wrench: Vector6::new(f.x, f.y, f.z, m.x, m.y, m.z),
        normal_n: normal,
        damping: touching.then(|| sums.matrix()),
    }
}

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

/// Wⁱᵀ·M⁻¹·Wᵏ (6×6) for the object mobility M⁻¹ = diag(1/m·I, Q) (Q = world inverse inertia,
/// symmetric),
/// in 3×3 blocks with Sⁱ = [rⁱ]×: [[1/m·I − SⁱQSᵏ, −SⁱQ], [QSᵏ, Q]].
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
/// Sⁱ = [rⁱ]×: X·Wᵏ = [[A + B·Sᵏ, B], [Bᵀ + D·Sᵏ, D]], then Wⁱᵀ = [[I, −Sⁱ], [0, I]] on the
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
/// rows mᵢ of M) and Sⁱ·M columns rⁱ × m_j. Inlined with `lower` a constant, the entries it
/// does not store are never computed.
#[inline(always)]
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

/// W⁺ for equal load sharing (12×6, eq. 3.46): ½[I 0; −Rⁱ I] per arm, Rⁱ = [rⁱ]×.
/// W·W⁺ = I.
pub fn grasp_pinv_equal_share(r: &[Vector3<f64>; 2]) -> SMatrix<f64, 12, 6> {
    let mut p = SMatrix::<f64, 12, 6>::zeros();
    for (i, ri) in r.iter().enumerate() {
        let mut b = Matrix6::identity();
        b.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-skew(ri)));
        p.fixed_view_mut::<6, 6>(6 * i, 0).copy_from(&(b * 0.5));
    }
    p
}

/// V (12×6, eq. 3.47) with aⁱ = 2(−1)ⁱ/(N − (−1)ⁱ(1 − (−1)ᴺ)/2): for N = 2, a¹ = −1, a² = 1;
/// blocks aⁱ[I 0; −Rⁱ I]. W·V = 0.
pub fn internal_basis(r: &[Vector3<f64>; 2]) -> SMatrix<f64, 12, 6> {
    let n = 2.0_f64;
    let mut v = SMatrix::<f64, 12, 6>::zeros();
    for (k, ri) in r.iter().enumerate() {
        let i = (k + 1) as i32;
        let s = (-1.0_f64).powi(i);
        let a = 2.0 * s / (n - s * (1.0 - (-1.0_f64).powi(2)) / 2.0);
        let mut b = Matrix6::identity();
        b.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-skew(ri)));
        v.fixed_view_mut::<6, 6>(6 * k, 0).copy_from(&(b * a));
    }
    v
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

/// Grasp state, with the colour code of Lim §4.1 (Fig. 4-4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GraspState {
    /// No jaw holds the object.
    Free,
    /// One jaw holds it and it still touches the seabed (black).
    OneOnSurface,
    /// One jaw holds it clear of the seabed (light blue).
    OneLifted,
    /// One jaw holds it and the other arm touches it (red).
    OneHoldingOtherContact,
    /// Both jaws hold it (yellow).
    BothHolding,
}

impl GraspState {
    /// Snake-case name used in CSV and JSON.
    pub fn as_str(self) -> &'static str {
        match self {
            GraspState::Free => "free",
            GraspState::OneOnSurface => "one_on_surface",
            GraspState::OneLifted => "one_lifted",
            GraspState::OneHoldingOtherContact => "one_holding_other_contact",
            GraspState::BothHolding => "both_holding",
        }
    }

    /// Colour of the object in the GUI (Lim §4.1): "" (default colour), black, light blue, red, yellow.
    pub fn colour(self) -> &'static str {
        match self {
            GraspState::Free => "",
            GraspState::OneOnSurface => "black",
            GraspState::OneLifted => "lightblue",
            GraspState::OneHoldingOtherContact => "red",
            GraspState::BothHolding => "yellow",
        }
    }

    /// Classifies from per-arm holding/contact flags and seabed contact.
    pub fn classify(holding: [bool; 2], contact: [bool; 2], on_surface: bool) -> GraspState {
        match (holding[0], holding[1]) {
            (true, true) => GraspState::BothHolding,
            (false, false) => GraspState::Free,
            (h0, _) => {
                let other = if h0 { contact[1] } else { contact[0] };
                if other {
                    GraspState::OneHoldingOtherContact
                } else if on_surface {
                    GraspState::OneOnSurface
                } else {
                    GraspState::OneLifted
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    /// The damping matrix as it was formed before the closed form: three rank-one updates
    /// c_d·a_d·a_dᵀ, a_d = [d; r × d], per touching corner (the definition in
    /// [`seabed_contact`]'s documentation).
    fn rank_one_sum(corners: &[(Vector3<f64>, f64, f64)]) -> Matrix6<f64> {
        let mut c = Matrix6::zeros();
        for (r, c_t, c_n) in corners {
            for (axis, coef) in [
                (Vector3::x(), *c_t),
                (Vector3::y(), *c_t),
                (Vector3::z(), *c_n),
            ] {
                let rd = r.cross(&axis);
                let a = Vector6::new(axis.x, axis.y, axis.z, rd.x, rd.y, rd.z);
                c.ger(coef, &a, &a, 1.0);
            }
        }
        c
    }

    /// The seabed contact as it was computed before (quaternion-rotated corners, bounding
    /// sphere reject, rank-one damping updates), written plainly.
    fn seabed_contact_reference(
        p: &ObjectParams,
        pose: &Isometry3<f64>,
        v: &Vector3<f64>,
        w: &Vector3<f64>,
    ) -> SeabedContact {
        let mut f = Vector3::zeros();
        let mut m = Vector3::zeros();
        let mut normal = 0.0;
        let mut touching = Vec::new();
        for c in p.corners() {
            let r = pose.rotation * c;
            let pen = p.seabed_z_m - (pose.translation.vector.z + r.z);
            if pen <= 0.0 {
                continue;
            }
            let vc = v + w.cross(&r);
            let fn_ = (p.contact_stiffness_n_m * pen - p.contact_damping_n_s_m * vc.z).max(0.0);
            let vt = Vector3::new(vc.x, vc.y, 0.0);
            let s = (vt.norm_squared() + p.friction_speed_m_s.powi(2)).sqrt();
            let c_t = p.friction * fn_ / s;
            let fc = Vector3::new(-vt.x * c_t, -vt.y * c_t, fn_);
            f += fc;
            m += r.cross(&fc);
            normal += fn_;
            if fn_ > 0.0 {
                touching.push((r, c_t, p.contact_damping_n_s_m));
            }
        }
        SeabedContact {
            wrench: Vector6::new(f.x, f.y, f.z, m.x, m.y, m.z),
            normal_n: normal,
            damping: (!touching.is_empty()).then(|| rank_one_sum(&touching)),
        }
    }

    /// The closed-form sums give the matrix of the rank-one updates, for arbitrary corner
    /// positions and coefficients, one corner and several, and it is exactly symmetric.
    #[test]
    fn dashpot_sums_equal_rank_one_updates() {
        let corners: Vec<(Vector3<f64>, f64, f64)> = (0..6)
            .map(|k| {
                let t = k as f64;
                (
                    Vector3::new(
                        (1.3 * t).sin(),
                        (0.7 * t + 0.4).cos(),
                        (2.1 * t).sin() - 0.3,
                    ),
                    100.0 + 900.0 * (0.9 * t).sin().abs(),
                    2.0e4 * (1.0 + 0.1 * t),
                )
            })
            .collect();
        for n in 1..=corners.len() {
            let mut sums = DashpotSums::default();
            for (r, c_t, c_n) in &corners[..n] {
                sums.add(r, *c_t, *c_n);
            }
            let ours = sums.matrix();
            let reference = rank_one_sum(&corners[..n]);
            assert!(
                (ours - reference).abs().max() < 1e-12 * reference.abs().max(),
                "{n} corners: {ours} vs {reference}"
            );
            assert_eq!(ours, ours.transpose());
        }
    }

    /// `seabed_contact` agrees with the previous formulation to round-off in the wrench, the
    /// normal force and the damping matrix, over tilted, sliding and spinning poses at
    /// several depths — also just above the seabed, where the exact lowest-corner reject and
    /// the old bounding-sphere one must agree that nothing touches.
    #[test]
    fn seabed_contact_agrees_with_the_plain_formulation() {
        let p = ObjectParams::case_study_box(1.0, 0.5, -0.45);
        let mut touched = 0;
        let mut free = 0;
        for k in 0..200 {
            let t = k as f64;
            let rot = UnitQuaternion::from_euler_angles(
                0.6 * (0.37 * t).sin(),
                0.5 * (0.53 * t).cos(),
                3.0 * (0.11 * t).sin(),
            );
            let lowest = p
                .corners()
                .iter()
                .map(|c| (rot * c).z)
                .fold(f64::INFINITY, f64::min);
            // From 1 cm into the seabed to 5 mm above it.
            let depth = 0.01 - 0.015 * ((k % 20) as f64 / 19.0);
            let pose = Isometry3::from_parts(
                nalgebra::Translation3::new(1.0, 0.5, p.seabed_z_m - lowest - depth),
                rot,
            );
            let v = Vector3::new(0.05 * (0.3 * t).sin(), -0.04 * (0.7 * t).cos(), -0.02);
            let w = Vector3::new(0.2 * (0.2 * t).cos(), 0.1 * (0.9 * t).sin(), 0.3);
            let ours = seabed_contact(&p, &pose, &v, &w);
            let reference = seabed_contact_reference(&p, &pose, &v, &w);
            let scale = 1.0 + reference.wrench.norm();
            assert!(
                (ours.wrench - reference.wrench).norm() < 1e-9 * scale,
                "{k}: {} vs {}",
                ours.wrench,
                reference.wrench
            );
            assert!((ours.normal_n - reference.normal_n).abs() < 1e-9 * scale);
            assert_eq!(seabed_wrench(&p, &pose, &v, &w).0, ours.wrench);
            match (ours.damping, reference.damping) {
                (Some(a), Some(b)) => {
                    touched += 1;
                    assert!(
                        (a - b).abs().max() < 1e-10 * b.abs().max(),
                        "{k}: {a} vs {b}"
                    );
                }
                (None, None) => free += 1,
                (a, b) => panic!("{k}: {a:?} vs {b:?}"),
            }
        }
        // Both branches exercised.
        assert!(touched > 50 && free > 20, "{touched} touching, {free} free");
    }

    /// The exact reject: a box lifted just clear of the seabed on one corner is rejected
    /// before the corner loop although its bounding sphere still reaches into the seabed,
    /// and the same box lowered by 1 µm is not.
    #[test]
    fn lowest_corner_reject_is_exact() {
        let p = ObjectParams::case_study_box(0.0, 0.0, -0.45);
        let rot = UnitQuaternion::from_euler_angles(0.3, 0.2, 0.1);
        let lowest = p
            .corners()
            .iter()
            .map(|c| (rot * c).z)
            .fold(f64::INFINITY, f64::min);
        let z = p.seabed_z_m - lowest;
        assert!(
            z - 0.5 * p.size_m.norm() < p.seabed_z_m,
            "sphere reaches down"
        );
        let zero = Vector3::zeros();
        let above = Isometry3::from_parts(nalgebra::Translation3::new(0.0, 0.0, z + 1e-6), rot);
        let c = seabed_contact(&p, &above, &zero, &zero);
        assert_eq!((c.normal_n, c.damping), (0.0, None));
        let below = Isometry3::from_parts(nalgebra::Translation3::new(0.0, 0.0, z - 1e-6), rot);
        let c = seabed_contact(&p, &below, &zero, &zero);
        assert!((c.normal_n - p.contact_stiffness_n_m * 1e-6).abs() < 1e-3);
        assert!(c.damping.is_some());
    }
}
