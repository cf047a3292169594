//! Links and jaws do not pass through the seabed, the box, the panel or the other arm: driven
//! at full stick into them (joint and Cartesian mode, air and water) no collision shape goes
//! more than 1 cm in (issue 27's acceptance), the contact force and a strike are reported,
//! and the stall shows in the line pressures; a jaw pushes the box; the box resting on the
//! seabed carries its weight in water, and dropped from 0.3 m it settles without jitter; the
//! start postures and the case studies' grasp approach touch nothing; the narrow phase
//! agrees with closed-form geometry; a step in contact allocates nothing.

mod common;

use nalgebra::{Isometry3, Vector3};
use seaarms_core::collision::{
    ArmPart, ArmShapes, CollisionSpec, Epa, Exclusions, Item, Partner, Posed, Touch, World,
    arm_touches, world_touches,
};
use seaarms_core::control::teleop::cartesian_to_joint_velocity;
use seaarms_core::redundancy::{Redundancy, RedundancyParams};
use seaarms_core::sim::{
    Arm, ArmInput, Event, Input, PanelParams, STRIKE_WINDOW_S, SimParams, Simulation, Strike,
};

use common::scenario_util::start;

/// The acceptance's bound on how far any collision shape may go into anything (m).
const MAX_DEPTH_M: f64 = 0.01;

