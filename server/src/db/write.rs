//! What the recorder writes, one transaction per flush, and the start-up and retention
//! maintenance. Every insert is `ON CONFLICT DO NOTHING`, so a batch retried after a commit
//! whose answer was lost (PostgreSQL connection cut) adds nothing twice.

use std::collections::HashMap;

use anyhow::Result;
use sqlx::Row;

use super::attempt::{AttemptEnd, AttemptStart};
use super::{Db, INTERRUPTED, SessionRecord};

/// One write of the recorder.
#[derive(Debug, Clone)]
pub enum Write {
    /// A session started (its trainee is added when new, by name and group).
    Session {
        /// Id.
        id: String,
        /// Trainee display name ("" = none).
        trainee: String,
        /// Class or group.
        group: String,
        /// Scenario.
        scenario: String,
        /// Unix seconds.
        created_unix: f64,
        /// SHA-256 (hex) of its control token.
        token_sha256: String,
    },
    /// A typed event.
    Event {
        /// Session id.
        session: String,
        /// Order within the session (0, 1, 2, …).
        seq: i64,
        /// Attempt it happened in.
        attempt: Option<String>,
        /// Simulated seconds since the attempt's start.
        t: f64,
        /// Unix seconds when recorded.
        unix: f64,
        /// Kind.
        kind: String,
        /// Who gave it.
        actor: Option<&'static str>,
        /// Details (JSON text).
        detail: String,
    },
    /// An attempt started.
    AttemptStart(Box<AttemptStart>),
    /// The next piece of an attempt's input stream, and how far the attempt has run.
    AttemptInputs {
        /// Attempt id.
        id: String,
        /// Order within the attempt (0, 1, 2, …).
        seq: i64,
        /// Bytes (none: only the progress is written).
        data: Vec<u8>,
        /// Simulated seconds so far (the running attempt's `sim_seconds`).
        sim_seconds: f64,
    },
    /// An attempt ended.
    AttemptEnd(Box<AttemptEnd>),
    /// Queue a stored attempt's xAPI statements ([`crate::xapi`], `migrations/0003`): it
    /// follows the attempt's end in the same transaction and adds a row only for a finished
    /// exercise attempt (`passed` or `failed`, not practice) of a named trainee, while the outbox holds
    /// fewer than [`super::xapi::OUTBOX_CAPACITY`] rows.
    XapiQueue {
        /// Attempt id.
        attempt: String,
        /// Unix seconds.
        queued_unix: f64,
    },
    /// A live session's figures as of the rows on disk.
    Progress {
        /// Id.
        id: String,
        /// Simulated seconds.
        sim_seconds: f64,
        /// Relief events so far.
        overloads: u64,
        /// Part of its record could not be written.
        recording_failed: bool,
    },
    /// A session ended.
    SessionEnd {
        /// Id.
        id: String,
        /// Unix seconds.
        ended_unix: f64,
        /// Simulated seconds at the end.
        sim_seconds: f64,
        /// Why.
        reason: String,
        /// Relief events over the session.
        overloads: u64,
        /// Part of its record could not be written.
        recording_failed: bool,
    },
}

fn recording(failed: bool) -> &'static str {
    if failed { "failed" } else { "ok" }
}

fn count(n: u64) -> i64 {
    i64::try_from(n).unwrap_or(i64::MAX)
}

/// `recording` never goes back from `failed` to `ok`.
const KEEP_FAILED: &str = "CASE WHEN recording = 'failed' THEN 'failed' ELSE $4 END";

