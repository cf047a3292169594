//! Limits on the work one request may ask for, in one place (docs/operations.md lists them).
//!
//! Every computing route checks its request against these **before** it allocates or
//! computes anything in proportion to the request; a request over a limit gets a 400 with the
//! server's JSON error body, whose `detail` names the limit and its value:
//! `{"error": "...", "detail": {"limit": "max_study_rows", "value": 20000, "requested": 52000}}`.
//! Nonsense numbers (non-finite, a step ≤ 0, coordinates or angles far beyond any arm) are
//! 400s too. Time and concurrency are bounded by the compute pool ([`crate::compute`]): a
//! full queue is a 503 with `Retry-After`, a request past its deadline a 504.
//!
//! The figures below were chosen from release-build timings on a 2-core x86-64 machine: the
//! worst accepted request of each route runs in well under 2 s of one core and stays far
//! below 1 GB of memory (the bounded-work integration test sends each of them).

use serde_json::{Value, json};

use crate::error::ApiError;

/// Rows of one study, summed over all its series, counted as the most the request could
/// produce (series × samples per series; a sweep that stops early at the workspace boundary
/// still counts in full). About 10 µs and 3 KiB of answer per row.
pub const MAX_STUDY_ROWS: usize = 20_000;
/// Series of one study (`z_levels`, `x_levels`, `points`).
pub const MAX_STUDY_SERIES: usize = 64;
/// Largest |coordinate| of a study or map position, range end or base offset (m): every
/// built-in arm reaches less than 2 m.
pub const MAX_STUDY_COORDINATE_M: f64 = 10.0;
/// Largest |angle| of a study's pitch, yaw or swing range and step (deg).
pub const MAX_STUDY_ANGLE_DEG: f64 = 360.0;
/// Cells of one workspace map (nx · nz), e.g. 256 × 256. At most ~30 µs per cell.
pub const MAX_MAP_CELLS: usize = 65_536;
/// Initial candidates × joints of one optimal-posture request (64 starts of an 8-joint arm,
/// 16 of a 32-joint one); each start is an IK solve plus one SQP run of up to 400
/// evaluations.
pub const MAX_POSTURE_START_JOINTS: usize = 512;
/// Largest |q| of an analysis request (rad or m): anything larger is a client error, not a
/// posture.
pub const MAX_ABS_Q: f64 = 1.0e4;
/// Largest |coordinate| of a posture target or of an arm's base position (m).
pub const MAX_POSITION_M: f64 = 1.0e3;
/// Seconds a client is told to wait (`Retry-After`) when the compute queue is full.
pub const RETRY_AFTER_SECS: u64 = 2;

/// The 400 for a request over `limit` (named as in docs/operations.md, e.g.
/// `max_study_rows`): `what` says what was counted.
pub fn exceeded(
    limit: &'static str,
    value: impl Into<Value>,
    requested: impl Into<Value>,
    what: &str,
) -> ApiError {
    let (value, requested) = (value.into(), requested.into());
    ApiError::bad_request(format!(
        "{what}: {requested} is over the limit {limit} = {value}"
    ))
    .with_detail(json!({ "limit": limit, "value": value, "requested": requested }))
}

/// Checks that `v` is finite and |v| ≤ `max` (the limit named `limit`).
pub fn within(limit: &'static str, max: f64, what: &str, v: f64) -> Result<(), ApiError> {
    if !v.is_finite() {
        return Err(ApiError::bad_request(format!(
            "{what} must be finite, got {v}"
        )));
    }
    if v.abs() > max {
        return Err(exceeded(limit, max, v.abs(), &format!("|{what}|")));
    }
    Ok(())
}

/// Samples `start, start + step, …` up to `end` (the core's
/// [`seaarms_core::studies::sample_count`]), checked against [`MAX_STUDY_ROWS`] before any integer
/// conversion; `start ≤ end`, `step > 0`, everything finite.
pub fn samples(what: &str, start: f64, end: f64, step: f64) -> Result<usize, ApiError> {
    if !(start.is_finite() && end.is_finite() && step.is_finite()) {
        return Err(ApiError::bad_request(format!(
            "{what}: start, end and step must be finite"
        )));
    }
    if step <= 0.0 || end < start {
        return Err(ApiError::bad_request(format!(
            "{what}: needs start ≤ end and step > 0 (got start {start}, end {end}, step {step})"
        )));
    }
    let n = seaarms_core::studies::sample_count(start, end, step);
    if n > MAX_STUDY_ROWS as f64 {
        return Err(exceeded(
            "max_study_rows",
            MAX_STUDY_ROWS,
            n,
            &format!("{what}: samples (end − start)/step + 1"),
        ));
    }
    Ok(n as usize)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sample_counts_match_the_closed_form_and_absurd_ranges_are_refused() {
        // (end − start)/step + 1 samples: 0.9 to 1.0 by 0.01 is 11 (both ends included).
        assert_eq!(samples("x", 0.9, 1.0, 0.01).expect("ok"), 11);
        assert_eq!(samples("x", 1.0, 1.0, 0.5).expect("ok"), 1);
        // The attack of issue 13: a step of 1e-300 over 1e308 m, and a zero or negative step.
        for (s, e, st) in [
            (0.0, 1e308, 1e-300),
            (0.0, 1.0, 0.0),
            (0.0, 1.0, -1.0),
            (1.0, 0.0, 0.1),
            (0.0, f64::INFINITY, 1.0),
            (0.0, 1.0, f64::NAN),
        ] {
            assert!(samples("x", s, e, st).is_err(), "{s} {e} {st}");
        }
        let e = samples("x", 0.0, 1.0, 1e-5).expect_err("100 001 samples");
        assert_eq!(e.detail.expect("detail")["limit"], "max_study_rows");
    }

    #[test]
    fn within_refuses_non_finite_and_large_values() {
        assert!(within("max_position_m", 10.0, "x", 9.9).is_ok());
        assert!(within("max_position_m", 10.0, "x", -10.1).is_err());
        assert!(within("max_position_m", 10.0, "x", f64::NAN).is_err());
    }
}
