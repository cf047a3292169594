//! The seabed's push on the object: penalty springs and dashpots at the box corners below
//! the seabed, regularized Coulomb friction, and the dashpots' damping matrix for an
//! implicit integrator.

use nalgebra::{Isometry3, Matrix3, Matrix6, Vector3, Vector6};

use super::ObjectParams;

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
