//! Static friction on the seabed (issue 27, item 3): a box resting on the seabed stays put
//! under a side load below μ·N — the corners' anchored stick springs (`grasp::seabed`) hold
//! it, where the regularized law μN·v/√(v²+ε²) let it creep at 3.7 mm/s in a 1 m/s current —
//! and above μ·N it slides at the speed where the current's drag balances kinetic friction:
//! ½ρ·C_D·A·(u − v)² = μ·(m − ρV)·g (Morison/Hoerner drag of `sim::water`, Coulomb friction on
//! the wet weight), v = u − √(μ(m − ρV)g / (½ρC_D·A)).

mod common;

use seaarms_core::sim::water::{BOX_DRAG, SEA_WATER_DENSITY_KGM3};
use seaarms_core::sim::{Current, Environment, Input, SimParams, Simulation, Water};

/// The training scene in sea water with `current` flowing since the start; the box rests on
/// the seabed, the arms at their start pose clear of it; `contacts`: the arms collide.
fn resting_box(current: Current, contacts: bool) -> Simulation {
    let m = common::builtin("magnum");
    let mut p = SimParams::training(&m, &m).expect("params");
    p.step.environment = Environment::Subsea(Water {
        density_kgm3: SEA_WATER_DENSITY_KGM3,
        current,
    });
    p.contact.enabled = contacts;
    Simulation::new(m.clone(), m, p).expect("sim")
}

/// The box's weight in water (N).
fn wet_weight_n(sim: &Simulation) -> f64 {
    let op = &sim.params().object;
    let v = op.size_m.x * op.size_m.y * op.size_m.z;
    (op.mass_kg - SEA_WATER_DENSITY_KGM3 * v) * sim.params().step.gravity.norm()
}

#[test]
fn a_box_on_the_seabed_holds_against_a_1_m_s_current() {
    for heading in [0.0, 90.0, 30.0] {
        let mut sim = resting_box(Current::new(1.0, heading).expect("current"), true);
        let p0 = sim.object().pose.translation.vector;
        let input = Input::default();
        for _ in 0..60_000 {
            sim.step(&input);
        }
        let o = sim.object();
        let moved = (o.pose.translation.vector - p0).norm();
        let w = wet_weight_n(&sim);
        println!(
            "1 m/s at {heading}°: moved {:.3} mm in 60 s; seabed force {:.2} N (wet weight {w:.2} N)",
            moved * 1e3,
            o.seabed_force_n
        );
        assert!(moved < 1e-3, "{heading}°: moved {moved} m");
        // Resting: the seabed carries the wet weight (±1 %).
        assert!((o.seabed_force_n - w).abs() < 0.01 * w);
        assert_eq!(sim.numerical_faults(), 0);
    }
}

#[test]
fn a_box_slides_at_the_closed_form_speed_in_a_2_5_m_s_current() {
    let u = 2.5;
    // Heading 0°: the current meets the box's y–z face (0.40 × 0.20 m); 90°: its x–z face.
    for heading in [0.0_f64, 90.0] {
        // The slide is metres long: at 90° it runs into the left arm's links (y ≈ 0.9 m),
        // which push it aside (collisions.rs's business). Here the seabed alone.
        let mut sim = resting_box(Current::new(u, heading).expect("current"), false);
        let op = sim.params().object;
        let area = if heading == 0.0 {
            op.size_m.y * op.size_m.z
        } else {
            op.size_m.x * op.size_m.z
        };
        let friction = op.friction * wet_weight_n(&sim);
        let k = 0.5 * SEA_WATER_DENSITY_KGM3 * BOX_DRAG * area;
        let v_closed = u - (friction / k).sqrt();
        let input = Input::default();
        // The slide settles with τ = (m + m_a)/(ρC_D·A·(u − v)) ≈ 0.5 s: measure over 5–10 s.
        for _ in 0..5_000 {
            sim.step(&input);
        }
        let dir =
            nalgebra::Vector3::new(heading.to_radians().cos(), heading.to_radians().sin(), 0.0);
        let p5 = sim.object().pose.translation.vector;
        for _ in 0..5_000 {
            sim.step(&input);
        }
        let o = sim.object();
        let v = (o.pose.translation.vector - p5).dot(&dir) / 5.0;
        let across = (o.pose.translation.vector - p5).cross(&dir).norm() / 5.0;
        println!(
            "{u} m/s at {heading}°: slides at {v:.4} m/s, closed form {v_closed:.4} m/s \
             (drag = μ·wet weight = {friction:.1} N); across {across:.2e} m/s"
        );
        // Within 1 %: the regularized kinetic force is within 10⁻⁴ of μN at this speed, the
        // remainder is the pitch the friction couple gives the sliding box.
        assert!((v - v_closed).abs() < 0.01 * v_closed, "{v} vs {v_closed}");
        assert!(across < 1e-3 * v_closed);
        assert_eq!(sim.numerical_faults(), 0);
    }
}
