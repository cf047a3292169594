//! Rigid-body dynamics checked by independent computations (Lim eq. 3.38; Featherstone 2008
//! ch. 5–6): RNEA columns = CRBA mass matrix, H symmetric positive definite, gravity torques =
//! Jacobian-transpose statics of the link weights, J̇q̇ = finite-differenced J·q̇, and energy
//! conservation of the unactuated arm.

mod common;

use nalgebra::{DMatrix, DVector, Vector3};
use seaarms_core::dynamics::{
    DynData, Inertials, crba, rnea, step_terms, tool_bias_acceleration, tool_bias_from_rnea,
};
use seaarms_core::kinematics::{KinData, forward_kinematics, jacobian, jacobian_at};

const G: Vector3<f64> = Vector3::new(0.0, 0.0, -9.81);

/// Deterministic pseudo-random postures within the joint limits.
fn postures(n: usize) -> Vec<[f64; 6]> {
    let mut s: u64 = 0x9e3779b97f4a7c15;
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let m = common::builtin("magnum");
    (0..n)
        .map(|_| {
            core::array::from_fn(|j| {
                let l = m.joints[j].limits;
                let (lo, hi) = if l[0].is_finite() {
                    (l[0], l[1])
                } else {
                    (-3.0, 3.0)
                };
                lo + (hi - lo) * next()
            })
        })
        .collect()
}

#[test]
fn rnea_columns_equal_crba_and_mass_matrix_is_spd() {
    let m = common::builtin("magnum");
    let inr = Inertials::magnum(&m).expect("inertials");
    assert!(
        (inr.total_mass_kg() - 71.0).abs() < 1e-9,
        "Lim Table 1-1: 71 kg in air"
    );
    let mut kin = KinData::new(&m);
    let mut d = DynData::new(&m);
    for q in postures(50) {
        forward_kinematics(&m, &mut kin, &q);
        crba(&m, &inr, &kin, &mut d);
        let h = d.mass_matrix.clone();
        for k in 0..6 {
            let mut e = [0.0; 6];
            e[k] = 1.0;
            let mut tau = [0.0; 6];
            rnea(
                &m,
                &inr,
                &kin,
                &[0.0; 6],
                &e,
                &Vector3::zeros(),
                0.0,
                &mut tau,
                &mut d,
            );
            for r in 0..6 {
                assert!(
                    (tau[r] - h[(r, k)]).abs() < 1e-9 * (1.0 + h[(r, k)].abs()),
                    "H[{r},{k}]: RNEA {} CRBA {}",
                    tau[r],
                    h[(r, k)]
                );
            }
        }
        assert!((&h - h.transpose()).abs().max() < 1e-12);
        assert!(
            h.clone().cholesky().is_some(),
            "H must be positive definite at {q:?}"
        );
    }
}

#[test]
fn gravity_torques_equal_jacobian_transpose_statics() {
    // G(q) = −Σ_i J_{v,c_i}ᵀ m_i g: each link weight through the Jacobian of its COM, built here
    // from a model whose tool point is moved to that COM.
    let m = common::builtin("magnum");
    let inr = Inertials::magnum(&m).expect("inertials");
    let mut kin = KinData::new(&m);
    let mut d = DynData::new(&m);
    for q in postures(20) {
        forward_kinematics(&m, &mut kin, &q);
        let mut g = [0.0; 6];
        rnea(
            &m, &inr, &kin, &[0.0; 6], &[0.0; 6], &G, 0.0, &mut g, &mut d,
        );
        let mut statics = DVector::<f64>::zeros(6);
        for (i, link) in inr.links.iter().enumerate() {
            // Truncated chain 0..=i with the tool at link i's COM.
            let mut sub = m.clone();
            sub.joints.truncate(i + 1);
            sub.flange = nalgebra::IsometryMatrix3::identity();
            sub.tool = link.com_m;
            let j = jacobian_at(&sub, &q[..=i]);
            let w = G * link.mass_kg;
            for k in 0..=i {
                statics[k] -= j[(0, k)] * w.x + j[(1, k)] * w.y + j[(2, k)] * w.z;
            }
        }
        for k in 0..6 {
            assert!(
                (g[k] - statics[k]).abs() < 1e-9 * (1.0 + g[k].abs()),
                "joint {k}: RNEA {} statics {}",
                g[k],
                statics[k]
            );
        }
    }
}

