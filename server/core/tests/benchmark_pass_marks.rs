//! An exercise whose pass marks are `benchmark` (issue 30 item 1, docs/exercises.md
//! "Benchmarks from reference operators"): the attempt is judged by the reference operators'
//! lines it was given at its start instead of the file's `min_score`; the file's limits still
//! hold; without lines, and for an exercise with fixed marks, the file's `min_score` decides.
//! The lines here are built by hand (mean ∓ k·SD), so each verdict follows from arithmetic.

mod common;

use std::sync::Arc;

use seaarms_core::exercise::proficiency::{Benchmark, ExerciseBenchmark, PassLine, PassLines};
use seaarms_core::exercise::{ExerciseRun, ExerciseSpec};
use seaarms_core::sim::{Input, Simulation};

/// One step that holds at the start (no jaw holds anything), no scoring terms: the attempt
/// completes at its first sample with score 100 (100 × the completed fraction).
fn spec(marks: &str) -> ExerciseSpec {
    let s: ExerciseSpec = serde_json::from_str(&format!(
        r#"{{"id":"t","version":1,"title":"t","goal":"g","skills":[],
        "control":{{"mode":"joint","arm":"left"}},
        "steps":[{{"id":"a","text":"a","done_when":{{"kind":"released"}}}}],
        "time_limit_s":100,"pass":{{"marks":"{marks}","min_score":50,"limits":[]}},
        "scoring":[],"autopilot":[]}}"#
    ))
    .expect("spec");
    s.check().expect("checks");
    s
}

/// The attempt run to its end (a few 1 ms steps, then one assessment sample).
fn finish(spec: ExerciseSpec, lines: Option<PassLines>) -> seaarms_core::exercise::Assessment {
    let m = common::builtin("magnum");
    let p = spec.sim_params(&m, &m).expect("params");
    let mut sim = Simulation::new(m.clone(), m, p).expect("sim");
    let mut run = ExerciseRun::new(Arc::new(spec), &sim, 1);
    run.set_pass_lines(lines);
    for _ in 0..10 {
        sim.step(&Input::default());
    }
    run.sample(&mut sim, true);
    let a = run.assessment();
    assert!(a.done && a.completed, "{a:?}");
    assert_eq!(a.score, 100.0);
    a
}

/// A score line at `mean − 1·sd`.
fn score_line(mean: f64, sd: f64) -> PassLines {
    PassLines {
        reference_attempts: 5,
        k: 1.0,
        lines: vec![PassLine {
            metric: "score".into(),
            higher_is_better: true,
            mean,
            sd,
            line: mean - sd,
        }],
    }
}

#[test]
fn benchmark_marks_judge_the_attempt_by_the_reference_lines() {
    // Score 100 ≥ 95 − 2 = 93: passed, by the benchmark.
    let a = finish(spec("benchmark"), Some(score_line(95.0, 2.0)));
    assert!(a.passed, "{:?}", a.failed_because);
    assert_eq!(a.pass_marks.kind, "benchmark");
    assert_eq!(a.pass_marks.benchmark.as_ref().unwrap().lines[0].line, 93.0);
    // A line above 100 (mean 104, SD 2 → 102) fails an attempt the file's 50 would pass.
    let a = finish(spec("benchmark"), Some(score_line(104.0, 2.0)));
    assert!(!a.passed);
    assert_eq!(a.failed_because.len(), 1, "{:?}", a.failed_because);
    assert!(
        a.failed_because[0].contains("benchmark line 102.00"),
        "{:?}",
        a.failed_because
    );
    // A time line: the attempt took ~0.01 s; a line at 0.005 s fails it (lower is better).
    let time = PassLines {
        reference_attempts: 5,
        k: 1.0,
        lines: vec![PassLine {
            metric: "time_s".into(),
            higher_is_better: false,
            mean: 0.004,
            sd: 0.001,
            line: 0.005,
        }],
    };
    let a = finish(spec("benchmark"), Some(time));
    assert!(!a.passed && a.failed_because[0].starts_with("time_s"));
}

#[test]
fn without_lines_or_with_fixed_marks_the_files_pass_mark_decides() {
    // The benchmark does not apply yet: the file's 50 decides, and the card says why.
    let a = finish(spec("benchmark"), None);
    assert!(a.passed);
    assert_eq!(a.pass_marks.kind, "fixed");
    assert!(
        a.pass_marks
            .note
            .as_deref()
            .unwrap()
            .contains("5 reference attempts")
    );
    // Fixed marks ignore the lines.
    let a = finish(spec("fixed"), Some(score_line(104.0, 2.0)));
    assert!(a.passed);
    assert_eq!(a.pass_marks.kind, "fixed");
    assert!(a.pass_marks.benchmark.is_none() && a.pass_marks.note.is_none());
}

/// The lines an exercise's benchmark gives: its required measures' (the default: score and
/// time) mean, SD and line, as `Benchmark::from_reference` computes them; none while it does
/// not apply. References score 80, 84, 88, 92, 96 → mean 88, SD √40 = 6.325; times 30–50 s
/// in steps of 5 → mean 40, SD √62.5 = 7.906.
#[test]
fn pass_lines_are_the_required_measures_of_the_benchmark() {
    let mut s = spec("benchmark");
    s.scoring =
        serde_json::from_str(r#"[{"metric":"time_s","good":20,"bad":100,"weight":1}]"#).unwrap();
    let refs: Vec<_> = (0..5)
        .map(|i| {
            [
                ("score".to_string(), 80.0 + 4.0 * i as f64),
                ("time_s".to_string(), 30.0 + 5.0 * i as f64),
            ]
            .into_iter()
            .collect()
        })
        .collect();
    let b = ExerciseBenchmark::of(&s, &refs);
    let l = b.pass_lines().expect("applies");
    assert_eq!(l.reference_attempts, 5);
    let score = Benchmark::from_reference(&[80.0, 84.0, 88.0, 92.0, 96.0]).unwrap();
    assert_eq!(
        (l.lines[0].metric.as_str(), l.lines[0].mean, l.lines[0].sd),
        ("score", score.mean, score.sd)
    );
    assert!((l.lines[0].line - (88.0 - 40f64.sqrt())).abs() < 1e-12);
    assert!((l.lines[1].line - (40.0 + 62.5f64.sqrt())).abs() < 1e-12);
    assert!(!l.lines[1].higher_is_better);
    assert!(ExerciseBenchmark::of(&s, &refs[..4]).pass_lines().is_none());
}
