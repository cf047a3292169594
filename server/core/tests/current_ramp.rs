//! The instructor's current ramps (issue 27, item 3): after `set_current` the water's motion
//! follows the critically damped second-order lag of `sim::water` (τ = 1.5 s) — checked
//! against its closed form u(t) = Δu·(1 − (1 + t/τ)·e^(−t/τ)) — and while it accelerates the
//! Morison inertia force (1 + C_A)ρV·u̇ (DNV-RP-C205 (2010) eq. 6.1, C_M = 1 + C_A) carries a
//! free box along: with drag negligible early in the ramp, (m + C_AρV)·v̇ = (1 + C_A)ρV·u̇, so
//! the box moves at v = (1 + C_A)ρV/(m + C_AρV)·u (Newman (1977) §4.13: a body in an
//! accelerating stream).

mod common;

use seaarms_core::sim::water::{BOX_ADDED_MASS, CURRENT_TIME_CONSTANT_S, SEA_WATER_DENSITY_KGM3};
use seaarms_core::sim::{Current, Environment, Input, SimParams, Simulation, Water};

/// Sea water at rest, the box hung far above a deep seabed (it falls freely; the arms stay
/// clear of it), as in `water.rs`.
fn free_box() -> Simulation {
    let m = common::builtin("magnum");
    let mut p = SimParams::training(&m, &m).expect("params");
    p.step.environment = Environment::Subsea(Water::default());
    p.object.seabed_z_m = -1.0e4;
    Simulation::new(m.clone(), m, p).expect("sim")
}

/// The lag's closed form for a step Δu at t = 0 from rest: velocity and acceleration.
fn closed_form(du: f64, t: f64) -> (f64, f64) {
    let tau = CURRENT_TIME_CONSTANT_S;
    let e = (-t / tau).exp();
    (du * (1.0 - (1.0 + t / tau) * e), du * t / (tau * tau) * e)
}

#[test]
fn the_current_ramps_as_the_closed_form() {
    let mut sim = free_box();
    sim.set_current(Current::new(2.5, 90.0).expect("current"))
        .expect("water");
    // Nothing moves before the next step.
    assert_eq!(sim.flow().expect("water").velocity_m_s.norm(), 0.0);
    let input = Input::default();
    let mut worst = 0.0_f64;
    let mut last_acc = 0.0;
    let mut peak_acc = 0.0_f64;
    for k in 1..=15_000 {
        sim.step(&input);
        let t = k as f64 * 1e-3;
        let f = sim.flow().expect("water");
        let (u, a) = closed_form(2.5, t);
        // Heading 90°: along +y.
        assert!(f.velocity_m_s.x.abs() < 1e-12 && f.velocity_m_s.z == 0.0);
        worst = worst.max((f.velocity_m_s.y - u).abs() / 2.5);
        assert!((f.acceleration_m_s2.y - a).abs() < 0.01 * 2.5 / CURRENT_TIME_CONSTANT_S);
        // u̇ continuous (no step at the start): it changes per step by at most the largest
        // jerk of the lag, Δu/τ² (at t = 0), times dt: 1.1·10⁻³ m/s².
        let jerk = 2.5 / (CURRENT_TIME_CONSTANT_S * CURRENT_TIME_CONSTANT_S);
        assert!((f.acceleration_m_s2.y - last_acc).abs() <= 1.0001 * jerk * 1e-3);
        last_acc = f.acceleration_m_s2.y;
        peak_acc = peak_acc.max(last_acc);
        assert!(f.velocity_m_s.y <= 2.5, "no overshoot");
    }
    println!("largest deviation from the closed form: {worst:.2e} of the step");
    assert!(worst < 5e-3);
    // Peak u̇ = Δu/(e·τ) at t = τ.
    let expect = 2.5 / (std::f64::consts::E * CURRENT_TIME_CONSTANT_S);
    assert!(
        (peak_acc - expect).abs() < 0.01 * expect,
        "{peak_acc} vs {expect}"
    );
    // 10–90 % within 5.0 s (3.36·τ) and 99.9 % of the way after 15 s.
    assert!(sim.flow().expect("water").velocity_m_s.y > 0.999 * 2.5);
    // A reset starts with the set current flowing steadily.
    sim.reset();
    let f = sim.flow().expect("water");
    assert!((f.velocity_m_s.y - 2.5).abs() < 1e-12 && f.acceleration_m_s2.norm() == 0.0);
    let m = common::builtin("magnum");
    let air = Simulation::new(
        m.clone(),
        m,
        SimParams::case_study(&common::builtin("magnum"), &common::builtin("magnum"))
            .expect("params"),
    )
    .expect("sim");
    assert!(air.flow().is_none());
}

#[test]
fn the_accelerating_current_carries_a_free_box_by_its_inertia_force() {
    let mut sim = free_box();
    let op = sim.params().object;
    let rho = SEA_WATER_DENSITY_KGM3;
    let v = op.size_m.x * op.size_m.y * op.size_m.z;
    let ratio = (1.0 + BOX_ADDED_MASS) * rho * v / (op.mass_kg + BOX_ADDED_MASS * rho * v);
    sim.set_current(Current::new(2.5, 0.0).expect("current"))
        .expect("water");
    let input = Input::default();
    for _ in 0..500 {
        sim.step(&input);
    }
    let u = sim.flow().expect("water").velocity_m_s.x;
    let vx = sim.object().velocity.x;
    println!(
        "t = 0.5 s: current {u:.4} m/s, box {vx:.4} m/s, (1+C_A)ρV/(m+C_AρV)·u = {:.4} m/s",
        ratio * u
    );
    // Drag on the relative speed (≈ 0.04 m/s) is < 1 % of the inertia force at 0.5 s.
    assert!(
        (vx - ratio * u).abs() < 0.02 * ratio * u,
        "{vx} vs {}",
        ratio * u
    );
}
