//! Determinism: the same inputs give bit-identical output (issue criterion 5), and `reset`
//! returns exactly to the freshly built state.

mod common;

use common::rng::Rng;
use seaarms_core::sim::{Arm, ControlMethod, Input, SimParams, Simulation};

fn fingerprint(s: &Simulation) -> Vec<u64> {
    let mut v = Vec::new();
    for arm in Arm::BOTH {
        let a = s.arm(arm);
        for x in
            a.q.iter()
                .chain(&a.qd)
                .chain(&a.p_in)
                .chain(&a.p_out)
                .chain(&a.contact_wrench)
                .chain(&a.spool)
        {
            v.push(x.to_bits());
        }
        v.push(a.jaw_opening_m.to_bits());
    }
    let o = s.object();
    for x in o
        .pose
        .translation
        .vector
        .iter()
        .chain(o.pose.rotation.coords.iter())
        .chain(o.velocity.iter())
    {
        v.push(x.to_bits());
    }
    v.extend(s.internal_wrench().iter().map(|x| x.to_bits()));
    v
}

fn random_inputs(n: usize, seed: u64) -> Vec<Input> {
    let mut r = Rng(seed);
    let mut out = Vec::with_capacity(n);
    let mut cur = Input::default();
    for k in 0..n {
        if k % 250 == 0 {
            for a in cur.arms.iter_mut() {
                for v in a.valves.iter_mut() {
                    *v = r.sym(1.0);
                }
                a.jaw = r.sym(1.0);
            }
            cur.method = if r.next() < 0.5 {
                ControlMethod::Open
            } else {
                ControlMethod::Closed
            };
            cur.speed_scale = 0.2 + 0.8 * r.next();
        }
        out.push(cur);
    }
    out
}

#[test]
fn same_inputs_give_bit_identical_states() {
    let m = common::builtin("magnum");
    let p = SimParams::case_study(&m, &m).expect("params");
    let mut a = Simulation::new(m.clone(), m.clone(), p.clone()).expect("sim");
    let mut b = Simulation::new(m.clone(), m, p).expect("sim");
    let inputs = random_inputs(5000, 42);
    for (k, inp) in inputs.iter().enumerate() {
        a.step(inp);
        b.step(inp);
        if k % 500 == 0 {
            assert_eq!(fingerprint(&a), fingerprint(&b), "diverged at step {k}");
        }
    }
    assert_eq!(fingerprint(&a), fingerprint(&b));
    // Reset, replay: identical again.
    let end = fingerprint(&a);
    a.reset();
    let fresh = {
        let m = common::builtin("magnum");
        let p = SimParams::case_study(&m, &m).expect("params");
        Simulation::new(m.clone(), m, p).expect("sim")
    };
    assert_eq!(
        fingerprint(&a),
        fingerprint(&fresh),
        "reset differs from a fresh simulation"
    );
    for inp in &inputs {
        a.step(inp);
    }
    assert_eq!(fingerprint(&a), end, "replay after reset differs");
}
