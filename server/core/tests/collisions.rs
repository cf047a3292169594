//! Links and jaws do not pass through the seabed, the box, the panel or the other arm: driven
//! at full stick into them, no collision shape goes more than 1 cm in, the contact force is
//! reported and shows in the line pressures; the box is pushed by a jaw; the resting box
//! carries its wet weight; nothing is in contact at the start postures.

mod common;

use seaarms_core::collision::Partner;
use seaarms_core::sim::{Arm, ArmInput, Input, PanelParams, SimParams, Simulation};

fn magnum() -> seaarms_core::Model {
    common::builtin("magnum")
}

fn sim(wet: bool, panel: bool) -> Simulation {
    let m = magnum();
    let mut p = if wet {
        SimParams::training(&m, &m).expect("params")
    } else {
        SimParams::case_study(&m, &m).expect("params")
    };
    if panel {
        p = p.with_panel(PanelParams::standard());
    }
    Simulation::new(m.clone(), m, p).expect("sim")
}

/// What a run of full-stick driving shows.
#[derive(Debug, Default)]
struct Run {
    max_depth_m: f64,
    max_force_n: f64,
    partners: Vec<Partner>,
    max_dp_pa: f64,
    strikes: u64,
    relief: u64,
}

fn drive(s: &mut Simulation, arms: [ArmInput; 2], seconds: f64) -> Run {
    let input = Input {
        arms,
        ..Input::default()
    };
    let mut r = Run::default();
    let n = (seconds / 1e-3).round() as usize;
    for _ in 0..n {
        s.step(&input);
        for i in 0..2 {
            let c = &s.contacts().arms[i];
            r.max_depth_m = r.max_depth_m.max(c.max_depth_m);
            if let Some(st) = c.strongest {
                r.max_force_n = r.max_force_n.max(st.normal_force_n);
                if !r.partners.contains(&st.partner) {
                    r.partners.push(st.partner);
                }
            }
        }
    }
    r.strikes = s.contacts().arms.iter().map(|a| a.strikes).sum();
    r.relief = s.relief_events();
    r
}

fn valves(v: [f64; 6]) -> ArmInput {
    ArmInput {
        valves: v,
        ..ArmInput::default()
    }
}

#[test]
fn probe() {
    for wet in [false, true] {
        for j in 0..6 {
            for sign in [-1.0, 1.0] {
                let mut s = sim(wet, false);
                let mut v = [0.0; 6];
                v[j] = sign;
                let r = drive(&mut s, [valves(v), valves(v)], 5.0);
                let tl = s.end_effector(Arm::Left).translation.vector;
                println!(
                    "wet {wet} joint {j} sign {sign}: depth {:.4} force {:.0} {:?} strikes {} relief {} tool z {:.3} faults {}",
                    r.max_depth_m, r.max_force_n, r.partners, r.strikes, r.relief, tl.z, s.numerical_faults()
                );
            }
        }
    }
}

#[test]
fn probe2() {
    let mut s = sim(false, false);
    let v = [0.0, -1.0, 0.0, 0.0, 0.0, 0.0];
    let input = Input { arms: [valves(v), valves([0.0; 6])], ..Input::default() };
    for k in 0..3000 {
        s.step(&input);
        let c = &s.contacts().arms[0];
        if (150..215).contains(&k) {
            let a = s.arm(Arm::Left);
            println!("t {:.3} q {:?} qd1 {:.3} depth {:.4} n {} strongest {:?}", s.time_s(), a.q.map(|x| (x * 57.3 * 10.0).round() / 10.0), a.qd[1], c.max_depth_m, c.points, c.strongest.map(|x| (x.part, x.normal_force_n, x.point_m)));
        }
    }
}

#[test]
fn probe3() {
    use parry3d_f64::math::{Pose, Vector};
    use parry3d_f64::shape::{Cuboid, HalfSpace};
    let c = Cuboid::new(Vector::new(0.0175, 0.008, 0.05));
    let plane = HalfSpace::new(Vector::Z);
    let pp = Pose::translation(0.0, 0.0, -0.45);
    for z in [-0.38, -0.40, -0.41] {
        let p = Pose::translation(1.28, 0.96, z);
        let r = parry3d_f64::query::contact(&p, &c, &pp, &plane, 0.0);
        println!("z {z}: {r:?}");
        let r = parry3d_f64::query::contact(&pp, &plane, &p, &c, 0.0);
        println!("z {z} swapped: {r:?}");
    }
}

#[test]
fn probe4() {
    // arms into each other
    for wet in [false, true] {
        let mut s = sim(wet, false);
        let r = drive(&mut s, [valves([-1.0, 0.0, 0.0, 0.0, 0.0, 0.0]), valves([1.0, 0.0, 0.0, 0.0, 0.0, 0.0])], 5.0);
        println!("swing together wet {wet}: {r:?} L {:?} R {:?}", s.contacts().arms[0].strongest, s.contacts().arms[1].strongest);
        let mut s = sim(wet, false);
        let r = drive(&mut s, [valves([-1.0, 0.0, 0.0, 0.0, -1.0, 0.0]), valves([1.0, 0.0, 0.0, 0.0, 1.0, 0.0])], 5.0);
        println!("swing+yaw together wet {wet}: {r:?} L {:?} R {:?}", s.contacts().arms[0].strongest, s.contacts().arms[1].strongest);
        // panel
        for v in [[0.0, 1.0, 1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 1.0, 0.0, 0.0]] {
            let mut s = sim(wet, true);
            let r = drive(&mut s, [valves(v), valves(v)], 5.0);
            println!("panel {v:?} wet {wet}: {r:?} L {:?}", s.contacts().arms[0].strongest);
        }
        // box push: right arm swing +
        for v in [[1.0, 0.0, 0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0, 1.0, 0.0], [0.5, -0.3, 0.0, 0.0, 0.0, 0.0]] {
            let mut s = sim(wet, false);
            let p0 = s.object().pose.translation.vector;
            let r = drive(&mut s, [valves([0.0; 6]), valves(v)], 5.0);
            let p1 = s.object().pose.translation.vector;
            println!("box push {v:?} wet {wet}: {r:?} moved {:.3} R {:?} box force {:?}", (p1 - p0).norm(), s.contacts().arms[1].strongest, s.contacts().box_force_n);
        }
    }
}
