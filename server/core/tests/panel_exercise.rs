//! The exercise framework's panel additions (issue 15): the `valve-turn` and `hot-stab`
//! files parse and check, the scene's `panel` builds the standard panel, the `holding`
//! (valve, stab), `valve_angle`, `stab_seated` and `released` conditions read the panel's
//! state, and `move`'s `attitude_rotvec` steers the angular sticks.

mod common;

use common::panel_util::{insert_pose, run_toward, stab_in_hand};

use std::sync::Arc;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use seaarms_core::exercise::{Action, Autopilot, Condition, ExerciseRun, ExerciseSpec};
use seaarms_core::ik::magnum_ik;
use seaarms_core::panel::PanelParams;
use seaarms_core::sim::{Arm, ControlMode, Input, Simulation, StabPhase};

const VALVE_TURN: &str = include_str!("../../../exercises/valve-turn.json");
const HOT_STAB: &str = include_str!("../../../exercises/hot-stab.json");

fn spec(text: &str) -> ExerciseSpec {
    let s: ExerciseSpec = serde_json::from_str(text).expect("parses");
    s.check().expect("checks");
    s
}

fn cond(json: &str) -> Condition {
    serde_json::from_str(json).expect("condition parses")
}

/// The jaw pointing into the panel (+x): the rotation vector of the files' `attitude_rotvec`,
/// π about (1, 0, 1)/√2, which maps the tool's z axis to +x.
fn jaw_into_panel() -> UnitQuaternion<f64> {
    UnitQuaternion::from_scaled_axis(Vector3::new(1.0, 0.0, 1.0).normalize() * std::f64::consts::PI)
}

#[test]
fn panel_files_parse_check_and_build_the_standard_panel() {
    let m = common::builtin("magnum");
    for text in [VALVE_TURN, HOT_STAB] {
        let s = spec(text);
        let p = s.sim_params(&m, &m).expect("params");
        assert_eq!(p.panel, Some(PanelParams::standard()));
        // The same file without the panel is refused: its conditions need it.
        let bare: ExerciseSpec =
            serde_json::from_str(&text.replace("\"panel\": true", "\"panel\": false"))
                .expect("parses");
        assert!(bare.check().is_err());
    }
    // The files' attitude is the jaw along +x.
    let z = jaw_into_panel() * Vector3::z();
    assert!((z - Vector3::x()).norm() < 1e-12);
}

