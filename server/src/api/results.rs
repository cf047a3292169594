//! `GET /api/results.csv?group=&exercise=` (instructor): a class's results, one row per
//! finished exercise attempt (outcome `passed` or `failed`), with the assessment's metrics,
//! written by [`crate::csv_out`].

use axum::extract::{Query, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use serde::Deserialize;

use crate::app::AppState;
use crate::auth::Credentials;
use crate::csv_out::{CsvOut, Field};
use crate::db::AttemptRow;
use crate::error::ApiError;

/// Query of `GET /api/results.csv` (both optional; empty = any).
#[derive(Debug, Default, Deserialize)]
pub struct ResultsQuery {
    /// Class or group.
    #[serde(default)]
    pub group: Option<String>,
    /// Exercise id.
    #[serde(default)]
    pub exercise: Option<String>,
}

/// The columns of the export.
pub const COLUMNS: [&str; 13] = [
    "trainee",
    "group",
    "exercise",
    "attempt",
    "session",
    "started_utc",
    "outcome",
    "score",
    "duration_s",
    "strikes",
    "overloads",
    "drops",
    "interventions",
];

/// `GET /api/results.csv`.
pub async fn export(
    State(state): State<AppState>,
    creds: Credentials,
    Query(q): Query<ResultsQuery>,
) -> Result<Response, ApiError> {
    creds.require_instructor(&state)?;
    let group = q.group.filter(|g| !g.is_empty());
    let exercise = q.exercise.filter(|e| !e.is_empty());
    let name = match (&group, &exercise) {
        (Some(g), _) => file_safe(g),
        (None, Some(e)) => file_safe(e),
        (None, None) => "all".to_string(),
    };
    // Streamed: rows come from the database a few at a time and leave in chunks, so memory
    // stays flat however many attempts the class has (issue 29: 60k attempts took 1.2 GB).
    let mut rows = state
        .db
        .results_stream(group.as_deref(), exercise.as_deref(), ROWS_IN_FLIGHT);
    // The first row (or the end) before answering: a database that cannot be read is a 503,
    // not a 200 cut short.
    let mut first = match rows.recv().await {
        Some(Err(e)) => return Err(crate::db::unavailable(e)),
        other => other,
    };
    let body = async_stream(move |tx| async move {
        let mut chunk = CsvOut::new(Vec::with_capacity(CHUNK_BYTES));
        let _ = chunk.header(&COLUMNS[..]);
        loop {
            let row = match first.take() {
                Some(row) => row,
                None => match rows.recv().await {
                    Some(row) => row,
                    None => break,
                },
            };
            match row {
                Ok(a) => {
                    if let Err(e) = row_of(&mut chunk, &a) {
                        let _ = tx.send(Err(e)).await;
                        return;
                    }
                }
                Err(e) => {
                    tracing::warn!("results.csv: {e:#}");
                    let _ = tx.send(Err(std::io::Error::other(e.to_string()))).await;
                    return;
                }
            }
            if chunk.get_ref().len() >= CHUNK_BYTES {
                let full =
                    std::mem::replace(&mut chunk, CsvOut::new(Vec::with_capacity(CHUNK_BYTES)));
                let sent = match full.into_inner() {
                    Ok(bytes) => tx.send(Ok(bytes)).await.is_ok(),
                    Err(_) => false,
                };
                if !sent {
                    return; // the client went away
                }
            }
        }
        if let Ok(bytes) = chunk.into_inner() {
            let _ = tx.send(Ok(bytes)).await;
        }
    });
    Ok((
        [
            (header::CONTENT_TYPE, "text/csv; charset=utf-8".to_string()),
            (
                header::CONTENT_DISPOSITION,
                format!("attachment; filename=\"seaarms-results-{name}.csv\""),
            ),
        ],
        body,
    )
        .into_response())
}

/// Rows the database may have read ahead of the response.
const ROWS_IN_FLIGHT: usize = 64;
/// Bytes of CSV sent at once.
const CHUNK_BYTES: usize = 32 * 1024;

/// A response body fed by `fill` through a small channel (it runs as its own task and stops
/// when the body is dropped).
fn async_stream<F, Fut>(fill: F) -> axum::body::Body
where
    F: FnOnce(tokio::sync::mpsc::Sender<std::io::Result<Vec<u8>>>) -> Fut,
    Fut: std::future::Future<Output = ()> + Send + 'static,
{
    let (tx, rx) = tokio::sync::mpsc::channel(2);
    tokio::spawn(fill(tx));
    let stream = futures_util::stream::unfold(rx, |mut rx| async move {
        rx.recv().await.map(|item| (item, rx))
    });
    axum::body::Body::from_stream(stream)
}

/// A name for a file: letters, digits, `-` and `_` kept, the rest `_` (at most 40).
pub(crate) fn file_safe(s: &str) -> String {
    s.chars()
        .take(40)
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Writes attempt `a`'s row of the export.
fn row_of(out: &mut CsvOut<Vec<u8>>, a: &AttemptRow) -> std::io::Result<()> {
    {
        let metric = |name: &str| {
            a.assessment
                .as_ref()
                .and_then(|v| v.get(name))
                .and_then(serde_json::Value::as_f64)
        };
        // Counts are whole numbers stored as f64 in the assessment.
        let count = |x: Option<f64>| match x {
            Some(v) if v.is_finite() && v >= 0.0 => Field::Int(v.round() as u64),
            _ => Field::Empty,
        };
        let strikes = match (metric("seabed_strikes"), metric("obstacle_strikes")) {
            (None, None) => None,
            (s, o) => Some(s.unwrap_or(0.0) + o.unwrap_or(0.0)),
        };
        let started = rfc3339(a.started_unix);
        out.row([
            Field::Text(&a.trainee),
            Field::Text(&a.group),
            Field::Text(a.exercise.as_deref().unwrap_or_default()),
            Field::Text(&a.id),
            Field::Text(&a.session),
            Field::Text(&started),
            Field::Text(a.outcome.as_deref().unwrap_or_default()),
            Field::from(a.score),
            Field::Num(metric("time_s").unwrap_or(a.sim_seconds)),
            count(strikes),
            count(metric("overloads")),
            count(metric("drops")),
            count(metric("interventions")),
        ])
    }
}

/// Unix seconds as UTC calendar fields: (year, month, day, hour, minute, second,
/// millisecond), rounded to the millisecond. Days to a civil date by Howard Hinnant's
/// `civil_from_days` (<https://howardhinnant.github.io/date_algorithms.html>; proleptic
/// Gregorian calendar). Shared by every timestamp the server writes (CSV, logbook, xAPI).
pub fn utc_fields(unix: f64) -> [i64; 7] {
    let ms_total = (unix * 1000.0).round() as i64;
    let (secs, ms) = (ms_total.div_euclid(1000), ms_total.rem_euclid(1000));
    let (days, sod) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    [year, month, day, sod / 3600, sod % 3600 / 60, sod % 60, ms]
}

/// Unix seconds as RFC 3339 UTC: `2023-11-14T22:13:20Z`, with milliseconds when not whole
/// (`…:20.500Z`).
pub fn rfc3339(unix: f64) -> String {
    let [year, month, day, h, m, s, ms] = utc_fields(unix);
    let frac = if ms == 0 {
        String::new()
    } else {
        format!(".{ms:03}")
    };
    format!("{year:04}-{month:02}-{day:02}T{h:02}:{m:02}:{s:02}{frac}Z")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Known instants: the epoch, 2000-02-29 (a leap day of a century leap year; 951782400
    /// s), 1 700 000 000 s = 2023-11-14T22:13:20Z, and a day before the epoch.
    #[test]
    fn rfc3339_matches_known_instants() {
        assert_eq!(rfc3339(0.0), "1970-01-01T00:00:00Z");
        assert_eq!(rfc3339(951_782_400.0), "2000-02-29T00:00:00Z");
        assert_eq!(rfc3339(1_700_000_000.0), "2023-11-14T22:13:20Z");
        assert_eq!(rfc3339(1_700_000_000.25), "2023-11-14T22:13:20.250Z");
        assert_eq!(rfc3339(-86_400.0), "1969-12-31T00:00:00Z");
    }
}
