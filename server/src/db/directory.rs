//! The session directory and replica heartbeats (`migrations/0002_cluster.sql`): which
//! replica holds which live session, with the live summary the instructor's list shows, and
//! each replica's last heartbeat. Written only in multi-replica mode ([`crate::cluster`]);
//! every statement is portable (SQLite and PostgreSQL). Like the query API, each call runs
//! on the database's own runtime ([`Db::run`]).

use anyhow::Result;
use sqlx::{Any, AnyPool, Row, Transaction};

use super::Db;

/// One replica's heartbeat.
#[derive(Debug, Clone)]
pub struct ReplicaBeat {
    /// Replica name.
    pub name: String,
    /// When it started (Unix seconds).
    pub started_unix: f64,
    /// Now (Unix seconds).
    pub now_unix: f64,
    /// Live sessions it holds.
    pub live_sessions: i64,
    /// Its session cap.
    pub max_sessions: i64,
    /// Whether it is draining (refusing new sessions).
    pub draining: bool,
}

/// A replica another one declared lost, and what was marked interrupted.
#[derive(Debug, Clone, PartialEq)]
pub struct LostReplica {
    /// Its name.
    pub name: String,
    /// Its last heartbeat (Unix seconds).
    pub last_heartbeat_unix: f64,
    /// Sessions marked interrupted.
    pub sessions: u64,
    /// Running attempts marked interrupted.
    pub attempts: u64,
}

/// The end reason of the sessions of a lost replica.
pub fn lost_reason(replica: &str) -> String {
    format!("interrupted (replica {replica} stopped answering)")
}

impl Db {
    /// One heartbeat: the replica's row (its `lost_unix` cleared), its live sessions'
    /// directory rows (`(id, summary JSON)`, upserted), and the deletion of its rows not
    /// refreshed since `since_unix` (sessions that ended). One transaction.
    pub async fn heartbeat(
        &self,
        beat: ReplicaBeat,
        sessions: Vec<(String, String)>,
        since_unix: f64,
    ) -> Result<()> {
        self.run(move |pool| async move {
            let mut tx = pool.begin().await?;
            sqlx::query(
                "INSERT INTO replicas (name, started_unix, heartbeat_unix, live_sessions, \
                 max_sessions, draining, lost_unix) VALUES ($1, $2, $3, $4, $5, $6, NULL) \
                 ON CONFLICT (name) DO UPDATE SET started_unix = excluded.started_unix, \
                 heartbeat_unix = excluded.heartbeat_unix, \
                 live_sessions = excluded.live_sessions, max_sessions = excluded.max_sessions, \
                 draining = excluded.draining, lost_unix = NULL",
            )
            .bind(beat.name.as_str())
            .bind(beat.started_unix)
            .bind(beat.now_unix)
            .bind(beat.live_sessions)
            .bind(beat.max_sessions)
            .bind(i64::from(beat.draining))
            .execute(&mut *tx)
            .await?;
            for (id, summary) in &sessions {
                upsert(&mut tx, id, &beat.name, beat.now_unix, summary).await?;
            }
            sqlx::query("DELETE FROM session_directory WHERE replica = $1 AND updated_unix < $2")
                .bind(beat.name.as_str())
                .bind(since_unix)
                .execute(&mut *tx)
                .await?;
            tx.commit().await?;
            Ok(())
        })
        .await
    }

    /// Adds (or refreshes) one session's directory row at once (a session just created, so
    /// that other replicas know where it lives before the next heartbeat).
    pub async fn directory_put(
        &self,
        id: String,
        replica: String,
        now_unix: f64,
        summary: String,
    ) -> Result<()> {
        self.run(move |pool| async move {
            let mut tx = pool.begin().await?;
            upsert(&mut tx, &id, &replica, now_unix, &summary).await?;
            tx.commit().await?;
            Ok(())
        })
        .await
    }

    /// The replica holding live session `id`, if the directory lists it.
    pub async fn directory_replica(&self, id: &str) -> Result<Option<String>> {
        let id = id.to_string();
        self.run(move |pool| async move {
            let row = sqlx::query("SELECT replica FROM session_directory WHERE id = $1")
                .bind(id)
                .fetch_optional(&pool)
                .await?;
            Ok(match row {
                Some(r) => Some(r.try_get("replica")?),
                None => None,
            })
        })
        .await
    }

    /// Every directory row of other replicas than `me`: (id, replica, summary JSON).
    pub async fn directory_others(&self, me: &str) -> Result<Vec<(String, String, String)>> {
        let me = me.to_string();
        self.run(move |pool| async move {
            let rows = sqlx::query(
                "SELECT id, replica, summary FROM session_directory WHERE replica <> $1 \
                 ORDER BY replica, id",
            )
            .bind(me)
            .fetch_all(&pool)
            .await?;
            rows.iter()
                .map(|r| {
                    Ok((
                        r.try_get("id")?,
                        r.try_get("replica")?,
                        r.try_get("summary")?,
                    ))
                })
                .collect()
        })
        .await
    }

