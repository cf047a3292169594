//! Training records in a database: trainees, sessions, attempts (with their compressed input
//! streams) and typed events; and the xAPI outbox (`xapi`: finished attempts waiting for
//! the Learning Record Store). One code path for SQLite (the default, a file in the data
//! folder) and PostgreSQL (`--database-url postgres://…`) through sqlx's `Any` driver, with
//! the portable schema of `migrations/` applied at start-up.
//!
//! The database runs on its own small tokio runtime (one worker thread), so it works the same
//! whoever calls it: request handlers (any runtime) await the query API, the recorder thread
//! writes through [`Db::block_on`], and no caller's runtime has to drive its connections.
//! Writes come from the recorder ([`crate::sessions::record`]) only, one transaction per
//! flush ([`Db::write_batch`]); everything here is queries with `$1, $2, …` placeholders,
//! which both back ends take (SQLite reads `$N` as parameter N).

pub mod attempt;
mod directory;
mod signoff;
mod unlock;
mod write;
mod xapi;

use std::future::Future;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use anyhow::{Context, Result, anyhow};
use attempt::TakenOver;
use serde::Serialize;
use sqlx::any::{AnyPoolOptions, AnyRow};
use sqlx::{AnyPool, Executor, Row};

pub use directory::{LostReplica, ReplicaBeat, lost_reason};
pub use signoff::Signoff;
pub use write::Write;
pub use xapi::{OUTBOX_CAPACITY, XapiSource};

/// Which server the URL names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    /// An SQLite file.
    Sqlite,
    /// A PostgreSQL server.
    Postgres,
}

impl Backend {
    /// The back end of a database URL.
    pub fn of(url: &str) -> Result<Backend> {
        if url.starts_with("sqlite:") {
            Ok(Backend::Sqlite)
        } else if url.starts_with("postgres://") || url.starts_with("postgresql://") {
            Ok(Backend::Postgres)
        } else {
            Err(anyhow!(
                "unsupported database URL `{}` (sqlite://PATH or postgres://…)",
                redact(url)
            ))
        }
    }
}

/// The URL with any password replaced by `***` (for messages and logs).
pub fn redact(url: &str) -> String {
    let Some((scheme, rest)) = url.split_once("://") else {
        return url.to_string();
    };
    match rest.split_once('@') {
        Some((user, host)) if user.contains(':') => {
            let name = user.split(':').next().unwrap_or_default();
            format!("{scheme}://{name}:***@{host}")
        }
        _ => url.to_string(),
    }
}

/// The default database of a data folder: `sqlite://DATA/seaarms.db?mode=rwc` (created when
/// missing). `%`, `?` and `#` in the path are percent-encoded, as the SQLite URL requires.
pub fn default_url(data_dir: &std::path::Path) -> String {
    let path = data_dir.join("seaarms.db").to_string_lossy().into_owned();
    let mut encoded = String::with_capacity(path.len());
    for c in path.chars() {
        match c {
            '%' => encoded.push_str("%25"),
            '?' => encoded.push_str("%3F"),
            '#' => encoded.push_str("%23"),
            c => encoded.push(c),
        }
    }
    format!("sqlite://{encoded}?mode=rwc")
}

/// An SQLite URL that creates its file when missing: `mode=rwc` added unless a `mode` is
/// given (other URLs unchanged).
fn sqlite_creating(url: &str) -> String {
    if !url.starts_with("sqlite:") {
        return url.to_string();
    }
    match url.split_once('?') {
        Some((_, query)) if query.split('&').any(|kv| kv.starts_with("mode=")) => url.to_string(),
        Some(_) => format!("{url}&mode=rwc"),
        None => format!("{url}?mode=rwc"),
    }
}

/// The file of an SQLite URL (None for an in-memory database).
fn sqlite_file(url: &str) -> Option<PathBuf> {
    let rest = url
        .strip_prefix("sqlite://")
        .or_else(|| url.strip_prefix("sqlite:"))?;
    let path = rest.split('?').next().unwrap_or_default();
    if path.is_empty() || path == ":memory:" {
        return None;
    }
    // Percent-decoding, as sqlx does for the file name.
    let bytes = path.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            if let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    Some(PathBuf::from(String::from_utf8_lossy(&out).into_owned()))
}

