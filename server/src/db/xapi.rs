//! The xAPI outbox (`migrations/0003_xapi_outbox.sql`): finished attempts whose statements
//! wait for the Learning Record Store. Rows are added by the recorder's batch
//! ([`super::Write::XapiQueue`]) and taken by [`crate::xapi`]'s sender.

use anyhow::Result;
use sqlx::Row;

use super::{AttemptRow, Db};

/// Most rows the outbox holds (the queue's bound); an attempt finished while it is full is
/// not queued, and `seaarms_xapi_pending` shows the cap. About 70 days of a busy class (8
/// trainees × 180 attempts a day) with the LRS down.
pub const OUTBOX_CAPACITY: u64 = 100_000;

/// What an attempt's statements are built from: its stored row and its trainee's id.
#[derive(Debug, Clone)]
pub struct XapiSource {
    /// The attempt as stored.
    pub attempt: AttemptRow,
    /// The trainee's id (`trainees.id`).
    pub trainee_id: String,
}

impl Db {
    /// Claims up to `limit` due outbox rows (not rejected, `next_unix` ≤ `now`): each is
    /// moved `lease_s` ahead first, so another replica sharing the database does not send it
    /// meanwhile (a sender that dies leaves it due again after the lease). Oldest first, with
    /// the tries each has had.
    pub async fn xapi_claim(
        &self,
        now: f64,
        lease_s: f64,
        limit: usize,
    ) -> Result<Vec<(String, i64)>> {
        let limit = i64::try_from(limit).unwrap_or(i64::MAX);
        self.run(move |pool| async move {
            let rows = sqlx::query(
                "SELECT attempt_id, tries FROM xapi_outbox WHERE rejected = 0 AND next_unix <= $1 \
                 ORDER BY queued_unix, attempt_id LIMIT $2",
            )
            .bind(now)
            .bind(limit)
            .fetch_all(&pool)
            .await?;
            let mut claimed = Vec::with_capacity(rows.len());
            for r in &rows {
                let id: String = r.try_get("attempt_id")?;
                let tries: i64 = r.try_get("tries")?;
                let done = sqlx::query(
                    "UPDATE xapi_outbox SET next_unix = $2 \
                     WHERE attempt_id = $1 AND rejected = 0 AND next_unix <= $3",
                )
                .bind(id.as_str())
                .bind(now + lease_s)
                .bind(now)
                .execute(&pool)
                .await?
                .rows_affected();
                if done == 1 {
                    claimed.push((id, tries));
                }
            }
            Ok(claimed)
        })
        .await
    }

    /// The stored attempt and its trainee's id (None when either is gone: retention deleted
    /// it, or the session had no trainee).
    pub async fn xapi_source(&self, attempt: &str) -> Result<Option<XapiSource>> {
        let Some(row) = self.attempt(attempt).await? else {
            return Ok(None);
        };
        let session = row.session.clone();
        let trainee: Option<String> = self
            .run(move |pool| async move {
                let r = sqlx::query("SELECT trainee_id FROM sessions WHERE id = $1")
                    .bind(session)
                    .fetch_optional(&pool)
                    .await?;
                Ok(match r {
                    Some(r) => r.try_get("trainee_id")?,
                    None => None,
                })
            })
            .await?;
        Ok(trainee.map(|trainee_id| XapiSource {
            attempt: row,
            trainee_id,
        }))
    }

    /// The attempt's statements were accepted (or it has none to send): its row goes.
    pub async fn xapi_done(&self, attempt: &str) -> Result<()> {
        let attempt = attempt.to_string();
        self.run(move |pool| async move {
            sqlx::query("DELETE FROM xapi_outbox WHERE attempt_id = $1")
                .bind(attempt)
                .execute(&pool)
                .await?;
            Ok(())
        })
        .await
    }

    /// A try failed: the row's tries go up by one and it is due again at `next_unix`.
    pub async fn xapi_retry(&self, attempt: &str, next_unix: f64, error: &str) -> Result<()> {
        let (attempt, error) = (attempt.to_string(), error.to_string());
        self.run(move |pool| async move {
            sqlx::query(
                "UPDATE xapi_outbox SET tries = tries + 1, next_unix = $2, last_error = $3 \
                 WHERE attempt_id = $1",
            )
            .bind(attempt)
            .bind(next_unix)
            .bind(error)
            .execute(&pool)
            .await?;
            Ok(())
        })
        .await
    }

    /// The LRS refused the statements for good (a 400 or a 409): the row stays, marked, with
    /// the LRS's answer, and is not tried again.
    pub async fn xapi_reject(&self, attempt: &str, error: &str) -> Result<()> {
        let (attempt, error) = (attempt.to_string(), error.to_string());
        self.run(move |pool| async move {
            sqlx::query(
                "UPDATE xapi_outbox SET tries = tries + 1, rejected = 1, last_error = $2 \
                 WHERE attempt_id = $1",
            )
            .bind(attempt)
            .bind(error)
            .execute(&pool)
            .await?;
            Ok(())
        })
        .await
    }

    /// Outbox rows waiting to be sent (not rejected).
    pub async fn xapi_pending(&self) -> Result<u64> {
        self.run(|pool| async move {
            let n: i64 = sqlx::query_scalar(
                "SELECT CAST(COUNT(*) AS BIGINT) FROM xapi_outbox WHERE rejected = 0",
            )
            .fetch_one(&pool)
            .await?;
            Ok(u64::try_from(n).unwrap_or(0))
        })
        .await
    }
}
