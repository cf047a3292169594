//! Two jaws hold the nominal 50 kg box in open loop (not the cooperative closed loop) with
//! the jaws' finite grip: once the operator lets go of the sticks the box stays held. With
//! the valves centred the closed-centre valves trap the oil and lock the cylinders (Lim
//! eqs 3.49–3.50 with zero valve flow: the chamber volumes, hence the joints, cannot move but
//! by compressing the oil), so nothing can make the closed chain's internal load grow: its
//! internal force is what the grasp and the lift left in it and stays there. The operator
//! drives the arms through the core's operator ([`Operator`], as live sessions do) either joint
//! by joint (joystick per valve, Lim case studies 1–3) or in Cartesian mode (an end-effector
//! speed per arm through the joint servo);
//! both must hold, in air (Lim's setting) and subsea (training). Before the fix, the joint
//! servo's position hold in Cartesian mode pushed each arm towards its own reference through
//! the rigid box: λ rose by ≈ 0.05 per second and the box slipped out of the jaws after
//! ≈ 20 s (docs/physics.md, "Holding a box in open loop").

mod common;

use common::scenario_util::dual_grasp;
use seaarms_core::control::teleop::cartesian_to_joint_velocity;
use seaarms_core::grasp::GraspState;
use seaarms_core::redundancy::{Redundancy, RedundancyParams};
use seaarms_core::sim::{Arm, ControlMode, Environment, Input, Operator, Simulation, Sticks};

/// The core's operator (stage 0, as live sessions, exercises and replays drive the arms) in
/// `mode` at full speed, open loop: joint mode puts the axes on the valves; Cartesian mode
/// resolves them per arm, the tools' orientation held while both jaws hold.
fn operator(mode: ControlMode) -> Operator {
    let m = common::builtin("magnum");
    let mut op = Operator::new(&m, &m);
    op.set_mode(mode);
    op
}

/// One step with `axes` on both arms' sticks (grips centred).
fn step_with(sim: &mut Simulation, op: &mut Operator, axes: [f64; 6]) {
    op.set_sticks(&[Sticks { axes, grip: 0.0 }; 2], &[0.0; 6]);
    op.step(sim);
}

/// The counterfactual the operator does not do: Cartesian `stick` on both arms resolved on
/// the translational rows only, although both jaws hold (`resolvers`: one per arm).
fn translational_rows_only(
    sim: &Simulation,
    resolvers: &mut [Redundancy; 2],
    stick: [f64; 6],
) -> Input {
    let m = common::builtin("magnum");
    let mut input = Input::default();
    for arm in Arm::BOTH {
        let i = arm.index();
        input.arms[i].joint_velocity_ref = Some(cartesian_to_joint_velocity(
            &mut resolvers[i],
            &m,
            &sim.params().arms[i].base.rotation,
            &sim.arm(arm).q,
            &stick,
            false,
            1e-3,
        ));
    }
    input
}