/// The database's runtime, shut down without waiting when the last [`Db`] goes (dropping a
/// runtime normally blocks, which is not allowed inside another runtime).
struct OwnRuntime(Option<tokio::runtime::Runtime>);

impl Drop for OwnRuntime {
    fn drop(&mut self) {
        if let Some(rt) = self.0.take() {
            rt.shutdown_background();
        }
    }
}

struct Inner {
    pool: AnyPool,
    handle: tokio::runtime::Handle,
    backend: Backend,
    /// SQLite: the file, and its identity (device, inode) when opened.
    file: Option<(PathBuf, FileId)>,
    // Last: dropped after the pool.
    _runtime: OwnRuntime,
}

/// A file's identity: (device, inode) on Unix; its path elsewhere.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FileId(u64, u64);

impl FileId {
    /// The identity of the file at `path`, if there is one.
    fn of(path: &std::path::Path) -> Option<FileId> {
        let m = std::fs::metadata(path).ok()?;
        #[cfg(unix)]
        {
            use std::os::unix::fs::MetadataExt;
            Some(FileId(m.dev(), m.ino()))
        }
        #[cfg(not(unix))]
        {
            Some(FileId(m.len().min(1), 0))
        }
    }
}

/// The records database (cheap to clone).
#[derive(Clone)]
pub struct Db {
    inner: Arc<Inner>,
}

/// Filters of [`Db::attempts`] (all optional; `limit` 0 = no limit).
#[derive(Debug, Clone, Default)]
pub struct AttemptFilter {
    /// Trainee display name.
    pub trainee: Option<String>,
    /// Class or group.
    pub group: Option<String>,
    /// Exercise id.
    pub exercise: Option<String>,
    /// Session id.
    pub session: Option<String>,
    /// Most rows (newest first).
    pub limit: usize,
    /// Leave out practice attempts ([`AttemptRow::practice`]): what counts towards progress.
    pub without_practice: bool,
}

/// One attempt as stored.
#[derive(Debug, Clone, Serialize)]
pub struct AttemptRow {
    /// Attempt id.
    pub id: String,
    /// Session id.
    pub session: String,
    /// Trainee display name (the session's).
    pub trainee: String,
    /// Class or group (the session's).
    pub group: String,
    /// Scenario name.
    pub scenario: String,
    /// Exercise id, for exercises.
    pub exercise: Option<String>,
    /// Version stamp of the exercise file.
    pub exercise_version: Option<String>,
    /// Version stamp of the simulator that recorded it.
    pub sim_version: String,
    /// Unix seconds.
    pub started_unix: f64,
    /// Unix seconds, once ended.
    pub ended_unix: Option<f64>,
    /// Simulated seconds it ran (0 until it ends).
    pub sim_seconds: f64,
    /// `passed`, `failed`, `abandoned`, `ended`, `interrupted`, or None while running.
    pub outcome: Option<String>,
    /// Score 0–100 (exercises).
    pub score: Option<f64>,
    /// The exercise's assessment.
    pub assessment: Option<serde_json::Value>,
    /// Initial conditions for replay.
    pub init: serde_json::Value,
    /// Bytes of its compressed input stream.
    pub inputs_bytes: i64,
    /// A practice attempt ("take over from here"): left out of learning curves, proficiency,
    /// benchmarks, the logbook and xAPI.
    pub practice: bool,
    /// The attempt and time a practice attempt was taken over from.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub taken_over_from: Option<TakenOver>,
}

/// One typed event of an attempt.
#[derive(Debug, Clone, Serialize)]
pub struct EventRow {
    /// Simulated seconds since the attempt's start.
    pub t: f64,
    /// Kind (`grasp`, `relief`, `exercise`, or a command name).
    pub kind: String,
    /// Who gave it, for commands.
    pub actor: Option<String>,
    /// Details (JSON object).
    pub detail: serde_json::Value,
}