#[test]
fn bias_acceleration_matches_finite_difference() {
    let m = common::builtin("magnum");
    let mut kin = KinData::new(&m);
    let mut d = DynData::new(&m);
    let qd = [0.3, -0.2, 0.4, 0.5, -0.6, 1.0];
    for q in postures(10) {
        forward_kinematics(&m, &mut kin, &q);
        let jb = tool_bias_acceleration(&m, &kin, &qd, &[0.0; 6], &mut d);
        let inr = Inertials::magnum(&m).expect("inertials");
        let mut tau = [0.0; 6];
        rnea(&m, &inr, &kin, &qd, &[0.0; 6], &G, 0.0, &mut tau, &mut d);
        let from_rnea = tool_bias_from_rnea(&m, &kin, &G, &d);
        for r in 0..6 {
            assert!(
                (jb[r] - from_rnea[r]).abs() < 1e-9,
                "row {r}: {} vs {}",
                jb[r],
                from_rnea[r]
            );
        }
        let eps = 1e-6;
        let jv =
            |q: &[f64; 6]| -> DVector<f64> { jacobian_at(&m, q) * DVector::from_column_slice(&qd) };
        let qp: [f64; 6] = core::array::from_fn(|k| q[k] + eps * qd[k]);
        let qm: [f64; 6] = core::array::from_fn(|k| q[k] - eps * qd[k]);
        let fd = (jv(&qp) - jv(&qm)) / (2.0 * eps);
        for r in 0..6 {
            assert!(
                (jb[r] - fd[r]).abs() < 1e-5,
                "row {r}: {} vs {}",
                jb[r],
                fd[r]
            );
        }
    }
}

/// Kinetic + potential energy of the arm.
fn energy(m: &seaarms_core::Model, inr: &Inertials, q: &[f64; 6], qd: &[f64; 6]) -> f64 {
    let mut kin = KinData::new(m);
    let mut d = DynData::new(m);
    forward_kinematics(m, &mut kin, q);
    crba(m, inr, &kin, &mut d);
    let v = DVector::from_column_slice(qd);
    let t = 0.5 * (v.transpose() * &d.mass_matrix * &v)[(0, 0)];
    let u: f64 = inr
        .links
        .iter()
        .enumerate()
        .map(|(i, l)| l.mass_kg * 9.81 * kin.joint_frames[i].transform_point(&l.com_m.into()).z)
        .sum();
    t + u
}

