//! Benchmarks from reference operators and proficiency from a trainee's attempts (issue 30):
//! the statistics of proficiency-based progression and the CUSUM charts of learning.
//!
//! * [`Benchmark::from_reference`]: for one metric, the reference operators' mean and sample
//!   standard deviation after removing outliers beyond 1.96 SD of the first mean (the
//!   proficiency-based progression procedure of surgical simulation: Gallagher et al. 2005,
//!   "Virtual reality simulation for the operating room: proficiency-based training as a
//!   paradigm shift in surgical skills training", Ann Surg 241(2); `../shared/TRAINING.md`).
//!   The pass line is a stated number `k` of SDs from the mean, on the worse side.
//! * [`Cusum`]: Biau's learning-curve CUSUM (LC-CUSUM: Biau, Williams, Schlup, Nizard &
//!   Porcher 2008, "Quantitative and individualized assessment of the learning curve using
//!   LC-CUSUM", Br J Surg 95(7):925–929) on each attempt's pass or fail, which signals
//!   proficiency, then the standard CUSUM (Biau, Resche-Rigon, Godiris-Petit, Nizard &
//!   Porcher 2007, "Quality control of surgical and interventional procedures: a review of
//!   the CUSUM", Qual Saf Health Care 16(3):203–207), which signals a relapse.
//! * [`progress`]: a trainee's state on an exercise from its attempts in order.
//!
//! Pure functions of their inputs, as the rest of the core: the server reads the attempts.

use serde::{Deserialize, Serialize};

/// Reference values beyond this many SDs of their first mean are outliers (1.96: the two-sided
/// 95 % normal quantile, as the proficiency-based progression studies remove them).
pub const OUTLIER_SD: f64 = 1.96;

/// A metric's benchmark from reference operators' attempts.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Benchmark {
    /// Mean of the kept values.
    pub mean: f64,
    /// Sample standard deviation (n − 1) of the kept values (0 for one value).
    pub sd: f64,
    /// Values kept.
    pub n: usize,
    /// Values removed as outliers.
    pub outliers: usize,
}

fn mean_sd(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let sd = if values.len() > 1 {
        (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
    } else {
        0.0
    };
    (mean, sd)
}

impl Benchmark {
    /// The benchmark of `values` (non-finite values are ignored): mean and SD, then the values
    /// beyond [`OUTLIER_SD`] SDs of that mean removed once and both recomputed. None without
    /// a finite value.
    pub fn from_reference(values: &[f64]) -> Option<Benchmark> {
        let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
        if finite.is_empty() {
            return None;
        }
        let (mean, sd) = mean_sd(&finite);
        let kept: Vec<f64> = finite
            .iter()
            .copied()
            .filter(|v| sd == 0.0 || (v - mean).abs() <= OUTLIER_SD * sd)
            .collect();
        let (mean, sd) = mean_sd(&kept);
        Some(Benchmark {
            mean,
            sd,
            n: kept.len(),
            outliers: finite.len() - kept.len(),
        })
    }

    /// The pass line `k` SDs from the mean on the worse side: below the mean when higher is
    /// better, above it when lower is better.
    pub fn pass_line(&self, k: f64, higher_is_better: bool) -> f64 {
        if higher_is_better {
            self.mean - k * self.sd
        } else {
            self.mean + k * self.sd
        }
    }

    /// Whether `value` meets the benchmark (`k` SDs, [`Benchmark::pass_line`]).
    pub fn met_by(&self, value: f64, k: f64, higher_is_better: bool) -> bool {
        let line = self.pass_line(k, higher_is_better);
        value.is_finite()
            && if higher_is_better {
                value >= line
            } else {
                value <= line
            }
    }
}

/// One benchmarked measure of an exercise: its band from the reference attempts.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeasureBenchmark {
    /// `score`, or a metric of [`super::assess::Metrics`] the exercise scores.
    pub metric: String,
    /// Better upward (the score; a scoring term whose `good` is above its `bad`).
    pub higher_is_better: bool,
    /// The reference operators' benchmark (None without a finite reference value).
    pub benchmark: Option<Benchmark>,
    /// Its pass line ([`Benchmark::pass_line`], `k` = the exercise's `benchmark_sd`).
    pub line: Option<f64>,
    /// Meeting the benchmark requires this measure (the exercise's `benchmark_on`).
    pub required: bool,
}

