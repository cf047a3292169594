//! The live state frame's manipulability ellipsoid is the one `POST /api/analysis` gives at
//! the same joint angles: the frame's radii (world frame) equal the analysis's translational
//! ellipsoid radii (base frame), and its axes, rotated into the base frame, span the same
//! directions (Lim eq. 3.62: the ellipsoid of the translational rows of J). Two independent
//! paths through the server: the physics worker's frame and the analysis route.

#![allow(clippy::unwrap_used)]

mod common;

use std::time::Duration;

use common::*;
use serde_json::{Value, json};

/// 3×3 rotation from a `PoseOut`'s row-major `rotation`.
fn rotation(pose: &Value) -> [[f64; 3]; 3] {
    let r = &pose["rotation"];
    std::array::from_fn(|i| std::array::from_fn(|j| r[i][j].as_f64().unwrap()))
}

fn vec3(v: &Value) -> [f64; 3] {
    std::array::from_fn(|i| v[i].as_f64().unwrap())
}

/// Rᵀ·v: a world-frame direction in the base frame.
fn to_base(r: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|j| (0..3).map(|i| r[i][j] * v[i]).sum())
}

#[tokio::test]
async fn the_state_frames_ellipsoid_is_the_analysis_routes_at_the_same_angles() {
    let s = start().await;
    let (id, token) = new_session(&s).await;
    // The trainee's own connection: its `hello` carries the models with their bases.
    let mut ws = connect(&s, &id, &format!("token={token}")).await.unwrap();
    let hello = next_of(&mut ws, "hello", Duration::from_secs(5)).await;
    // Both bases are translations along y today, but the check rotates by whatever they are.
    let bases = [
        rotation(&hello["arms"][0]["base"]),
        rotation(&hello["arms"][1]["base"]),
    ];
    // Move both arms off the reset posture (swing, shoulder, elbow) so the check is not at
    // one special posture.
    let axes = json!({"axes": [0.6, -0.5, 0.7, 0.0, 0.0, 0.0]});
    hold_sticks(&mut ws, 1, 25, json!({"left": axes, "right": axes})).await;
    hold_sticks(&mut ws, 26, 3, json!({})).await;
    let frame = next_of(&mut ws, "state", Duration::from_secs(5)).await;
    let client = reqwest::Client::new();
    for (k, side) in ["left", "right"].into_iter().enumerate() {
        let arm = &frame["arms"][side];
        let q = &arm["q"];
        assert!(
            q.as_array()
                .unwrap()
                .iter()
                .any(|v| v.as_f64().unwrap().abs() > 0.05),
            "{side} arm still at the reset posture: {q}"
        );
        let body: Value = client
            .post(format!("{}/api/analysis", s.base))
            .json(&json!({"robot": "magnum", "q": q}))
            .send()
            .await
            .unwrap()
            .json()
            .await
            .unwrap();
        let e = &body["measures"]["translational"]["ellipsoid"];
        let mut want: Vec<(f64, [f64; 3])> = (0..3)
            .map(|i| (e["radii"][i].as_f64().unwrap(), vec3(&e["axes"][i])))
            .collect();
        want.sort_by(|a, b| b.0.total_cmp(&a.0));
        let got_e = &arm["ellipsoid"];
        let mut got: Vec<(f64, [f64; 3])> = (0..3)
            .map(|i| {
                let axis = to_base(&bases[k], vec3(&got_e["axes"][i]));
                (got_e["radii"][i].as_f64().unwrap(), axis)
            })
            .collect();
        got.sort_by(|a, b| b.0.total_cmp(&a.0));
        for ((rg, ag), (rw, aw)) in got.iter().zip(&want) {
            assert!(
                (rg - rw).abs() <= 1e-9 * rw.max(1e-3),
                "{side}: radius {rg} in the frame, {rw} from /api/analysis"
            );
            // Axes are defined up to sign: |a·b| = 1 for the same direction.
            let dot: f64 = ag.iter().zip(aw).map(|(a, b)| a * b).sum();
            assert!(
                (dot.abs() - 1.0).abs() < 1e-6,
                "{side}: axis {ag:?} in the frame (base frame), {aw:?} from /api/analysis"
            );
        }
        // Same posture, same Yoshikawa measure (√det JJᵀ = σ₁σ₂σ₃).
        let yg = arm["measures"]["yoshikawa"].as_f64().unwrap();
        let yw = body["measures"]["translational"]["yoshikawa"]
            .as_f64()
            .unwrap();
        assert!(
            (yg - yw).abs() <= 1e-9 * yw,
            "{side}: yoshikawa {yg} vs {yw}"
        );
    }
    s.stop().await;
}