impl Db {
    /// Writes `ops` in order in ONE transaction: all of them or none (a killed process
    /// leaves the previous batch). Call through [`Db::block_on`] or from async code.
    pub async fn write_batch(&self, ops: &[Write]) -> Result<()> {
        if ops.is_empty() {
            return Ok(());
        }
        let mut tx = self.inner.pool.begin().await?;
        for op in ops {
            match op {
                Write::Session {
                    id,
                    trainee,
                    group,
                    scenario,
                    created_unix,
                    token_sha256,
                } => {
                    let mut trainee_id: Option<String> = None;
                    if !trainee.is_empty() {
                        sqlx::query(
                            "INSERT INTO trainees (id, name, grp, created_unix) \
                             VALUES ($1, $2, $3, $4) ON CONFLICT (name, grp) DO NOTHING",
                        )
                        .bind(crate::ids::random_hex(8))
                        .bind(trainee.as_str())
                        .bind(group.as_str())
                        .bind(*created_unix)
                        .execute(&mut *tx)
                        .await?;
                        let row =
                            sqlx::query("SELECT id FROM trainees WHERE name = $1 AND grp = $2")
                                .bind(trainee.as_str())
                                .bind(group.as_str())
                                .fetch_one(&mut *tx)
                                .await?;
                        trainee_id = Some(row.try_get("id")?);
                    }
                    sqlx::query(
                        "INSERT INTO sessions (id, trainee_id, label, grp, scenario, \
                         created_unix, ended_unix, end_reason, sim_seconds, overloads, \
                         recording, token_sha256) \
                         VALUES ($1, $2, $3, $4, $5, $6, NULL, NULL, $7, $8, 'ok', $9) \
                         ON CONFLICT (id) DO NOTHING",
                    )
                    .bind(id.as_str())
                    .bind(trainee_id)
                    .bind(trainee.as_str())
                    .bind(group.as_str())
                    .bind(scenario.as_str())
                    .bind(*created_unix)
                    .bind(0.0_f64)
                    .bind(0_i64)
                    .bind(token_sha256.as_str())
                    .execute(&mut *tx)
                    .await?;
                }
                Write::Event {
                    session,
                    seq,
                    attempt,
                    t,
                    unix,
                    kind,
                    actor,
                    detail,
                } => {
                    sqlx::query(
                        "INSERT INTO events (session_id, seq, attempt_id, t, unix, kind, actor, \
                         detail) VALUES ($1, $2, $3, $4, $5, $6, $7, $8) \
                         ON CONFLICT (session_id, seq) DO NOTHING",
                    )
                    .bind(session.as_str())
                    .bind(*seq)
                    .bind(attempt.as_deref())
                    .bind(*t)
                    .bind(*unix)
                    .bind(kind.as_str())
                    .bind(*actor)
                    .bind(detail.as_str())
                    .execute(&mut *tx)
                    .await?;
                }
                Write::AttemptStart(a) => {
                    sqlx::query(
                        "INSERT INTO attempts (id, session_id, scenario, exercise, \
                         exercise_version, sim_version, started_unix, ended_unix, sim_seconds, \
                         outcome, score, assessment, init, taken_over_from, taken_over_t) \
                         VALUES ($1, $2, $3, $4, $5, $6, $7, NULL, $8, NULL, NULL, NULL, $9, \
                         $10, $11) ON CONFLICT (id) DO NOTHING",
                    )
                    .bind(a.id.as_str())
                    .bind(a.session.as_str())
                    .bind(a.scenario.as_str())
                    .bind(a.exercise.as_deref())
                    .bind(a.exercise_version.as_deref())
                    .bind(a.sim_version.as_str())
                    .bind(a.started_unix)
                    .bind(0.0_f64)
                    .bind(a.init.to_string())
                    .bind(a.taken_over_from().map(|f| f.attempt))
                    .bind(a.taken_over_from().map(|f| f.t))
                    .execute(&mut *tx)
                    .await?;
                }
                Write::AttemptInputs {
                    id,
                    seq,
                    data,
                    sim_seconds,
                } => {
                    if !data.is_empty() {
                        sqlx::query(
                            "INSERT INTO attempt_inputs (attempt_id, seq, data) \
                             VALUES ($1, $2, $3) ON CONFLICT (attempt_id, seq) DO NOTHING",
                        )
                        .bind(id.as_str())
                        .bind(*seq)
                        .bind(data.as_slice())
                        .execute(&mut *tx)
                        .await?;
                    }
                    sqlx::query(
                        "UPDATE attempts SET sim_seconds = $2 WHERE id = $1 AND outcome IS NULL",
                    )
                    .bind(id.as_str())
                    .bind(*sim_seconds)
                    .execute(&mut *tx)
                    .await?;
                }
                Write::AttemptEnd(e) => {
                    sqlx::query(
                        "UPDATE attempts SET ended_unix = $2, sim_seconds = $3, outcome = $4, \
                         score = $5, assessment = $6 WHERE id = $1",
                    )
                    .bind(e.id.as_str())
                    .bind(e.ended_unix)
                    .bind(e.sim_seconds)
                    .bind(e.outcome.as_str())
                    .bind(e.score)
                    .bind(e.assessment.as_ref().map(|a| a.to_string()))
                    .execute(&mut *tx)
                    .await?;
                }
                Write::XapiQueue {
                    attempt,
                    queued_unix,
                } => {
                    sqlx::query(
                        "INSERT INTO xapi_outbox (attempt_id, queued_unix, tries, next_unix, \
                         last_error, rejected) \
                         SELECT a.id, $2, 0, $2, NULL, 0 FROM attempts a \
                         JOIN sessions s ON s.id = a.session_id \
                         WHERE a.id = $1 AND a.exercise IS NOT NULL \
                         AND a.outcome IN ('passed', 'failed') AND s.trainee_id IS NOT NULL \
                         AND a.taken_over_from IS NULL \
                         AND (SELECT COUNT(*) FROM xapi_outbox) < $3 \
                         ON CONFLICT (attempt_id) DO NOTHING",
                    )
                    .bind(attempt.as_str())
                    .bind(*queued_unix)
                    .bind(count(super::xapi::OUTBOX_CAPACITY))
                    .execute(&mut *tx)
                    .await?;
                }
                Write::Progress {
                    id,
                    sim_seconds,
                    overloads,
                    recording_failed,
                } => {
                    sqlx::query(&format!(
                        "UPDATE sessions SET sim_seconds = $2, overloads = $3, \
                         recording = {KEEP_FAILED} WHERE id = $1"
                    ))
                    .bind(id.as_str())
                    .bind(*sim_seconds)
                    .bind(count(*overloads))
                    .bind(recording(*recording_failed))
                    .execute(&mut *tx)
                    .await?;
                }
                Write::SessionEnd {
                    id,
                    ended_unix,
                    sim_seconds,
                    reason,
                    overloads,
                    recording_failed,
                } => {
                    sqlx::query(&format!(
                        "UPDATE sessions SET sim_seconds = $2, overloads = $3, \
                         recording = {KEEP_FAILED}, ended_unix = $5, end_reason = $6 \
                         WHERE id = $1"
                    ))
                    .bind(id.as_str())
                    .bind(*sim_seconds)
                    .bind(count(*overloads))
                    .bind(recording(*recording_failed))
                    .bind(*ended_unix)
                    .bind(reason.as_str())
                    .execute(&mut *tx)
                    .await?;
                }
            }
        }
        tx.commit().await?;
        Ok(())
    }