/// One session as stored.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SessionRecord {
    /// Id.
    pub id: String,
    /// Trainee display name.
    pub trainee: String,
    /// Class or group.
    pub group: String,
    /// Scenario at creation.
    pub scenario: String,
    /// Unix seconds.
    pub created_unix: f64,
    /// Unix seconds, when it ended (None while live, and for interrupted sessions).
    pub ended_unix: Option<f64>,
    /// Why it ended (None while live).
    pub end_reason: Option<String>,
    /// Simulated seconds: at the end, or of the last rows written while it ran.
    pub sim_seconds: f64,
    /// Relief events over the session (so far, while it runs).
    pub overloads: u64,
    /// Part of the record could not be written.
    pub recording_failed: bool,
}

/// The answer to a request whose database query failed: 503, the error logged (its text may
/// name the server, so the client gets none of it).
pub fn unavailable(e: anyhow::Error) -> crate::error::ApiError {
    tracing::error!("records database: {e:#}");
    crate::error::ApiError::new(
        axum::http::StatusCode::SERVICE_UNAVAILABLE,
        "the records database is not answering; try again",
    )
}

/// The end reason given to sessions cut off by a crash or kill.
pub const INTERRUPTED: &str = "interrupted (server stopped)";

const ATTEMPT_COLUMNS: &str = "a.id, a.session_id, COALESCE(s.label, '') AS label, \
     COALESCE(s.grp, '') AS grp, a.scenario, a.exercise, a.exercise_version, a.sim_version, \
     a.started_unix, a.ended_unix, a.sim_seconds, a.outcome, a.score, a.assessment, a.init, \
     a.taken_over_from, a.taken_over_t, (SELECT CAST(COALESCE(SUM(LENGTH(i.data)), 0) AS BIGINT) FROM attempt_inputs i \
      WHERE i.attempt_id = a.id) AS inputs_bytes \
     FROM attempts a LEFT JOIN sessions s ON s.id = a.session_id";

/// [`ATTEMPT_COLUMNS`] without what the class export does not need (the initial conditions,
/// the input bytes), in the same names for [`attempt_row`].
const RESULT_COLUMNS: &str = "a.id, a.session_id, COALESCE(s.label, '') AS label, \
     COALESCE(s.grp, '') AS grp, a.scenario, a.exercise, a.exercise_version, a.sim_version, \
     a.started_unix, a.ended_unix, a.sim_seconds, a.outcome, a.score, a.assessment, \
     'null' AS init, a.taken_over_from, a.taken_over_t, CAST(0 AS BIGINT) AS inputs_bytes \
     FROM attempts a LEFT JOIN sessions s ON s.id = a.session_id";

const SESSION_COLUMNS: &str = "id, label, grp, scenario, created_unix, ended_unix, end_reason, \
     sim_seconds, overloads, recording FROM sessions";

fn json_or_null(text: Option<String>) -> Option<serde_json::Value> {
    text.and_then(|t| serde_json::from_str(&t).ok())
}

fn attempt_row(r: &AnyRow) -> Result<AttemptRow> {
    let from: Option<String> = r.try_get("taken_over_from")?;
    let t: Option<f64> = r.try_get("taken_over_t")?;
    Ok(AttemptRow {
        id: r.try_get("id")?,
        session: r.try_get("session_id")?,
        trainee: r.try_get("label")?,
        group: r.try_get("grp")?,
        scenario: r.try_get("scenario")?,
        exercise: r.try_get("exercise")?,
        exercise_version: r.try_get("exercise_version")?,
        sim_version: r.try_get("sim_version")?,
        started_unix: r.try_get("started_unix")?,
        ended_unix: r.try_get("ended_unix")?,
        sim_seconds: r.try_get("sim_seconds")?,
        outcome: r.try_get("outcome")?,
        score: r.try_get("score")?,
        assessment: json_or_null(r.try_get("assessment")?),
        init: json_or_null(Some(r.try_get("init")?)).unwrap_or(serde_json::Value::Null),
        inputs_bytes: r.try_get("inputs_bytes")?,
        practice: from.is_some(),
        taken_over_from: from.map(|attempt| TakenOver {
            attempt,
            t: t.unwrap_or(0.0),
        }),
    })
}

