//! The subsea environment (issue 17 item 7) against closed forms:
//! * a box released in still water accelerates at (m − ρV)g/(m + m_a) (Newton's second law
//!   with buoyancy and added mass; DNV-RP-H103 (2011) §3.2 "added mass") and approaches
//!   v(t) = v_t·tanh(a₀t/v_t), v_t = √(2(m − ρV)g/(ρC_D·A)) — the solution of
//!   (m + m_a)v̇ = (m − ρV)g − ½ρC_D·A·v² (e.g. Newman (1977) "Marine Hydrodynamics" §2.5);
//! * with a current, each horizontal body-axis component of the velocity relative to the
//!   water decays as v_r(t) = v_r0/(1 + k·v_r0·t/(m + m_a)) (the same equation without
//!   weight, solved by separation), so the box drifts downstream towards the current;
//! * link drag only takes energy out of still water: q̇ᵀτ_drag = −Σ k|w|·|w|² ≤ 0.

mod common;

use nalgebra::Vector3;
use seaarms_core::dynamics::Inertials;
use seaarms_core::kinematics::{KinData, forward_kinematics};
use seaarms_core::sim::water::{self, BOX_ADDED_MASS, BOX_DRAG, MAX_CURRENT_M_S};
use seaarms_core::sim::{Arm, Current, Environment, Flow, Input, SimParams, Simulation, Water};

const RHO: f64 = 1025.0;
const G: f64 = 9.81;

/// A simulation in sea water (current `c`) with the box hung far above a deep seabed, so it
/// falls freely (the arms stay at rest clear of it).
fn free_box(c: Current) -> Simulation {
    let m = common::builtin("magnum");
    let mut p = SimParams::training(&m, &m).expect("params");
    p.step.environment = Environment::Subsea(Water {
        density_kgm3: RHO,
        current: c,
    });
    p.object.seabed_z_m = -1.0e4;
    Simulation::new(m.clone(), m, p).expect("sim")
}

/// The box's mass, displaced volume, added mass and the effective mass (kg, m³).
fn box_figures(s: &Simulation) -> (f64, f64, f64, f64) {
    let op = &s.params().object;
    let v = op.size_m.x * op.size_m.y * op.size_m.z;
    let ma = BOX_ADDED_MASS * RHO * v;
    (op.mass_kg, v, ma, op.mass_kg + ma)
}

#[test]
fn a_box_sinks_at_the_closed_form_terminal_velocity() {
    let mut s = free_box(Current::default());
    let (m, v, _, m_eff) = box_figures(&s);
    let op = s.params().object;
    let area = op.size_m.x * op.size_m.y; // the face normal to z (the box falls flat)
    let a0 = (m - RHO * v) * G / m_eff;
    let vt = (2.0 * (m - RHO * v) * G / (RHO * BOX_DRAG * area)).sqrt();
    let h = s.params().step.dt_s;
    let input = Input::default();
    s.step(&input);
    let a_measured = -s.object().velocity.z / h;
    // Drag at v = a₀h is (a₀h/v_t)² ≈ 4·10⁻⁶ of the weight: the first step's acceleration is a₀.
    assert!(
        (a_measured - a0).abs() < 1e-4 * a0,
        "initial acceleration {a_measured} vs {a0} m/s²"
    );
    // v(t) = v_t·tanh(a₀t/v_t) at 0.5 s (mid-transient) and at 10 s (terminal).
    let mut t = h;
    while t < 0.5 - 1e-9 {
        s.step(&input);
        t += h;
    }
    let v_half = -s.object().velocity.z;
    let closed = vt * (a0 * t / vt).tanh();
    assert!(
        (v_half - closed).abs() < 2e-3 * closed,
        "v(0.5 s) {v_half} vs {closed} m/s"
    );
    for _ in 0..9500 {
        s.step(&input);
    }
    let vz = -s.object().velocity.z;
    eprintln!("terminal velocity: measured {vz:.5} m/s, closed form {vt:.5} m/s, a0 {a0:.4}");
    assert!((vz - vt).abs() < 1e-3 * vt, "terminal {vz} vs {vt} m/s");
    let horiz = s.object().velocity.xy().norm();
    assert!(horiz < 1e-9, "still water: no sideways motion ({horiz})");
    assert_eq!(s.numerical_faults(), 0);
}

