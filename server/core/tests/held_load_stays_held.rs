//! A held load stays held (issue 27, item 2): both jaws on the 50 kg box, in air and in
//! water, open loop (joint sticks, or Cartesian sticks through the rate-controlled servo)
//! and closed loop (the cooperative controller, Zeng & Sepehri 2004 / Lim §3.4), for 60 s
//! with the sticks at zero, at 10⁻⁶ of full and at a slow 0.02-of-full lift: no slip, no
//! drop, and a bounded internal force. Invariant: with valve opening ∝ commanded rate
//! (Lim eqs 3.48–3.51) and centred closed-centre valves locking the cylinders (eqs 3.49–3.50
//! with zero flow), nothing integrates a mismatch of the two arms into pressure, so the
//! chain's internal load cannot ramp. Also: after a drop, a 10⁻⁶ Cartesian stick no longer
//! reconfigures the arm (the null-space motion of Jun eq. 21 scales with the command).

mod common;

use common::scenario_util::{dual_grasp, start};
use seaarms_core::grasp::GraspState;
use seaarms_core::sim::{
    self, Arm, ControlMethod, ControlMode, Current, Environment, Input, Simulation, Sticks,
};

/// How the operator's sticks reach the valves.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Mode {
    /// One valve per stick, open loop (Lim case studies 1–3).
    Joint,
    /// End-effector speeds per arm through redundancy resolution and the joint servo, open
    /// loop (the page's Cartesian mode; orientation held while both jaws hold).
    Cartesian,
    /// The object's twist through the cooperative controller (Lim case study 4).
    ClosedLoop,
}

/// The operator: the same stick on both arms (joint or Cartesian) or on the object, through
/// the core's operator stage (`sim::Operator`), as live sessions drive it.
struct Operator {
    mode: Mode,
    stage: sim::Operator,
}

impl Operator {
    fn new(mode: Mode) -> Operator {
        let m = common::builtin("magnum");
        let mut stage = sim::Operator::new(&m, &m);
        match mode {
            Mode::Joint => stage.set_mode(ControlMode::Joint),
            Mode::Cartesian => stage.set_mode(ControlMode::Cartesian),
            Mode::ClosedLoop => stage.set_method(ControlMethod::Closed),
        }
        Operator { mode, stage }
    }

    /// The input for one step with every stick axis of `stick` (fractions of full stick):
    /// joint mode puts it on both arms' valves, Cartesian mode on both arms' end-effector
    /// speed (orientation held while both jaws hold), closed loop on the object twist (scaled
    /// to the controller's maxima by the stage).
    fn input(&mut self, sim: &Simulation, stick: [f64; 6]) -> Input {
        let arms = Sticks {
            axes: stick,
            grip: 0.0,
        };
        match self.mode {
            Mode::Joint | Mode::Cartesian => self.stage.set_sticks(&[arms; 2], &[0.0; 6]),
            Mode::ClosedLoop => self.stage.set_sticks(&[Sticks::default(); 2], &stick),
        }
        *self.stage.input(sim)
    }
}