/// Norm of the internal force (N).
fn internal_force_n(sim: &Simulation) -> f64 {
    let w = sim.internal_wrench();
    (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt()
}

/// What a hold with the sticks at zero saw.
#[derive(Debug)]
struct Hold {
    /// Largest load fraction of either jaw over the hold from 0.2 s on (the arms have stopped:
    /// the spools are within 3·10⁻⁴ of centre, 8 time constants).
    peak_load: f64,
    /// Load fraction of either jaw (the larger) 2 s into the hold, when the spools have
    /// centred (τ = 25 ms) and the chain has settled.
    load_at_2_s: f64,
    /// Load fraction at the end.
    load_at_end: f64,
    /// Internal force 2 s into the hold (N).
    internal_at_2_s_n: f64,
    /// Largest internal force after that (N).
    internal_peak_n: f64,
}

/// The larger load fraction of the two jaws.
fn load(sim: &Simulation) -> f64 {
    Arm::BOTH
        .map(|a| sim.arm(a).grip.load_fraction)
        .into_iter()
        .fold(0.0, f64::max)
}

/// Sticks at zero for `seconds` (≥ 30 s of simulated time in every test): the box stays held
/// by both jaws with no slip and no drop, and the state stays finite.
fn hold(sim: &mut Simulation, op: &mut Operator, seconds: f64) -> Hold {
    let slips0 = Arm::BOTH.map(|a| sim.arm(a).grip.slips);
    let mut h = Hold {
        peak_load: 0.0,
        load_at_2_s: 0.0,
        load_at_end: 0.0,
        internal_at_2_s_n: 0.0,
        internal_peak_n: 0.0,
    };
    let n = (seconds * 1000.0).round() as usize;
    for k in 0..n {
        step_with(sim, op, [0.0; 6]);
        if k >= 200 {
            h.peak_load = h.peak_load.max(load(sim));
        }
        if k == 2000 {
            h.internal_at_2_s_n = internal_force_n(sim);
            h.load_at_2_s = load(sim);
        } else if k > 2000 {
            h.internal_peak_n = h.internal_peak_n.max(internal_force_n(sim));
        }
    }
    h.load_at_end = load(sim);
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

/// The bounds every hold meets.
/// * λ ≤ `max_load` throughout: 0.8 (a 20 % margin on the static friction ellipsoid) where
///   only the grasp loads the jaws; after an open-loop lift, whatever internal load the lift
///   left (the thesis's lesson: moving the pair in open loop loads the chain), at most 1.
/// * Nothing grows: with the cylinders locked by trapped oil nothing drives the chain, so
///   after the spools have centred neither λ nor the internal force may rise — at most 1 %
///   of the grip (λ + 0.01) and 1 % + 2 N of the internal force (round-off and the oil's
///   settling) over their values 2 s into the hold.
/// * The internal force stays below the box's weight in air (490 N): an internal force
///   larger than the load itself is the arms fighting each other.
fn assert_held(what: &str, h: &Hold, max_load: f64) {
    println!("{what}: {h:?}");
    assert!(h.peak_load <= max_load, "{what}: {h:?}");
    assert!(
        h.load_at_end <= h.load_at_2_s + 0.01,
        "{what}: λ grew: {h:?}"
    );
    assert!(
        h.internal_peak_n <= 1.01 * h.internal_at_2_s_n + 2.0,
        "{what}: internal force grew: {h:?}"
    );
    assert!(h.internal_peak_n < 50.0 * 9.81, "{what}: {h:?}");
}

/// Lifts the held box off the seabed with both arms' shoulders at the same small signal
/// (0.1 for 0.4 s; joint mode, Lim case 3's open-loop lift in miniature).
fn lift_a_little(sim: &mut Simulation) -> f64 {
    let z0 = sim.object().pose.translation.vector.z;
    let mut op = operator(ControlMode::Joint);
    for _ in 0..400 {
        step_with(sim, &mut op, [0.0, 0.1, 0.0, 0.0, 0.0, 0.0]);
    }
    let dz = sim.object().pose.translation.vector.z - z0;
    // Off the seabed: the jaws carry the box.
    assert!(
        dz > 0.01 && sim.object().seabed_force_n == 0.0,
        "lifted {dz} m"
    );
    assert_eq!(sim.grasp_state(), GraspState::BothHolding);
    dz
}

fn grasp_and_hold(env: Environment, mode: ControlMode) {
    let mut sim = dual_grasp(env);
    let mut op = operator(mode);
    let h = hold(&mut sim, &mut op, 30.0);
    assert_held(&format!("{mode:?} {env:?} on the seabed"), &h, 0.8);
}

fn lift_and_hold(env: Environment, mode: ControlMode) {
    let mut sim = dual_grasp(env);
    let dz = lift_a_little(&mut sim);
    let mut op = operator(mode);
    let h = hold(&mut sim, &mut op, 30.0);
    assert_held(&format!("{mode:?} {env:?} lifted {dz:.3} m"), &h, 1.0);
}

#[test]
fn a_box_grasped_on_the_seabed_stays_held() {
    grasp_and_hold(Environment::Air, ControlMode::Joint);
    grasp_and_hold(Environment::subsea(), ControlMode::Cartesian);
}

#[test]
fn a_lifted_box_stays_held_in_joint_mode() {
    for env in [Environment::Air, Environment::subsea()] {
        lift_and_hold(env, ControlMode::Joint);
    }
}

#[test]
fn a_lifted_box_stays_held_in_cartesian_mode() {
    // Failed before the servo centred the valves in a closed chain: the internal force grew
    // from 11 N to 1.58 kN (air) and the box was dropped.
    for env in [Environment::Air, Environment::subsea()] {
        lift_and_hold(env, ControlMode::Cartesian);
    }
}

/// One open-loop Cartesian lift of the held pair: both sticks pushed up over `ramp_s` to 0.1 of
/// full stick (2 cm/s) and held there until `t_s`, the tools' orientation held (`chain`, as the
/// page's resolver does while both jaws hold) or the translational rows only. Returns the box's
/// rise (m), the slips of both jaws, the time of the first slip (s) and the peak load fraction.
fn cartesian_pair_lift(
    env: Environment,
    chain: bool,
    ramp_s: f64,
    t_s: f64,
) -> (f64, u64, Option<f64>, f64) {
    let mut sim = dual_grasp(env);
    let mut op = operator(ControlMode::Cartesian);
    let m = common::builtin("magnum");
    let mut resolvers = [
        Redundancy::new(&m, RedundancyParams::default()),
        Redundancy::new(&m, RedundancyParams::default()),
    ];
    let z0 = sim.object().pose.translation.vector.z;
    let slips0: u64 = Arm::BOTH.map(|a| sim.arm(a).grip.slips).iter().sum();
    let (mut first_slip, mut peak) = (None, 0.0f64);
    let n = (t_s / 1e-3).round() as usize;
    for k in 0..n {
        let t = k as f64 * 1e-3;
        let stick = [0.0, 0.0, 0.1 * (t / ramp_s).min(1.0), 0.0, 0.0, 0.0];
        if chain {
            step_with(&mut sim, &mut op, stick);
        } else {
            let input = translational_rows_only(&sim, &mut resolvers, stick);
            sim.step(&input);
        }
        peak = peak.max(load(&sim));
        let slips: u64 = Arm::BOTH.map(|a| sim.arm(a).grip.slips).iter().sum();
        if first_slip.is_none() && slips > slips0 {
            first_slip = Some(t);
        }
    }
    let slips: u64 = Arm::BOTH.map(|a| sim.arm(a).grip.slips).iter().sum();
    let dz = sim.object().pose.translation.vector.z - z0;
    (dz, slips - slips0, first_slip, peak)
}

/// Both arms driven in Cartesian mode with the same upward end-effector speed in open loop,
/// the box held by both jaws (Lim §4.2.3's lesson: "it is very hard to move an object by using
/// dual arms cooperating with open-loop control"). With the tools' orientation held (the page's
/// resolver while both jaws hold) and the stick pushed over 0.5 s, the pair lifts the box by
/// about the commanded 2.5 cm in 1.5 s without a slip; the two servos' errors still twist the
/// bars (the roll about the bar axis grows; in air the jaws slip about 0.4 s later).
/// With the translational rows only, each arm's null-space motion (Jun eq. 21, scaled by the
/// stick's deflection) turns its jaw against the other through the box: the pair loses part of
/// the lift.
/// Other stick speeds and ramps sit just as close to the grip's limit, some slipping and some
/// not (docs/physics.md, "Moving the pair in Cartesian mode"); trainees lift the pair in closed
/// loop (the `dual-lift` exercise).
#[test]
fn a_cartesian_lift_of_the_pair_lifts_best_with_the_orientation_held() {
    for env in [Environment::Air, Environment::subsea()] {
        let (dz_held, slips, first, peak) = cartesian_pair_lift(env, true, 0.5, 1.5);
        println!("{env:?} orientation held: rose {dz_held:.4} m, {slips} slips, peak λ {peak:.3}");
        assert_eq!((slips, first), (0, None), "{env:?}: slipped");
        // 0.02 m/s × (1.5 s − 0.25 s of ramp) = 0.025 m commanded, less the servo's lag.
        assert!(
            (0.018..=0.026).contains(&dz_held),
            "{env:?}: rose {dz_held} m"
        );
        // The onset and the growing twist take λ to ≈ 1: the pads creep, under the slip notice
        // (2 mm / 2°), and grip again.
        assert!(peak <= 1.1, "{env:?}: peak λ {peak}");
        let (dz, slips, first, peak_t) = cartesian_pair_lift(env, false, 0.5, 1.5);
        println!(
            "{env:?} translational rows only: rose {dz:.4} m, {slips} slips, first at {first:?} s, peak λ {peak_t:.3}"
        );
        // The null-space twist scales with the stick (ε × 0.1 here, issue 27) and turns the
        // jaws against each other through the box: the pads are loaded to their limit and
        // creep (λ 1.00 against 0.39 in air, 0.20 in water with the orientation held) and the
        // pair loses part of the lift (on the restored arm of issue 27 item 5 with pads rigid
        // in torsion: air 0.0218 of 0.0242 m, water 0.0229 of 0.0244 m; on the earlier
        // 0.10/0.60/0.40/0.25/0.10/0.16 m arm it also slipped the jaws in air). With the pads
        // compliant in torsion (issue 27 item 4) the twist about the closing axes goes into the
        // pads: air 0.0232 of 0.0242 m, water 0.0241 of 0.0244 m.
        assert!(peak_t > 2.0 * peak, "{env:?}: peak λ {peak_t} vs {peak}");
        let margin = if env == Environment::Air {
            5.0e-4
        } else {
            1.0e-4
        };
        assert!(dz < dz_held - margin, "{env:?}: rose {dz} m of {dz_held} m");
    }
}