/// An exercise's benchmark from its reference attempts (issue 30 item 1): the score and every
/// scoring term's metric, each with its reference mean, SD and pass line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExerciseBenchmark {
    /// Reference attempts it was computed from (before outliers are removed per measure).
    pub reference_attempts: usize,
    /// Fewest reference attempts for the benchmark to apply (the exercise's
    /// `min_reference_attempts`).
    pub min_reference_attempts: usize,
    /// Whether it applies: every required measure keeps at least `min_reference_attempts`
    /// values after its outliers are removed. When it does not, the file's pass marks alone
    /// apply.
    pub applies: bool,
    /// The pass lines' distance from the mean in reference SDs (`benchmark_sd`).
    pub k: f64,
    /// The measures, the score first.
    pub measures: Vec<MeasureBenchmark>,
}

impl ExerciseBenchmark {
    /// The measures `spec` is benchmarked on: the score, then each scoring term's metric once,
    /// then any other metric its `benchmark_on` names (lower better).
    pub fn measures_of(spec: &super::ExerciseSpec) -> Vec<(String, bool)> {
        let mut out = vec![("score".to_string(), true)];
        for t in &spec.scoring {
            if !out.iter().any(|(m, _)| *m == t.metric) {
                out.push((t.metric.clone(), t.good > t.bad));
            }
        }
        for m in &spec.proficiency.benchmark_on {
            if !out.iter().any(|(o, _)| o == m) {
                out.push((m.clone(), false));
            }
        }
        out
    }

    /// The benchmark of `spec` from its reference attempts' values (each a map from measure to
    /// value: the score and the assessment's metrics).
    pub fn of(
        spec: &super::ExerciseSpec,
        reference: &[std::collections::BTreeMap<String, f64>],
    ) -> ExerciseBenchmark {
        let p = &spec.proficiency;
        let measures: Vec<MeasureBenchmark> = Self::measures_of(spec)
            .into_iter()
            .map(|(metric, higher_is_better)| {
                let values: Vec<f64> = reference
                    .iter()
                    .filter_map(|r| r.get(&metric).copied())
                    .collect();
                let benchmark = Benchmark::from_reference(&values);
                let line = benchmark
                    .as_ref()
                    .map(|b| b.pass_line(p.benchmark_sd, higher_is_better));
                MeasureBenchmark {
                    required: p.benchmark_on.contains(&metric),
                    metric,
                    higher_is_better,
                    benchmark,
                    line,
                }
            })
            .collect();
        let applies = !reference.is_empty()
            && measures.iter().filter(|m| m.required).all(|m| {
                m.benchmark
                    .as_ref()
                    .is_some_and(|b| b.n >= p.min_reference_attempts.max(1))
            });
        ExerciseBenchmark {
            reference_attempts: reference.len(),
            min_reference_attempts: p.min_reference_attempts,
            applies,
            k: p.benchmark_sd,
            measures,
        }
    }

    /// Whether an attempt with `values` meets the benchmark: every required measure on the
    /// better side of its pass line (a missing value does not). None when the benchmark does
    /// not apply.
    pub fn met_by(&self, values: &std::collections::BTreeMap<String, f64>) -> Option<bool> {
        self.applies.then(|| {
            let mut required = self.measures.iter().filter(|m| m.required);
            required.all(|m| match (&m.benchmark, values.get(&m.metric)) {
                (Some(b), Some(&v)) => b.met_by(v, self.k, m.higher_is_better),
                _ => false,
            })
        })
    }
}

/// One benchmark pass line of an attempt ([`PassLines`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PassLine {
    /// `score` or a metric of [`super::assess::Metrics`].
    pub metric: String,
    /// Better upward.
    pub higher_is_better: bool,
    /// The reference mean.
    pub mean: f64,
    /// The reference SD.
    pub sd: f64,
    /// The line: `mean ∓ k·sd` on the worse side ([`Benchmark::pass_line`]).
    pub line: f64,
}

impl PassLine {
    /// Whether `value` is on the better side of the line (or on it).
    pub fn met_by(&self, value: f64) -> bool {
        value.is_finite()
            && if self.higher_is_better {
                value >= self.line
            } else {
                value <= self.line
            }
    }
}

