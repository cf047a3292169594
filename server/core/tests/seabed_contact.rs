//! The seabed contact's damping matrix, which the step treats implicitly
//! (`grasp::seabed_contact`), checked against finite differences of the contact wrench, and
//! a box dropped onto one corner settling without gaining energy.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3, Vector6};
use seaarms_core::grasp::{ObjectParams, SeabedAnchors, seabed_contact, seabed_wrench};
use seaarms_core::sim::{Input, SimParams, Simulation};

mod common;

/// The case-study box tilted onto one corner (or one edge), that corner `depth_m` into the
/// seabed.
fn tilted(p: &ObjectParams, rx: f64, ry: f64, depth_m: f64) -> Isometry3<f64> {
    let rot = UnitQuaternion::from_euler_angles(rx, ry, 0.0);
    let lowest = p
        .corners()
        .iter()
        .map(|c| (rot * c).z)
        .fold(f64::INFINITY, f64::min);
    Isometry3::from_parts(
        Translation3::new(1.0, 0.5, p.seabed_z_m - lowest - depth_m),
        rot,
    )
}

/// C = −∂wrench/∂[v; ω] by central differences, at twists whose touching corners do not
/// slide (they stick to fresh anchors: the tangential force is the linear −(c_t + h·k_t)·v_t),
/// on a corner and on an edge.
#[test]
fn damping_matrix_is_the_wrench_velocity_derivative() {
    let p = ObjectParams::case_study_box(1.0, 0.5, -0.45);
    for (rx, ry) in [(0.3, 0.2), (0.0, 0.25)] {
        let pose = tilted(&p, rx, ry, 0.004);
        // Pure vertical motion: touching corners move along z only.
        let v = Vector3::new(0.0, 0.0, -0.05);
        let w = Vector3::zeros();
        let fresh = SeabedAnchors::default();
        let c = seabed_contact(&p, &pose, &v, &w, &fresh, 1e-3);
        let damping = c.damping.expect("a corner touches");
        assert_eq!(
            c.wrench,
            seabed_wrench(&p, &pose, &v, &w, &fresh, 1e-3).wrench
        );
        let h = 1e-7;
        for k in 0..6 {
            let mut t = Vector6::new(v.x, v.y, v.z, w.x, w.y, w.z);
            t[k] += h;
            let wrench_at = |t: &Vector6<f64>| {
                seabed_wrench(
                    &p,
                    &pose,
                    &t.fixed_rows::<3>(0).into(),
                    &t.fixed_rows::<3>(3).into(),
                    &fresh,
                    1e-3,
                )
                .wrench
            };
            let plus = wrench_at(&t);
            t[k] -= 2.0 * h;
            let minus = wrench_at(&t);
            let fd = -(plus - minus) / (2.0 * h);
            let col = damping.column(k);
            assert!(
                (fd - col).norm() <= 1e-5 * damping.norm(),
                "({rx}, {ry}) column {k}: {fd} vs {col}"
            );
        }
        // Symmetric positive semidefinite.
        assert!((damping - damping.transpose()).norm() < 1e-9 * damping.norm());
        assert!(damping.symmetric_eigenvalues().min() > -1e-9 * damping.norm());
    }
    let above = Isometry3::translation(1.0, 0.5, 0.5);
    assert!(
        seabed_contact(
            &p,
            &above,
            &Vector3::zeros(),
            &Vector3::zeros(),
            &SeabedAnchors::default(),
            1e-3
        )
        .damping
        .is_none()
    );
}

/// A box released on one corner, 1 cm into the seabed, with a spin: the corner springs push
/// it up, it tips onto a face and comes to rest. With the seabed dashpots explicit it gained
/// energy at every corner impact (the effective mass at a corner is a few kg); implicit, it
/// never rises more than the spring energy allows and ends at rest on its face.
#[test]
fn box_dropped_on_a_corner_settles() {
    let m = common::builtin("magnum");
    let mut params = SimParams::case_study(&m, &m).expect("params");
    let pose = tilted(&params.object, 0.35, 0.25, 0.01);
    params.object.initial_pose = pose;
    let mut sim = Simulation::new(m.clone(), m, params).expect("sim");
    let p = sim.params().object;
    let mg = p.mass_kg * 9.81;
    // Upper bound on the rise: all the corner's spring energy ½k·d² turned into height.
    let spring = 0.5 * p.contact_stiffness_n_m * 0.01 * 0.01;
    let z0 = sim.object().pose.translation.z;
    let mut z_max = z0;
    let input = Input::default();
    for _ in 0..4000 {
        sim.step(&input);
        z_max = z_max.max(sim.object().pose.translation.z);
        assert!(
            sim.object().velocity.norm() < 2.0,
            "{:?}",
            sim.object().velocity
        );
    }
    assert!(z_max <= z0 + spring / mg, "rose {} m", z_max - z0);
    let o = sim.object();
    assert!(
        o.velocity.norm() < 1e-2 && o.angular_velocity.norm() < 5e-2,
        "{o:?}"
    );
    assert!(
        (o.seabed_force_n - mg).abs() < 0.02 * mg,
        "resting on the seabed: {o:?}"
    );
    assert_eq!(sim.numerical_faults(), 0);
}