#[test]
fn panel_conditions_follow_the_grasp_and_the_valve() {
    let m = common::builtin("magnum");
    let s = spec(VALVE_TURN);
    let mut p = s.sim_params(&m, &m).expect("params");
    let panel = PanelParams::standard();
    let target = Isometry3::from_parts(Translation3::from(panel.valve_grip_m()), jaw_into_panel());
    let local = p.arms[1].base.inverse() * target;
    p.arms[1].initial_q = magnum_ik(&m, &local).expect("ik")[0];
    let mut sim = Simulation::new(m.clone(), m, p).expect("sim");
    let run = ExerciseRun::new(Arc::new(s), &sim, 1);
    let holding = cond(r#"{"kind": "holding", "arm": "right", "item": "valve"}"#);
    let holding_stab = cond(r#"{"kind": "holding", "arm": "either", "item": "stab"}"#);
    let closed = cond(r#"{"kind": "valve_angle", "angle_deg": 0, "tolerance_deg": 3}"#);
    let open = cond(r#"{"kind": "valve_angle", "angle_deg": 90, "tolerance_deg": 3}"#);
    let seated = cond(r#"{"kind": "stab_seated"}"#);
    let released = cond(r#"{"kind": "released"}"#);
    let f = run.facts();
    assert!(!holding.evaluate(&sim, &f).met);
    assert!(closed.evaluate(&sim, &f).met);
    let v = open.evaluate(&sim, &f);
    assert!(!v.met && v.fraction < 0.1, "{v:?}");
    assert!(!seated.evaluate(&sim, &f).met);
    assert!(released.evaluate(&sim, &f).met);
    let mut close = Input::default();
    close.arms[1].jaw = -1.0;
    for _ in 0..800 {
        sim.step(&close);
    }
    assert!(holding.evaluate(&sim, &f).met);
    assert!(!holding_stab.evaluate(&sim, &f).met);
    assert!(
        !released.evaluate(&sim, &f).met,
        "a jaw on the valve is not released"
    );
    // Readouts: the valve angle against its target.
    let mut out = vec![];
    open.readouts(&sim, &f, &mut out);
    assert_eq!(out.len(), 1);
    assert_eq!(out[0].target, 90.0);
    assert!(out[0].value.abs() < 1e-9);
    let mut open_jaw = Input::default();
    open_jaw.arms[1].jaw = 1.0;
    for _ in 0..300 {
        sim.step(&open_jaw);
    }
    assert!(released.evaluate(&sim, &f).met);
}

#[test]
fn move_with_an_attitude_steers_the_angular_sticks() {
    let m = common::builtin("magnum");
    let s = spec(VALVE_TURN);
    let p = s.sim_params(&m, &m).expect("params");
    let sim = Simulation::new(m.clone(), m, p).expect("sim");
    let run = ExerciseRun::new(Arc::new(s), &sim, 1);
    let tool = sim.end_effector(Arm::Right);
    let at = tool.translation.vector;
    // Wanted: the present attitude turned 0.1 rad about world z; the tool is already there.
    let want = UnitQuaternion::from_scaled_axis(Vector3::z() * 0.1) * tool.rotation;
    let rv = want.scaled_axis();
    let action = |rv: Vector3<f64>| -> Action {
        serde_json::from_value(serde_json::json!({
            "do": "move", "arm": "right", "to": {"point": [at.x, at.y, at.z]},
            "attitude_rotvec": [rv.x, rv.y, rv.z]
        }))
        .expect("action parses")
    };
    let mut pilot = Autopilot::new(vec![action(rv)], ControlMode::Cartesian);
    let out = pilot.tick(&sim, &run.facts());
    // Proportional: 5 stick per rad × 0.1 rad about z (autopilot::ATTITUDE_GAIN_PER_RAD).
    let w = Vector3::new(out.axes[1][3], out.axes[1][4], out.axes[1][5]);
    assert!((w - Vector3::z() * 0.5).norm() < 1e-9, "{w:?}");
    assert!(!pilot.finished(), "not there yet");
    // Already at the attitude: done at once, sticks at zero.
    let mut pilot = Autopilot::new(
        vec![action(tool.rotation.scaled_axis())],
        ControlMode::Cartesian,
    );
    let out = pilot.tick(&sim, &run.facts());
    assert_eq!(out.axes[1], [0.0; 6]);
    assert!(pilot.finished());
}

#[test]
fn assessment_counts_side_load_faults_and_fails_the_hot_stab_on_one() {
    let arm = Arm::Right;
    let (mut sim, panel) = stab_in_hand(arm);
    let mut run = ExerciseRun::new(Arc::new(spec(HOT_STAB)), &sim, 1);
    let sp = panel.stab;
    // Drive in 10 ms slices (the assessment's sample interval) towards each pose.
    let go = |sim: &mut Simulation, run: &mut ExerciseRun, target, slices: usize| {
        for _ in 0..slices {
            run_toward(sim, arm, &target, 10);
            run.sample(sim, false);
        }
    };
    // In stages, as tests/panel.rs does, letting the tool settle on the axis at each; then
    // push (towards 12 mm past full depth, 600 N on the latch) only until it latches.
    for (depth, slices) in [(-0.01, 400), (0.025, 300)] {
        go(
            &mut sim,
            &mut run,
            insert_pose(&panel, depth, Vector3::zeros(), 0.0),
            slices,
        );
    }
    let push = insert_pose(&panel, sp.insertion_depth_m + 0.012, Vector3::zeros(), 0.0);
    for _ in 0..300 {
        go(&mut sim, &mut run, push, 1);
        if sim.panel().expect("panel").stab_phase == StabPhase::Seated {
            break;
        }
    }
    assert_eq!(sim.panel().expect("panel").stab_phase, StabPhase::Seated);
    let seated = insert_pose(&panel, sp.insertion_depth_m, Vector3::zeros(), 0.0);
    go(&mut sim, &mut run, seated, 150);
    assert_eq!(run.assessment().metrics.side_load_faults, 0.0);
    // 30 mm sideways on the seated stab: 2·10⁴ N/m across the axis asks 600 N > 400 N.
    let sideways = insert_pose(
        &panel,
        sp.insertion_depth_m,
        Vector3::new(0.0, 0.03, 0.0),
        0.0,
    );
    go(&mut sim, &mut run, sideways, 300);
    go(&mut sim, &mut run, seated, 200);
    let a = run.assessment();
    assert_eq!(a.metrics.side_load_faults, 1.0);
    assert!(a.metrics.peak_side_load_n > sp.side_load_limit_n);
    let limit = a
        .limits
        .iter()
        .find(|l| l.metric == "side_load_faults")
        .expect("limit");
    assert!(!limit.met);
    assert!(!a.passed);
}