    /// A replica that stopped gracefully (its sessions ended and recorded): its directory
    /// rows go and its row is marked gone (`lost_unix`), so no other replica declares it lost.
    pub async fn leave(&self, me: &str, now_unix: f64) -> Result<()> {
        let me = me.to_string();
        self.run(move |pool| async move {
            let mut tx = pool.begin().await?;
            sqlx::query("DELETE FROM session_directory WHERE replica = $1")
                .bind(me.as_str())
                .execute(&mut *tx)
                .await?;
            sqlx::query("UPDATE replicas SET lost_unix = $1, live_sessions = 0 WHERE name = $2")
                .bind(now_unix)
                .bind(me.as_str())
                .execute(&mut *tx)
                .await?;
            tx.commit().await?;
            Ok(())
        })
        .await
    }

    /// Start-up of replica `me`: whatever its previous run left in the directory (a crash,
    /// a restart quicker than the heartbeat timeout) is interrupted, as a single server's
    /// start-up marks its own ([`super::INTERRUPTED`]). Returns (sessions, attempts) marked.
    pub async fn forget_replica(&self, me: &str) -> Result<(u64, u64)> {
        let me = me.to_string();
        self.run(move |pool| async move {
            let mut tx = pool.begin().await?;
            let marked = interrupt_directory(&mut tx, &me, super::INTERRUPTED).await?;
            tx.commit().await?;
            Ok(marked)
        })
        .await
    }

    /// Declares lost every replica other than `me` whose heartbeat is older than
    /// `before_unix` and not yet declared lost: its sessions (ids in the directory) get the
    /// end reason [`lost_reason`], its running attempts the outcome `interrupted`, its
    /// directory rows go. Each replica in one transaction; of several replicas doing this at
    /// once only the first marks it (the conditional update of its row).
    pub async fn reap_lost(
        &self,
        me: &str,
        before_unix: f64,
        now_unix: f64,
    ) -> Result<Vec<LostReplica>> {
        let me = me.to_string();
        self.run(move |pool| reap(pool, me, before_unix, now_unix))
            .await
    }
}

async fn reap(
    pool: AnyPool,
    me: String,
    before_unix: f64,
    now_unix: f64,
) -> Result<Vec<LostReplica>> {
    let rows = sqlx::query(
        "SELECT name, heartbeat_unix FROM replicas \
         WHERE heartbeat_unix < $1 AND lost_unix IS NULL AND name <> $2",
    )
    .bind(before_unix)
    .bind(me)
    .fetch_all(&pool)
    .await?;
    let mut lost = Vec::new();
    for r in rows {
        let name: String = r.try_get("name")?;
        let last: f64 = r.try_get("heartbeat_unix")?;
        let mut tx = pool.begin().await?;
        let claimed = sqlx::query(
            "UPDATE replicas SET lost_unix = $1 \
             WHERE name = $2 AND lost_unix IS NULL AND heartbeat_unix < $3",
        )
        .bind(now_unix)
        .bind(name.as_str())
        .bind(before_unix)
        .execute(&mut *tx)
        .await?
        .rows_affected();
        if claimed == 0 {
            tx.rollback().await?;
            continue;
        }
        let reason = lost_reason(&name);
        let (sessions, attempts) = interrupt_directory(&mut tx, &name, &reason).await?;
        tx.commit().await?;
        lost.push(LostReplica {
            name,
            last_heartbeat_unix: last,
            sessions,
            attempts,
        });
    }
    Ok(lost)
}

async fn upsert(
    tx: &mut Transaction<'_, Any>,
    id: &str,
    replica: &str,
    now_unix: f64,
    summary: &str,
) -> Result<()> {
    sqlx::query(
        "INSERT INTO session_directory (id, replica, updated_unix, summary) \
         VALUES ($1, $2, $3, $4) ON CONFLICT (id) DO UPDATE SET replica = excluded.replica, \
         updated_unix = excluded.updated_unix, summary = excluded.summary",
    )
    .bind(id)
    .bind(replica)
    .bind(now_unix)
    .bind(summary)
    .execute(&mut **tx)
    .await?;
    Ok(())
}

/// Marks the directory's sessions of `replica` interrupted (sessions without an end get the
/// end reason `reason`, attempts without an outcome `interrupted`) and deletes its rows;
/// returns (sessions, attempts) marked.
async fn interrupt_directory(
    tx: &mut Transaction<'_, Any>,
    replica: &str,
    reason: &str,
) -> Result<(u64, u64)> {
    let attempts = sqlx::query(
        "UPDATE attempts SET outcome = 'interrupted' WHERE outcome IS NULL AND session_id IN \
         (SELECT id FROM session_directory WHERE replica = $1)",
    )
    .bind(replica)
    .execute(&mut **tx)
    .await?
    .rows_affected();
    let sessions = sqlx::query(
        "UPDATE sessions SET end_reason = $1 WHERE end_reason IS NULL AND id IN \
         (SELECT id FROM session_directory WHERE replica = $2)",
    )
    .bind(reason)
    .bind(replica)
    .execute(&mut **tx)
    .await?
    .rows_affected();
    sqlx::query("DELETE FROM session_directory WHERE replica = $1")
        .bind(replica)
        .execute(&mut **tx)
        .await?;
    Ok((sessions, attempts))
}
