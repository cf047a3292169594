mod common;
use common::scenario_util::start;
use seaarms_core::sim::Arm;

#[test]
fn approach_probe() {
    let (sc, mut sim) = start("case4-dual-closed-loop");
    let mut last = String::new();
    for seg in sc.segments.iter() {
        let n = (seg.duration_s / sc.params.step.dt_s).round() as usize;
        for _ in 0..n {
            let input = sc.input_at(&sim, seg, sim.time_s());
            sim.step(&input);
            let c = sim.contacts();
            let line = format!(
                "stage {} L {:?} R {:?} holdL {} holdR {}",
                seg.stage,
                c.arms[0].strongest.map(|s| (s.partner, s.part, s.point_m.map(|x| (x * 1000.0).round() / 1000.0))),
                c.arms[1].strongest.map(|s| (s.partner, s.part, s.point_m.map(|x| (x * 1000.0).round() / 1000.0), s.depth_m, s.normal_force_n)),
                sim.arm(Arm::Left).holding,
                sim.arm(Arm::Right).holding
            );
            if line != last {
                let tl = sim.end_effector(Arm::Left);
                let o = sim.object().pose.translation.vector; println!("obj {:?}", o.as_slice()); println!("t {:.3} {line} depthL {:.4} forceL {:.0} toolL {:?} zaxis {:?}", sim.time_s(), c.arms[0].max_depth_m, c.arms[0].total_normal_force_n, tl.translation.vector.as_slice(), (tl.rotation * nalgebra::Vector3::z()).as_slice());
                last = line;
            }
        }
        if sim.time_s() > 30.0 { break; }
    }
}
