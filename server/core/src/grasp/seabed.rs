//! The seabed's push on the object: penalty springs and dashpots at the box corners below
//! the seabed, stick–slip Coulomb friction, and the dashpots' damping matrix for an implicit
//! integrator.
//!
//! # Friction
//! Each touching corner holds an **anchor**, the point of the seabed it stuck to
//! ([`SeabedAnchors`], part of the object's state). While it sticks, the seabed pulls it back
//! towards the anchor with a tangential spring-damper, f_t = −k_t·d − c_t·v_t (d the corner's
//! horizontal offset from its anchor, v_t its horizontal velocity). The spring is linearly
//! implicit like the end stops of the arms: the integrator's velocity update sees
//! f_t = −k_t·(d + h·v_t⁺) − c_t·v_t⁺, so the force carries −h·k_t·v_t and the damping matrix
//! the coefficient c_t + h·k_t; h·√(k_t/m_corner) ≈ 0.2 for a few kg at one corner, and the
//! implicit form is stable whatever the ratio. While the trial force exceeds the Coulomb cap
//! μ·f_n the corner slips: the kinetic force −μ·f_n·v_t/√(|v_t|²+ε²) (regularized only so
//! that its secant is a finite dashpot for the implicit step; within 10⁻⁴ of μ·f_n above
//! 0.7 m/s at ε = 1 cm/s) and the anchor is moved so that the spring alone would pull with
//! exactly the cap against the trial direction (the return mapping of an elastic–perfectly
//! plastic spring: Simo & Hughes (1998) "Computational Inelasticity" §1.2; in contact
//! dynamics the "stiction spring" of Cundall & Strack (1979) and of game engines' anchored
//! friction). A box at rest under a side load below μ·f_n therefore stays put (the springs
//! stretch by F/(4k_t), at most 0.31 mm at the cap under the 50 kg box in water) instead of creeping
//! at v = ε·F/√((μN)² − F²) as the purely regularized law did (3.7 mm/s at 1 m/s of current).
//!
//! Parameters (per corner): k_t = [`STICK_STIFFNESS_N_M`] = 1·10⁵ N/m; c_t = c_n·√(k_t/k_n)
//! (4.5·10³ N·s/m: the normal direction's damping ratio); μ_s = μ_k =
//! [`ObjectParams::friction`] (0.5: one coefficient, as the seabed's was; the stick–slip comes
//! from the anchor, not from a μ_s > μ_k step). k_t is chosen, not measured: Mindlin's ratio of
//! tangential to normal contact stiffness, 2(1 − ν)/(2 − ν) = 0.82 at ν = 0.3 (Mindlin (1949)
//! "Compliance of elastic bodies in contact", J. Appl. Mech. 16; Johnson (1985) "Contact
//! Mechanics" §7.2), would give 1.65·10⁶ N/m, and with that the cooperative controller holding
//! a box that rests on the seabed in water drifted into a growing oscillation (λ to 1.03 in
//! 2 s at zero stick): its internal-force admittance (10⁻⁴ m/s per N) pushing against a
//! 6.6·10⁶ N/m anchorage closes a loop of 660 s⁻¹, far above the valve spools' 40 s⁻¹. At
//! 1·10⁵ N/m (a soft sediment's shear compliance rather than steel on rock) that hold decays,
//! and the springs stretch at most μ·f_n/k_t = 0.31 mm at the cap under the box in water
//! (0.6 mm in air) — a box that sticks moves by that much, never more.

use nalgebra::{Isometry3, Matrix3, Matrix6, Vector2, Vector3, Vector6};

use super::ObjectParams;

/// Tangential (stick) stiffness of a corner (N/m): 1·10⁵ (see the module docs: chosen for the
/// closed loop's stability, 1/20 of the normal stiffness).
pub const STICK_STIFFNESS_N_M: f64 = 1.0e5;