/// Norm of the internal force (N).
fn internal_force_n(sim: &Simulation) -> f64 {
    let w = sim.internal_wrench();
    (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt()
}

/// The larger load fraction λ of the two jaws.
fn load(sim: &Simulation) -> f64 {
    Arm::BOTH
        .map(|a| sim.arm(a).grip.load_fraction)
        .into_iter()
        .fold(0.0, f64::max)
}

/// What a 60 s hold saw.
#[derive(Debug)]
struct Hold {
    /// Internal force 2 s in (N: the spools of a preceding move have centred, τ = 25 ms, and
    /// the chain has settled), at the end, and its largest value from 2 s on.
    internal_2_s_n: f64,
    internal_end_n: f64,
    internal_peak_n: f64,
    /// Largest λ after the first 0.2 s.
    peak_load: f64,
    /// The box's rise over the hold (m).
    rise_m: f64,
}

/// `stick` for `seconds`: the box stays held by both jaws, no slip, no drop, finite state.
fn hold(sim: &mut Simulation, mode: Mode, stick: [f64; 6], seconds: f64) -> Hold {
    let mut op = Operator::new(mode);
    let slips0 = Arm::BOTH.map(|a| sim.arm(a).grip.slips);
    let z0 = sim.object().pose.translation.vector.z;
    let mut h = Hold {
        internal_2_s_n: 0.0,
        internal_end_n: 0.0,
        internal_peak_n: 0.0,
        peak_load: 0.0,
        rise_m: 0.0,
    };
    let n = (seconds * 1000.0).round() as usize;
    for k in 0..n {
        let input = op.input(sim, stick);
        sim.step(&input);
        if k >= 200 {
            h.peak_load = h.peak_load.max(load(sim));
        }
        if k == 2000 {
            h.internal_2_s_n = internal_force_n(sim);
        }
        if k >= 2000 {
            h.internal_peak_n = h.internal_peak_n.max(internal_force_n(sim));
        }
    }
    h.internal_end_n = internal_force_n(sim);
    h.rise_m = sim.object().pose.translation.vector.z - z0;
    assert_eq!(sim.numerical_faults(), 0);
    for a in Arm::BOTH {
        let s = sim.arm(a);
        assert!(
            s.q.iter()
                .chain(&s.qd)
                .chain(&s.p_in)
                .chain(&s.p_out)
                .all(|v| v.is_finite())
        );
    }
    assert_eq!(sim.grasp_state(), GraspState::BothHolding, "{h:?}");
    assert_eq!(
        Arm::BOTH.map(|a| sim.arm(a).grip.slips),
        slips0,
        "slipped: {h:?}"
    );
    assert_eq!(Arm::BOTH.map(|a| sim.arm(a).grip.slid_out), [0, 0]);
    h
}

/// The sticks of the acceptance: zero, 10⁻⁶ of full on every axis, and a slow lift (0.02 of
/// full: 4 mm/s up in Cartesian mode and closed loop). Joint mode has no slow pair lift: one
/// valve per joint moves the two jaws along different arcs (the arms are yawed towards each
/// other), so any joint-space move of the pair loads the chain — Lim case study 3's lesson
/// ("it is very hard to move an object by using dual arms cooperating with open-loop
/// control", §4.2); `dual_hold.rs` lifts 1.2 cm that way.
fn sticks(mode: Mode) -> &'static [(&'static str, [f64; 6])] {
    const ZERO: (&str, [f64; 6]) = ("zero", [0.0; 6]);
    const TINY: (&str, [f64; 6]) = ("1e-6", [1e-6; 6]);
    const LIFT: (&str, [f64; 6]) = ("0.02 lift", [0.0, 0.0, 0.02, 0.0, 0.0, 0.0]);
    match mode {
        Mode::Joint => &[ZERO, TINY],
        Mode::Cartesian | Mode::ClosedLoop => &[ZERO, TINY, LIFT],
    }
}

/// Lifts the held box off the seabed with both shoulders at 0.1 for 0.4 s (joint mode, Lim
/// case 3's open-loop lift in miniature, as in `dual_hold.rs`).
fn lift_a_little(sim: &mut Simulation) {
    let mut op = Operator::new(Mode::Joint);
    for _ in 0..400 {
        let input = op.input(sim, [0.0, 0.1, 0.0, 0.0, 0.0, 0.0]);
        sim.step(&input);
    }
    assert_eq!(sim.object().seabed_force_n, 0.0, "lifted off the seabed");
    assert_eq!(sim.grasp_state(), GraspState::BothHolding);
}

