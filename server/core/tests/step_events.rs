//! The step's event stream (`Simulation::events`) says exactly what the simulation's own
//! state says happened in that step, every step: a grasp-state change is one `Grasp` event
//! with the new state; each slip onset and slide-out counted in the jaw's `GripState` is one
//! `Slip` (with the load fraction at the onset) or `SlidOut` event of that arm; each relief
//! opening counted in `ArmState::relief_events` is one `Relief` event of an actuator whose
//! valve is open; a joint that was within its limits and now is past them (the model's
//! limits) is one `EndStop` event. Checked over Lim case study 3 as scripted (relief opens,
//! Lim §4.2.3) and with an overloaded box (its jaws slip and lose it, issue 17), and over
//! both arms driven hard into their limits.

mod common;

use common::scenario_util::start;
use seaarms_core::sim::{Arm, Event, Input, Simulation};

/// What one step reported, checked against the state before and after it. Returns the
/// events of the step by kind: [grasp, slip, slid out, relief, end stop].
fn step_and_check(sim: &mut Simulation, input: &Input) -> [usize; 5] {
    let grasp0 = sim.grasp_state();
    let before = Arm::BOTH.map(|a| *sim.arm(a));
    sim.step(input);
    let events = sim.events().to_vec();
    let mut seen = [0; 5];
    let grasp = sim.grasp_state();
    let grasps: Vec<_> = events
        .iter()
        .filter_map(|e| match e {
            Event::Grasp(g) => Some(*g),
            _ => None,
        })
        .collect();
    if grasp == grasp0 {
        assert!(grasps.is_empty(), "t {}: {events:?}", sim.time_s());
    } else {
        assert_eq!(grasps, [grasp], "t {}", sim.time_s());
    }
    seen[0] = grasps.len();
    for arm in Arm::BOTH {
        let (a0, a) = (&before[arm.index()], sim.arm(arm));
        let of_arm = |f: &dyn Fn(&Event) -> bool| events.iter().filter(|e| f(e)).count();
        let slips = of_arm(&|e| matches!(e, Event::Slip { arm: x, .. } if *x == arm));
        assert_eq!(slips as u64, a.grip.slips - a0.grip.slips, "{arm:?}");
        for e in &events {
            if let Event::Slip {
                arm: x,
                load_fraction,
            } = e
            {
                if *x == arm {
                    assert_eq!(*load_fraction, a.grip.load_fraction);
                    assert!(*load_fraction > 0.0);
                }
            }
        }
        let out = of_arm(&|e| matches!(e, Event::SlidOut { arm: x } if *x == arm));
        assert_eq!(out as u64, a.grip.slid_out - a0.grip.slid_out, "{arm:?}");
        if out > 0 {
            assert!(!a.holding, "{arm:?} slid out but holds");
        }
        let relief = of_arm(&|e| matches!(e, Event::Relief { arm: x, .. } if *x == arm));
        assert_eq!(relief as u64, a.relief_events - a0.relief_events, "{arm:?}");
        for e in &events {
            if let Event::Relief { arm: x, actuator } = e {
                if *x == arm {
                    assert!(a.relief_open[*actuator] && !a0.relief_open[*actuator]);
                }
            }
        }
        // End stops from the model's joint limits (not the simulation's flags).
        let limits = &sim.model(arm).joints;
        let past =
            |q: &[f64; 6], j: usize| q[j] < limits[j].limits[0] || q[j] > limits[j].limits[1];
        let mut stops = Vec::new();
        for j in 0..6 {
            if past(&a.q, j) && !past(&a0.q, j) {
                stops.push(j);
            }
        }
        let reported: Vec<usize> = events
            .iter()
            .filter_map(|e| match e {
                Event::EndStop { arm: x, joint } if *x == arm => Some(*joint),
                _ => None,
            })
            .collect();
        assert_eq!(reported, stops, "{arm:?} t {}", sim.time_s());
        seen[1] += slips;
        seen[2] += out;
        seen[3] += relief;
        seen[4] += stops.len();
    }
    seen
}

/// Runs the case-study scenario `name` (with `edit` applied to it) step by step, checking
/// every step; returns the events seen by kind.
fn run_case(name: &str, edit: impl Fn(&mut seaarms_core::sim::scenario::Scenario)) -> [usize; 5] {
    let (mut sc, _) = start(name);
    edit(&mut sc);
    let m = common::builtin("magnum");
    let mut sim = Simulation::new(m.clone(), m, sc.params.clone()).expect("sim");
    let mut total = [0; 5];
    for seg in &sc.segments {
        let n = (seg.duration_s / sc.params.step.dt_s).round() as usize;
        for _ in 0..n {
            let input = sc.input_at(&sim, seg, sim.time_s());
            let seen = step_and_check(&mut sim, &input);
            for (t, s) in total.iter_mut().zip(seen) {
                *t += s;
            }
        }
    }
    assert_eq!(sim.numerical_faults(), 0);
    println!("{name}: grasp, slip, slid out, relief, end stop: {total:?}");
    total
}

#[test]
fn an_overloaded_dual_lift_reports_its_grasps_slips_and_slide_outs_once() {
    // The overloaded box of grasp_slip.rs: 2.1× the jaws' kinetic capacity, finite grip.
    let total = run_case("case3-dual-open-loop", |sc| {
        sc.params.rigid_grasp = false;
        sc.params.object.mass_kg = 250.0;
    });
    assert!(total[0] >= 2, "the grasps were reported: {total:?}");
    assert!(
        total[1] >= 1 && total[2] >= 1,
        "the slips and the loss: {total:?}"
    );
}

#[test]
fn the_open_loop_dual_carry_reports_its_relief_openings_once() {
    // Lim case study 3 as scripted (rigid grasp): the internal force opens relief valves
    // (case_studies.rs).
    let total = run_case("case3-dual-open-loop", |_| {});
    assert!(total[3] >= 1, "{total:?}");
}

#[test]
fn arms_driven_into_their_limits_report_end_stops_once() {
    let (_, mut sim) = start("case1-single-arm");
    let mut input = Input::default();
    input.arms[0].valves = [1.0; 6];
    input.arms[1].valves = [-1.0; 6];
    let mut total = [0; 5];
    for _ in 0..15_000 {
        let seen = step_and_check(&mut sim, &input);
        for (t, s) in total.iter_mut().zip(seen) {
            *t += s;
        }
    }
    assert_eq!(sim.numerical_faults(), 0);
    println!("grasp, slip, slid out, relief, end stop: {total:?}");
    assert!(total[4] >= 6, "{total:?}");
}
