//! Fault injection hooks act physically and keep the simulation finite when set and cleared;
//! non-finite inputs are treated as 0 (the documented validation rule on `Input`).

mod common;

use seaarms_core::sim::{Arm, Input, SimParams, Simulation};

fn sim() -> Simulation {
    let m = common::builtin("magnum");
    let p = SimParams::case_study(&m, &m).expect("params");
    Simulation::new(m.clone(), m, p).expect("sim")
}

fn run(s: &mut Simulation, inp: &Input, steps: usize) {
    for _ in 0..steps {
        s.step(inp);
    }
}

#[test]
fn non_finite_inputs_act_as_zero() {
    let mut a = sim();
    let mut b = sim();
    let mut bad = Input::default();
    bad.arms[0].valves = [
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NAN,
        f64::NAN,
        f64::NAN,
    ];
    bad.arms[1].jaw = f64::NAN;
    bad.object_velocity = [f64::NAN; 6];
    let good = Input::default();
    run(&mut a, &bad, 500);
    run(&mut b, &good, 500);
    assert_eq!(a.arm(Arm::Left).q, b.arm(Arm::Left).q);
    assert_eq!(a.arm(Arm::Left).p_in, b.arm(Arm::Left).p_in);
    // Non-finite speed scale stops everything.
    let mut c = sim();
    let mut nan_speed = Input {
        speed_scale: f64::NAN,
        ..Input::default()
    };
    nan_speed.arms[0].valves = [1.0; 6];
    run(&mut c, &nan_speed, 500);
    assert_eq!(c.arm(Arm::Left).q, b.arm(Arm::Left).q);
    assert_eq!(c.numerical_faults(), 0);
}

#[test]
fn stuck_valve_moves_the_joint_without_command() {
    let mut s = sim();
    let q0 = s.arm(Arm::Left).q[0];
    s.faults_mut(Arm::Left).stuck_valve[0] = Some(0.5);
    run(&mut s, &Input::default(), 500);
    let moved = s.arm(Arm::Left).q[0] - q0;
    assert!(
        moved > 0.05,
        "stuck-open swing valve moved the joint {moved} rad in 0.5 s"
    );
    s.faults_mut(Arm::Left).stuck_valve[0] = None;
    let q1 = s.arm(Arm::Left).q[0];
    run(&mut s, &Input::default(), 500);
    assert!(
        (s.arm(Arm::Left).q[0] - q1).abs() < 0.01,
        "cleared fault: joint stops"
    );
}

#[test]
fn supply_drop_slows_the_arm_and_leak_makes_it_drift() {
    let mut full = sim();
    let mut weak = sim();
    weak.faults_mut(Arm::Left).supply_drop_pa = 5.0e6;
    let mut inp = Input::default();
    inp.arms[Arm::Left.index()].valves[5] = 1.0;
    run(&mut full, &inp, 500);
    run(&mut weak, &inp, 500);
    let (a, b) = (full.arm(Arm::Left).q[5], weak.arm(Arm::Left).q[5]);
    assert!(
        b < 0.8 * a,
        "rotate with 1.89 MPa supply: {b} rad vs {a} rad"
    );

    let mut leaky = sim();
    let q0 = leaky.arm(Arm::Left).q[1];
    leaky.faults_mut(Arm::Left).leak_m3_s_pa[1] = 1e-10;
    run(&mut leaky, &Input::default(), 3000);
    // Cross-piston leakage equalizes the chamber pressures; on a single-rod cylinder the area
    // difference then decides where the joint creeps (here it extends): it no longer holds.
    let drift = (q0 - leaky.arm(Arm::Left).q[1]).abs();
    let mut tight = sim();
    run(&mut tight, &Input::default(), 3000);
    let still = (q0 - tight.arm(Arm::Left).q[1]).abs();
    assert!(
        drift > 1e-3 && still < 1e-6,
        "leaking shoulder drifts {drift} rad in 3 s, tight one {still} rad"
    );
    assert_eq!(leaky.numerical_faults(), 0);
}

#[test]
fn entrained_air_softens_the_oil_column_and_everything_stays_finite() {
    let mut s = sim();
    let mut inp = Input::default();
    inp.arms[Arm::Left.index()].valves = [0.5, 0.5, -0.5, 0.5, 0.5, 1.0];
    for k in 0..20 {
        s.faults_mut(Arm::Left).bulk_modulus_scale = if k % 2 == 0 { 0.02 } else { 1.0 };
        s.faults_mut(Arm::Left).supply_drop_pa = if k % 3 == 0 { 6.89e6 } else { 0.0 };
        run(&mut s, &inp, 200);
        inp.arms[Arm::Left.index()]
            .valves
            .iter_mut()
            .for_each(|v| *v = -*v);
    }
    assert_eq!(s.numerical_faults(), 0);
    assert!(s.arm(Arm::Left).q.iter().all(|q| q.is_finite()));
    assert!(
        s.arm(Arm::Left)
            .p_in
            .iter()
            .all(|p| p.is_finite() && *p >= 0.0)
    );
}