#[test]
fn a_current_carries_a_free_box_downstream() {
    let c = Current::new(0.5, 30.0).expect("current");
    let u = c.velocity();
    let mut s = free_box(c);
    let (_, _, _, m_eff) = box_figures(&s);
    let op = s.params().object;
    // Drag constants ½ρC_D·A_k of the faces normal to x and y (the box does not turn).
    let kx = 0.5 * RHO * BOX_DRAG * op.size_m.y * op.size_m.z;
    let ky = 0.5 * RHO * BOX_DRAG * op.size_m.x * op.size_m.z;
    let input = Input::default();
    let h = s.params().step.dt_s;
    let steps = 20_000;
    for _ in 0..steps {
        s.step(&input);
    }
    let t = steps as f64 * h;
    let vel = s.object().velocity;
    // Relative velocity starts at −u (the box at rest in moving water).
    let closed = |k: f64, u: f64| u - u / (1.0 + k * u.abs() * t / m_eff);
    let (cx, cy) = (closed(kx, u.x), closed(ky, u.y));
    eprintln!(
        "drift after {t} s: ({:.4}, {:.4}) m/s, closed form ({cx:.4}, {cy:.4}), current ({:.4}, {:.4})",
        vel.x, vel.y, u.x, u.y
    );
    assert!(
        (vel.x - cx).abs() < 5e-3 * u.x.abs(),
        "vx {} vs {cx}",
        vel.x
    );
    assert!(
        (vel.y - cy).abs() < 5e-3 * u.y.abs(),
        "vy {} vs {cy}",
        vel.y
    );
    // Downstream: most of the way to the current's speed, along its heading.
    let along = vel.xy().dot(&u.xy()) / u.norm();
    assert!(along > 0.8 * u.norm(), "drift {along} m/s of {}", u.norm());
    let heading = vel.y.atan2(vel.x).to_degrees();
    assert!((heading - 30.0).abs() < 5.0, "drift heading {heading}°");
}

#[test]
fn link_drag_only_takes_energy_out_of_still_water() {
    let model = common::builtin("magnum");
    let inr = Inertials::magnum(&model).expect("inertials");
    let mut kin = KinData::new(&model);
    let mut rng = common::rng::Rng(0x5eed_0017);
    let still = Water::default();
    for _ in 0..200 {
        let q: [f64; 6] = core::array::from_fn(|_| rng.sym(1.0));
        let qd: [f64; 6] = core::array::from_fn(|_| rng.sym(0.6));
        forward_kinematics(&model, &mut kin, &q);
        let hy = water::arm_hydro(
            &model,
            &inr,
            &kin,
            &qd,
            &still,
            &Flow::steady(&still.current),
            1e-3,
        );
        let power: f64 = (0..6).map(|j| hy.torque[j] * qd[j]).sum();
        assert!(power < 0.0, "drag power {power} W at q̇ {qd:?}");
        // Added mass and the drag Jacobian: symmetric positive semi-definite.
        let m = hy.matrix;
        assert!((m - m.transpose()).norm() < 1e-12 * (1.0 + m.norm()));
        let eig = m.symmetric_eigenvalues();
        assert!(eig.min() > -1e-12 * m.norm(), "eigenvalues {eig}");
        // At rest in still water: no drag, the added mass alone.
        let rest = water::arm_hydro(
            &model,
            &inr,
            &kin,
            &[0.0; 6],
            &still,
            &Flow::steady(&still.current),
            1e-3,
        );
        assert_eq!(rest.torque.norm(), 0.0);
    }
}

#[test]
fn the_links_added_mass_is_the_cylinders_closed_form() {
    // Only the swing joint turns (about the base z axis) at q = 0: the upper links lie in the
    // horizontal plane, every piece moves normal to its axis or along it. For a single link
    // lying radially (the swing housing, from the swing axis out along x) the added inertia
    // about z is C_A·ρ·(V/n)·Σ r_s² over its n pieces at radii r_s (midpoints) — the
    // potential-flow added mass per unit length ρπr² (Newman (1977) §4.13) on each piece.
    let model = common::builtin("magnum");
    let mut inr = Inertials::magnum(&model).expect("inertials");
    for l in inr.links.iter_mut().skip(1) {
        l.volume_m3 = 0.0; // only link 0 displaces water
    }
    let mut kin = KinData::new(&model);
    forward_kinematics(&model, &mut kin, &[0.0; 6]);
    let hy = water::arm_hydro(
        &model,
        &inr,
        &kin,
        &[0.0; 6],
        &Water::default(),
        &Flow::default(),
        0.0,
    );
    let p0 = kin.joint_frames[0].translation.vector;
    let p1 = kin.joint_frames[1].translation.vector;
    let z0 = kin.joint_frames[0].rotation * model.joints[0].axis.into_inner();
    let seg = p1 - p0;
    let t = seg.normalize();
    let n = water::LINK_SEGMENTS;
    let mut expected = 0.0;
    for s in 0..n {
        let x = p0 + seg * ((s as f64 + 0.5) / n as f64);
        let vel = z0.cross(&(x - p0)); // velocity per unit swing rate
        let normal = vel - t * t.dot(&vel);
        expected += RHO * inr.links[0].volume_m3 / n as f64 * normal.norm_squared();
    }
    assert!(expected > 0.0);
    assert!(
        (hy.matrix[(0, 0)] - expected).abs() < 1e-12 * expected,
        "{} vs {expected}",
        hy.matrix[(0, 0)]
    );
}