fn sim(wet: bool, panel: bool) -> Simulation {
    let m = common::builtin("magnum");
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

fn valves(v: [f64; 6]) -> ArmInput {
    ArmInput {
        valves: v,
        ..ArmInput::default()
    }
}

/// What a run showed, both arms.
#[derive(Debug, Default)]
struct Run {
    /// Deepest penetration of any shape (m).
    max_depth_m: f64,
    /// Largest strongest-contact normal force (N).
    max_force_n: f64,
    /// Partners of the strongest contacts seen, per arm.
    partners: [Vec<Partner>; 2],
    /// The strike events of the step's event stream, with the time they came.
    strikes: Vec<(Arm, Strike, f64)>,
}

/// Steps `s` for `seconds` with `input(s)` each step.
fn drive(s: &mut Simulation, seconds: f64, mut input: impl FnMut(&Simulation) -> Input) -> Run {
    let mut r = Run::default();
    for _ in 0..(seconds / 1e-3).round() as usize {
        let inp = input(s);
        s.step(&inp);
        for e in s.events() {
            if let Event::Strike { arm, strike } = e {
                r.strikes.push((*arm, *strike, s.time_s()));
            }
        }
        for (i, c) in s.contacts().arms.iter().enumerate() {
            r.max_depth_m = r.max_depth_m.max(c.max_depth_m);
            if let Some(st) = c.strongest {
                r.max_force_n = r.max_force_n.max(st.normal_force_n);
                if !r.partners[i].contains(&st.partner) {
                    r.partners[i].push(st.partner);
                }
            }
        }
    }
    assert_eq!(s.numerical_faults(), 0);
    r
}

fn sticks(arms: [ArmInput; 2]) -> impl FnMut(&Simulation) -> Input {
    move |_| Input {
        arms,
        ..Input::default()
    }
}

#[test]
fn full_stick_into_the_seabed_stalls_on_it_and_the_pressures_show_it() {
    // Lowering the shoulder or folding the elbow from the reset posture (jaw 11 cm above the
    // seabed), or pitching the wrist down from a posture with the jaw as high but 13° below
    // the horizontal (the 0.20 m wrist of the issue-27 links pitched down from the reset's 50°
    // would lower the jaw by 5 cm only), drives the jaw into it.
    for wet in [false, true] {
        for j in [1, 2, 3] {
            let mut s = if j == 3 {
                let m = common::builtin("magnum");
                let mut p = if wet {
                    SimParams::training(&m, &m).expect("params")
                } else {
                    SimParams::case_study(&m, &m).expect("params")
                };
                let deg = std::f64::consts::PI / 180.0;
                p.arms[0].initial_q = [0.0, 17.0 * deg, -75.0 * deg, 45.0 * deg, 0.0, 0.0];
                Simulation::new(m.clone(), m, p).expect("sim")
            } else {
                sim(wet, false)
            };
            let mut v = [0.0; 6];
            v[j] = -1.0;
            let arm = Arm::Left;
            let dp = |s: &Simulation| s.arm(arm).p_out[j] - s.arm(arm).p_in[j];
            // Free motion first: 0.1 s at full stick (the jaw is still above the seabed).
            let free = drive(&mut s, 0.1, sticks([valves(v), valves([0.0; 6])]));
            assert_eq!(free.max_force_n, 0.0, "joint {j}: touched too early");
            let dp_free = dp(&s);
            let r = drive(&mut s, 4.9, sticks([valves(v), valves([0.0; 6])]));
            let c = s.contacts().arms[0];
            let dp_stall = dp(&s);
            let supply = s.params().arms[0].hydraulics.supply_pa;
            println!(
                "wet {wet} joint {}: depth {:.2} mm, strongest {:.0} N, strike {:?}, Δp free {:.2} MPa stalled {:.2} MPa",
                j + 1,
                r.max_depth_m * 1e3,
                r.max_force_n,
                c.last_strike,
                dp_free / 1e6,
                dp_stall / 1e6
            );
            assert!(
                r.max_depth_m < MAX_DEPTH_M,
                "joint {j}: {} m",
                r.max_depth_m
            );
            let st = c.strongest.expect("resting on the seabed");
            assert_eq!(st.partner, Partner::Seabed);
            assert!(st.normal_force_n > 100.0, "{st:?}");
            let strike = c.last_strike.expect("a strike");
            assert_eq!(strike.partner, Partner::Seabed);
            assert!(
                strike.impact_speed_m_s > 0.02 && strike.peak_force_n > st.normal_force_n * 0.5
            );
            // The event stream carries the same strike once, closed after the impact window
            // with its peak force.
            let seabed: Vec<_> = r
                .strikes
                .iter()
                .filter(|(a, s, _)| *a == arm && s.partner == Partner::Seabed)
                .collect();
            assert_eq!(seabed.len(), 1, "joint {j}: {:?}", r.strikes);
            let (_, ev, came) = seabed[0];
            assert_eq!(*ev, strike, "the report's record, closed");
            // (pushed in the step after the window closed: one 1 ms step late at most)
            assert!(!ev.ongoing && came - ev.time_s <= STRIKE_WINDOW_S + 1.0e-3 + 1e-9);
            assert_eq!(c.strikes.iter().sum::<u64>(), 1, "joint {j}");
            // Stalled at full stick, the valve connects the driving side to supply and the
            // other to tank: the pressure difference across the actuator approaches the
            // supply pressure (orifice law with no flow), far from its free-motion value.
            assert!(
                dp_stall.abs() > 0.8 * supply && (dp_stall - dp_free).abs() > 1.0e6,
                "joint {j}: Δp free {dp_free} stalled {dp_stall}"
            );
        }
    }
}

#[test]
fn cartesian_full_stick_down_stops_on_the_seabed() {
    for wet in [false, true] {
        let mut s = sim(wet, false);
        let m = common::builtin("magnum");
        let mut res = [
            Redundancy::new(&m, RedundancyParams::default()),
            Redundancy::new(&m, RedundancyParams::default()),
        ];
        let r = drive(&mut s, 5.0, |s| {
            let mut input = Input::default();
            for arm in Arm::BOTH {
                let i = arm.index();
                input.arms[i].joint_velocity_ref = Some(cartesian_to_joint_velocity(
                    &mut res[i],
                    s.model(arm),
                    &s.params().arms[i].base.rotation,
                    &s.arm(arm).q,
                    &[0.0, 0.0, -1.0, 0.0, 0.0, 0.0],
                    false,
                    1e-3,
                ));
            }
            input
        });
        println!("Cartesian down, wet {wet}: {r:?}");
        assert!(r.max_depth_m < MAX_DEPTH_M, "{} m", r.max_depth_m);
        for i in 0..2 {
            assert!(r.partners[i].contains(&Partner::Seabed), "{r:?}");
        }
    }
}

#[test]
fn arms_swung_into_each_other_push_on_both() {
    for wet in [false, true] {
        for yaw in [0.0, 1.0] {
            let mut s = sim(wet, false);
            let r = drive(
                &mut s,
                5.0,
                sticks([
                    valves([-1.0, 0.0, 0.0, 0.0, -yaw, 0.0]),
                    valves([1.0, 0.0, 0.0, 0.0, yaw, 0.0]),
                ]),
            );
            println!("swing together (yaw {yaw}), wet {wet}: {r:?}");
            assert!(r.max_depth_m < MAX_DEPTH_M, "{} m", r.max_depth_m);
            for i in 0..2 {
                assert!(r.partners[i].contains(&Partner::OtherArm), "{r:?}");
            }
        }
    }
}

#[test]
fn a_jaw_driven_into_the_panel_stops_on_it() {
    for wet in [false, true] {
        let mut s = sim(wet, true);
        // Swing the left arm in front of the panel (0.6 s), then stretch the elbow towards it
        // with the shoulder lowering.
        let swing = drive(
            &mut s,
            0.6,
            sticks([valves([-1.0, 0.0, 0.0, 0.0, 0.0, 0.0]), valves([0.0; 6])]),
        );
        // (The wrist held level with the forearm: pitch driven towards 0 from the reset's 40°.)
        let r = drive(&mut s, 5.0, |s| {
            let pitch = (-3.0 * s.arm(Arm::Left).q[3]).clamp(-1.0, 1.0);
            Input {
                arms: [valves([0.0, -0.3, 1.0, pitch, 0.0, 0.0]), valves([0.0; 6])],
                ..Input::default()
            }
        });
        println!("into the panel, wet {wet}: {swing:?} {r:?}");
        assert!(r.max_depth_m < MAX_DEPTH_M, "{} m", r.max_depth_m);
        assert!(r.partners[0].contains(&Partner::Panel), "{r:?}");
    }
}

#[test]
fn a_jaw_pushed_into_the_box_moves_it() {
    for wet in [false, true] {
        let mut s = sim(wet, false);
        let p0 = s.object().pose.translation.vector;
        // The right arm swung towards the box: its wrist meets the box's side.
        let r = drive(
            &mut s,
            5.0,
            sticks([valves([0.0; 6]), valves([1.0, 0.0, 0.0, 0.0, 0.0, 0.0])]),
        );
        let moved = (s.object().pose.translation.vector - p0).norm();
        println!(
            "box pushed, wet {wet}: moved {moved:.3} m, relief events {}, {r:?}",
            s.relief_events()
        );
        assert!(r.max_depth_m < MAX_DEPTH_M, "{} m", r.max_depth_m);
        assert!(r.partners[1].contains(&Partner::Object), "{r:?}");
        // Moved, or stalled at relief.
        assert!(moved > 0.05 || s.relief_events() > 0, "moved {moved} m");
    }
}

#[test]
fn the_box_on_the_seabed_carries_its_wet_weight_and_a_dropped_box_settles() {
    // Weight in water: (m − ρ·V)·g, the box's 50 kg less 0.3 × 0.4 × 0.2 m³ of sea water
    // (1025 kg/m³): 249.2 N.
    let mut s = sim(true, false);
    let idle = Input::default();
    for _ in 0..1000 {
        s.step(&idle);
    }
    let op = s.params().object;
    let wet = (op.mass_kg - 1025.0 * op.size_m.x * op.size_m.y * op.size_m.z) * 9.81;
    let f = s.object().seabed_force_n;
    assert!(
        (f - wet).abs() < 0.01 * wet,
        "seabed carries {f} N of {wet} N"
    );
    // Dropped from 0.3 m (in air and water): after 3 s at rest, no motion and a steady
    // seabed force over the last second (no jitter).
    let m = common::builtin("magnum");
    for env in [false, true] {
        let mut p = if env {
            SimParams::training(&m, &m).expect("params")
        } else {
            SimParams::case_study(&m, &m).expect("params")
        };
        p.object.initial_pose.translation.vector.z += 0.3;
        let mut s = Simulation::new(m.clone(), m.clone(), p).expect("sim");
        let weight = if env { wet } else { op.mass_kg * 9.81 };
        let (mut lo, mut hi, mut vmax) = (f64::INFINITY, 0.0_f64, 0.0_f64);
        for k in 0..4000 {
            s.step(&idle);
            if k >= 3000 {
                let o = s.object();
                lo = lo.min(o.seabed_force_n);
                hi = hi.max(o.seabed_force_n);
                vmax = vmax.max(o.velocity.norm() + o.angular_velocity.norm() * 0.25);
            }
        }
        println!("dropped (water {env}): seabed force {lo:.2}..{hi:.2} N, speed ≤ {vmax:.2e} m/s");
        assert!(vmax < 1e-4, "still moving: {vmax} m/s");
        assert!(
            lo > 0.99 * weight && hi < 1.01 * weight,
            "{lo}..{hi} N of {weight} N"
        );
    }
}

#[test]
fn start_postures_and_the_case_studies_grasp_approach_touch_nothing() {
    for (wet, panel) in [(false, false), (true, false), (true, true)] {
        let mut s = sim(wet, panel);
        for _ in 0..200 {
            s.step(&Input::default());
            for c in &s.contacts().arms {
                assert_eq!(c.points, 0, "at reset (water {wet}, panel {panel}): {c:?}");
            }
        }
    }
    // The case studies reach, grasp and lift (stages A–C): no link or jaw touches anything
    // (the jaws on their handles are grasps, not contacts).
    for name in ["case2-single-arm-load", "case4-dual-closed-loop"] {
        let (sc, mut s) = start(name);
        let mut grasped = false;
        'run: for seg in &sc.segments {
            if seg.stage == "D" {
                break 'run;
            }
            for _ in 0..(seg.duration_s / sc.params.step.dt_s).round() as usize {
                let input = sc.input_at(&s, seg, s.time_s());
                s.step(&input);
                for c in &s.contacts().arms {
                    assert_eq!(
                        c.points,
                        0,
                        "{name} stage {} at {} s: {c:?}",
                        seg.stage,
                        s.time_s()
                    );
                }
                grasped |= s.arm(Arm::Left).holding;
            }
        }
        assert!(grasped, "{name}: the left jaw took its handle");
    }
}

