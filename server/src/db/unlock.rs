//! Instructor unlocks (`migrations/0007_unlocks.sql`, issue 30 item 4): exercises opened for
//! a trainee (name and group, as the records keep them) whatever their `requires`.

use anyhow::Result;
use sqlx::Row;

use super::Db;

impl Db {
    /// The exercises unlocked for the trainee `name` of `group`: (exercise, when, Unix s),
    /// by exercise.
    pub async fn unlocks(&self, name: &str, group: &str) -> Result<Vec<(String, f64)>> {
        let (name, group) = (name.to_string(), group.to_string());
        self.run(|pool| async move {
            let rows = sqlx::query(
                "SELECT exercise, unlocked_unix FROM unlocks \
                 WHERE name = $1 AND grp = $2 ORDER BY exercise",
            )
            .bind(name)
            .bind(group)
            .fetch_all(&pool)
            .await?;
            rows.iter()
                .map(|r| Ok((r.try_get("exercise")?, r.try_get("unlocked_unix")?)))
                .collect()
        })
        .await
    }

    /// Unlocks (`on`) or locks again `exercise` for the trainee `name` of `group`. Unlocking
    /// one already unlocked keeps the first time.
    pub async fn set_unlock(
        &self,
        name: &str,
        group: &str,
        exercise: &str,
        on: bool,
    ) -> Result<()> {
        let (name, group, exercise) = (name.to_string(), group.to_string(), exercise.to_string());
        self.run(move |pool| async move {
            if on {
                sqlx::query(
                    "INSERT INTO unlocks (name, grp, exercise, unlocked_unix) \
                     VALUES ($1, $2, $3, $4) ON CONFLICT (name, grp, exercise) DO NOTHING",
                )
                .bind(name)
                .bind(group)
                .bind(exercise)
                .bind(crate::clock::unix_now())
                .execute(&pool)
                .await?;
            } else {
                sqlx::query("DELETE FROM unlocks WHERE name = $1 AND grp = $2 AND exercise = $3")
                    .bind(name)
                    .bind(group)
                    .bind(exercise)
                    .execute(&pool)
                    .await?;
            }
            Ok(())
        })
        .await
    }
}
