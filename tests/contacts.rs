//! A solid world over real sockets (issue 27's acceptance, "the contact force and the strike
//! event are in the frames and the record; the line pressures show it"): the trainee lowers
//! the left shoulder at full stick from the start posture (jaw about 11 cm above the seabed,
//! `sim::INITIAL_Q`); the seabed stops the jaw. The frames then carry the arm's touch
//! (partner `seabed`, a normal force the stall pushes far above the jaw's weight), one
//! strike, and the wrist-pitch actuator's pressure difference near the supply pressure (a
//! stalled valve at full opening connects one side to supply and the other to tank: the
//! orifice law with no flow, Lim eq. 3.51). The strike event in the record is checked on the
//! headless path in tests/exercises.rs.

#![allow(clippy::unwrap_used)]

mod common;

use std::time::Duration;

use common::*;
use serde_json::json;

#[tokio::test]
async fn a_jaw_driven_into_the_seabed_shows_its_touch_strike_and_pressures_in_the_frames() {
    let s = start().await;
    let (id, token) = new_session(&s).await;
    let mut ws = connect(&s, &id, &format!("token={token}")).await.unwrap();
    let hello = next_of(&mut ws, "hello", Duration::from_secs(5)).await;
    let seabed = hello["seabed_z_m"].as_f64().unwrap();
    let first = next_of(&mut ws, "state", Duration::from_secs(5)).await;
    assert!(
        first["arms"]["left"]["touch"].is_null(),
        "touches at the start"
    );
    assert_eq!(first["arms"]["left"]["strikes"], 0);
    // 3 s of full stick on the shoulder (joint 2), downwards.
    let axes = json!({"axes": [0.0, -1.0, 0.0, 0.0, 0.0, 0.0]});
    hold_sticks(&mut ws, 1, 75, json!({"left": axes})).await;
    let t0 = first["t"].as_f64().unwrap();
    let f = state_after(&mut ws, t0 + 2.9).await;
    let arm = &f["arms"]["left"];
    let touch = &arm["touch"];
    assert_eq!(touch["partner"], "seabed", "{arm}");
    let force = touch["total_force_n"].as_f64().unwrap();
    // The jaw and the wrist links weigh tens of newtons; a stalled shoulder presses with
    // hundreds (collisions.rs measures the same stall in the core).
    assert!(force > 100.0, "{touch}");
    let point = touch["point_m"].as_array().unwrap();
    let z = point[2].as_f64().unwrap();
    assert!(
        z > seabed - 0.01 && z < seabed + 0.01,
        "contact at z {z}, seabed {seabed}"
    );
    assert!(touch["depth_m"].as_f64().unwrap() < 0.01);
    assert_eq!(arm["strikes"], 1, "{arm}");
    let dp = arm["p_out"][1].as_f64().unwrap() - arm["p_in"][1].as_f64().unwrap();
    let supply = 6.89e6; // Lim Table 1-1 operating pressure (server/core HydraulicParams)
    assert!(dp.abs() > 0.8 * supply, "shoulder Δp {dp} Pa");
    // The other arm touches nothing.
    assert!(f["arms"]["right"]["touch"].is_null());
    s.stop().await;
}