fn session_record(r: &AnyRow) -> Result<SessionRecord> {
    let overloads: i64 = r.try_get("overloads")?;
    let recording: String = r.try_get("recording")?;
    Ok(SessionRecord {
        id: r.try_get("id")?,
        trainee: r.try_get("label")?,
        group: r.try_get("grp")?,
        scenario: r.try_get("scenario")?,
        created_unix: r.try_get("created_unix")?,
        ended_unix: r.try_get("ended_unix")?,
        end_reason: r.try_get("end_reason")?,
        sim_seconds: r.try_get("sim_seconds")?,
        overloads: u64::try_from(overloads).unwrap_or(0),
        recording_failed: recording == "failed",
    })
}

impl Db {
    /// Opens (SQLite: creates the file and its folder) the database at `url` and applies the
    /// migrations. SQLite runs with a rollback journal (`journal_mode=DELETE`) and
    /// `synchronous=FULL`: a commit is atomic and survives the process being killed and a
    /// power cut. Not WAL: its shared-memory index is a memory-mapped file, and an unwritable
    /// or vanished `-shm` file killed the process with SIGBUS (issue 29); one commit a second
    /// needs none of WAL's concurrency. Blocking: call at start-up.
    pub fn open(url: &str) -> Result<Db> {
        sqlx::any::install_default_drivers();
        let backend = Backend::of(url)?;
        let url = &sqlite_creating(url);
        if let Some(file) = sqlite_file(url).filter(|_| backend == Backend::Sqlite) {
            if let Some(dir) = file.parent().filter(|d| !d.as_os_str().is_empty()) {
                std::fs::create_dir_all(dir)
                    .with_context(|| format!("cannot create {}", dir.display()))?;
            }
        }
        let runtime = OwnRuntime(Some(
            tokio::runtime::Builder::new_multi_thread()
                .worker_threads(1)
                .thread_name("seaarms-db")
                .enable_all()
                .build()?,
        ));
        let handle = runtime
            .0
            .as_ref()
            .map(|rt| rt.handle().clone())
            .ok_or_else(|| anyhow!("no database runtime"))?;
        let connect = {
            let url = url.to_string();
            async move {
                let mut options = AnyPoolOptions::new()
                    .max_connections(if backend == Backend::Sqlite { 4 } else { 8 })
                    .acquire_timeout(Duration::from_secs(10));
                if backend == Backend::Sqlite {
                    options = options.after_connect(|conn, _| {
                        Box::pin(async move {
                            conn.execute("PRAGMA journal_mode = DELETE").await?;
                            conn.execute("PRAGMA synchronous = FULL").await?;
                            conn.execute("PRAGMA mmap_size = 0").await?;
                            Ok(())
                        })
                    });
                }
                let pool = options
                    .connect(&url)
                    .await
                    .with_context(|| format!("cannot open the database {}", redact(&url)))?;
                sqlx::migrate!()
                    .run(&pool)
                    .await
                    .with_context(|| format!("migrating the database {}", redact(&url)))?;
                anyhow::Ok(pool)
            }
        };
        let pool = blocking(&handle, connect)?;
        tracing::info!(url = %redact(url), "records database open");
        let file = sqlite_file(url)
            .filter(|_| backend == Backend::Sqlite)
            .and_then(|f| FileId::of(&f).map(|id| (f, id)));
        Ok(Db {
            inner: Arc::new(Inner {
                pool,
                handle,
                backend,
                file,
                _runtime: runtime,
            }),
        })
    }

    /// SQLite or PostgreSQL.
    pub fn backend(&self) -> Backend {
        self.inner.backend
    }

