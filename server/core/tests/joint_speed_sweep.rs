//! Issue 17 item 1: every Magnum joint driven at full valve command across its whole range, in
//! both directions, stays within ±20 % of its Lim Table 1-1 speed (20/20/30/30/30/150 °/s), and
//! starts without overshooting its steady speed by more than 10 %.
//!
//! Setting (the thesis's, Lim §4.2.1 case 1): in air, no payload, the arm's own weight, the
//! left arm of the case-study pair; the joint under test starts 0.5° inside one limit and runs
//! at full command to the other; the other joints hold the neutral posture [`NEUTRAL`] (their
//! valves shut), and nothing to collide with (contacts off: some of these postures put the
//! jaw below the seabed). Samples are the joint speed after every 1 ms step. Excluded, and why:
//! * the first [`STARTUP_S`] after the command: the spool and the oil columns accelerating the
//!   link (checked separately: the peak over that window ≤ 1.1 × the steady speed, taken as
//!   the mean over the next [`STEADY_S`]);
//! * the last [`END_EXCLUDED_DEG`] before the far limit, where the link runs onto its end stop
//!   (the stop's spring acts beyond the limit; the sweep ends when the joint reaches it).
//!
//! `cargo test -p seaarms-core --test joint_speed_sweep -- --nocapture` prints the table that
//! docs/physics.md quotes.

mod common;

use seaarms_core::hydraulics::MAGNUM_SPEEDS_DEG_S;
use seaarms_core::sim::{Arm, Environment, Input, SimParams, Simulation};

/// Neutral posture of the joints not under test (rad): swing 0, shoulder 45° and elbow −65°
/// (the middles of their ranges), pitch, yaw, rotate 0.
const NEUTRAL: [f64; 6] = [
    0.0,
    std::f64::consts::FRAC_PI_4,
    -1.134_464_013_796_314,
    0.0,
    0.0,
    0.0,
];
/// Start-up window excluded from the ±20 % check (s).
const STARTUP_S: f64 = 0.25;
/// Window after start-up over which the steady speed is averaged for the overshoot check (s).
const STEADY_S: f64 = 0.25;
/// Degrees before the far limit excluded from the ±20 % check.
const END_EXCLUDED_DEG: f64 = 2.0;
/// Start offset inside the near limit (deg).
const START_INSIDE_DEG: f64 = 0.5;
/// The ±20 % band of issue 17.
const BAND: f64 = 0.20;
/// Largest start-up peak over the steady speed.
const OVERSHOOT: f64 = 1.10;

/// One sweep's figures (°/s).
struct Sweep {
    min: f64,
    max: f64,
    peak_startup: f64,
    steady: f64,
    samples: usize,
}

/// Runs joint `j` at full command `dir` (±1) from one end of its range to the other.
fn sweep(j: usize, dir: f64) -> Sweep {
    let m = common::builtin("magnum");
    let mut p = SimParams::case_study(&m, &m).expect("params");
    p.step.environment = Environment::Air;
    // The arm alone, as on a test bench: with the shoulder near horizontal and the elbow at
    // −65° the jaw is below the seabed, so the sweep runs with contacts off (a speed, not a
    // collision, is measured; tests/collisions.rs covers contacts).
    p.contact.enabled = false;
    let left = Arm::Left.index();
    let joint = &m.joints[j];
    let (start, end) = if joint.is_limited() {
        let (lo, hi) = (joint.limits[0], joint.limits[1]);
        let inside = START_INSIDE_DEG.to_radians();
        if dir > 0.0 {
            (lo + inside, hi)
        } else {
            (hi - inside, lo)
        }
    } else {
        // Continuous rotate joint: one revolution.
        (0.0, dir * std::f64::consts::TAU)
    };
    let mut q = NEUTRAL;
    q[j] = start;
    p.arms[left].initial_q = q;
    let dt = p.step.dt_s;
    let mut s = Simulation::new(m.clone(), m, p).expect("sim");
    let mut inp = Input::default();
    inp.arms[left].valves[j] = dir;
    let nominal = MAGNUM_SPEEDS_DEG_S[j];
    let end_excluded = END_EXCLUDED_DEG.to_radians();
    let (mut min, mut max, mut peak) = (f64::INFINITY, 0.0f64, 0.0f64);
    let (mut steady_sum, mut steady_n, mut samples) = (0.0, 0, 0);
    let max_steps = (2.0 * (end - start).abs().to_degrees() / nominal / dt) as usize + 2000;
    for k in 1..=max_steps {
        s.step(&inp);
        let t = k as f64 * dt;
        let a = s.arm(Arm::Left);
        let v = a.qd[j].to_degrees() * dir;
        let to_go = (end - a.q[j]) * dir;
        if to_go <= 0.0 {
            break;
        }
        if t <= STARTUP_S {
            peak = peak.max(v);
            continue;
        }
        if t <= STARTUP_S + STEADY_S {
            steady_sum += v;
            steady_n += 1;
        }
        if to_go > end_excluded {
            min = min.min(v);
            max = max.max(v);
            samples += 1;
        }
        assert!(
            k < max_steps,
            "joint {} dir {dir}: did not reach the limit",
            j + 1
        );
    }
    Sweep {
        min,
        max,
        peak_startup: peak,
        steady: steady_sum / steady_n.max(1) as f64,
        samples,
    }
}

#[test]
fn full_command_speed_within_20_percent_of_table_1_1_over_the_whole_range() {
    let names = ["swing", "shoulder", "elbow", "pitch", "yaw", "rotate"];
    println!(
        "| joint | Table 1-1 (°/s) | direction | min (°/s) | max (°/s) | start-up peak / steady |"
    );
    println!("|---|---|---|---|---|---|");
    let mut failures = Vec::new();
    for (j, name) in names.iter().enumerate() {
        let nominal = MAGNUM_SPEEDS_DEG_S[j];
        for dir in [1.0, -1.0] {
            let r = sweep(j, dir);
            let over = r.peak_startup / r.steady;
            println!(
                "| {name} | {nominal:.0} | {} | {:.1} | {:.1} | {:.3} |",
                if dir > 0.0 { "+" } else { "−" },
                r.min,
                r.max,
                over
            );
            assert!(r.samples > 100, "{name} {dir}: {} samples", r.samples);
            if r.min < (1.0 - BAND) * nominal || r.max > (1.0 + BAND) * nominal {
                failures.push(format!("{name} {dir:+}: {:.1}..{:.1} °/s", r.min, r.max));
            }
            if over > OVERSHOOT {
                failures.push(format!("{name} {dir:+}: start-up overshoot {over:.3}"));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