/// An attempt's pass marks from the reference operators' benchmark (an exercise whose
/// `pass.marks` is `benchmark`): the required measures' lines as they stood when the attempt
/// started. The attempt's record keeps them, so its replay gives the same verdict however the
/// benchmark has moved since.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PassLines {
    /// Reference attempts the benchmark came from.
    pub reference_attempts: usize,
    /// The lines' distance from the mean in reference SDs.
    pub k: f64,
    /// One line per required measure (the exercise's `benchmark_on`).
    pub lines: Vec<PassLine>,
}

impl ExerciseBenchmark {
    /// The pass lines of this benchmark's required measures; None when it does not apply.
    pub fn pass_lines(&self) -> Option<PassLines> {
        if !self.applies {
            return None;
        }
        let lines = self
            .measures
            .iter()
            .filter(|m| m.required)
            .filter_map(|m| {
                let b = m.benchmark.as_ref()?;
                Some(PassLine {
                    metric: m.metric.clone(),
                    higher_is_better: m.higher_is_better,
                    mean: b.mean,
                    sd: b.sd,
                    line: m.line?,
                })
            })
            .collect();
        Some(PassLines {
            reference_attempts: self.reference_attempts,
            k: self.k,
            lines,
        })
    }
}

/// How proficiency is judged on an exercise (its file's `proficiency`, every field optional).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ProficiencySpec {
    /// Attempts in a row meeting the benchmark that make a trainee proficient: 3 (the
    /// proficiency-based progression studies ask for two consecutive attempts at the
    /// benchmark; one more here, as a simulator attempt is short).
    pub consecutive: usize,
    /// The benchmark's pass line in reference SDs from the reference mean: 1 (the
    /// "often one SD" of the procedure).
    pub benchmark_sd: f64,
    /// Fewest reference attempts (after outliers) for a benchmark: 5; with fewer, the file's
    /// pass marks alone apply.
    pub min_reference_attempts: usize,
    /// The measures an attempt must meet for the benchmark (each on the better side of its
    /// line): `score` and `time_s` — the overall quality and the time, the two measures every
    /// proficiency-based progression study benchmarks (Gallagher et al. 2005: time and
    /// errors). Every other scored metric's band is shown, not required; an exercise file
    /// can require more.
    pub benchmark_on: Vec<String>,
    /// The CUSUM charts.
    pub cusum: CusumParams,
}

impl Default for ProficiencySpec {
    fn default() -> ProficiencySpec {
        ProficiencySpec {
            consecutive: 3,
            benchmark_sd: 1.0,
            min_reference_attempts: 5,
            benchmark_on: vec!["score".into(), "time_s".into()],
            cusum: CusumParams::default(),
        }
    }
}

impl ProficiencySpec {
    /// Checks the numbers.
    pub fn check(&self) -> Result<(), String> {
        if !(self.benchmark_sd.is_finite() && self.benchmark_sd >= 0.0) {
            return Err(format!(
                "proficiency.benchmark_sd must be ≥ 0 (got {})",
                self.benchmark_sd
            ));
        }
        if let Some(m) = self
            .benchmark_on
            .iter()
            .find(|m| *m != "score" && super::assess::Metrics::default().get(m).is_none())
        {
            return Err(format!("proficiency.benchmark_on: unknown metric `{m}`"));
        }
        self.cusum.check()
    }
}

/// The CUSUM's settings (an exercise file's `proficiency.cusum`; defaults below).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CusumParams {
    /// Acceptable failure rate p0: 0.1 (Biau et al. 2008 used 10 % for their procedure; a
    /// trainee who fails one attempt in ten is taken as proficient).
    pub acceptable_failure: f64,
    /// Unacceptable failure rate p1: 0.3 (three attempts in ten failed is not proficient).
    pub unacceptable_failure: f64,
    /// Decision limit h: 2.77 = ln((1 − β)/α) for α = 0.05, β = 0.2, Wald's sequential
    /// probability-ratio bound, which Biau et al. 2007 give as the starting point for h.
    pub limit: f64,
}

impl Default for CusumParams {
    fn default() -> CusumParams {
        CusumParams {
            acceptable_failure: 0.1,
            unacceptable_failure: 0.3,
            limit: (0.8_f64 / 0.05).ln(),
        }
    }
}