/// Where each bottom corner of the box stuck to the seabed: the world (x, y) of its anchor,
/// `None` for a corner not touching (indexed as [`ObjectParams::corners`]). The friction's
/// state, carried from step to step with the object's.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SeabedAnchors {
    /// Anchor per corner (m, world x and y).
    pub points: [Option<Vector2<f64>>; 8],
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
    /// touching corners, normal and tangential (a sticking corner's c_t + h·k_t, a slipping
    /// one's friction secant). `None` when nothing touches (or it was not asked for).
    pub damping: Option<Matrix6<f64>>,
    /// The corners' anchors after this contact (re-anchored where a corner slipped, set where
    /// one started touching, cleared where one stopped).
    pub anchors: SeabedAnchors,
    /// Corners that stick (bit k for corner k).
    pub sticking: u8,
}

/// Seabed contact wrench on the object (force, moment about the COM; world frame) from
/// penalty springs at the box corners below the seabed, with stick–slip friction about the
/// corners' `anchors` (see the module docs; `h` is the integrator's step for the linearly
/// implicit stick spring), without the damping matrix.
pub fn seabed_wrench(
    p: &ObjectParams,
    pose: &Isometry3<f64>,
    v: &Vector3<f64>,
    w: &Vector3<f64>,
    anchors: &SeabedAnchors,
    h: f64,
) -> SeabedContact {
    seabed_contact_impl(p, pose, v, w, anchors, h, false)
}

/// [`seabed_wrench`] with its damping matrix, for an integrator that treats the dashpots
/// implicitly. A corner's velocity along a direction d is a_dᵀ·[v; ω] with a_d = [d; r × d]
/// (r from the COM), and a force f·d there is the wrench a_d·f, so a dashpot of coefficient
/// c adds c·a_d·a_dᵀ. The normal dashpot is the contact damping while the corner pushes
/// (f_n > 0); tangentially a sticking corner is a dashpot c_t + h·k_t (exact: its force is
/// linear in v_t), a slipping one μ·f_n/√(|v_t|²+ε²) along both seabed axes (the secant of
/// the kinetic force, its tangent at v_t = 0).
pub fn seabed_contact(
    p: &ObjectParams,
    pose: &Isometry3<f64>,
    v: &Vector3<f64>,
    w: &Vector3<f64>,
    anchors: &SeabedAnchors,
    h: f64,
) -> SeabedContact {
    seabed_contact_impl(p, pose, v, w, anchors, h, true)
}

