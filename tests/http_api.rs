//! Every analysis route over a real socket: success shapes, values against the documents,
//! and every error path (unknown robot, wrong q length, non-finite numbers, malformed JSON,
//! bodies over 64 KiB) answered with a 4xx and a JSON `{"error": ...}` body.

#![allow(clippy::unwrap_used)]

use serde_json::{Value, json};

mod common;
use common::{Server, start};

async fn post(s: &Server, path: &str, body: String) -> (u16, Value) {
    let resp = reqwest::Client::new()
        .post(format!("{}{path}", s.base))
        .header("content-type", "application/json")
        .body(body)
        .send()
        .await
        .unwrap();
    let status = resp.status().as_u16();
    let text = resp.text().await.unwrap();
    let v: Value = serde_json::from_str(&text)
        .unwrap_or_else(|_| panic!("{path} answered non-JSON ({status}): {text}"));
    (status, v)
}

async fn get(s: &Server, path: &str) -> (u16, Value) {
    let resp = reqwest::get(format!("{}{path}", s.base)).await.unwrap();
    let status = resp.status().as_u16();
    (status, resp.json().await.unwrap())
}

fn assert_error(status: u16, body: &Value, expected: u16, needle: &str) {
    assert_eq!(status, expected, "{body}");
    let msg = body["error"]
        .as_str()
        .unwrap_or_else(|| panic!("no error message in {body}"));
    assert!(
        msg.contains(needle),
        "error `{msg}` does not mention `{needle}`"
    );
}

#[tokio::test]
async fn robots_are_listed_and_returned_in_the_inline_schema() {
    let s = start().await;
    let (status, list) = get(&s, "/api/robots").await;
    assert_eq!(status, 200);
    let names: Vec<&str> = list
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["name"].as_str().unwrap())
        .collect();
    for n in ["magnum", "orion", "rx90", "puma560", "pa10", "planar2r"] {
        assert!(names.contains(&n), "{n} missing from {names:?}");
    }
    let (status, magnum) = get(&s, "/api/robots/magnum").await;
    assert_eq!(status, 200);
    assert_eq!(magnum["dh"], "standard");
    assert_eq!(magnum["joints"].as_array().unwrap().len(), 6);
    assert_eq!(magnum["joints"][4]["twist_axis"], "y");
    assert!(magnum["source"].as_str().unwrap().contains("Lim"));
    // The returned spec is itself a valid inline model giving the same analysis.
    let q = json!([0.1, 0.5, -1.0, 0.3, 0.2, 0.1]);
    let (_, by_name) = post(
        &s,
        "/api/analysis",
        json!({"robot": "magnum", "q": q}).to_string(),
    )
    .await;
    let (st, inline) = post(
        &s,
        "/api/analysis",
        json!({"robot": magnum, "q": q}).to_string(),
    )
    .await;
    assert_eq!(st, 200, "{inline}");
    assert_eq!(by_name["jacobian"], inline["jacobian"]);
    let (status, body) = get(&s, "/api/robots/nope").await;
    assert_error(status, &body, 404, "unknown robot");
}