    /// Whether the database can be written now (the recorder asks every
    /// `sessions::record::HEALTH_INTERVAL`): SQLite's file is still there and still the file
    /// it opened (deleted or replaced, the writes would go to an unlinked file and be lost at
    /// the next start), and a test write commits (`PRAGMA user_version`, written back
    /// unchanged, goes through the journal); PostgreSQL answers a query.
    pub async fn probe(&self) -> Result<()> {
        if let Some((path, id)) = &self.inner.file {
            match FileId::of(path) {
                Some(now) if now == *id => {}
                Some(_) => return Err(anyhow!("{} was replaced", path.display())),
                None => return Err(anyhow!("{} is gone", path.display())),
            }
        }
        let sqlite = self.inner.backend == Backend::Sqlite;
        self.run(move |pool| async move {
            if sqlite {
                let mut tx = pool.begin().await?;
                let v: i64 = sqlx::query_scalar("PRAGMA user_version")
                    .fetch_one(&mut *tx)
                    .await?;
                sqlx::query(&format!("PRAGMA user_version = {}", v ^ 1))
                    .execute(&mut *tx)
                    .await?;
                sqlx::query(&format!("PRAGMA user_version = {v}"))
                    .execute(&mut *tx)
                    .await?;
                tx.commit().await?;
            } else {
                sqlx::query("SELECT 1").execute(&pool).await?;
            }
            Ok(())
        })
        .await
    }

    /// Runs `fut` to completion on the database's runtime from synchronous code (the
    /// recorder thread; start-up), blocking the calling thread.
    pub fn block_on<F>(&self, fut: F) -> F::Output
    where
        F: Future + Send,
        F::Output: Send,
    {
        blocking(&self.inner.handle, fut)
    }

    /// Runs a query future on the database's runtime and awaits it from any runtime.
    async fn run<T, Fut>(&self, f: impl FnOnce(AnyPool) -> Fut) -> Result<T>
    where
        T: Send + 'static,
        Fut: Future<Output = Result<T>> + Send + 'static,
    {
        let fut = f(self.inner.pool.clone());
        self.inner
            .handle
            .spawn(fut)
            .await
            .map_err(|e| anyhow!("database task failed: {e}"))?
    }

    /// Attempts matching `f`, newest first.
    pub async fn attempts(&self, f: &AttemptFilter) -> Result<Vec<AttemptRow>> {
        let f = f.clone();
        self.run(|pool| async move {
            let sql = format!(
                "SELECT {ATTEMPT_COLUMNS} WHERE ($1 IS NULL OR s.label = $1) \
                 AND ($2 IS NULL OR s.grp = $2) AND ($3 IS NULL OR a.exercise = $3) \
                 AND ($4 IS NULL OR a.session_id = $4) \
                 AND ($6 = 0 OR a.taken_over_from IS NULL) \
                 ORDER BY a.started_unix DESC, a.id DESC LIMIT $5"
            );
            let limit = if f.limit == 0 {
                i64::MAX
            } else {
                i64::try_from(f.limit).unwrap_or(i64::MAX)
            };
            let rows = sqlx::query(&sql)
                .bind(f.trainee)
                .bind(f.group)
                .bind(f.exercise)
                .bind(f.session)
                .bind(limit)
                .bind(i64::from(f.without_practice))
                .fetch_all(&pool)
                .await?;
            rows.iter().map(attempt_row).collect()
        })
        .await
    }

    /// The reference operators (issue 30 item 1): (name, group, marked at, Unix s), by name.
    pub async fn reference_operators(&self) -> Result<Vec<(String, String, f64)>> {
        self.run(|pool| async move {
            let rows = sqlx::query(
                "SELECT name, grp, marked_unix FROM reference_operators ORDER BY name, grp",
            )
            .fetch_all(&pool)
            .await?;
            rows.iter()
                .map(|r| {
                    Ok((
                        r.try_get("name")?,
                        r.try_get("grp")?,
                        r.try_get("marked_unix")?,
                    ))
                })
                .collect()
        })
        .await
    }