#[test]
fn the_swing_actuator_carries_the_links_drag() {
    // The swing axis is vertical: turning the arm about it at steady speed with the other
    // joints still needs no torque for gravity, buoyancy or velocity products (q̈ = 0, one
    // joint moving), so in water the actuator's torque is the links' drag moment about the
    // axis, and in air ≈ 0. The valves are flow-controlled: the speed hardly changes, the
    // pressure does. Averaged over the last 0.2 s to smooth the hydraulic ripple.
    let run = |env: Environment| {
        let m = common::builtin("magnum");
        let p = SimParams::case_study(&m, &m)
            .expect("params")
            .with_environment(env);
        let mut s = Simulation::new(m.clone(), m, p).expect("sim");
        let mut inp = Input::default();
        inp.arms[Arm::Left.index()].valves[0] = 0.8;
        let (mut torque, mut drag, mut n) = (0.0, 0.0, 0.0);
        let inr = s.params().arms[Arm::Left.index()].inertials.clone();
        let model = s.model(Arm::Left).clone();
        let mut kin = KinData::new(&model);
        for k in 0..1000 {
            s.step(&inp);
            if k >= 800 {
                let a = s.arm(Arm::Left);
                torque += a.torque[0];
                if let Some(w) = s.environment().water() {
                    forward_kinematics(&model, &mut kin, &a.q);
                    drag += water::arm_hydro(
                        &model,
                        &inr,
                        &kin,
                        &a.qd,
                        w,
                        &Flow::steady(&w.current),
                        0.0,
                    )
                    .torque[0];
                }
                n += 1.0;
            }
        }
        assert_eq!(s.numerical_faults(), 0);
        (torque / n, drag / n, s.arm(Arm::Left).qd[0])
    };
    let (air, _, rate_air) = run(Environment::Air);
    let (wet, drag, rate_wet) = run(Environment::subsea());
    eprintln!(
        "swing at {rate_wet:.4} rad/s (air {rate_air:.4}): actuator torque {wet:.3} N·m in water, \
         {air:.3} in air; drag moment {drag:.3} N·m"
    );
    assert!(drag < 0.0, "drag opposes the swing: {drag}");
    assert!(
        (wet - air + drag).abs() < 0.05 * drag.abs(),
        "actuator torque in water {wet} − air {air} vs the drag moment {}",
        -drag
    );
    // The strongest current at a quartering heading: finite and without rollbacks.
    let m = common::builtin("magnum");
    let env = Environment::Subsea(Water {
        density_kgm3: RHO,
        current: Current::new(MAX_CURRENT_M_S, 200.0).expect("current"),
    });
    let p = SimParams::case_study(&m, &m)
        .expect("params")
        .with_environment(env);
    let mut s = Simulation::new(m.clone(), m, p).expect("sim");
    let mut inp = Input::default();
    inp.arms[Arm::Right.index()].valves = [1.0, 1.0, -1.0, 1.0, 1.0, 1.0];
    for _ in 0..3000 {
        s.step(&inp);
    }
    assert_eq!(s.numerical_faults(), 0);
}

#[test]
fn the_current_is_bounded_and_only_set_in_water() {
    for (speed, heading) in [
        (f64::NAN, 0.0),
        (-0.1, 0.0),
        (MAX_CURRENT_M_S + 0.01, 0.0),
        (1e300, 0.0),
        (0.5, f64::INFINITY),
        (0.5, 1e9),
    ] {
        assert!(Current::new(speed, heading).is_err(), "{speed}, {heading}");
    }
    let c = Current::new(1.0, -90.0).expect("current");
    assert_eq!(c.heading_deg, 270.0);
    assert!((c.velocity() - Vector3::new(0.0, -1.0, 0.0)).norm() < 1e-12);
    let m = common::builtin("magnum");
    let p = SimParams::case_study(&m, &m).expect("params");
    let mut air = Simulation::new(m.clone(), m, p).expect("sim");
    assert!(air.set_current(c).is_err());
    assert_eq!(air.environment(), &Environment::Air);
}
