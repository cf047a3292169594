//! Task-oriented redundancy resolution (Jun 2008 §4.2, eqs 20–24; Kilic 2005 eqs 0.2–0.10):
//! the task is met, the null-space term does not disturb it (J₁(I − J₁⁺J₁) = 0), it raises the
//! performance index, a second task is met with lower priority, velocity limits scale q̇
//! uniformly, and Jun §4.2's simulation keeps JLM > 0 where the plain J⁺ solution hits a limit.

mod common;

use seaarms_core::kinematics::{end_effector_pose, jacobian_at};
use seaarms_core::manipulability::{jlm, measures, select_rows};
use seaarms_core::optimize::{PostureOptions, optimal_posture};
use seaarms_core::redundancy::{Redundancy, RedundancyParams, Task};

const EXAMPLE_DEG: [f64; 6] = [-15.3, 49.6, -31.0, 75.5, 85.2, -18.0];

fn example_q() -> Vec<f64> {
    EXAMPLE_DEG.iter().map(|d| d.to_radians()).collect()
}

/// Resolution without damping or velocity limits (the equations as written).
fn undamped(model: &seaarms_core::Model) -> Redundancy {
    Redundancy::new(
        model,
        RedundancyParams {
            max_damping: 0.0,
            limit_velocity: false,
            ..Default::default()
        },
    )
}

fn task_velocity(model: &seaarms_core::Model, q: &[f64], qdot: &[f64], rows: &[usize]) -> Vec<f64> {
    let j = select_rows(&jacobian_at(model, q), rows).expect("rows");
    (0..rows.len())
        .map(|i| (0..q.len()).map(|c| j[(i, c)] * qdot[c]).sum())
        .collect()
}

/// Jun §4.2: ORION from the JLM-optimal posture (Fig. 4(c)), ṙ = [0.1, 0.08, −0.08] m/s for
/// 5 s at Δt = 0.05 s. Plain J⁺ of the full 6-row Jacobian (ṙ = [.., 0, 0, 0]), q integrated
/// without clamping: a joint reaches its limit (JLM → 0). Eq. 21 (translational rows, α = 0.5):
/// JLM stays > 0 and the performance index stays higher.
#[test]
fn jun_4_2_eq21_keeps_away_from_joint_limits() {
    let model = common::builtin("orion");
    let p = end_effector_pose(&model, &example_q()).translation.vector;
    let start = optimal_posture(
        &model,
        &[p.x, p.y, p.z],
        &PostureOptions {
            alpha: 0.0,
            ..Default::default()
        },
    )
    .expect("JLM optimum")
    .q;
    let dt = 0.05;
    let steps = 100;
    let plain_params = RedundancyParams {
        epsilon: 0.0,
        max_damping: 0.0,
        limit_velocity: false,
        ..Default::default()
    };
    let mut plain = Redundancy::new(&model, plain_params);
    let mut eq21 = Redundancy::new(
        &model,
        RedundancyParams {
            alpha: 0.5,
            ..Default::default()
        },
    );
    let (mut qa, mut qb) = (start.clone(), start.clone());
    let full = [0usize, 1, 2, 3, 4, 5];
    let trans = [0usize, 1, 2];
    let v6 = [0.1, 0.08, -0.08, 0.0, 0.0, 0.0];
    let v3 = [0.1, 0.08, -0.08];
    let perf = |q: &[f64]| {
        let t = measures(&select_rows(&jacobian_at(&model, q), &trans).expect("rows"))
            .expect("svd")
            .yoshikawa;
        0.5 * t + 0.5 * jlm(&model, q)
    };
    let mut plain_min_jlm = f64::INFINITY;
    let mut first_zero = None;
    for s in 1..=steps {
        plain.step(&model, &qa, &v6, &full, dt).expect("plain step");
        qa.copy_from_slice(plain.q_next());
        eq21.step_tracking(&model, &qb, &v3, &trans, dt)
            .expect("eq21 step");
        qb.copy_from_slice(eq21.q_next());
        let (ja, jb) = (jlm(&model, &qa), jlm(&model, &qb));
        plain_min_jlm = plain_min_jlm.min(ja);
        if ja == 0.0 && first_zero.is_none() {
            first_zero = Some(s as f64 * dt);
        }
        if s % 10 == 0 {
            println!(
                "t {:.2}: plain JLM {ja:.4} P {:.4} | eq21 JLM {jb:.4} P {:.4} scale {:.2}",
                s as f64 * dt,
                perf(&qa),
                perf(&qb),
                eq21.info().velocity_scale
            );
        }
        assert!(
            jb > 0.0,
            "eq. 21 reached a joint limit at t = {}",
            s as f64 * dt
        );
        assert!(
            perf(&qb) >= perf(&qa) - 1e-12,
            "eq. 21 index below J+ at t = {}",
            s as f64 * dt
        );
    }
    println!(
        "plain J+ JLM first 0 at {first_zero:?} s; final JLM plain {:.4}, eq21 {:.4}",
        jlm(&model, &qa),
        jlm(&model, &qb)
    );
    assert_eq!(
        plain_min_jlm, 0.0,
        "the plain J+ solution should reach a joint limit"
    );
    // The feedback form (eqs 22–24) ends within 1 cm of the commanded 5 s · ṙ (0.75 m away).
    let goal = p_of(&model, &start) + nalgebra::Vector3::new(0.5, 0.4, -0.4);
    assert!(
        (p_of(&model, &qb) - goal).norm() <= 1e-2,
        "eq21 tracking error {}",
        (p_of(&model, &qb) - goal).norm()
    );
}

