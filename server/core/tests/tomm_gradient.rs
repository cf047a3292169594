//! ∂TOMM/∂q and ∂P/∂q (Jun eqs 4, 16, 17) equal finite differences of independently computed
//! measures: TOMM from the SVD (Yoshikawa Πσᵢ of the selected rows) and JLM from eq. 16.

mod common;

use proptest::prelude::*;
use seaarms_core::kinematics::{KinData, jacobian_at};
use seaarms_core::manipulability::{jlm, measures, select_rows};
use seaarms_core::optimize::{PerformanceIndex, tomm, tomm_gradient};

fn tomm_svd(model: &seaarms_core::Model, q: &[f64], rows: &[usize]) -> f64 {
    measures(&select_rows(&jacobian_at(model, q), rows).expect("rows"))
        .expect("svd")
        .yoshikawa
}

fn inner_q() -> impl Strategy<Value = Vec<f64>> {
    let m = common::builtin("orion");
    m.joints
        .iter()
        .map(|j| {
            let w = j.limits[1] - j.limits[0];
            (j.limits[0] + 0.05 * w)..(j.limits[1] - 0.05 * w)
        })
        .collect::<Vec<_>>()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// TOMM by determinant = TOMM by SVD; its gradient = a 1e-5 central difference of the SVD value.
    #[test]
    fn tomm_gradient_matches_svd_differences(q in inner_q(), sel in 0usize..3) {
        let model = common::builtin("orion");
        let rows: &[usize] = [&[0usize, 1, 2][..], &[3, 4, 5][..], &[0, 4][..]][sel];
        let mut data = KinData::new(&model);
        let t = tomm(&model, &mut data, &q, rows);
        prop_assert!((t - tomm_svd(&model, &q, rows)).abs() <= 1e-10 * (1.0 + t));
        let mut grad = vec![0.0; 6];
        let mut sq = vec![0.0; 6];
        tomm_gradient(&model, &mut data, &mut sq, &q, rows, &mut grad);
        let h = 1e-5;
        for i in 0..6 {
            let mut up = q.clone();
            up[i] += h;
            let mut dn = q.clone();
            dn[i] -= h;
            let fd = (tomm_svd(&model, &up, rows) - tomm_svd(&model, &dn, rows)) / (2.0 * h);
            prop_assert!((grad[i] - fd).abs() <= 1e-6 * (1.0 + fd.abs()), "joint {}: {} vs {}", i, grad[i], fd);
        }
    }

    /// ∂P/∂q of P = α·TOMM + (1 − α)·JLM against central differences of P.
    #[test]
    fn performance_gradient_matches_differences(q in inner_q(), alpha in 0.0f64..=1.0) {
        let model = common::builtin("orion");
        let rows = [0usize, 1, 2];
        let p = |q: &[f64]| alpha * tomm_svd(&model, q, &rows) + (1.0 - alpha) * jlm(&model, q);
        let mut index = PerformanceIndex::new(&model, alpha);
        let mut grad = vec![0.0; 6];
        index.gradient(&model, &q, &rows, &mut grad);
        let h = 1e-6;
        for i in 0..6 {
            let mut up = q.clone();
            up[i] += h;
            let mut dn = q.clone();
            dn[i] -= h;
            let fd = (p(&up) - p(&dn)) / (2.0 * h);
            prop_assert!((grad[i] - fd).abs() <= 1e-6 * (1.0 + fd.abs()), "joint {}: {} vs {}", i, grad[i], fd);
        }
    }
}

/// A Stanford-like arm (prismatic third joint), inline model, to exercise the prismatic terms.
fn stanford() -> seaarms_core::Model {
    let h = std::f64::consts::FRAC_PI_2;
    let spec: seaarms_core::ModelSpec = serde_json::from_value(serde_json::json!({
        "name": "stanford-like", "dh": "standard",
        "joints": [
            {"type": "revolute", "alpha": -h, "d": 0.4},
            {"type": "revolute", "alpha": h, "d": 0.15},
            {"type": "prismatic", "theta": 0.0, "limits": [0.2, 1.0]},
            {"type": "revolute", "alpha": -h},
            {"type": "revolute", "alpha": h, "a": 0.05},
            {"type": "revolute", "d": 0.2}
        ]
    }))
    .expect("spec");
    seaarms_core::Model::from_spec(&spec).expect("model")
}

/// Closed-form ∂TOMM/∂q equals the central difference for every built-in model, a prismatic
/// arm, and several row selections, at deterministic pseudo-random postures.
#[test]
fn closed_form_tomm_gradient_equals_central_differences() {
    use seaarms_core::optimize::tomm_gradient_analytic;
    let mut models = common::all_builtin();
    models.push(stanford());
    let row_sets: [&[usize]; 5] = [
        &[0, 1, 2],
        &[3, 4, 5],
        &[0, 1, 2, 3, 4, 5],
        &[0, 4],
        &[1, 2, 5],
    ];
    let mut seed = 12345u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut checked = 0;
    for model in &models {
        let n = model.dof();
        for rows in row_sets {
            for _ in 0..5 {
                let q: Vec<f64> = model
                    .joints
                    .iter()
                    .map(|j| {
                        if j.is_limited() {
                            j.limits[0] + (0.05 + 0.9 * rnd()) * (j.limits[1] - j.limits[0])
                        } else {
                            -3.0 + 6.0 * rnd()
                        }
                    })
                    .collect();
                let mut data = KinData::new(model);
                tomm(model, &mut data, &q, rows);
                let mut analytic = vec![0.0; n];
                if !tomm_gradient_analytic(model, &data, rows, &mut analytic) {
                    continue; // singular selection (e.g. 6 rows of a 2-joint arm)
                }
                let mut fd = vec![0.0; n];
                let mut scratch = KinData::new(model);
                let mut sq = vec![0.0; n];
                tomm_gradient(model, &mut scratch, &mut sq, &q, rows, &mut fd);
                let scale = fd.iter().fold(1e-3f64, |m, v| m.max(v.abs()));
                for i in 0..n {
                    assert!(
                        (analytic[i] - fd[i]).abs() <= 1e-6 * scale,
                        "{} rows {rows:?} joint {i}: {} vs {}",
                        model.name,
                        analytic[i],
                        fd[i]
                    );
                }
                checked += 1;
            }
        }
    }
    assert!(checked > 100, "{checked}");
}
