//! Outcomes of the four dynamic case studies (Lim §4.2.1–4.2.5): case 1 pressures stay within
//! [0, relief] and the arm settles when the input stops; case 2 the link-2 line pressures
//! change when the load is taken and when it is released; case 3 open loop drives pressures to
//! the relief limit with large internal force; case 4 closed loop keeps the peak internal force
//! ≤ 20 % of case 3's without relief events and lifts the object by the commanded height
//! within 1 cm. Grasp states follow the colour sequence of Lim Fig. 4-4. Every case runs in
//! the thesis's setting (rigid grasp, in air) and says so. Where ours departs from the
//! thesis's text (docs/physics.md, "Grasp and the dynamic case studies"): case 2 stage B —
//! taking the handle of a box still resting on the seabed changes no line pressure, the load
//! reaches the arm only when it leaves the seabed; case 3 stage C — the elbow cylinders stay
//! far from pump pressure and the lift does not stall, with or without relief valves.

mod common;

use common::scenario_util::run_rows;
use seaarms_core::grasp::GraspState;
use seaarms_core::sim::scenario::{Row, Scenario, Summary, scenario};
use seaarms_core::sim::{Arm, Environment};

fn build(name: &str) -> Scenario {
    let m = common::builtin("magnum");
    let mut sc = scenario(name, &m, &m).expect("scenario");
    // The thesis's setting, stated: in air.
    sc.params.step.environment = Environment::Air;
    sc
}

fn run_case(name: &str) -> (Summary, Vec<Row>) {
    let (s, rows) = run_rows(&build(name));
    // Lim's assumption (i) (§3.5.2.1), the case studies' default, and said in the output.
    assert_eq!(s.grasp_model, "rigid");
    assert_eq!((s.slips, s.drops), (0, 0));
    (s, rows)
}

fn states(rows: &[Row]) -> Vec<GraspState> {
    let mut v: Vec<GraspState> = Vec::new();
    for r in rows {
        if v.last() != Some(&r.grasp) {
            v.push(r.grasp);
        }
    }
    v
}

#[test]
fn case1_pressures_bounded_and_arm_settles() {
    let (s, rows) = run_case("case1-single-arm");
    let min = rows
        .iter()
        .flat_map(|r| {
            r.p_in[Arm::Left.index()]
                .iter()
                .chain(r.p_out[Arm::Left.index()].iter())
        })
        .fold(f64::INFINITY, |a, &b| a.min(b));
    assert!(min >= 0.0, "negative line pressure {min}");
    assert!(
        s.peak_line_pressure_pa <= s.relief_setting_pa,
        "peak {} above relief {}",
        s.peak_line_pressure_pa,
        s.relief_setting_pa
    );
    assert_eq!(s.relief_events, 0);
    assert!(
        s.final_max_joint_speed_rad_s < 1e-3,
        "arm still moving: {} rad/s",
        s.final_max_joint_speed_rad_s
    );
    // Every joint actually moved.
    for j in 0..6 {
        let span = rows
            .iter()
            .map(|r| r.q[Arm::Left.index()][j])
            .fold(f64::NEG_INFINITY, f64::max)
            - rows
                .iter()
                .map(|r| r.q[Arm::Left.index()][j])
                .fold(f64::INFINITY, f64::min);
        assert!(span > 0.2, "joint {} moved only {span} rad", j + 1);
    }
}

fn mean_link2(rows: &[Row], t0: f64, t1: f64) -> (f64, f64) {
    let sel: Vec<&Row> = rows.iter().filter(|r| r.t_s >= t0 && r.t_s <= t1).collect();
    let n = sel.len() as f64;
    (
        sel.iter()
            .map(|r| r.p_in[Arm::Left.index()][1])
            .sum::<f64>()
            / n,
        sel.iter()
            .map(|r| r.p_out[Arm::Left.index()][1])
            .sum::<f64>()
            / n,
    )
}

#[test]
fn case2_link2_pressures_change_with_load() {
    let (s, rows) = run_case("case2-single-arm-load");
    let seq = states(&rows);
    assert_eq!(
        seq,
        vec![
            GraspState::Free,
            GraspState::OneOnSurface,
            GraspState::OneLifted,
            GraspState::Free
        ],
        "{seq:?}"
    );
    assert!(s.object_lift_m > 0.1, "object lifted {} m", s.object_lift_m);
    // Stage boundaries of the chart: A ends 10 s, B ends 15 s, C ends 21 s, D ends 26 s.
    let before_grasp = mean_link2(&rows, 9.0, 10.0);
    let grasped_on_seabed = mean_link2(&rows, 14.0, 15.0);
    let held = mean_link2(&rows, 20.0, 21.0);
    let released = mean_link2(&rows, 25.0, 26.0);
    println!(
        "link 2 (P_in, P_out): grasped on seabed {grasped_on_seabed:?}, held {held:?}, released {released:?}"
    );
    let change = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).abs().max((a.1 - b.1).abs());
    // Stage B (Lim Fig. 4-15 reports a change): the box still rests on the seabed, which
    // carries its weight, so taking the handle moves the link-2 pressures by under 1 % of
    // supply; the change the thesis shows comes when the load leaves the seabed (stage C).
    println!("link 2 before the grasp {before_grasp:?}");
    assert!(
        change(before_grasp, grasped_on_seabed) < 0.01 * 6.89e6,
        "grasping on the seabed changed link-2 pressures"
    );
    assert!(
        change(grasped_on_seabed, held) > 2e5,
        "taking the load must change link-2 pressures"
    );
    assert!(
        change(held, released) > 2e5,
        "releasing the load must change link-2 pressures"
    );
    assert!(s.peak_line_pressure_pa <= s.relief_setting_pa * 1.02);
}