/// Eqs 22–24: the feedback term G(r₁ᵈ − r₁) removes the drift of open-loop Euler integration.
#[test]
fn feedback_form_tracks_better_than_open_loop() {
    let model = common::builtin("orion");
    let q0 = example_q();
    let trans = [0usize, 1, 2];
    let v = [0.05, -0.04, 0.03];
    let mut open = Redundancy::new(&model, RedundancyParams::default());
    let mut closed = Redundancy::new(&model, RedundancyParams::default());
    let (mut qa, mut qb) = (q0.clone(), q0.clone());
    for _ in 0..40 {
        open.step(&model, &qa, &v, &trans, 0.05).expect("step");
        qa.copy_from_slice(open.q_next());
        closed
            .step_tracking(&model, &qb, &v, &trans, 0.05)
            .expect("step");
        qb.copy_from_slice(closed.q_next());
    }
    let goal = p_of(&model, &q0) + nalgebra::Vector3::new(0.1, -0.08, 0.06);
    let (ea, eb) = (
        (p_of(&model, &qa) - goal).norm(),
        (p_of(&model, &qb) - goal).norm(),
    );
    assert!(
        eb < 0.5 * ea && eb < 2e-3,
        "open-loop error {ea:e}, feedback error {eb:e}"
    );
}

/// Task achieved (J₁q̇ = ṙ₁ with ε = 0) and the null-space term invisible to the task
/// (J₁q̇ = 0 for ṙ₁ = 0, ε > 0), without damping at a regular posture; σ_min equals the SVD's.
#[test]
fn null_space_term_does_not_disturb_the_task() {
    let model = common::builtin("orion");
    let q = example_q();
    let rows = [0usize, 1, 2];
    let mut r = undamped(&model);
    let v = [0.1, 0.08, -0.08];
    r.params.epsilon = 0.0;
    let qd = r.step(&model, &q, &v, &rows, 0.01).expect("step").to_vec();
    for (a, b) in task_velocity(&model, &q, &qd, &rows).iter().zip(v) {
        assert!((a - b).abs() <= 1e-12, "task velocity {a} vs {b}");
    }
    let svd = measures(&select_rows(&jacobian_at(&model, &q), &rows).expect("rows")).expect("svd");
    let smin = svd.singular_values[2];
    assert_eq!(
        r.info().sigma_min,
        None,
        "well-conditioned: σ_min ≥ σ_0 proven, not computed"
    );
    r.params.singular_threshold = 10.0; // force the exact σ_min (λ_max = 0: still no damping)
    r.step(&model, &q, &v, &rows, 0.01).expect("step");
    let got = r.info().sigma_min.expect("computed below the threshold");
    assert!(
        (got - smin).abs() <= 1e-12 * (1.0 + smin),
        "{got} vs {smin}"
    );
    assert!(smin >= RedundancyParams::default().singular_threshold);
    r.params.singular_threshold = RedundancyParams::default().singular_threshold;
    r.params.epsilon = 1.0;
    let qn = r
        .step(&model, &q, &[0.0; 3], &rows, 0.01)
        .expect("step")
        .to_vec();
    assert!(
        qn.iter().map(|v| v * v).sum::<f64>() > 1e-6,
        "null-space motion expected"
    );
    for a in task_velocity(&model, &q, &qn, &rows) {
        assert!(a.abs() <= 1e-12, "J1 (I - J1+ J1) y = {a}");
    }
}