    /// Ids of sessions stored without an end (cut off by a crash, or live elsewhere).
    pub async fn unfinished_sessions(&self) -> Result<Vec<String>> {
        // Sessions other replicas hold (the directory) are theirs, not cut off.
        let rows = sqlx::query(
            "SELECT id FROM sessions WHERE end_reason IS NULL \
             AND id NOT IN (SELECT id FROM session_directory) ORDER BY id",
        )
        .fetch_all(&self.inner.pool)
        .await?;
        rows.iter()
            .map(|r| Ok(r.try_get("id")?))
            .collect::<Result<Vec<String>>>()
    }

    /// Start-up, nothing live yet: every session without an end is `interrupted (server
    /// stopped)`, every attempt without an outcome `interrupted` (one transaction) — except
    /// sessions other replicas hold (listed in `session_directory`; this replica's own rows
    /// were cleared first by [`Db::forget_replica`]). Returns (sessions, attempts) marked.
    pub async fn mark_interrupted(&self) -> Result<(u64, u64)> {
        let mut tx = self.inner.pool.begin().await?;
        let sessions = sqlx::query(
            "UPDATE sessions SET end_reason = $1 WHERE end_reason IS NULL \
             AND id NOT IN (SELECT id FROM session_directory)",
        )
        .bind(INTERRUPTED)
        .execute(&mut *tx)
        .await?
        .rows_affected();
        let attempts = sqlx::query(
            "UPDATE attempts SET outcome = 'interrupted' WHERE outcome IS NULL \
                 AND session_id NOT IN (SELECT id FROM session_directory)",
        )
        .execute(&mut *tx)
        .await?
        .rows_affected();
        tx.commit().await?;
        Ok((sessions, attempts))
    }

    /// Every stored session with the approximate bytes of its database rows (input pieces,
    /// event details, plus 48 bytes a row for keys and numbers), for retention.
    pub async fn sessions_with_bytes(&self) -> Result<Vec<(SessionRecord, u64)>> {
        let sql = format!(
            "SELECT {} ORDER BY created_unix, id",
            super::SESSION_COLUMNS
        );
        let rows = sqlx::query(&sql).fetch_all(&self.inner.pool).await?;
        let records = rows
            .iter()
            .map(super::session_record)
            .collect::<Result<Vec<_>>>()?;
        let mut bytes: HashMap<String, u64> = HashMap::new();
        for sql in [
            "SELECT a.session_id AS sid, \
             CAST(COALESCE(SUM(LENGTH(i.data)), 0) + COUNT(*) * 48 AS BIGINT) AS n \
             FROM attempt_inputs i JOIN attempts a ON a.id = i.attempt_id GROUP BY a.session_id",
            "SELECT session_id AS sid, \
             CAST(COALESCE(SUM(LENGTH(detail)), 0) + COUNT(*) * 48 AS BIGINT) AS n \
             FROM events GROUP BY session_id",
        ] {
            for r in sqlx::query(sql).fetch_all(&self.inner.pool).await? {
                let sid: String = r.try_get("sid")?;
                let n: i64 = r.try_get("n")?;
                *bytes.entry(sid).or_default() += u64::try_from(n).unwrap_or(0);
            }
        }
        Ok(records
            .into_iter()
            .map(|r| {
                let n = bytes.get(&r.id).copied().unwrap_or(0);
                (r, n)
            })
            .collect())
    }

    /// Deletes sessions with their attempts, input pieces and events (one transaction).
    /// Trainees stay.
    pub async fn delete_sessions(&self, ids: &[String]) -> Result<()> {
        if ids.is_empty() {
            return Ok(());
        }
        let mut tx = self.inner.pool.begin().await?;
        for id in ids {
            for sql in [
                "DELETE FROM attempt_inputs WHERE attempt_id IN \
                 (SELECT id FROM attempts WHERE session_id = $1)",
                "DELETE FROM xapi_outbox WHERE attempt_id IN \
                 (SELECT id FROM attempts WHERE session_id = $1)",
                "DELETE FROM events WHERE session_id = $1",
                "DELETE FROM attempts WHERE session_id = $1",
                "DELETE FROM sessions WHERE id = $1",
            ] {
                sqlx::query(sql).bind(id.as_str()).execute(&mut *tx).await?;
            }
        }
        tx.commit().await?;
        Ok(())
    }
}
