//! The intervention panel (issue 15): the valve's 1-DOF stick–slip dynamics against closed
//! forms, the valve turned by a Magnum's wrist through the jaw, the hot stab's aligned
//! insertion, seating and side-load faults, reach of both arms, and stability of the
//! jaw–item coupling at the 1 ms step.

mod common;

use common::panel_util::{ik, insert_pose, jaw, run_toward, sim_at, stab_in_hand, tool_at, toward};
use nalgebra::{DVector, Vector3};
use seaarms_core::dynamics::{DynData, crba};
use seaarms_core::kinematics::{KinData, forward_kinematics};
use seaarms_core::panel::{PanelParams, StabPhase, ValveParams, valve_step};
use seaarms_core::sim::{Arm, Graspable, Input, SimParams, Simulation};

const H: f64 = 1.0e-3;

#[test]
fn valve_one_dof_matches_closed_forms() {
    let v0 = PanelParams::standard().valve;
    // Below breakaway (40 N·m) from rest: no motion.
    let (mut a, mut w) = (0.3, 0.0);
    for _ in 0..1000 {
        valve_step(&v0, &mut a, &mut w, 39.9, 0.0, 0.0, H);
    }
    assert_eq!((a, w), (0.3, 0.0), "stuck below breakaway");
    // Above breakaway, no viscous term: θ̈ = (τ − τ_run)/I exactly (Newton, I θ̈ = Στ).
    let v = ValveParams {
        viscous_nm_s_rad: 0.0,
        ..v0
    };
    let (mut a, mut w) = (0.0, 0.0);
    let mut rates = vec![];
    for _ in 0..20 {
        valve_step(&v, &mut a, &mut w, 50.0, 0.0, 0.0, H);
        rates.push(w);
    }
    let alpha = (50.0 - 25.0) / 0.02;
    for k in 1..rates.len() {
        let measured = (rates[k] - rates[k - 1]) / H;
        assert!(
            (measured - alpha).abs() < 1e-6 * alpha,
            "{measured} vs {alpha}"
        );
    }
    // With the viscous term: ω(t) = (τ − τ_run)/b·(1 − e^{−b t/I}) (linear ODE, closed form);
    // backward Euler is first order: within 1 % at t = 0.05 s (b t/I = 2.5).
    let (mut a, mut w) = (0.0, 0.0);
    for _ in 0..50 {
        valve_step(&v0, &mut a, &mut w, 50.0, 0.0, 0.0, H);
    }
    let (b, i) = (v0.viscous_nm_s_rad, v0.inertia_kg_m2);
    let exact = 25.0 / b * (1.0 - (-b * 0.05 / i).exp());
    assert!((w - exact).abs() < 0.01 * exact, "{w} vs {exact}");
    // Coasting with no torque: running friction stops it after I·ω₀/τ_run (+ viscous), then
    // it stays stuck.
    let (mut a, mut w) = (0.5, 2.0);
    let mut steps = 0;
    while w != 0.0 && steps < 10_000 {
        valve_step(&v, &mut a, &mut w, 0.0, 0.0, 0.0, H);
        steps += 1;
    }
    let t_stop = 0.02 * 2.0 / 25.0;
    assert!(
        (steps as f64 * H - t_stop).abs() <= H,
        "{steps} ms vs {t_stop} s"
    );
    let a_stop = a;
    for _ in 0..100 {
        valve_step(&v, &mut a, &mut w, 0.0, 0.0, 0.0, H);
    }
    assert_eq!(a, a_stop);
    // End stops: driven open it stops at exactly 90°, driven closed at exactly 0.
    let (mut a, mut w) = (0.0, 0.0);
    for _ in 0..2000 {
        valve_step(&v0, &mut a, &mut w, 60.0, 0.0, 0.0, H);
    }
    assert_eq!((a, w), (std::f64::consts::FRAC_PI_2, 0.0));
    for _ in 0..2000 {
        valve_step(&v0, &mut a, &mut w, -60.0, 0.0, 0.0, H);
    }
    assert_eq!((a, w), (0.0, 0.0));
}