/// One touching corner's tangential force (N, world x and y), its dashpot coefficient for the
/// damping matrix (N·s/m), its new anchor and whether it sticks (the module docs' law).
/// `xy`: the corner's position, `vt` its velocity (both world x, y), `fn_` the normal force,
/// `anchor` the previous anchor (`None`: the corner just touched down and sticks where it is).
pub fn corner_friction(
    p: &ObjectParams,
    xy: &Vector2<f64>,
    vt: &Vector2<f64>,
    fn_: f64,
    anchor: Option<Vector2<f64>>,
    h: f64,
) -> (Vector2<f64>, f64, Vector2<f64>, bool) {
    let k_t = STICK_STIFFNESS_N_M;
    let c_t = p.contact_damping_n_s_m * (k_t / p.contact_stiffness_n_m).sqrt();
    let c_stick = c_t + h * k_t;
    let a = anchor.unwrap_or(*xy);
    let trial = -(xy - a) * k_t - vt * c_stick;
    let cap = p.friction * fn_;
    let t = trial.norm();
    if t <= cap {
        return (trial, c_stick, a, true);
    }
    let s = (vt.norm_squared() + p.friction_speed_m_s * p.friction_speed_m_s).sqrt();
    let c_slip = cap / s;
    // Re-anchor: the spring alone would pull with the cap along the trial force.
    let anchor = if k_t > 0.0 && t > 0.0 {
        xy + trial * (cap / (t * k_t))
    } else {
        *xy
    };
    (-vt * c_slip, c_slip, anchor, false)
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
    anchors: &SeabedAnchors,
    h: f64,
    with_damping: bool,
) -> SeabedContact {
    let mut f = Vector3::zeros();
    let mut m = Vector3::zeros();
    let mut normal = 0.0;
    let mut out_anchors = SeabedAnchors::default();
    let mut sticking = 0u8;
    // The box's half edges in the world frame, u_j = h_j·R_j (R's columns): the corner
    // (±h_x, ±h_y, ±h_z) of the object frame is at r = ±u_0 ± u_1 ± u_2 from the COM.
    let rot = pose.rotation.to_rotation_matrix();
    let half = p.size_m * 0.5;
    let u = [
        rot.matrix().column(0) * half.x,
        rot.matrix().column(1) * half.y,
        rot.matrix().column(2) * half.z,
    ];
    let c0 = pose.translation.vector;
    let z0 = c0.z;
    // Quick reject: the lowest corner, z_0 − Σ_j |u_j,z| (each sign chosen to go down), is
    // above the seabed — exactly the test of the loop below for every corner, so nothing
    // touches.
    if z0 - (u[0].z.abs() + u[1].z.abs() + u[2].z.abs()) > p.seabed_z_m {
        return SeabedContact {
            wrench: Vector6::zeros(),
            normal_n: 0.0,
            damping: None,
            anchors: out_anchors,
            sticking,
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
        if fn_ <= 0.0 {
            // Below the seabed but leaving it faster than the spring pushes: no contact
            // force, and the corner lets go of its anchor.
            continue;
        }
        let xy = Vector2::new(c0.x + r.x, c0.y + r.y);
        let vt = Vector2::new(vc.x, vc.y);
        let (ft, c_t, anchor, stick) = corner_friction(p, &xy, &vt, fn_, anchors.points[k], h);
        out_anchors.points[k] = Some(anchor);
        if stick {
            sticking |= 1 << k;
        }
        let fc = Vector3::new(ft.x, ft.y, fn_);
        f += fc;
        m += r.cross(&fc);
        normal += fn_;
        if with_damping {
            touching = true;
            sums.add(&r, c_t, p.contact_damping_n_s_m);
        }
    }
    SeabedContact {
        wrench: Vector6::new(f.x, f.y, f.z, m.x, m.y, m.z),
        normal_n: normal,
        damping: touching.then(|| sums.matrix()),
        anchors: out_anchors,
        sticking,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    /// The integrator step the tests assume (s).
    const STEP: f64 = 1e-3;
    /// No corner anchored yet.
    const FRESH: SeabedAnchors = SeabedAnchors { points: [None; 8] };

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
    /// sphere reject, rank-one damping updates), written plainly; the corners' friction law
    /// is [`corner_friction`]'s (fresh anchors: each touching corner sticks where it is unless
    /// its damping force alone exceeds the cap).
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
            if fn_ <= 0.0 {
                continue;
            }
            let xy = Vector2::new(
                pose.translation.vector.x + r.x,
                pose.translation.vector.y + r.y,
            );
            let (ft, c_t, _, _) =
                corner_friction(p, &xy, &Vector2::new(vc.x, vc.y), fn_, None, STEP);
            let fc = Vector3::new(ft.x, ft.y, fn_);
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
            anchors: SeabedAnchors::default(),
            sticking: 0,
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
            let ours = seabed_contact(&p, &pose, &v, &w, &FRESH, STEP);
            let reference = seabed_contact_reference(&p, &pose, &v, &w);
            let scale = 1.0 + reference.wrench.norm();
            assert!(
                (ours.wrench - reference.wrench).norm() < 1e-9 * scale,
                "{k}: {} vs {}",
                ours.wrench,
                reference.wrench
            );
            assert!((ours.normal_n - reference.normal_n).abs() < 1e-9 * scale);
            assert_eq!(
                seabed_wrench(&p, &pose, &v, &w, &FRESH, STEP).wrench,
                ours.wrench
            );
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
        let c = seabed_contact(&p, &above, &zero, &zero, &FRESH, STEP);
        assert_eq!((c.normal_n, c.damping), (0.0, None));
        let below = Isometry3::from_parts(nalgebra::Translation3::new(0.0, 0.0, z - 1e-6), rot);
        let c = seabed_contact(&p, &below, &zero, &zero, &FRESH, STEP);
        assert!((c.normal_n - p.contact_stiffness_n_m * 1e-6).abs() < 1e-3);
        assert!(c.damping.is_some());
    }
}
