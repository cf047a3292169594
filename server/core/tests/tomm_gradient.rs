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