/// Kilic eq. 0.10: with ṙ₁ = 0 the index rises, ṗ = ε ∂P/∂q (I − J₁⁺J₁) ∂P/∂qᵀ ≥ 0.
#[test]
fn null_space_motion_raises_the_performance_index() {
    let model = common::builtin("orion");
    let rows = [0usize, 1, 2];
    let perf = |q: &[f64]| {
        let t = measures(&select_rows(&jacobian_at(&model, q), &rows).expect("rows"))
            .expect("svd")
            .yoshikawa;
        0.5 * t + 0.5 * jlm(&model, q)
    };
    for q in [
        example_q(),
        vec![0.3, 0.4, -0.5, 1.0, 0.2, 0.5],
        vec![-0.5, 1.2, -1.2, -1.5, 1.0, 2.0],
    ] {
        let mut r = Redundancy::new(&model, RedundancyParams::default());
        r.step(&model, &q, &[0.0; 3], &rows, 1e-3).expect("step");
        assert!(perf(r.q_next()) > perf(&q), "P did not rise at {q:?}");
    }
}

/// Kilic eq. 0.6: task 1 (translation) is met exactly, task 2 (wx, wy) too when the 6 joints
/// leave enough freedom; task 1 keeps priority when task 2 conflicts (all three rotations).
#[test]
fn second_task_has_lower_priority() {
    let model = common::builtin("orion");
    let q = example_q();
    let mut r = undamped(&model);
    let v1 = [0.05, 0.0, -0.02];
    let v2 = [0.1, -0.2];
    let qd = r
        .step_priority(
            &model,
            &q,
            &v1,
            &[0, 1, 2],
            Task {
                rows: &[3, 4],
                velocity: &v2,
            },
            0.01,
        )
        .expect("step")
        .to_vec();
    let got = task_velocity(&model, &q, &qd, &[0, 1, 2, 3, 4]);
    for (a, b) in got.iter().zip(v1.iter().chain(&v2)) {
        assert!((a - b).abs() <= 1e-9, "{got:?}");
    }
    // Conflicting second task (4 more rows, only 3 joints of freedom left): with damping,
    // task 1 is still met exactly and task 2 as well as possible.
    r.params = RedundancyParams {
        limit_velocity: false,
        ..Default::default()
    };
    let qd = r
        .step_priority(
            &model,
            &q,
            &v1,
            &[0, 1, 2],
            Task {
                rows: &[0, 3, 4, 5],
                velocity: &[1.0, 0.3, 0.2, 0.1],
            },
            0.01,
        )
        .expect("step")
        .to_vec();
    for (a, b) in task_velocity(&model, &q, &qd, &[0, 1, 2]).iter().zip(v1) {
        assert!((a - b).abs() <= 1e-6, "task 1 lost priority: {a} vs {b}");
    }
}

/// Velocity limits: q̇ is scaled by one factor, so |q̇ᵢ| ≤ max and the direction is kept.
#[test]
fn velocity_limits_scale_uniformly() {
    let model = common::builtin("orion");
    let q = example_q();
    let rows = [0usize, 1, 2];
    let fast = [2.0, -1.0, 1.5];
    let mut free = Redundancy::new(
        &model,
        RedundancyParams {
            limit_velocity: false,
            ..Default::default()
        },
    );
    let mut limited = Redundancy::new(&model, RedundancyParams::default());
    let a = free
        .step(&model, &q, &fast, &rows, 0.01)
        .expect("step")
        .to_vec();
    let b = limited
        .step(&model, &q, &fast, &rows, 0.01)
        .expect("step")
        .to_vec();
    let s = limited.info().velocity_scale;
    assert!(s < 1.0);
    for ((x, y), j) in a.iter().zip(&b).zip(&model.joints) {
        assert!(y.abs() <= j.max_velocity * (1.0 + 1e-12));
        assert!((x * s - y).abs() <= 1e-12);
    }
}

/// Damping near a singularity: the stretched planar 2R arm (q₂ = 0) gives a finite q̇ with
/// λ > 0, and a plain pseudo-inverse (λ_max = 0) reports the singularity instead of NaN.
#[test]
fn damping_keeps_singular_steps_finite() {
    let model = common::builtin("planar2r");
    let q = [0.3, 0.0];
    let mut r = Redundancy::new(
        &model,
        RedundancyParams {
            epsilon: 0.0,
            limit_velocity: false,
            ..Default::default()
        },
    );
    let qd = r
        .step(&model, &q, &[0.1, 0.1], &[0, 1], 0.01)
        .expect("damped step")
        .to_vec();
    assert!(
        qd.iter().all(|v| v.is_finite() && v.abs() < 100.0),
        "{qd:?}"
    );
    assert!(r.info().damping > 0.0 && r.info().sigma_min.expect("near singular") < 1e-6);
    r.params.max_damping = 0.0;
    assert!(r.step(&model, &q, &[0.1, 0.1], &[0, 1], 0.01).is_err());
}

fn p_of(model: &seaarms_core::Model, q: &[f64]) -> nalgebra::Vector3<f64> {
    end_effector_pose(model, q).translation.vector
}