#[test]
fn case3_open_loop_hits_relief_and_case4_closed_loop_does_not() {
    let (s3, rows3) = run_case("case3-dual-open-loop");
    let (s4, rows4) = run_case("case4-dual-closed-loop");
    for rows in [&rows3, &rows4] {
        let seq = states(rows);
        let want = [
            GraspState::OneOnSurface,
            GraspState::OneHoldingOtherContact,
            GraspState::BothHolding,
        ];
        let mut it = seq.iter();
        for w in want {
            assert!(
                it.any(|s| *s == w),
                "grasp states {seq:?} lack {w:?} in order"
            );
        }
        assert_eq!(*seq.last().expect("states"), GraspState::Free);
    }
    // Case 3: open loop drives line pressures to the relief limit, with large internal force.
    assert!(
        s3.peak_line_pressure_pa >= 0.99 * s3.relief_setting_pa,
        "case 3 peak {} Pa",
        s3.peak_line_pressure_pa
    );
    assert!(s3.peak_line_pressure_pa <= 1.02 * s3.relief_setting_pa);
    assert!(s3.relief_events > 0);
    assert!(
        s3.peak_internal_force_n > 1000.0,
        "case 3 internal force {} N",
        s3.peak_internal_force_n
    );
    // Case 4: closed loop keeps internal force ≤ 20 % of case 3's, no relief, lift within 1 cm.
    assert!(
        s4.peak_internal_force_n <= 0.2 * s3.peak_internal_force_n,
        "case 4 {} N vs case 3 {} N",
        s4.peak_internal_force_n,
        s3.peak_internal_force_n
    );
    assert_eq!(s4.relief_events, 0);
    assert!(s4.peak_line_pressure_pa < s4.relief_setting_pa);
    let lift = s4.closed_loop_lift_m.expect("lift stage");
    let want = s4.commanded_lift_m.expect("commanded");
    assert!(
        (lift - want).abs() <= 0.01,
        "lifted {lift} m for {want} m commanded"
    );
    assert!(s4.peak_grasp_error_m < 1e-3 && s3.peak_grasp_error_m < 1e-3);
    // Case 3 stage C: the thesis's lift stalls with cylinder 3 (elbow) at pump pressure; here
    // the elbow lines stay well below it and the box rises (the relief-valve yield of the
    // swing and wrist joints is what the open-loop chain spends its pressure on).
    let c = stage_span(&rows3, "C");
    let elbow = rows3[c.0..c.1]
        .iter()
        .flat_map(|r| (0..2).map(move |i| r.p_in[i][2].max(r.p_out[i][2])))
        .fold(0.0, f64::max);
    let rise = rows3[c.1 - 1].object_xyz[2] - rows3[c.0].object_xyz[2];
    println!("case 3 stage C: elbow peak {elbow} Pa, rise {rise} m");
    assert!(elbow < 0.8 * 6.89e6, "elbow line at {elbow} Pa");
    assert!(rise > 0.1, "the open-loop lift rose {rise} m");
}

/// Rows [start, end) of the first run of `stage`.
fn stage_span(rows: &[Row], stage: &str) -> (usize, usize) {
    let start = rows.iter().position(|r| r.stage == stage).expect("stage");
    let end = start
        + rows[start..]
            .iter()
            .take_while(|r| r.stage == stage)
            .count();
    (start, end)
}

#[test]
fn case3_without_relief_valves_still_lifts() {
    // Lim's simulator had no relief valves (§4.2.3). Without them (relief far above any
    // pressure reached) the closed chain's back-driven swing and wrist lines climb far past
    // the thesis's 12 MPa on cylinder 4, and the lift still does not stall: the relief
    // setting is not what makes ours rise where the thesis's stopped.
    let mut sc = build("case3-dual-open-loop");
    for a in sc.params.arms.iter_mut() {
        a.hydraulics.relief_pa = 1.0e9;
    }
    let (s, rows) = run_rows(&sc);
    assert_eq!(s.relief_events, 0);
    assert!(
        s.peak_line_pressure_pa > 12.0e6,
        "{}",
        s.peak_line_pressure_pa
    );
    let c = stage_span(&rows, "C");
    let rise = rows[c.1 - 1].object_xyz[2] - rows[c.0].object_xyz[2];
    println!(
        "no relief: peak {} Pa, stage C rise {rise} m",
        s.peak_line_pressure_pa
    );
    assert!(rise > 0.1, "rose {rise} m");
    // The internal force, no longer capped by the yielding joints, is larger than with
    // relief valves (case 3's, asserted above to be over 1 kN).
    assert!(
        s.peak_internal_force_n > 5000.0,
        "{}",
        s.peak_internal_force_n
    );
}

#[test]
fn case3_with_the_finite_grip_slips() {
    // The training setting's grip on case 3's open-loop lift of the nominal 50 kg box: the
    // rigid grasp needs tens of times the jaws' friction limits (issue 17: 3.97 kN, 1.39 kN·m
    // per jaw), so the jaws slip.
    let mut sc = build("case3-dual-open-loop");
    sc.params.rigid_grasp = false;
    let (s, _) = run_rows(&sc);
    assert_eq!(s.grasp_model, "finite");
    assert!(s.slips > 0, "{s:?}");
}