#[test]
fn both_arms_reach_the_valve_receptacle_and_holster() {
    let m = common::builtin("magnum");
    let p = SimParams::case_study(&m, &m).expect("params");
    let panel = PanelParams::standard();
    let n = panel.normal();
    let seated = panel.seated_stab().translation.vector;
    let pre = seated - n * (panel.stab.insertion_depth_m + 0.01);
    let holster = panel.holstered_stab().translation.vector;
    for arm in Arm::BOTH {
        for (what, x) in [
            ("valve", panel.valve_grip_m()),
            ("seated", seated),
            ("pre-insert", pre),
            ("holster", holster),
        ] {
            assert!(
                ik(&p, arm, &tool_at(x)).is_some(),
                "{arm:?} reaches the {what} at {x}"
            );
        }
    }
    // Clear of the box: the face is ≥ 0.3 m beyond the box's far side (x = 1.15).
    assert!(panel.pose.translation.x - 1.15 >= 0.3);
}

#[test]
fn wrist_turns_the_held_valve_to_its_stops_only_above_breakaway() {
    let panel = PanelParams::standard();
    let arm = Arm::Right;
    let mut sim = sim_at(arm, &tool_at(panel.valve_grip_m()));
    assert_eq!(sim.in_capture_range(arm), Some(Graspable::Valve));
    for _ in 0..800 {
        sim.step(&jaw(arm, -1.0));
    }
    let s = *sim.panel().expect("panel");
    assert_eq!(s.valve_holder, Some(arm));
    assert_eq!(sim.arm(arm).jaw_opening_m, panel.valve.grip_width_m);
    // The rotate joint turns about the jaw axis (+x); the valve's axis is −x, so a negative
    // rotate command opens the valve.
    let mut turn = jaw(arm, -0.3);
    turn.arms[arm.index()].valves[5] = -0.5;
    let mut peak_torque: f64 = 0.0;
    for _ in 0..3000 {
        sim.step(&turn);
        peak_torque = peak_torque.max(sim.panel().expect("panel").valve_torque_nm);
    }
    let s = *sim.panel().expect("panel");
    assert_eq!(s.valve_angle_rad, panel.valve.travel_rad, "stopped at 90°");
    assert!(
        peak_torque > panel.valve.breakaway_torque_nm,
        "{peak_torque}"
    );
    turn.arms[arm.index()].valves[5] = 0.5;
    for _ in 0..3000 {
        sim.step(&turn);
    }
    assert_eq!(
        sim.panel().expect("panel").valve_angle_rad,
        0.0,
        "back at 0"
    );
    assert_eq!(sim.numerical_faults(), 0);

    // Supply cut to 1 MPa: the rotate motor's stall torque scales with the pressure,
    // 150 N·m × 1/6.89 ≈ 22 N·m (hydraulics::sizing: design torque = displacement × supply)
    // — below the 40 N·m breakaway, so the valve does not move.
    let mut sim = sim_at(arm, &tool_at(panel.valve_grip_m()));
    for _ in 0..800 {
        sim.step(&jaw(arm, -1.0));
    }
    let supply = sim.params().arms[arm.index()].hydraulics.supply_pa;
    sim.faults_mut(arm).supply_drop_pa = supply - 1.0e6;
    turn.arms[arm.index()].valves[5] = -1.0;
    let mut peak: f64 = 0.0;
    for _ in 0..3000 {
        sim.step(&turn);
        peak = peak.max(sim.panel().expect("panel").valve_torque_nm.abs());
    }
    let s = *sim.panel().expect("panel");
    assert_eq!(
        s.valve_angle_rad, 0.0,
        "held shut below breakaway (peak {peak} N·m)"
    );
    assert!(
        peak > 5.0 && peak < panel.valve.breakaway_torque_nm,
        "{peak}"
    );
}

#[test]
fn misaligned_stab_is_blocked_by_the_panel_face() {
    for (offset, tilt) in [
        (Vector3::new(0.0, 0.0, 0.02), 0.0),
        (Vector3::zeros(), 0.15),
    ] {
        let arm = Arm::Right;
        let (mut sim, panel) = stab_in_hand(arm);
        run_toward(
            &mut sim,
            arm,
            &insert_pose(&panel, -0.01, offset, tilt),
            4000,
        );
        assert_eq!(sim.panel().expect("panel").stab_depth_m, 0.0);
        // Push 2 cm into the face: blocked (depth stays 0, tip stopped at the face).
        run_toward(
            &mut sim,
            arm,
            &insert_pose(&panel, 0.02, offset, tilt),
            3000,
        );
        let s = *sim.panel().expect("panel");
        assert_eq!(
            s.stab_phase,
            StabPhase::Held(arm),
            "offset {offset:?} tilt {tilt}"
        );
        assert_eq!(s.stab_depth_m, 0.0);
        // The tip rests on the face: its penetration is the penalty spring's deflection under
        // the arm's push, face force / 5·10⁶ N/m (a stalled hydraulic arm pushes kilonewtons),
        // far short of the 2 cm commanded.
        let tip = s.stab_tip_m(&panel);
        let past_face = (tip - panel.receptacle_mouth_m()).dot(&panel.normal());
        let deflection = s.face_force_n / panel.stab.face_stiffness_n_m;
        assert!(
            s.face_force_n > 0.0 && past_face < 0.01,
            "tip {past_face} m past the face"
        );
        assert!(
            (past_face - deflection).abs() < 1e-3,
            "{past_face} vs {deflection}"
        );
        assert_eq!(sim.numerical_faults(), 0);
    }
}