impl CusumParams {
    /// Checks 0 < p0 < p1 < 1 and h > 0.
    pub fn check(&self) -> Result<(), String> {
        let (p0, p1) = (self.acceptable_failure, self.unacceptable_failure);
        if !(p0 > 0.0 && p0 < p1 && p1 < 1.0) {
            return Err(format!(
                "cusum needs 0 < acceptable_failure < unacceptable_failure < 1 (got {p0}, {p1})"
            ));
        }
        if !(self.limit.is_finite() && self.limit > 0.0) {
            return Err(format!("cusum limit must be > 0 (got {})", self.limit));
        }
        Ok(())
    }

    /// The log-likelihood ratio of one attempt, "acceptable (p0)" over "unacceptable (p1)":
    /// ln((1 − p0)/(1 − p1)) > 0 for a pass, ln(p0/p1) < 0 for a failure (Biau et al. 2008).
    pub fn weight(&self, passed: bool) -> f64 {
        let (p0, p1) = (self.acceptable_failure, self.unacceptable_failure);
        if passed {
            ((1.0 - p0) / (1.0 - p1)).ln()
        } else {
            (p0 / p1).ln()
        }
    }
}

/// Where a trainee is on an exercise.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ProficiencyState {
    /// No attempt yet.
    NotStarted,
    /// Attempts, not yet proficient.
    Practising,
    /// Proficient, and no relapse since.
    Proficient,
    /// Was proficient; the relapse CUSUM crossed its limit since.
    Relapsed,
}

/// The two CUSUM charts over a trainee's attempts in order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Cusum {
    /// LC-CUSUM after each attempt while not proficient: S_n = max(0, S_{n−1} + w_n), w from
    /// [`CusumParams::weight`]; proficiency when S_n ≥ h (it then holds its value).
    pub learning: Vec<f64>,
    /// Relapse CUSUM after each attempt from the one after proficiency on (0 before):
    /// T_n = max(0, T_{n−1} − w_n); a relapse when T_n ≥ h (it restarts at 0 then, and the
    /// learning chart with it).
    pub relapse: Vec<f64>,
    /// Attempt numbers (1-based) at which the trainee became proficient (the learning chart
    /// crossed its limit, or the benchmark was met on enough attempts in a row).
    pub proficient_at: Vec<usize>,
    /// Attempt numbers (1-based) at which the relapse chart crossed its limit.
    pub relapsed_at: Vec<usize>,
}

impl Cusum {
    /// Runs both charts over `passed` (each attempt's outcome, in order), with no benchmark
    /// ([`progress`] with the CUSUM alone).
    pub fn run(params: &CusumParams, passed: &[bool]) -> Cusum {
        let attempts: Vec<AttemptOutcome> = passed
            .iter()
            .map(|&passed| AttemptOutcome::without_benchmark(passed))
            .collect();
        progress(params, 0, &attempts).cusum
    }
}

/// One attempt as proficiency sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AttemptOutcome {
    /// Passed the exercise's pass criteria.
    pub passed: bool,
    /// Met the benchmark (every benchmarked metric within its band); None without one.
    pub met_benchmark: Option<bool>,
}

impl AttemptOutcome {
    /// An attempt judged by its pass or fail alone (no benchmark to meet).
    pub fn without_benchmark(passed: bool) -> AttemptOutcome {
        AttemptOutcome {
            passed,
            met_benchmark: None,
        }
    }
}

/// A trainee's state on an exercise and how it was reached.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Progress {
    /// The state after the last attempt.
    pub state: ProficiencyState,
    /// Attempt number (1-based) at which the trainee last became proficient.
    pub proficient_at: Option<usize>,
    /// What made them proficient then: `benchmark` (N consecutive attempts met it) or `cusum`.
    pub by: Option<&'static str>,
    /// The charts.
    pub cusum: Cusum,
}

