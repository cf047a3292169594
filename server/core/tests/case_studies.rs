//! Outcomes of the four dynamic case studies (Lim §4.2.1–4.2.5): case 1 pressures stay within
//! [0, relief] and the arm settles when the input stops; case 2 the link-2 line pressures
//! change when the load is taken and when it is released; case 3 open loop drives pressures to
//! the relief limit with large internal force; case 4 closed loop keeps the peak internal force
//! ≤ 20 % of case 3's without relief events and lifts the object by the commanded height
//! within 1 cm. Grasp states follow the colour sequence of Lim Fig. 4-4.

mod common;

use seaarms_core::grasp::GraspState;
use seaarms_core::sim::Arm;
use seaarms_core::sim::scenario::{Row, Summary, run, scenario};

fn run_case(name: &str) -> (Summary, Vec<Row>) {
    let m = common::builtin("magnum");
    let sc = scenario(name, &m, &m).expect("scenario");
    let mut rows = Vec::new();
    let s = run(&sc, &m, &m, |r| rows.push(r.clone())).expect("run");
    println!("{name}: {s:?}");
    assert_eq!(s.numerical_faults, 0);
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
    // Stage boundaries of the chart: B ends 15 s, C ends 21 s, D ends 26 s.
    let grasped_on_seabed = mean_link2(&rows, 14.0, 15.0);
    let held = mean_link2(&rows, 20.0, 21.0);
    let released = mean_link2(&rows, 25.0, 26.0);
    println!(
        "link 2 (P_in, P_out): grasped on seabed {grasped_on_seabed:?}, held {held:?}, released {released:?}"
    );
    let change = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).abs().max((a.1 - b.1).abs());
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
}
