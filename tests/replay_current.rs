//! The instructor's water current in the replay (issue 17 item 7): a current set mid-attempt
//! is logged and replayed at the same step, and an attempt that starts with a current set
//! (after a reset) carries it in its `init`, so the re-simulated state equals the recorded
//! one bit for bit. The reference is the recorded run itself, not the replay code.

#![allow(clippy::unwrap_used)]

use std::collections::BTreeMap;
use std::sync::Arc;

use seaarms::replay::{Init, Replay, log};
use seaarms::sessions::command::{ArmSticks, Command, StickInput};
use seaarms::sessions::record::RecordMsg;
use seaarms::sessions::{Live, Scenario};
use seaarms_core::sim::Arm;

fn magnum() -> [Arc<seaarms_core::Model>; 2] {
    let robots = seaarms::robots::Robots::load().expect("built-in robots");
    let m = robots.get("magnum").expect("magnum");
    [m.clone(), m]
}

/// q, q̇, pressures of both arms and the object's pose and velocity, as bits.
fn state_bits(live: &Live) -> Vec<u64> {
    let sim = live.sim();
    let mut v = Vec::new();
    for arm in Arm::BOTH {
        let a = sim.arm(arm);
        for x in a.q.iter().chain(&a.qd).chain(&a.p_in).chain(&a.p_out) {
            v.push(x.to_bits());
        }
    }
    let o = sim.object();
    let t = o.pose.translation.vector;
    let r = o.pose.rotation.coords;
    for x in t.iter().chain(r.iter()).chain(o.velocity.iter()) {
        v.push(x.to_bits());
    }
    v
}

/// Steps `n` times with both arms' swing and shoulder sticks at `stick`, recording states.
fn drive(live: &mut Live, seq: &mut u64, stick: f64, n: u64, states: &mut BTreeMap<u64, Vec<u64>>) {
    *seq += 1;
    let mut axes = [0.0; 6];
    axes[0] = stick;
    axes[1] = -stick;
    let input = StickInput {
        seq: *seq,
        arms: [ArmSticks { axes, grip: 0.0 }; 2],
        ..StickInput::default()
    };
    live.apply(&Command::Input(input)).unwrap();
    for _ in 0..n {
        live.advance();
        states.insert(live.sim().steps(), state_bits(live));
    }
}

/// The running attempt's init and input log after `end_attempt`.
fn records(live: &mut Live) -> (Init, Vec<u8>) {
    let (mut init, mut inputs) = (None, Vec::new());
    for msg in live.take_records(false) {
        match msg {
            RecordMsg::AttemptStarted(a) => init = Some(serde_json::from_value(a.init).unwrap()),
            RecordMsg::AttemptInputs { bytes, .. } => inputs.extend(bytes),
            _ => {}
        }
    }
    (init.expect("an attempt started"), inputs)
}

fn check_replay(init: Init, inputs: &[u8], states: &BTreeMap<u64, Vec<u64>>, what: &str) {
    let models = magnum();
    let entries = log::decode(inputs).expect("log decodes");
    let last = *states.keys().next_back().unwrap();
    let mut replay = Replay::new(&models, init, entries, last as f64 / 1000.0).unwrap();
    // Forward, then back across the current changes (a fresh start from the init).
    for step in [1, 700, 1201, 1999, last, 300, 1500] {
        let step = step.min(last);
        replay.seek_step(step).unwrap();
        assert!(
            state_bits(replay.live()) == states[&step],
            "{what}: the replayed state at step {step} differs from the recorded one"
        );
    }
}

#[test]
fn a_current_set_mid_attempt_and_at_an_attempts_start_replays_bit_for_bit() {
    let models = magnum();
    let scenario = Scenario::resolve("reach-targets").expect("exercise");
    let mut live = Live::new("t", &models, &scenario, None, None, 3).unwrap();
    assert!(
        live.sim().environment().water().is_some(),
        "exercises run in water"
    );
    let (mut seq, mut states) = (0, BTreeMap::new());
    // Attempt 1: still water, then a current mid-attempt, then another.
    drive(&mut live, &mut seq, 0.6, 700, &mut states);
    live.apply(&Command::current(0.8, 45.0).unwrap()).unwrap();
    drive(&mut live, &mut seq, -0.4, 500, &mut states);
    live.apply(&Command::current(1.5, -160.0).unwrap()).unwrap();
    drive(&mut live, &mut seq, 0.3, 800, &mut states);
    let moved = live.sim().environment().water().unwrap().current;
    assert_eq!((moved.speed_m_s, moved.heading_deg), (1.5, 200.0));
    live.end_attempt("abandoned");
    let (init, inputs) = records(&mut live);
    assert_eq!(init.current, None, "attempt 1 started in still water");
    check_replay(init, &inputs, &states, "current set mid-attempt");

    // Attempt 2 starts after a reset with the 1.5 m/s current still set: it is in the init.
    live.reset();
    let mut states = BTreeMap::new();
    drive(&mut live, &mut seq, 0.5, 2000, &mut states);
    live.end_attempt("abandoned");
    let (init, inputs) = records(&mut live);
    let c = init.current.expect("the init carries the current");
    assert_eq!((c.speed_m_s, c.heading_deg), (1.5, 200.0));
    check_replay(init, &inputs, &states, "current at the attempt's start");
}