/// The state after `attempts` (in order): proficient once `consecutive` attempts in a row met
/// the benchmark (0: never by the benchmark) or the LC-CUSUM crossed its limit, whichever
/// came first; then the relapse CUSUM runs, and relapsed when it crosses its limit (both
/// charts and the count restart at 0, and the trainee can become proficient again).
pub fn progress(params: &CusumParams, consecutive: usize, attempts: &[AttemptOutcome]) -> Progress {
    let mut cusum = Cusum {
        learning: Vec::with_capacity(attempts.len()),
        relapse: Vec::with_capacity(attempts.len()),
        proficient_at: Vec::new(),
        relapsed_at: Vec::new(),
    };
    let mut state = if attempts.is_empty() {
        ProficiencyState::NotStarted
    } else {
        ProficiencyState::Practising
    };
    let (mut s, mut t, mut run) = (0.0_f64, 0.0_f64, 0usize);
    let (mut at, mut by) = (None, None);
    for (i, a) in attempts.iter().enumerate() {
        let n = i + 1;
        let w = params.weight(a.passed);
        if state == ProficiencyState::Proficient {
            t = (t - w).max(0.0);
            if t >= params.limit {
                state = ProficiencyState::Relapsed;
                cusum.relapsed_at.push(n);
                (s, t, run) = (0.0, 0.0, 0);
            }
        } else {
            s = (s + w).max(0.0);
            run = if a.met_benchmark == Some(true) {
                run + 1
            } else {
                0
            };
            let by_benchmark = consecutive > 0 && run >= consecutive;
            if by_benchmark || s >= params.limit {
                state = ProficiencyState::Proficient;
                cusum.proficient_at.push(n);
                at = Some(n);
                by = Some(if by_benchmark { "benchmark" } else { "cusum" });
                t = 0.0;
            }
        }
        cusum.learning.push(s);
        cusum.relapse.push(t);
    }
    Progress {
        state,
        proficient_at: at,
        by,
        cusum,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> crate::exercise::ExerciseSpec {
        serde_json::from_str(
            r#"{"id":"t","version":1,"title":"t","goal":"g","skills":[],
            "control":{"mode":"joint","arm":"left"},
            "steps":[{"id":"a","text":"a","done_when":{"kind":"released"}}],
            "time_limit_s":100,"pass":{"min_score":50,"limits":[]},
            "scoring":[{"metric":"time_s","good":20,"bad":100,"weight":3},
                       {"metric":"mean_jlm","good":0.8,"bad":0.4,"weight":1},
                       {"metric":"time_s","good":10,"bad":200,"weight":1}],
            "proficiency":{"benchmark_sd":1,"min_reference_attempts":4,
                           "benchmark_on":["score","time_s","mean_jlm"]},
            "autopilot":[]}"#,
        )
        .expect("spec")
    }

    fn values(score: f64, time_s: f64, jlm: f64) -> std::collections::BTreeMap<String, f64> {
        [("score", score), ("time_s", time_s), ("mean_jlm", jlm)]
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect()
    }

    /// An exercise's benchmark by hand: the score and each scored metric once (time_s appears
    /// twice in the terms), lower time better (good < bad), higher JLM better. References
    /// score 80, 84, 88, 92 → mean 86, SD √(80/3) = 5.164, line 80.836; times 30, 34, 38, 42
    /// → line 36 + 5.164 = 41.164; JLM 0.6, 0.7, 0.7, 0.8 → mean 0.7, SD √(0.02/3) = 0.08165,
    /// line 0.61835.
    #[test]
    fn exercise_benchmark_is_each_measures_band_on_its_worse_side() {
        let spec = spec();
        let refs = [
            values(80.0, 30.0, 0.6),
            values(84.0, 34.0, 0.7),
            values(88.0, 38.0, 0.7),
            values(92.0, 42.0, 0.8),
        ];
        let b = ExerciseBenchmark::of(&spec, &refs);
        let names: Vec<(&str, bool)> = b
            .measures
            .iter()
            .map(|m| (m.metric.as_str(), m.higher_is_better))
            .collect();
        assert_eq!(
            names,
            [("score", true), ("time_s", false), ("mean_jlm", true)]
        );
        assert!(b.applies && b.reference_attempts == 4);
        let sd = (80.0f64 / 3.0).sqrt();
        assert!((b.measures[0].line.unwrap() - (86.0 - sd)).abs() < 1e-9);
        assert!((b.measures[1].line.unwrap() - (36.0 + sd)).abs() < 1e-9);
        assert!((b.measures[2].line.unwrap() - (0.7 - (0.02f64 / 3.0).sqrt())).abs() < 1e-9);
        // every required measure must be met (here all three)
        assert!(b.measures.iter().all(|m| m.required));
        assert_eq!(b.met_by(&values(81.0, 41.0, 0.62)), Some(true));
        assert_eq!(b.met_by(&values(95.0, 41.5, 0.9)), Some(false)); // too slow
        assert_eq!(b.met_by(&values(80.5, 20.0, 0.9)), Some(false)); // score under the line
        let mut missing = values(95.0, 20.0, 0.9);
        missing.remove("mean_jlm");
        assert_eq!(b.met_by(&missing), Some(false));
        // three references: below min_reference_attempts, the file's marks alone apply
        let few = ExerciseBenchmark::of(&spec, &refs[..3]);
        assert!(!few.applies);
        assert_eq!(few.met_by(&values(95.0, 20.0, 0.9)), None);
        assert_eq!(
            ExerciseBenchmark::of(&spec, &[]).met_by(&values(95.0, 20.0, 0.9)),
            None
        );
        // the default requires the score and the time only: a poor posture is shown, not held
        // against the attempt; an unknown metric is refused
        let mut default = spec.clone();
        default.proficiency.benchmark_on = ProficiencySpec::default().benchmark_on;
        let b = ExerciseBenchmark::of(&default, &refs);
        let req: Vec<bool> = b.measures.iter().map(|m| m.required).collect();
        assert_eq!(req, [true, true, false]);
        assert_eq!(b.met_by(&values(81.0, 41.0, 0.1)), Some(true));
        default.proficiency.benchmark_on.push("nope".into());
        assert!(default.proficiency.check().is_err());
    }

    /// Mean and SD by hand: 10, 12, 14, 16, 18 → mean 14, SD √(40/4) = √10; no value is
    /// beyond 1.96·√10 = 6.2 of 14.
    #[test]
    fn benchmark_of_five_values_is_their_mean_and_sample_sd() {
        let b = Benchmark::from_reference(&[10.0, 12.0, 14.0, 16.0, 18.0]).unwrap();
        assert_eq!((b.n, b.outliers), (5, 0));
        assert!((b.mean - 14.0).abs() < 1e-12);
        assert!((b.sd - 10f64.sqrt()).abs() < 1e-12);
        // pass lines one SD to the worse side
        assert!((b.pass_line(1.0, true) - (14.0 - 10f64.sqrt())).abs() < 1e-12);
        assert!((b.pass_line(1.0, false) - (14.0 + 10f64.sqrt())).abs() < 1e-12);
        assert!(b.met_by(11.0, 1.0, true) && !b.met_by(10.5, 1.0, true));
        assert!(!b.met_by(f64::NAN, 1.0, true));
    }

    /// An outlier by hand: nine values of 50 and one of 100 → first mean 55, SD
    /// √(9·25 + 2025)/9 = √250 = 15.81; 100 is 45 > 1.96·15.81 = 30.99 away: removed; the
    /// rest is 50 ± 0.
    #[test]
    fn a_reference_value_beyond_1_96_sd_is_removed_once() {
        let mut v = vec![50.0; 9];
        v.push(100.0);
        let b = Benchmark::from_reference(&v).unwrap();
        assert_eq!((b.n, b.outliers), (9, 1));
        assert_eq!((b.mean, b.sd), (50.0, 0.0));
        assert_eq!(Benchmark::from_reference(&[f64::NAN]), None);
        assert_eq!(Benchmark::from_reference(&[]), None);
    }

    /// The LC-CUSUM by hand with the defaults (p0 0.1, p1 0.3, h = ln 16 = 2.7726): a pass
    /// adds ln(0.9/0.7) = 0.25131, a failure ln(1/3) = −1.09861. Eleven passes make
    /// 2.7644 < h, the twelfth 3.0157 ≥ h: proficient at attempt 12. A failure at attempt 3
    /// (after 0.50263) resets the chart to 0: twelve more passes, proficient at 15.
    #[test]
    fn the_learning_cusum_crosses_at_the_attempt_computed_by_hand() {
        let p = CusumParams::default();
        assert!((p.limit - 16f64.ln()).abs() < 1e-12);
        assert!((p.weight(true) - (0.9f64 / 0.7).ln()).abs() < 1e-12);
        assert!((p.weight(false) - (1.0f64 / 3.0).ln()).abs() < 1e-12);
        let c = Cusum::run(&p, &[true; 12]);
        assert_eq!(c.proficient_at, vec![12]);
        assert!((c.learning[10] - 11.0 * (0.9f64 / 0.7).ln()).abs() < 1e-12);
        let mut seq = vec![true, true, false];
        seq.extend([true; 12]);
        let c = Cusum::run(&p, &seq);
        assert_eq!(c.learning[2], 0.0);
        assert_eq!(c.proficient_at, vec![15]);
    }

    /// The relapse chart by hand: after proficiency at 12, a failure adds ln 3 = 1.09861 and a
    /// pass takes 0.25131 off (floor 0): two failures make 2.1972 < h, the third 3.2958 ≥ h:
    /// relapsed at attempt 15.
    #[test]
    fn the_relapse_cusum_crosses_after_three_failures_in_a_row() {
        let p = CusumParams::default();
        let mut seq = vec![true; 12];
        seq.extend([false, false, false]);
        let c = Cusum::run(&p, &seq);
        assert_eq!(c.relapsed_at, vec![15]);
        assert!((c.relapse[13] - 2.0 * 3f64.ln()).abs() < 1e-12);
        let outcomes: Vec<AttemptOutcome> = seq
            .iter()
            .map(|&passed| AttemptOutcome::without_benchmark(passed))
            .collect();
        let pr = progress(&p, 3, &outcomes);
        assert_eq!(pr.state, ProficiencyState::Relapsed);
        assert_eq!((pr.proficient_at, pr.by), (Some(12), Some("cusum")));
    }

    /// N consecutive attempts meeting the benchmark make a trainee proficient before the
    /// CUSUM does; a miss in between starts the count again.
    #[test]
    fn consecutive_benchmark_attempts_make_a_trainee_proficient() {
        let p = CusumParams::default();
        let o = |passed, met| AttemptOutcome {
            passed,
            met_benchmark: Some(met),
        };
        let attempts = [
            o(true, true),
            o(true, false),
            o(true, true),
            o(true, true),
            o(true, true),
        ];
        let pr = progress(&p, 3, &attempts);
        assert_eq!(pr.state, ProficiencyState::Proficient);
        assert_eq!((pr.proficient_at, pr.by), (Some(5), Some("benchmark")));
        assert_eq!(
            progress(&p, 3, &attempts[..4]).state,
            ProficiencyState::Practising
        );
        assert_eq!(progress(&p, 3, &[]).state, ProficiencyState::NotStarted);
    }

    /// Proficiency by the benchmark starts the relapse chart too: three failures after it
    /// (3 ln 3 = 3.2958 ≥ h) are a relapse; proficient again after three more benchmark
    /// attempts in a row.
    #[test]
    fn a_trainee_proficient_by_the_benchmark_can_relapse_and_recover() {
        let p = CusumParams::default();
        let o = |passed, met| AttemptOutcome {
            passed,
            met_benchmark: Some(met),
        };
        let mut attempts = vec![o(true, true); 3];
        attempts.extend([o(false, false); 3]);
        let pr = progress(&p, 3, &attempts);
        assert_eq!(pr.state, ProficiencyState::Relapsed);
        assert_eq!(pr.cusum.proficient_at, vec![3]);
        assert_eq!(pr.cusum.relapsed_at, vec![6]);
        attempts.extend([o(true, true); 3]);
        let pr = progress(&p, 3, &attempts);
        assert_eq!(pr.state, ProficiencyState::Proficient);
        assert_eq!((pr.proficient_at, pr.by), (Some(9), Some("benchmark")));
    }

    #[test]
    fn cusum_settings_are_checked() {
        assert!(CusumParams::default().check().is_ok());
        let bad = CusumParams {
            acceptable_failure: 0.3,
            unacceptable_failure: 0.1,
            ..CusumParams::default()
        };
        assert!(bad.check().is_err());
        let bad = CusumParams {
            limit: f64::NAN,
            ..CusumParams::default()
        };
        assert!(bad.check().is_err());
    }
}