/// How much the internal force may rise over a 60 s hold above its value 2 s in (N): 40. That
/// value is what the grasp left (≈ 0 on the seabed) or what the open-loop lift left locked in
/// (≈ 280 N in air, 305 N in water: Lim case 3's lesson). Measured rises: zero stick
/// < 0.01 N; 10⁻⁶ stick < 4 N lifted, on the seabed ≤ 5 N in open loop and 34 N in closed
/// loop (the stick asks for 12 µm up in 60 s; the box, stuck to the seabed, does not follow, and
/// the object-pose loop's push grows — Lim's equal-share decomposition, which the reported
/// internal force uses, counts part of the moment-free share of that push as internal); the
/// 0.02 lift ≤ 13 N (docs/physics.md, "A held load stays held").
const MAX_RISE_N: f64 = 40.0;
/// Upper bound on the internal force at any time (N): the box's weight in air, 490 N — an
/// internal force larger than the load itself is the arms fighting each other.
const MAX_INTERNAL_N: f64 = 50.0 * 9.81;

fn all_sticks_hold(mode: Mode) {
    for env in [Environment::Air, Environment::subsea()] {
        let grasped = dual_grasp(env);
        let mut lifted = grasped.clone();
        lift_a_little(&mut lifted);
        for (start, sim0) in [("on the seabed", &grasped), ("lifted", &lifted)] {
            for (name, stick) in sticks(mode) {
                let mut sim = sim0.clone();
                let h = hold(&mut sim, mode, *stick, 60.0);
                println!("{mode:?} {} {start} {name}: {h:?}", env.name());
                assert!(h.peak_load <= 1.0, "{mode:?} {env:?} {name}: {h:?}");
                assert!(
                    h.internal_peak_n <= h.internal_2_s_n + MAX_RISE_N
                        && h.internal_peak_n < MAX_INTERNAL_N,
                    "{mode:?} {env:?} {start} {name}: {h:?}"
                );
            }
        }
    }
}

#[test]
fn joint_mode_holds_for_any_stick() {
    all_sticks_hold(Mode::Joint);
}

#[test]
fn cartesian_mode_holds_for_any_stick() {
    all_sticks_hold(Mode::Cartesian);
}

#[test]
fn closed_loop_holds_for_any_stick() {
    all_sticks_hold(Mode::ClosedLoop);
}

/// Sticks at zero while the instructor steps the current from still water to `speed_m_s`
/// at `heading_deg`, both jaws holding the box lifted off the seabed; 30 s. Returns the slips
/// of both jaws and the peak λ; asserts no drop, finite state.
fn current_step(mode: Mode, speed_m_s: f64, heading_deg: f64) -> (u64, f64) {
    let mut sim = dual_grasp(Environment::subsea());
    lift_a_little(&mut sim);
    sim.set_current(Current::new(speed_m_s, heading_deg).expect("current"))
        .expect("subsea");
    let mut op = Operator::new(mode);
    let slips0: u64 = Arm::BOTH.map(|a| sim.arm(a).grip.slips).iter().sum();
    let mut peak = 0.0_f64;
    for k in 0..30_000 {
        let input = op.input(&sim, [0.0; 6]);
        sim.step(&input);
        if k >= 200 {
            peak = peak.max(load(&sim));
        }
    }
    assert_eq!(sim.numerical_faults(), 0);
    assert_eq!(
        Arm::BOTH.map(|a| sim.arm(a).grip.slid_out),
        [0, 0],
        "{mode:?} {speed_m_s} m/s at {heading_deg}°: dropped"
    );
    assert_eq!(sim.grasp_state(), GraspState::BothHolding);
    let slips: u64 = Arm::BOTH.map(|a| sim.arm(a).grip.slips).iter().sum();
    println!(
        "current stepped to {speed_m_s} m/s at {heading_deg}°, {mode:?}: peak λ {peak:.3} \
         (from 0.2 s), {} slips",
        slips - slips0
    );
    (slips - slips0, peak)
}