    /// Marks (or unmarks) the trainee `name` of `group` as a reference operator. Marking one
    /// already marked keeps the first time.
    pub async fn set_reference_operator(&self, name: &str, group: &str, on: bool) -> Result<()> {
        let (name, group) = (name.to_string(), group.to_string());
        self.run(move |pool| async move {
            if on {
                sqlx::query(
                    "INSERT INTO reference_operators (name, grp, marked_unix) VALUES ($1, $2, $3) \
                     ON CONFLICT (name, grp) DO NOTHING",
                )
                .bind(name)
                .bind(group)
                .bind(crate::clock::unix_now())
                .execute(&pool)
                .await?;
            } else {
                sqlx::query("DELETE FROM reference_operators WHERE name = $1 AND grp = $2")
                    .bind(name)
                    .bind(group)
                    .execute(&pool)
                    .await?;
            }
            Ok(())
        })
        .await
    }

    /// The reference operators' finished (passed or failed) attempts at `exercise`, oldest
    /// first: what its benchmark is computed from.
    pub async fn reference_attempts(&self, exercise: &str) -> Result<Vec<AttemptRow>> {
        let exercise = exercise.to_string();
        self.run(|pool| async move {
            let sql = format!(
                "SELECT {ATTEMPT_COLUMNS} WHERE a.exercise = $1 \
                 AND a.outcome IN ('passed', 'failed') AND a.taken_over_from IS NULL \
                 AND EXISTS (SELECT 1 FROM \
                 reference_operators r WHERE r.name = s.label AND r.grp = s.grp) \
                 ORDER BY a.started_unix, a.id"
            );
            let rows = sqlx::query(&sql).bind(exercise).fetch_all(&pool).await?;
            rows.iter().map(attempt_row).collect()
        })
        .await
    }

    /// One attempt.
    pub async fn attempt(&self, id: &str) -> Result<Option<AttemptRow>> {
        let id = id.to_string();
        self.run(|pool| async move {
            let sql = format!("SELECT {ATTEMPT_COLUMNS} WHERE a.id = $1");
            let row = sqlx::query(&sql).bind(id).fetch_optional(&pool).await?;
            row.as_ref().map(attempt_row).transpose()
        })
        .await
    }

    /// An attempt's compressed input stream: its pieces concatenated in order (empty when
    /// there are none).
    pub async fn attempt_inputs(&self, id: &str) -> Result<Vec<u8>> {
        let id = id.to_string();
        self.run(|pool| async move {
            let rows =
                sqlx::query("SELECT data FROM attempt_inputs WHERE attempt_id = $1 ORDER BY seq")
                    .bind(id)
                    .fetch_all(&pool)
                    .await?;
            let mut out = Vec::new();
            for r in &rows {
                let piece: Vec<u8> = r.try_get("data")?;
                out.extend_from_slice(&piece);
            }
            Ok(out)
        })
        .await
    }

    /// An attempt's events, by time.
    pub async fn attempt_events(&self, id: &str) -> Result<Vec<EventRow>> {
        let id = id.to_string();
        self.run(|pool| async move {
            let rows = sqlx::query(
                "SELECT t, kind, actor, detail FROM events WHERE attempt_id = $1 \
                 ORDER BY t, seq",
            )
            .bind(id)
            .fetch_all(&pool)
            .await?;
            rows.iter()
                .map(|r| {
                    Ok(EventRow {
                        t: r.try_get("t")?,
                        kind: r.try_get("kind")?,
                        actor: r.try_get("actor")?,
                        detail: json_or_null(Some(r.try_get("detail")?))
                            .unwrap_or(serde_json::Value::Null),
                    })
                })
                .collect()
        })
        .await
    }

    /// SHA-256 (hex) of a session's control token.
    pub async fn session_token_sha256(&self, session: &str) -> Result<Option<String>> {
        let session = session.to_string();
        self.run(|pool| async move {
            let row = sqlx::query("SELECT token_sha256 FROM sessions WHERE id = $1")
                .bind(session)
                .fetch_optional(&pool)
                .await?;
            Ok(row.map(|r| r.try_get("token_sha256")).transpose()?)
        })
        .await
    }