#[test]
fn aligned_stab_enters_seats_above_the_seating_force_and_counts_side_load_faults() {
    let arm = Arm::Right;
    let (mut sim, panel) = stab_in_hand(arm);
    let sp = panel.stab;
    run_toward(
        &mut sim,
        arm,
        &insert_pose(&panel, -0.01, Vector3::zeros(), 0.0),
        4000,
    );
    // Halfway in: inserting, depth follows the tip.
    run_toward(
        &mut sim,
        arm,
        &insert_pose(&panel, 0.025, Vector3::zeros(), 0.0),
        3000,
    );
    let s = *sim.panel().expect("panel");
    assert_eq!(s.stab_phase, StabPhase::Inserting);
    assert!((s.stab_depth_m - 0.025).abs() < 0.003, "{}", s.stab_depth_m);
    // Onto the latch with 1 mm of overtravel: 5·10⁴ N/m × 1 mm = 50 N < 300 N.
    run_toward(
        &mut sim,
        arm,
        &insert_pose(&panel, sp.insertion_depth_m + 0.001, Vector3::zeros(), 0.0),
        3000,
    );
    let s = *sim.panel().expect("panel");
    assert_eq!(
        s.stab_phase,
        StabPhase::Inserting,
        "stop force {} N",
        s.stop_force_n
    );
    assert!(s.stop_force_n < sp.seating_force_n);
    // 12 mm of overtravel asks for 600 N: it latches the first time the latch force reaches
    // the 300 N seating force (6 mm).
    let target = insert_pose(&panel, sp.insertion_depth_m + 0.012, Vector3::zeros(), 0.0);
    let mut last = 0.0;
    for _ in 0..3000 {
        let i = toward(&sim, arm, &target, -0.2);
        sim.step(&i);
        let s = sim.panel().expect("panel");
        if s.stab_phase == StabPhase::Seated {
            break;
        }
        last = s.stop_force_n;
    }
    let s = *sim.panel().expect("panel");
    assert_eq!(s.stab_phase, StabPhase::Seated);
    assert_eq!(s.seatings, 1);
    assert!(last < sp.seating_force_n, "not latched earlier ({last} N)");
    assert_eq!(s.stab_depth_m, sp.insertion_depth_m);
    // Back off to the seated pose, then push sideways 30 mm: the seated stab's 2·10⁴ N/m
    // across the axis asks for 600 N > the 400 N limit: one fault (a rising edge), however
    // long it lasts.
    let seated_tool = insert_pose(&panel, sp.insertion_depth_m, Vector3::zeros(), 0.0);
    run_toward(&mut sim, arm, &seated_tool, 1500);
    assert_eq!(sim.panel().expect("panel").side_load_faults, 0);
    run_toward(
        &mut sim,
        arm,
        &insert_pose(
            &panel,
            sp.insertion_depth_m,
            Vector3::new(0.0, 0.03, 0.0),
            0.0,
        ),
        3000,
    );
    let s = *sim.panel().expect("panel");
    assert_eq!(
        s.side_load_faults, 1,
        "side load {} N, peak {}",
        s.side_load_n, s.peak_side_load_n
    );
    assert!(s.peak_side_load_n > sp.side_load_limit_n);
    assert_eq!(s.stab_phase, StabPhase::Seated);
    run_toward(&mut sim, arm, &seated_tool, 2000);
    assert!(sim.panel().expect("panel").side_load_n < sp.side_load_limit_n);
    // Released: it stays seated.
    for _ in 0..500 {
        sim.step(&jaw(arm, 1.0));
    }
    let s = *sim.panel().expect("panel");
    assert_eq!(s.stab_holder, None);
    assert_eq!(s.stab_phase, StabPhase::Seated);
    assert_eq!(s.side_load_faults, 1);
    assert_eq!(sim.numerical_faults(), 0);
}

