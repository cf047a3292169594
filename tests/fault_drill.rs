//! The `fault-diagnosis` exercise end to end, headless, through the trainee's controls only:
//! the autopilot's diagnosis (which reads what the page shows, never the injected fault) names
//! the drawn fault for every seed, covering each fault kind at least twice, and passes; an idle
//! attempt fails. Same seed, same assessment.

mod common;
use common::magnum;

use std::collections::BTreeMap;

use seaarms::catalogue::EXERCISES;
use seaarms::exercises::{Driver, run_headless};
use seaarms_core::exercise::Assessment;
use seaarms_core::hydraulics::FaultKind;

/// Seeds 1..=16: the drill's splitmix64 draw over the file's eight choices (two per kind)
/// gives each fault kind three to five times (checked below, not assumed).
const SEEDS: std::ops::RangeInclusive<u64> = 1..=16;

/// Runs one headless attempt at `fault-diagnosis`.
fn attempt(driver: Driver, seed: u64) -> Assessment {
    let spec = EXERCISES
        .get("fault-diagnosis")
        .expect("fault-diagnosis exercise");
    run_headless(spec, &magnum(), driver, seed).expect("run")
}

#[test]
fn autopilot_names_every_fault_and_passes() {
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    let mut failures = Vec::new();
    for seed in SEEDS {
        let a = attempt(Driver::Autopilot, seed);
        let d = a.diagnosis.clone().expect("a drill has a diagnosis");
        println!(
            "seed {seed:2}: {:11} at {:5.2} s → answer {:11} passed {} score {:.1} time {:.1} s {:?}",
            d.fault,
            d.injected_at_s,
            d.answer,
            a.passed,
            a.score,
            a.metrics.time_s,
            a.failed_because
        );
        *seen.entry(d.fault.clone()).or_default() += 1;
        if !(a.passed && d.correct) {
            failures.push((seed, d.fault, d.answer, a.failed_because.clone()));
        }
        let json = serde_json::to_value(&a).expect("json");
        for (k, v) in json.as_object().expect("object") {
            if let Some(x) = v.as_f64() {
                assert!(x.is_finite(), "seed {seed}: {k} = {x}");
            }
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
    for kind in FaultKind::NAMES {
        assert!(
            seen.get(kind).copied().unwrap_or(0) >= 2,
            "{kind} drawn < 2 times: {seen:?}"
        );
    }
}

#[test]
fn idle_attempt_fails_and_runs_are_deterministic() {
    let idle = attempt(Driver::Idle, 3);
    assert!(idle.done && !idle.passed, "{idle:?}");
    assert!(!idle.completed);
    assert_eq!(idle.diagnosis.as_ref().map(|d| d.answer.as_str()), Some(""));
    let a = attempt(Driver::Autopilot, 6);
    let b = attempt(Driver::Autopilot, 6);
    assert_eq!(a, b);
}