#[test]
fn unactuated_arm_conserves_energy() {
    // q̈ = H⁻¹(−(Cq̇ + G)) integrated with RK4 at 0.1 ms for 2 s, no joint limits: the total
    // energy stays constant (checks the Coriolis/centrifugal terms of RNEA against CRBA's H).
    let m = common::builtin("magnum");
    let inr = Inertials::magnum(&m).expect("inertials");
    let mut kin = KinData::new(&m);
    let mut d = DynData::new(&m);
    let mut acc = |q: &[f64; 6], qd: &[f64; 6]| -> [f64; 6] {
        forward_kinematics(&m, &mut kin, q);
        crba(&m, &inr, &kin, &mut d);
        let h = d.mass_matrix.clone();
        let mut b = [0.0; 6];
        rnea(&m, &inr, &kin, qd, &[0.0; 6], &G, 0.0, &mut b, &mut d);
        let x = h
            .cholesky()
            .expect("spd")
            .solve(&DMatrix::from_column_slice(6, 1, &b));
        core::array::from_fn(|k| -x[k])
    };
    let mut q = [0.1, 0.6, -1.0, -0.3, 0.4, 0.2];
    let mut qd = [0.2, 0.0, 0.5, -0.3, 0.8, 1.5];
    let e0 = energy(&m, &inr, &q, &qd);
    let h = 1e-4;
    let add = |a: &[f64; 6], b: &[f64; 6], s: f64| -> [f64; 6] {
        core::array::from_fn(|k| a[k] + s * b[k])
    };
    for _ in 0..20000 {
        let k1q = qd;
        let k1v = acc(&q, &qd);
        let k2q = add(&qd, &k1v, h / 2.0);
        let k2v = acc(&add(&q, &k1q, h / 2.0), &k2q);
        let k3q = add(&qd, &k2v, h / 2.0);
        let k3v = acc(&add(&q, &k2q, h / 2.0), &k3q);
        let k4q = add(&qd, &k3v, h);
        let k4v = acc(&add(&q, &k3q, h), &k4q);
        for k in 0..6 {
            q[k] += h / 6.0 * (k1q[k] + 2.0 * k2q[k] + 2.0 * k3q[k] + k4q[k]);
            qd[k] += h / 6.0 * (k1v[k] + 2.0 * k2v[k] + 2.0 * k3v[k] + k4v[k]);
        }
    }
    let e1 = energy(&m, &inr, &q, &qd);
    assert!(
        (e1 - e0).abs() < 1e-6 * e0.abs().max(1.0),
        "energy drift {e0} → {e1}"
    );
}

#[test]
fn jacobian_used_by_dynamics_is_the_kinematics_one() {
    let m = common::builtin("magnum");
    let mut kin = KinData::new(&m);
    let q = [0.1, 0.2, -0.3, 0.4, -0.5, 0.6];
    jacobian(&m, &mut kin, &q);
    assert_eq!(kin.jacobian, jacobian_at(&m, &q));
}

/// The fused step routine (`step_terms`) against the separate reference implementations it
/// fuses: H = `crba`, C q̇ + G = `rnea` at q̈ = 0 (with and without buoyancy), J̇q̇ =
/// `tool_bias_acceleration`, at 50 postures with joint rates up to 2 rad/s.
#[test]
fn fused_step_terms_equal_rnea_crba_and_bias() {
    let m = common::builtin("magnum");
    let inr = Inertials::magnum(&m).expect("inertials");
    let mut kin = KinData::new(&m);
    let mut d = DynData::new(&m);
    for (k, q) in postures(50).into_iter().enumerate() {
        let qd: [f64; 6] = core::array::from_fn(|j| 2.0 * ((k * 7 + j * 3) as f64).sin());
        forward_kinematics(&m, &mut kin, &q);
        crba(&m, &inr, &kin, &mut d);
        let h_ref = d.mass_matrix.clone();
        let jb = tool_bias_acceleration(&m, &kin, &qd, &[0.0; 6], &mut d);
        for rho in [0.0, 1025.0] {
            let mut tau = [0.0; 6];
            rnea(&m, &inr, &kin, &qd, &[0.0; 6], &G, rho, &mut tau, &mut d);
            let t = step_terms::<6>(&m, &inr, &kin, &qd, &G, rho);
            let scale = h_ref.amax();
            for r in 0..6 {
                for c in 0..6 {
                    assert!(
                        (t.mass_matrix[(r, c)] - h_ref[(r, c)]).abs() < 1e-12 * scale,
                        "H[{r},{c}]"
                    );
                }
                assert!(
                    (t.bias[r] - tau[r]).abs() < 1e-10 * (1.0 + tau[r].abs()),
                    "bias {r}: {} vs {}",
                    t.bias[r],
                    tau[r]
                );
            }
            for (ours, reference) in t.tool_bias.iter().zip(&jb) {
                assert!((ours - reference).abs() < 1e-10 * (1.0 + reference.abs()));
            }
        }
    }
}