    /// Every stored session, oldest first.
    pub async fn sessions(&self) -> Result<Vec<SessionRecord>> {
        self.run(|pool| async move {
            let sql = format!("SELECT {SESSION_COLUMNS} ORDER BY created_unix, id");
            let rows = sqlx::query(&sql).fetch_all(&pool).await?;
            rows.iter().map(session_record).collect()
        })
        .await
    }

    /// A page of ended sessions (those with an end reason: ended, or marked interrupted or
    /// lost), newest first: at most `limit`,
    /// those older than session `before` (the last of the previous page) when given.
    pub async fn sessions_page(
        &self,
        before: Option<&str>,
        limit: usize,
    ) -> Result<Vec<SessionRecord>> {
        let before = before.map(str::to_string);
        let limit = i64::try_from(limit).unwrap_or(i64::MAX);
        self.run(|pool| async move {
            let sql = format!(
                "SELECT {SESSION_COLUMNS} WHERE end_reason IS NOT NULL AND ($1 IS NULL \
                 OR created_unix < (SELECT created_unix FROM sessions WHERE id = $1) \
                 OR (created_unix = (SELECT created_unix FROM sessions WHERE id = $1) AND id < $1)) \
                 ORDER BY created_unix DESC, id DESC LIMIT $2"
            );
            let rows = sqlx::query(&sql)
                .bind(before)
                .bind(limit)
                .fetch_all(&pool)
                .await?;
            rows.iter().map(session_record).collect()
        })
        .await
    }

    /// Attempt ids of the sessions `ids`, newest first: (session, attempt).
    pub async fn attempt_ids_of(&self, ids: &[String]) -> Result<Vec<(String, String)>> {
        if ids.is_empty() {
            return Ok(Vec::new());
        }
        let ids = ids.to_vec();
        self.run(|pool| async move {
            let marks: Vec<String> = (1..=ids.len()).map(|i| format!("${i}")).collect();
            let sql = format!(
                "SELECT session_id, id FROM attempts WHERE session_id IN ({}) \
                 ORDER BY started_unix DESC, id DESC",
                marks.join(", ")
            );
            let mut q = sqlx::query(&sql);
            for id in &ids {
                q = q.bind(id.clone());
            }
            let rows = q.fetch_all(&pool).await?;
            rows.iter()
                .map(|r| Ok((r.try_get("session_id")?, r.try_get("id")?)))
                .collect()
        })
        .await
    }

    /// One stored session.
    pub async fn session(&self, id: &str) -> Result<Option<SessionRecord>> {
        let id = id.to_string();
        self.run(|pool| async move {
            let sql = format!("SELECT {SESSION_COLUMNS} WHERE id = $1");
            let row = sqlx::query(&sql).bind(id).fetch_optional(&pool).await?;
            row.as_ref().map(session_record).transpose()
        })
        .await
    }

    /// Attempt ids of sessions (all sessions, or one), newest first: (session, attempt).
    pub async fn attempt_ids(&self, session: Option<&str>) -> Result<Vec<(String, String)>> {
        let session = session.map(str::to_string);
        self.run(|pool| async move {
            let rows = sqlx::query(
                "SELECT session_id, id FROM attempts WHERE ($1 IS NULL OR session_id = $1) \
                 ORDER BY started_unix DESC, id DESC",
            )
            .bind(session)
            .fetch_all(&pool)
            .await?;
            rows.iter()
                .map(|r| Ok((r.try_get("session_id")?, r.try_get("id")?)))
                .collect()
        })
        .await
    }