/// The instructor steps the current to 2.5 m/s (the largest allowed; before the ramp the
/// step dropped a held box with 11–20 slips, issue 27) while both jaws hold the lifted box in
/// open loop, sticks at zero: the current ramps (`sim::water`, τ = 1.5 s) and the box stays
/// held — no drop along, across and quartering the pair, and no slip across and quartering
/// it (the pads creep below the slip notice at the steady 2.5 m/s load). Along the pair (0°,
/// along the bars) the jaws slip without dropping it: the drag on the box's 0.40 × 0.20 m face,
/// ½·ρ·C_d·A·u² = ½·1025·1.05·0.08·2.5² = 269 N at the centre of mass, acts 0.14 m below the
/// bars, and its 38 N·m about the horizontal normal to the bars can only be taken by the
/// jaws' moments (their forces are level with each other along x): 19 N·m each about their
/// closing axes, which since issue 27 item 4 lie normal to the bars (the grip's limits in the
/// bar frame, the wrist rotate turned onto the bar) — above the 15.2 N·m torsion limit
/// (`grasp::grip`), as in the closed loop below.
#[test]
fn a_current_stepped_to_full_does_not_drop_a_box_held_in_open_loop() {
    for mode in [Mode::Joint, Mode::Cartesian] {
        for heading in [0.0, 90.0, 225.0] {
            // `current_step` asserts no drop.
            let (slips, _) = current_step(mode, 2.5, heading);
            if heading != 0.0 {
                assert_eq!(slips, 0, "{mode:?} at {heading}°");
            }
        }
    }
}

/// The same in closed loop: stepped to 2.0 m/s at every heading and to 2.5 m/s across and
/// quartering the pair, no slip. (At 2.5 m/s along the pair the cooperative controller's
/// moment-free share asks each jaw for half of the drag's 35 N·m about the bar-normal axis,
/// above the 15.2 N·m torsion limit of `grasp::grip`: the grip slips once the current passes
/// 2.39 m/s, however slowly it ramps — a capacity limit of the finite grip in that share, left
/// to the grasp work of issue 27 item 4.)
#[test]
fn a_current_stepped_to_2_m_s_does_not_drop_a_box_held_in_closed_loop() {
    for (speed, heading) in [
        (2.0, 0.0),
        (2.0, 90.0),
        (2.0, 225.0),
        (2.5, 90.0),
        (2.5, 225.0),
    ] {
        let (slips, _) = current_step(Mode::ClosedLoop, speed, heading);
        assert_eq!(slips, 0, "closed loop, {speed} m/s at {heading}°");
    }
}

/// After the pair lets go, a Cartesian stick of 10⁻⁶ of full moves the free arm by no more
/// than the command asks (10⁻⁶ × 0.2 m/s for 4 s is 0.8 µm): the null-space term scales with
/// the command (before: 18° of reconfiguration in 4 s).
#[test]
fn a_tiny_cartesian_stick_does_not_reconfigure_a_free_arm() {
    let m = common::builtin("magnum");
    let (sc, _) = start("case3-dual-open-loop");
    let mut sim = Simulation::new(m.clone(), m, sc.params.clone()).expect("sim");
    let mut op = Operator::new(Mode::Cartesian);
    let q0 = sim.arm(Arm::Left).q;
    for _ in 0..4000 {
        let input = op.input(&sim, [1e-6; 6]);
        sim.step(&input);
    }
    let q1 = sim.arm(Arm::Left).q;
    let moved = q0
        .iter()
        .zip(&q1)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    println!("largest joint change under a 1e-6 stick in 4 s: {moved:.3e} rad");
    // The arm's own settling at the start pose is part of this; 18° = 0.31 rad before.
    assert!(moved < 1e-3, "{moved} rad");
}

/// Closed loop, the current stepped to 2.5 m/s along the pair (0°): the acceptance's "no
/// drop". The jaws slip (4 slip onsets measured on the bar-frame grip: the moment-free share
/// asks each jaw for more torsion than its 15.2 N·m holds once the current passes 2.39 m/s),
/// but the bars stay in both jaws and the pair holds the box (`current_step` asserts it).
#[test]
fn a_current_stepped_to_full_along_the_pair_does_not_drop_a_box_held_in_closed_loop() {
    let (slips, peak) = current_step(Mode::ClosedLoop, 2.5, 0.0);
    println!("closed loop, 2.5 m/s along the pair: {slips} slips, peak λ {peak:.3}");
    assert!(peak <= 1.0 + 1e-9, "λ is capped at 1 while sliding: {peak}");
}