#[test]
fn contacts_in_the_step_allocate_nothing() {
    let mut s = sim(true, false);
    let input = Input {
        arms: [
            valves([-1.0, -0.3, 0.0, 0.0, -1.0, 0.0]),
            valves([1.0, -0.3, 0.0, 0.0, 1.0, 0.0]),
        ],
        ..Input::default()
    };
    let mut seen = [false; 5];
    let counted = allocation_counter::measure(|| {
        for _ in 0..5000 {
            s.step(&input);
            for c in &s.contacts().arms {
                if let Some(st) = c.strongest {
                    seen[st.partner as usize] = true;
                }
            }
        }
    });
    println!("partners touched (seabed, box, panel, vehicle, other arm): {seen:?}");
    assert!(seen[Partner::OtherArm as usize] || seen[Partner::Object as usize]);
    assert_eq!(counted.count_total, 0);
}

/// A collision spec of one radius for every link and a small jaw.
fn spec(r: f64) -> CollisionSpec {
    CollisionSpec {
        source: None,
        link_radii_m: vec![r; 6],
        last_link_end_m: [0.0, 0.0, -0.08],
        wrist_centre_m: [0.0, 0.0, -0.055],
        wrist_half_extents_m: [0.045, 0.045, 0.01],
        finger_half_extents_m: [0.0175, 0.008, 0.02],
    }
}