/// Kinetic energy (J) of `arm`'s links, ½·q̇ᵀH(q)q̇ (H by the composite-rigid-body algorithm
/// on the simulation's own world-frame model and inertials).
fn arm_kinetic_energy(sim: &Simulation, arm: Arm) -> f64 {
    let model = sim.model(arm);
    let inertials = &sim.params().arms[arm.index()].inertials;
    let mut kin = KinData::new(model);
    let mut dynd = DynData::new(model);
    let a = sim.arm(arm);
    forward_kinematics(model, &mut kin, &a.q);
    crba(model, inertials, &kin, &mut dynd);
    let qd = DVector::from_column_slice(&a.qd);
    0.5 * (qd.transpose() * &dynd.mass_matrix * &qd)[(0, 0)]
}

#[test]
fn held_items_with_zero_input_stay_finite_and_do_not_gain_energy() {
    // Physical invariant: with the valves centred (critically lapped, no flow from the
    // supply) nothing drives the arm, so the jaw–item coupling (linearly implicit, stiff
    // against the wrist's small inertia) must not pump energy in: the mechanical kinetic
    // energy of arm and valve after the grasp dies away over 10 s of simulated time.
    let panel = PanelParams::standard();
    let arm = Arm::Left;
    let mut valve = sim_at(arm, &tool_at(panel.valve_grip_m()));
    for _ in 0..800 {
        valve.step(&jaw(arm, -1.0));
    }
    assert_eq!(valve.panel().expect("panel").valve_holder, Some(arm));
    // Set it moving: the wrist turning the valve for 0.3 s, then the sticks let go.
    let mut turn = jaw(arm, 0.0);
    turn.arms[arm.index()].valves[5] = -0.5;
    for _ in 0..300 {
        valve.step(&turn);
    }
    assert!(
        valve.panel().expect("panel").valve_rate_rad_s > 0.1,
        "turning"
    );
    let (stab, _) = stab_in_hand(Arm::Right);
    let inertia = panel.valve.inertia_kg_m2;
    for (mut sim, who) in [(valve, arm), (stab, Arm::Right)] {
        let mut per_second = vec![];
        for _ in 0..10 {
            let mut peak: f64 = 0.0;
            for _ in 0..1000 {
                sim.step(&Input::default());
                let rate = sim.panel().expect("panel").valve_rate_rad_s;
                peak = peak.max(arm_kinetic_energy(&sim, who) + 0.5 * inertia * rate * rate);
            }
            per_second.push(peak);
        }
        assert_eq!(sim.numerical_faults(), 0);
        let s = sim.panel().expect("panel");
        assert!(s.valve_angle_rad.is_finite() && s.stab_pose.translation.vector.norm().is_finite());
        assert!(
            per_second.windows(2).all(|w| w[1] <= w[0] + 1e-9) && per_second[9] < 1e-6,
            "{who:?}: peak kinetic energy per second (J) {per_second:?}"
        );
        assert!(s.held_by(who).is_some(), "still held");
    }
}

#[test]
fn without_a_panel_nothing_changes_and_capture_reports_box_handles_only() {
    let m = common::builtin("magnum");
    let p = SimParams::case_study(&m, &m).expect("params");
    assert!(p.panel.is_none());
    let sim = Simulation::new(m.clone(), m, p).expect("sim");
    assert!(sim.panel().is_none());
    assert_eq!(sim.in_capture_range(Arm::Left), None);
    assert!(sim.valve_grip_m().is_none());
}

#[test]
fn bad_panel_parameters_are_rejected() {
    let m = common::builtin("magnum");
    let mut panel = PanelParams::standard();
    panel.valve.running_torque_nm = 50.0;
    let p = SimParams::case_study(&m, &m)
        .expect("params")
        .with_panel(panel);
    assert!(Simulation::new(m.clone(), m.clone(), p).is_err());
    let mut panel = PanelParams::standard();
    panel.stab.mass_kg = f64::NAN;
    let p = SimParams::case_study(&m, &m)
        .expect("params")
        .with_panel(panel);
    assert!(Simulation::new(m.clone(), m.clone(), p).is_err());
    let mut panel = PanelParams::standard();
    panel.valve.grip_width_m = 0.2;
    let p = SimParams::case_study(&m, &m)
        .expect("params")
        .with_panel(panel);
    assert!(Simulation::new(m.clone(), m, p).is_err());
}