    /// The rows of [`Db::results`], one at a time through a channel of `capacity` rows: the
    /// query runs on the database's runtime and stops when the receiver is dropped (a client
    /// that went away), so a 60k-attempt export holds a few rows at once, not all (issue 29).
    /// The rows carry no `init` (null) and no input bytes (0).
    pub fn results_stream(
        &self,
        group: Option<&str>,
        exercise: Option<&str>,
        capacity: usize,
    ) -> tokio::sync::mpsc::Receiver<Result<AttemptRow>> {
        use futures_util::StreamExt;
        let (tx, rx) = tokio::sync::mpsc::channel(capacity.max(1));
        let (group, exercise) = (group.map(str::to_string), exercise.map(str::to_string));
        let pool = self.inner.pool.clone();
        self.inner.handle.spawn(async move {
            let sql = format!(
                "SELECT {RESULT_COLUMNS} WHERE a.exercise IS NOT NULL \
                 AND a.outcome IN ('passed', 'failed') AND a.taken_over_from IS NULL \
                 AND ($1 IS NULL OR s.grp = $1) AND ($2 IS NULL OR a.exercise = $2) \
                 ORDER BY COALESCE(s.label, ''), a.exercise, a.started_unix, a.id"
            );
            let mut rows = sqlx::query(&sql).bind(group).bind(exercise).fetch(&pool);
            while let Some(r) = rows.next().await {
                let row = r.map_err(anyhow::Error::from).and_then(|r| attempt_row(&r));
                let failed = row.is_err();
                if tx.send(row).await.is_err() || failed {
                    break;
                }
            }
        });
        rx
    }

    /// Finished exercise attempts (outcome `passed` or `failed`) of a group and/or an
    /// exercise, for the class export: by trainee, exercise, then start (all of
    /// [`Db::results_stream`] at once).
    pub async fn results(
        &self,
        group: Option<&str>,
        exercise: Option<&str>,
    ) -> Result<Vec<AttemptRow>> {
        let mut rx = self.results_stream(group, exercise, 256);
        let mut out = Vec::new();
        while let Some(row) = rx.recv().await {
            out.push(row?);
        }
        Ok(out)
    }
}

/// Runs `fut` on `handle`'s runtime and waits: directly on a plain thread, on a scoped helper
/// thread when the caller is itself inside a runtime (blocking there directly would panic).
fn blocking<F>(handle: &tokio::runtime::Handle, fut: F) -> F::Output
where
    F: Future + Send,
    F::Output: Send,
{
    if tokio::runtime::Handle::try_current().is_err() {
        return handle.block_on(fut);
    }
    std::thread::scope(|s| {
        match s.spawn(|| handle.block_on(fut)).join() {
            Ok(out) => out,
            // The future panicked: carry the panic on.
            Err(panic) => std::panic::resume_unwind(panic),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn urls_are_recognised_and_passwords_hidden() {
        assert_eq!(Backend::of("sqlite://x.db").unwrap(), Backend::Sqlite);
        assert_eq!(Backend::of("postgres://u@h/d").unwrap(), Backend::Postgres);
        assert!(Backend::of("mysql://h/d").is_err());
        assert_eq!(
            redact("postgres://me:secret@db:5432/x"),
            "postgres://me:***@db:5432/x"
        );
        assert_eq!(redact("postgres://me@db/x"), "postgres://me@db/x");
        let url = default_url(std::path::Path::new("/tmp/a?b%c#d"));
        assert_eq!(url, "sqlite:///tmp/a%3Fb%25c%23d/seaarms.db?mode=rwc");
        assert_eq!(
            sqlite_file(&url),
            Some(PathBuf::from("/tmp/a?b%c#d/seaarms.db"))
        );
        assert_eq!(sqlite_file("sqlite::memory:"), None);
        assert_eq!(
            sqlite_creating("sqlite:///a/b.db"),
            "sqlite:///a/b.db?mode=rwc"
        );
        assert_eq!(
            sqlite_creating("sqlite:///a/b.db?cache=shared"),
            "sqlite:///a/b.db?cache=shared&mode=rwc"
        );
        assert_eq!(
            sqlite_creating("sqlite:///a/b.db?mode=ro"),
            "sqlite:///a/b.db?mode=ro"
        );
        assert_eq!(sqlite_creating("postgres://h/d"), "postgres://h/d");
    }
}
