//! A keyboard tap is a jog (issue 28 item 2: "keyboard taps move a bounded, repeatable amount
//! at every arm speed"): the operator takes a target from the state when the tap comes
//! (`sim::Operator::jog`) and the servo takes the arm there, whatever the tap's length. Ten
//! taps on every axis at 25 % and 100 % arm speed each move the commanded amount —
//! `JOG_JOINT_RAD` of one joint in joint mode, `JOG_LINEAR_M` along or `JOG_ANGLE_RAD` about a
//! world axis at the jaw in Cartesian mode, times the speed — within 0.5°/0.5 cm of each
//! other (the acceptance's spread), measured by forward kinematics of the reached states.

mod common;

use nalgebra::Vector3;
use seaarms_core::sim::{
    Arm, ControlMode, JOG_ANGLE_RAD, JOG_JOINT_RAD, JOG_LINEAR_M, Operator, SimParams, Simulation,
};

fn setup(mode: ControlMode, speed: f64) -> (Operator, Simulation) {
    let m = common::builtin("magnum");
    let p = SimParams::training(&m, &m).expect("params");
    let mut op = Operator::new(&m, &m);
    op.set_mode(mode);
    op.set_speed(speed);
    (op, Simulation::new(m.clone(), m, p).expect("sim"))
}

/// Taps `axis` in direction `sign` ten times, each followed by the jog's end and 0.2 s of
/// rest; returns `measure` of each tap's before and after.
fn ten_taps<T>(
    op: &mut Operator,
    sim: &mut Simulation,
    axis: usize,
    sign: f64,
    measure: impl Fn(&Simulation, &Simulation) -> T,
) -> Vec<T> {
    let mut out = Vec::new();
    let mut axes = [0.0; 6];
    axes[axis] = sign;
    for tap in 0..10 {
        let before = sim.clone();
        op.jog(sim, Arm::Left, &axes);
        assert!(op.jogging(Arm::Left));
        let mut k = 0;
        while op.jogging(Arm::Left) {
            op.step(sim);
            k += 1;
            assert!(k < 3_000, "axis {axis}, tap {tap}: the jog did not end");
        }
        for _ in 0..200 {
            op.step(sim);
        }
        out.push(measure(&before, sim));
    }
    assert_eq!(sim.numerical_faults(), 0);
    out
}

fn spread(v: &[f64]) -> (f64, f64) {
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    let max = v.iter().cloned().fold(f64::MIN, f64::max);
    let min = v.iter().cloned().fold(f64::MAX, f64::min);
    (mean, max - min)
}

#[test]
fn joint_taps_turn_their_joint_by_a_repeatable_amount() {
    for speed in [0.25, 1.0] {
        for j in 0..6 {
            let (mut op, mut sim) = setup(ControlMode::Joint, speed);
            let d = ten_taps(&mut op, &mut sim, j, 1.0, |a, b| {
                let (qa, qb) = (a.arm(Arm::Left).q, b.arm(Arm::Left).q);
                let others = (0..6)
                    .filter(|k| *k != j)
                    .map(|k| (qb[k] - qa[k]).abs())
                    .fold(0.0, f64::max);
                ((qb[j] - qa[j]).to_degrees(), others.to_degrees())
            });
            let turned: Vec<f64> = d.iter().map(|x| x.0).collect();
            let (mean, sp) = spread(&turned);
            let others = d.iter().map(|x| x.1).fold(0.0, f64::max);
            println!(
                "speed {speed}, joint {}: {mean:.3}° per tap, spread {sp:.4}°, others ≤ {others:.3}°",
                j + 1
            );
            let want = (JOG_JOINT_RAD * speed).to_degrees();
            assert!(
                (mean - want).abs() < 0.1 * want,
                "joint {j}: {mean}° vs {want}°"
            );
            assert!(sp < 0.5, "joint {j}: spread {sp}°");
            assert!(others < 0.1, "joint {j}: the others moved {others}°");
        }
    }
}

#[test]
fn cartesian_taps_move_the_jaw_by_a_repeatable_amount() {
    for speed in [0.25, 1.0] {
        // Up, back, sideways (linear); about x, y, z (angular).
        for (axis, sign) in [(2, 1.0), (0, -1.0), (1, 1.0), (3, 1.0), (4, -1.0), (5, 1.0)] {
            let (mut op, mut sim) = setup(ControlMode::Cartesian, speed);
            let d = ten_taps(&mut op, &mut sim, axis, sign, |a, b| {
                let (pa, pb) = (a.end_effector(Arm::Left), b.end_effector(Arm::Left));
                let dp = pb.translation.vector - pa.translation.vector;
                let rot = (pb.rotation * pa.rotation.inverse()).scaled_axis();
                let e = Vector3::from_fn(|r, _| if r == axis % 3 { sign } else { 0.0 });
                if axis < 3 {
                    (dp.dot(&e), (dp - e * dp.dot(&e)).norm(), rot.norm())
                } else {
                    (rot.dot(&e), (rot - e * rot.dot(&e)).norm(), dp.norm())
                }
            });
            let along: Vec<f64> = d.iter().map(|x| x.0).collect();
            let (mean, sp) = spread(&along);
            let off = d.iter().map(|x| x.1.max(0.0)).fold(0.0, f64::max);
            let other = d.iter().map(|x| x.2).fold(0.0, f64::max);
            if axis < 3 {
                println!(
                    "speed {speed}, linear {axis}: {:.2} mm per tap, spread {:.3} mm, off-axis ≤ {:.3} mm, turned ≤ {:.3}°",
                    mean * 1e3,
                    sp * 1e3,
                    off * 1e3,
                    other.to_degrees()
                );
                let want = JOG_LINEAR_M * speed;
                assert!(
                    (mean - want).abs() < 0.1 * want,
                    "axis {axis}: {mean} vs {want}"
                );
                assert!(sp < 0.005, "axis {axis}: spread {sp} m");
            } else {
                println!(
                    "speed {speed}, angular {axis}: {:.3}° per tap, spread {:.4}°, off-axis ≤ {:.3}°, moved ≤ {:.2} mm",
                    mean.to_degrees(),
                    sp.to_degrees(),
                    off.to_degrees(),
                    other * 1e3
                );
                let want = JOG_ANGLE_RAD * speed;
                assert!(
                    (mean - want).abs() < 0.1 * want,
                    "axis {axis}: {mean} vs {want}"
                );
                assert!(sp.to_degrees() < 0.5, "axis {axis}: spread {sp} rad");
            }
        }
    }
}
