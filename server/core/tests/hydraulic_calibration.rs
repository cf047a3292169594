//! Hydraulic actuators calibrated against Lim Table 1-1: full valve command moves each
//! unloaded joint at its nominal speed (20/20/30/30/30/150 °/s) within ±15 %; at full extension
//! the arm holds 295 kg at the jaw at nominal (6.89 MPa) pressure, and cannot hold twice that
//! because the relief valves limit the line pressure.

mod common;

use seaarms_core::hydraulics::{MAGNUM_FULL_EXTENSION, MAGNUM_SPEEDS_DEG_S};
use seaarms_core::sim::{Arm, Input, SimParams, Simulation};

fn sim_with(q: [f64; 6], payload_kg: f64) -> Simulation {
    let m = common::builtin("magnum");
    let mut p = SimParams::case_study(&m, &m).expect("params");
    p.arms[Arm::Left.index()].initial_q = q;
    if payload_kg > 0.0 {
        let tool = m.flange.transform_point(&m.tool.into()).coords;
        let l = p.arms[Arm::Left.index()].inertials.links[5];
        p.arms[Arm::Left.index()].inertials.links[5] = l.with_point_mass(&tool, payload_kg);
    }
    Simulation::new(m.clone(), m, p).expect("sim")
}

/// Mid-range posture (shoulder 45° and elbow −65°: the middles of their ranges).
const MID: [f64; 6] = [0.0, std::f64::consts::FRAC_PI_4, -1.1345, 0.0, 0.0, 0.0];

#[test]
fn full_command_gives_nominal_speed_within_15_percent() {
    for (j, &nominal) in MAGNUM_SPEEDS_DEG_S.iter().enumerate() {
        for dir in [1.0, -1.0] {
            let mut s = sim_with(MID, 0.0);
            let mut inp = Input::default();
            inp.arms[Arm::Left.index()].valves[j] = dir;
            let mut q0 = 0.0;
            for k in 0..600 {
                s.step(&inp);
                if k == 199 {
                    q0 = s.arm(Arm::Left).q[j];
                }
            }
            let speed = ((s.arm(Arm::Left).q[j] - q0) / 0.4).to_degrees();
            println!(
                "joint {} dir {dir:+}: {speed:.2} °/s (nominal {nominal})",
                j + 1
            );
            assert!(
                (speed * dir - nominal).abs() <= 0.15 * nominal,
                "joint {} dir {dir}: {speed} °/s vs {nominal}",
                j + 1
            );
        }
    }
}

/// Holds the full-extension posture with the joint servo (q̇_ref = 0) for 5 s; returns the jaw
/// drop (m), the peak line pressure (Pa) and the relief events.
fn hold(payload_kg: f64) -> (f64, f64, u64, f64) {
    let mut s = sim_with(MAGNUM_FULL_EXTENSION, payload_kg);
    let z0 = s.end_effector(Arm::Left).translation.z;
    let mut inp = Input::default();
    inp.arms[Arm::Left.index()].joint_velocity_ref = Some([0.0; 6]);
    let mut peak: f64 = 0.0;
    for _ in 0..5000 {
        s.step(&inp);
        let a = s.arm(Arm::Left);
        for j in 0..6 {
            peak = peak.max(a.p_in[j]).max(a.p_out[j]);
        }
    }
    let relief = s.params().arms[Arm::Left.index()].hydraulics.relief_pa;
    (
        z0 - s.end_effector(Arm::Left).translation.z,
        peak,
        s.arm(Arm::Left).relief_events,
        relief,
    )
}

#[test]
fn holds_295_kg_at_full_extension_within_supply_pressure() {
    let (drop, peak, events, _) = hold(295.0);
    println!("295 kg: drop {drop:.5} m, peak {peak:.0} Pa, relief events {events}");
    assert!(drop.abs() < 0.005, "jaw dropped {drop} m");
    assert!(
        peak <= 6.89e6 * 1.001,
        "peak line pressure {peak} above supply"
    );
    assert_eq!(events, 0);
}

#[test]
fn cannot_hold_590_kg_relief_limits_pressure() {
    let (drop, peak, events, relief) = hold(590.0);
    println!(
        "590 kg: drop {drop:.4} m, peak {peak:.0} Pa (relief {relief:.0}), relief events {events}"
    );
    assert!(drop > 0.05, "jaw dropped only {drop} m");
    assert!(events > 0);
    assert!(
        peak <= relief * 1.02,
        "peak {peak} Pa above relief setting {relief}"
    );
}