#[tokio::test]
async fn analysis_reproduces_the_rx90_report_and_orion_paper() {
    let s = start().await;
    // RX90 report part VI: σ = 1.8760 1.5290 1.2439 0.5693 0.1521 0, 1-D null space.
    let q = json!([0.2, -0.3, -std::f64::consts::FRAC_PI_2, 0.6, 0.0, 0.7]);
    let (status, a) = post(
        &s,
        "/api/analysis",
        json!({"robot": "rx90", "q": q}).to_string(),
    )
    .await;
    assert_eq!(status, 200, "{a}");
    let sv: Vec<f64> = a["measures"]["full"]["singular_values"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    for (x, p) in sv.iter().zip([1.8760, 1.5290, 1.2439, 0.5693, 0.1521, 0.0]) {
        assert!((x - p).abs() < 5e-5, "{sv:?}");
    }
    assert_eq!(
        a["measures"]["full"]["condition_number"],
        Value::Null,
        "infinite → null"
    );
    assert_eq!(a["measures"]["full"]["force_manipulability"], Value::Null);
    assert_eq!(a["null_space"].as_array().unwrap().len(), 1);
    assert_eq!(a["jacobian"].as_array().unwrap().len(), 6);
    // Jun 2008 §2.2: TMM 0.41, JLM 0.09; task rows = translational.
    let q: Vec<f64> = [-15.3f64, 49.6, -31.0, 75.5, 85.2, -18.0]
        .iter()
        .map(|d| d.to_radians())
        .collect();
    let (status, a) = post(
        &s,
        "/api/analysis",
        json!({"robot": "orion", "q": q, "rows": [0, 1, 2]}).to_string(),
    )
    .await;
    assert_eq!(status, 200, "{a}");
    let tmm = a["measures"]["task"]["yoshikawa"].as_f64().unwrap();
    assert!((tmm - 0.41).abs() < 0.005, "TMM {tmm}");
    assert_eq!(
        a["measures"]["task"]["yoshikawa"],
        a["measures"]["translational"]["yoshikawa"]
    );
    assert!((a["jlm"].as_f64().unwrap() - 0.09).abs() < 0.005);
    let e = &a["measures"]["translational"]["ellipsoid"];
    assert_eq!(e["radii"].as_array().unwrap().len(), 3);
    assert_eq!(e["axes"].as_array().unwrap().len(), 3);
    let vol = e["volume"].as_f64().unwrap();
    assert!(
        (vol - 4.0 / 3.0 * std::f64::consts::PI * tmm).abs() < 1e-9,
        "eq. 2.18: c_3·w"
    );
    let pos = a["pose"]["position"].as_array().unwrap();
    assert_eq!(pos.len(), 3);
}

#[tokio::test]
async fn velocity_polytope_is_returned_when_asked() {
    let s = start().await;
    let q = json!([0.0, 0.785, 0.0, 0.785, 0.0, 0.785, 0.0]);
    let (status, a) = post(
        &s,
        "/api/analysis",
        json!({"robot": "pa10", "q": q, "polytope": true}).to_string(),
    )
    .await;
    assert_eq!(status, 200, "{a}");
    let p = &a["polytope"];
    assert!(p["vertices"].as_array().unwrap().len() >= 8);
    assert!(!p["facets"].as_array().unwrap().is_empty());
    let (v, w) = (p["volume"].as_f64().unwrap(), p["w_p"].as_f64().unwrap());
    assert!(
        v > 0.0 && (v - w).abs() < 1e-9 * v,
        "Kilic eq. 1.54 with d_n = n!: w_p = volume"
    );
    let (_, without) = post(
        &s,
        "/api/analysis",
        json!({"robot": "pa10", "q": q}).to_string(),
    )
    .await;
    assert!(without.get("polytope").is_none());
}

#[tokio::test]
async fn dual_analysis_of_identical_parallel_arms() {
    let s = start().await;
    // Lim §4.3.2.1: identical parallel arms → dual isotropy equals the single arm's; the
    // dual ellipsoid volume is 2^(-3/2) of one arm's (every radius / √2).
    let q = json!([0.0, 0.6, -1.2, 0.4, 0.0, 0.0]);
    let arm = |y: f64| json!({"robot": "magnum", "q": q, "base": {"position": [0.0, y, 0.0], "rotation": [[1,0,0],[0,1,0],[0,0,1]]}});
    let (status, d) = post(
        &s,
        "/api/analysis/dual",
        json!({"arms": [arm(0.0), arm(1.0)], "polytope": true}).to_string(),
    )
    .await;
    assert_eq!(status, 200, "{d}");
    let single = &d["arms"][0]["translational"];
    let dual = &d["translational"];
    let ratio = dual["ellipsoid"]["volume"].as_f64().unwrap()
        / single["ellipsoid"]["volume"].as_f64().unwrap();
    assert!((ratio - 2f64.powf(-1.5)).abs() < 1e-9, "{ratio}");
    assert!(
        (dual["isotropy"].as_f64().unwrap() - single["isotropy"].as_f64().unwrap()).abs() < 1e-9
    );
    let y1 = d["arms"][1]["pose"]["position"][1].as_f64().unwrap();
    let y0 = d["arms"][0]["pose"]["position"][1].as_f64().unwrap();
    assert!((y1 - y0 - 1.0).abs() < 1e-12, "bases 1 m apart");
    // Intersection of two identical polytopes is the polytope itself.
    let (_, one) = post(
        &s,
        "/api/analysis",
        json!({"robot": "magnum", "q": q, "polytope": true}).to_string(),
    )
    .await;
    let v1 = one["polytope"]["volume"].as_f64().unwrap();
    let vd = d["polytope"]["volume"].as_f64().unwrap();
    assert!((v1 - vd).abs() < 1e-9 * v1, "{v1} vs {vd}");
}

#[tokio::test]
async fn bad_input_gets_a_clear_json_error() {
    let s = start().await;
    let cases: Vec<(&str, String, u16, &str)> = vec![
        ("/api/analysis", r#"{"robot": "magnum", "q": [0, 0"#.into(), 400, "malformed JSON"),
        ("/api/analysis", "not json".into(), 400, "malformed JSON"),
        ("/api/analysis", json!({"robot": "nope", "q": [0]}).to_string(), 404, "unknown robot"),
        ("/api/analysis", json!({"robot": "magnum", "q": [0, 0, 0]}).to_string(), 400, "3 entries, 6 required"),
        ("/api/analysis", r#"{"robot": "magnum", "q": [0, 0, 0, 0, 0, NaN]}"#.into(), 400, "malformed JSON"),
        ("/api/analysis", r#"{"robot": "magnum", "q": [0, 0, 0, 0, 0, 1e999]}"#.into(), 400, "out of range"),
        ("/api/analysis", json!({"robot": "magnum", "q": [0, 0, 0, 0, 0, 1e300]}).to_string(), 400, "out of range"),
        ("/api/analysis", json!({"robot": "magnum", "q": [0, 0, 0, 0, 0, "x"]}).to_string(), 400, "q[5]"),
        ("/api/analysis", json!({"robot": "magnum", "q": [0, 0, 0, 0, 0, 0], "rows": [0, 9]}).to_string(), 400, "row 9"),
        ("/api/analysis", json!({"robot": "magnum", "q": [0, 0, 0, 0, 0, 0], "rows": [1, 1]}).to_string(), 400, "repeated"),
        ("/api/analysis", json!({"robot": "magnum", "q": [0, 0, 0, 0, 0, 0], "extra": 1}).to_string(), 400, "extra"),
        ("/api/analysis", json!({"robot": 5, "q": [0]}).to_string(), 400, "robot"),
        ("/api/analysis", json!({"robot": {"name": "x", "dh": "standard", "joints": []}, "q": []}).to_string(), 400, "at least one joint"),
        ("/api/analysis", json!({"robot": {"name": "x", "dh": "sideways", "joints": []}, "q": []}).to_string(), 400, "robot.dh"),
        ("/api/analysis", json!({"robot": {"name": "x", "dh": "standard", "joints": [{"type": "revolute", "limits": [1, -1]}]}, "q": [0]}).to_string(), 400, "lo < hi"),
        ("/api/analysis/dual", json!({"arms": []}).to_string(), 400, "exactly 2"),
        ("/api/analysis/dual", json!({"arms": [{"robot": "magnum", "q": [0,0.5,-1,0,0,0]}, {"robot": "magnum", "q": [0,0.5,-1,0,0,0], "base": {"position": [0,1,0], "rotation": [[2,0,0],[0,1,0],[0,0,1]]}}]}).to_string(), 400, "proper rotation"),
        ("/api/analysis/dual", json!({"arms": [{"robot": "magnum", "q": [0]}, {"robot": "magnum", "q": [0,0.5,-1,0,0,0]}]}).to_string(), 400, "arms[0]"),
    ];
    for (path, body, status, needle) in cases {
        let (st, v) = post(&s, path, body.clone()).await;
        assert_eq!(st, status, "{path} {body} → {v}");
        assert_error(st, &v, status, needle);
    }
    // Body over 64 KiB → 413 with a JSON error.
    let big = format!(
        r#"{{"robot": "magnum", "q": [0,0,0,0,0,0], "pad": "{}"}}"#,
        "x".repeat(70 * 1024)
    );
    let (st, v) = post(&s, "/api/analysis", big).await;
    assert_error(st, &v, 413, "larger than");
    // Unknown route → 404 JSON.
    let (st, v) = get(&s, "/api/nothing").await;
    assert_error(st, &v, 404, "no route");
    // The server still answers after all of that.
    let (st, _) = post(
        &s,
        "/api/analysis",
        json!({"robot": "planar2r", "q": [0.1, 1.0]}).to_string(),
    )
    .await;
    assert_eq!(st, 200);
}

/// Jun §3 over HTTP: the optimal posture reaches the target (violation ≤ 1e-6 m) and a
/// target outside the workspace is a 422 that says so; studies and the workspace map answer.
#[tokio::test]
async fn optimal_posture_and_studies() {
    let s = start().await;
    // ORION at the paper's example posture: its tool point is the target.
    let q: Vec<f64> = [-15.3f64, 49.6, -31.0, 75.5, 85.2, -18.0]
        .iter()
        .map(|d| d.to_radians())
        .collect();
    let (_, a) = post(
        &s,
        "/api/analysis",
        json!({"robot": "orion", "q": q}).to_string(),
    )
    .await;
    let target = a["pose"]["position"].clone();
    let (st, p) = post(
        &s,
        "/api/optimal-posture",
        json!({"robot": "orion", "target_position": target, "alpha": 0.0}).to_string(),
    )
    .await;
    assert_eq!(st, 200, "{p}");
    assert!(p["constraint_violation_m"].as_f64().unwrap() <= 1e-6);
    assert!(
        p["jlm"].as_f64().unwrap() > 0.09,
        "JLM-optimal beats the example posture's 0.09 (Jun Fig. 4c: 0.33)"
    );
    let (st, e) = post(
        &s,
        "/api/optimal-posture",
        json!({"robot": "orion", "target_position": [3, 0, 0], "alpha": 0.5}).to_string(),
    )
    .await;
    assert_error(st, &e, 422, "outside the workspace");
    let (st, e) = post(
        &s,
        "/api/optimal-posture",
        json!({"robot": "orion", "target_position": [0.5, 0, 0], "alpha": 2}).to_string(),
    )
    .await;
    assert_error(st, &e, 400, "alpha");
    let (st, list) = get(&s, "/api/studies").await;
    assert_eq!(st, 200);
    assert!(
        list.as_array()
            .unwrap()
            .iter()
            .any(|x| x["name"] == "dual-distance")
    );
    let (st, d) = post(&s, "/api/studies/dual-distance", "".into()).await;
    assert_eq!(st, 200, "{d}");
    // Rows marked unreachable carry no numbers (issue 17 item 4): the dual pitch/yaw study
    // has unreachable rows at the thesis's points.
    let (st, d) = post(&s, "/api/studies/dual-pitch-yaw", "".into()).await;
    assert_eq!(st, 200, "{d:.300}");
    let rows = d["rows"].as_array().unwrap();
    let unreachable: Vec<&Value> = rows.iter().filter(|r| r["reachable"] == false).collect();
    assert!(!unreachable.is_empty());
    for r in unreachable {
        for key in [
            "yoshikawa",
            "isotropy",
            "hong",
            "left_yoshikawa",
            "left_isotropy",
            "left_hong",
            "dual_yoshikawa",
            "dual_isotropy",
            "dual_hong",
            "distance_m",
            "q",
            "q_left",
        ] {
            assert!(
                r[key].is_null(),
                "unreachable row with {key} = {}: {r}",
                r[key]
            );
        }
    }
    assert!(
        rows.iter()
            .any(|r| r["reachable"] == true && r["dual_yoshikawa"].is_number())
    );
    let (st, e) = post(&s, "/api/studies/nope", "".into()).await;
    assert_error(st, &e, 404, "unknown study");
}

#[tokio::test]
async fn page_and_health_are_served() {
    let s = start().await;
    let resp = reqwest::get(format!("{}/", s.base)).await.unwrap();
    assert_eq!(resp.status().as_u16(), 200);
    assert!(
        resp.headers()["content-type"]
            .to_str()
            .unwrap()
            .starts_with("text/html")
    );
    assert!(resp.text().await.unwrap().contains("seaarms"));
    let resp = reqwest::get(format!("{}/healthz", s.base)).await.unwrap();
    assert_eq!(resp.status().as_u16(), 200);
}

/// Kilic Fig. 4.2 over HTTP: the planar 2R arm's velocity polytope for the task rows vx, vy is
/// the parallelogram spanned by ±j₁ and ±j₂ (unit joint rates), area 4·l1·l2·|sin q2| (the
/// closed form: |det J| = l1·l2·|sin q2| for the planar 2R Jacobian, times the 2×2 box's area
/// 4), with four corners; its cone-cell index equals the area (the origin is inside). With
/// joint-limit rates (here also 1 rad/s) it is the same; for a row set that is not planar
/// the 3-D polytope of a planar arm is flat and refused, as before.
#[tokio::test]
async fn the_planar_2r_polytope_is_kilics_parallelogram() {
    let s = start().await;
    let (l1, l2) = (1.0, 1.0);
    for (q1, q2) in [(0.1, 1.0), (-0.7, 2.3), (1.2, -0.4)] {
        for rates in ["unit", "limits"] {
            let (st, v) = post(
                &s,
                "/api/analysis",
                json!({"robot": "planar2r", "q": [q1, q2], "rows": [0, 1], "polytope": true,
                       "polytope_rates": rates})
                .to_string(),
            )
            .await;
            assert_eq!(st, 200, "{v}");
            let p = &v["polytope"];
            let area = 4.0 * l1 * l2 * f64::sin(q2).abs();
            let got = p["volume"].as_f64().unwrap();
            assert!((got - area).abs() < 1e-9 * area.max(1.0), "{got} vs {area}");
            assert!(
                (p["w_p"].as_f64().unwrap() - area).abs() < 1e-9,
                "{}",
                p["w_p"]
            );
            let verts = p["vertices"].as_array().unwrap();
            assert_eq!(verts.len(), 4, "a parallelogram: {verts:?}");
            // Its corners are ±j₁ ± j₂ (Jacobian columns from the same answer).
            let j = &v["jacobian"];
            for v in verts {
                let (x, y) = (v[0].as_f64().unwrap(), v[1].as_f64().unwrap());
                let hit = [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)]
                    .iter()
                    .any(|(a, b)| {
                        let cx = a * j[0][0].as_f64().unwrap() + b * j[0][1].as_f64().unwrap();
                        let cy = a * j[1][0].as_f64().unwrap() + b * j[1][1].as_f64().unwrap();
                        (cx - x).abs() < 1e-12 && (cy - y).abs() < 1e-12
                    });
                assert!(hit, "corner ({x}, {y}) is not ±j1 ± j2");
            }
        }
    }
    let (st, v) = post(
        &s,
        "/api/analysis",
        json!({"robot": "planar2r", "q": [0.1, 1.0], "polytope": true, "polytope_rates": "fast"})
            .to_string(),
    )
    .await;
    assert_eq!(st, 400, "{v}");
}
