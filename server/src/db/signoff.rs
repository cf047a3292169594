//! Instructor sign-offs (`migrations/0005_signoffs.sql`, issue 30 item 7): an assessor's
//! signature that a trainee (name and group, as the records keep them) is competent at an
//! exercise. One per trainee and exercise; signing again replaces it.

use anyhow::Result;
use serde::Serialize;
use sqlx::Row;

use super::Db;

/// One sign-off as stored.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Signoff {
    /// Exercise id.
    pub exercise: String,
    /// When it was signed (Unix s).
    pub signed_unix: f64,
    /// The assessor's name.
    pub assessor: String,
    /// The assessor's note (empty when none).
    pub note: String,
}

impl Db {
    /// The sign-offs of the trainee `name` of `group`, by exercise.
    pub async fn signoffs(&self, name: &str, group: &str) -> Result<Vec<Signoff>> {
        let (name, group) = (name.to_string(), group.to_string());
        self.run(|pool| async move {
            let rows = sqlx::query(
                "SELECT exercise, signed_unix, assessor, note FROM signoffs \
                 WHERE name = $1 AND grp = $2 ORDER BY exercise",
            )
            .bind(name)
            .bind(group)
            .fetch_all(&pool)
            .await?;
            rows.iter()
                .map(|r| {
                    Ok(Signoff {
                        exercise: r.try_get("exercise")?,
                        signed_unix: r.try_get("signed_unix")?,
                        assessor: r.try_get("assessor")?,
                        note: r.try_get("note")?,
                    })
                })
                .collect()
        })
        .await
    }

    /// Signs off the trainee `name` of `group` on `s.exercise` (replacing an earlier
    /// sign-off of the same exercise).
    pub async fn set_signoff(&self, name: &str, group: &str, s: &Signoff) -> Result<()> {
        let (name, group, s) = (name.to_string(), group.to_string(), s.clone());
        self.run(move |pool| async move {
            sqlx::query(
                "INSERT INTO signoffs (name, grp, exercise, signed_unix, assessor, note) \
                 VALUES ($1, $2, $3, $4, $5, $6) ON CONFLICT (name, grp, exercise) DO UPDATE \
                 SET signed_unix = excluded.signed_unix, assessor = excluded.assessor, \
                 note = excluded.note",
            )
            .bind(name)
            .bind(group)
            .bind(s.exercise)
            .bind(s.signed_unix)
            .bind(s.assessor)
            .bind(s.note)
            .execute(&pool)
            .await?;
            Ok(())
        })
        .await
    }

    /// Revokes the sign-off of `name` of `group` on `exercise`; whether there was one.
    pub async fn revoke_signoff(&self, name: &str, group: &str, exercise: &str) -> Result<bool> {
        let (name, group, exercise) = (name.to_string(), group.to_string(), exercise.to_string());
        self.run(move |pool| async move {
            let done =
                sqlx::query("DELETE FROM signoffs WHERE name = $1 AND grp = $2 AND exercise = $3")
                    .bind(name)
                    .bind(group)
                    .bind(exercise)
                    .execute(&pool)
                    .await?;
            Ok(done.rows_affected() > 0)
        })
        .await
    }
}