/// An arm laid out along +x at height z (joint origins 0.3 m apart), tool pointing +x.
fn straight_arm(z: f64, y: f64, r: f64) -> ArmShapes {
    let origins = core::array::from_fn(|k| Vector3::new(0.3 * k as f64, y, z));
    let tool = Isometry3::from_parts(
        Vector3::new(1.8, y, z).into(),
        nalgebra::UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2),
    );
    ArmShapes::new(&spec(r), &origins, &tool, 0.075)
}

fn touches(arm: &ArmShapes, world: &World) -> Vec<Touch> {
    let mut out = Vec::new();
    let mut epa = Epa::warm();
    world_touches(arm, world, &Exclusions::default(), &mut epa, |t| {
        out.push(t)
    });
    out
}

#[test]
fn narrow_phase_agrees_with_closed_form_geometry() {
    // A horizontal arm of 0.05 m capsules with its axis 0.03 m above the seabed: each link
    // capsule's two ends are 0.02 m deep (closed form: r − height), normal +z.
    let arm = straight_arm(-0.42, 0.0, 0.05);
    let world = World::new(-0.45);
    let t = touches(&arm, &world);
    let links: Vec<_> = t
        .iter()
        .filter(|t| matches!(t.part, ArmPart::Link(_)))
        .collect();
    assert_eq!(links.len(), 12, "two ends per link");
    for t in &links {
        assert!((t.depth_m - 0.02).abs() < 1e-9, "{t:?}");
        assert!((t.normal - Vector3::z()).norm() < 1e-12);
        assert!((t.point_arm.z - (-0.47)).abs() < 1e-9, "{t:?}");
    }
    // The same arm over a box whose top face is 0.04 m below the axis: depth 0.01 m
    // (closed form: r − gap) on the links over it, normal +z, the box a panel plate.
    let mut world = World::new(-10.0);
    let top = -0.42 - 0.04;
    world.push(
        Item::Plate,
        Posed::cuboid(
            &Vector3::new(0.2, 0.2, 0.1),
            &Isometry3::translation(0.45, 0.0, top - 0.1),
        ),
    );
    let t = touches(&arm, &world);
    assert!(!t.is_empty());
    for t in &t {
        assert_eq!(t.partner, Partner::Panel);
        assert!((t.depth_m - 0.01).abs() < 1e-6, "{t:?}");
        assert!((t.normal - Vector3::z()).norm() < 1e-6, "{t:?}");
    }
    // Two parallel arms 0.09 m apart (axes), 0.05 m capsules: 0.01 m deep, normals along ∓y.
    let a = straight_arm(0.0, 0.0, 0.05);
    let b = straight_arm(0.0, 0.09, 0.05);
    let mut epa = Epa::warm();
    let mut pairs = Vec::new();
    arm_touches(&a, &b, &mut epa, |ta, tb| pairs.push((ta, tb)));
    let link_pairs: Vec<_> = pairs
        .iter()
        .filter(|(ta, tb)| ta.part == tb.part && matches!(ta.part, ArmPart::Link(_)))
        .collect();
    assert_eq!(link_pairs.len(), 6, "{pairs:?}");
    for (ta, tb) in link_pairs {
        assert!((ta.depth_m - 0.01).abs() < 1e-6, "{ta:?}");
        // (EPA converges to its tolerance: normals to ~1e-6.)
        assert!((ta.normal + Vector3::y()).norm() < 1e-5, "{ta:?}");
        assert!((tb.normal - Vector3::y()).norm() < 1e-5, "{tb:?}");
        assert_eq!(ta.partner, Partner::OtherArm);
    }
}
