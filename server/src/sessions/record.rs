//! Session records, written by one recorder thread so no physics worker ever waits on a
//! file or the database:
//!
//! * The database ([`crate::db`]): trainees, sessions (with progress figures: simulated
//!   seconds and overloads of the rows on disk so far, so a killed server leaves true
//!   figures), attempts with their compressed input streams, and typed events. Everything
//!   received in a flush interval (about a second) is written in ONE transaction, so a
//!   process killed at any moment leaves every earlier batch and nothing of a later one.
//!   A batch that fails (disk full, database unreachable) is kept and retried with the next
//!   one, up to [`MAX_PENDING_WRITES`]; beyond that it is dropped and counted.
//! * `DATA/sessions/<id>.csv` — the time series at 100 Hz ([`SessionRow`], written by
//!   [`crate::csv_out`]) for analysis. Rows are formatted in memory and appended whole about
//!   every second (before the batch that records their figures); a write that fails (disk
//!   full, I/O error) is cut back to the last whole row, the session's recording is marked
//!   `failed`, and its later rows are dropped and counted. A process killed inside a write
//!   can leave part of a row; readers take [`crate::csv_out::complete_lines`], and start-up
//!   cuts the CSVs of interrupted sessions back to their last whole line.
//! * At start-up nothing is live: stored sessions without an end are marked
//!   [`crate::db::INTERRUPTED`] and attempts without an outcome `interrupted`.
//! * New sessions are refused while the data disk has less free space than the configured
//!   floor or the records folder cannot be written ([`Recorder::admit`]).
//! * Retention ([`Retention`]): at start-up and periodically, records older than the
//!   retention age, then the oldest ended records beyond the size cap, are deleted (CSV and
//!   database rows) — never a live session's.

mod retention;
mod row;

pub use crate::db::attempt::{AttemptEnd, AttemptStart, EventRecord};
pub use retention::Retention;
pub use row::{ArmRow, SessionRow};

use std::collections::{HashMap, HashSet};
use std::fs::{File, OpenOptions};
use std::io::{self, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender, TrySendError, sync_channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::csv_out::CsvOut;
use crate::db::{Db, SessionRecord, Write as DbWrite};
use crate::metrics::Metrics;

/// Longest time a record stays in memory before it is written.
pub const FLUSH_INTERVAL: Duration = Duration::from_secs(1);
/// Messages queued for the recorder before new ones are dropped (counted in /metrics).
pub const QUEUE_CAPACITY: usize = 65_536;
/// Start-up repair reads this much of the end of an interrupted record.
const REPAIR_TAIL_BYTES: u64 = 64 << 10;
/// Database writes kept for retry while the database fails; beyond, they are dropped and
/// counted (about a minute of a busy class).
pub const MAX_PENDING_WRITES: usize = 200_000;

/// Recorder settings (from [`crate::config::ServeConfig`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecordConfig {
    /// New sessions are refused while the data disk has less free space (bytes).
    pub min_free_disk_bytes: u64,
    /// What to delete.
    pub retention: Retention,
    /// How often retention runs (it also runs at start-up).
    pub retention_interval: Duration,
    /// Queue finished exercise attempts' xAPI statements in the outbox (`--xapi-endpoint`
    /// set; [`crate::xapi`]).
    pub xapi: bool,
}

/// What the recorder is asked to do.
#[derive(Debug)]
pub enum RecordMsg {
    /// A session started.
    Created {
        /// Id.
        id: String,
        /// Trainee label (display name).
        label: String,
        /// The trainee's class or group (may be empty).
        group: String,
        /// Scenario.
        scenario: String,
        /// Unix seconds.
        created_unix: f64,
        /// SHA-256 (hex) of the session's control token: the trainee who holds it may open
        /// the session's records after it ends.
        token_sha256: String,
    },
    /// One time-series row.
    Row {
        /// Session id.
        id: String,
        /// The row.
        row: Box<SessionRow>,
        /// Relief events of the session since creation, all resets included.
        overloads: u64,
    },
    /// One typed event.
    Event(Box<EventRecord>),
    /// An attempt started.
    AttemptStarted(Box<AttemptStart>),
    /// The next piece of an attempt's compressed input stream ([`crate::sessions::command::log`]):
    /// appended in order; the pieces so far always decode.
    AttemptInputs {
        /// Attempt id.
        id: String,
        /// Bytes to append (none: only the attempt's progress).
        bytes: Vec<u8>,
        /// Simulated seconds the attempt has run (stored with the piece, so an attempt cut
        /// off by a killed server keeps its length).
        sim_seconds: f64,
    },
    /// An attempt ended.
    AttemptEnded(Box<AttemptEnd>),
    /// A session ended.
    Ended {
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
    },
    /// Flush everything, then answer.
    Flush(SyncSender<()>),
    /// Flush everything, answer and stop.
    Shutdown(SyncSender<()>),
}

/// Cloneable, never-blocking handle for sending records.
#[derive(Clone)]
pub struct RecordSender {
    tx: SyncSender<RecordMsg>,
    metrics: Arc<Metrics>,
}

impl RecordSender {
    /// Queues a record; when the queue is full the record is dropped and counted.
    pub fn send(&self, msg: RecordMsg) {
        if let Err(TrySendError::Full(_)) = self.tx.try_send(msg) {
            self.metrics.records_dropped.fetch_add(1, Ordering::Relaxed);
        }
    }
}

/// Ids whose recording failed in this run, with the first error (shared with handlers).
type FailedSet = Arc<Mutex<HashMap<String, String>>>;

/// Session ends the database has not stored yet (a full disk, a database down): what the
/// session list shows for them until the end is written, rather than an unfinished row
/// (issue 29: sessions ended during a full disk were listed as interrupted, with the
/// duration of their last stored progress).
type UnstoredEnds = Arc<Mutex<HashMap<String, UnstoredEnd>>>;

/// A session's end as the recorder was given it.
#[derive(Debug, Clone, PartialEq)]
pub struct UnstoredEnd {
    /// Unix seconds.
    pub ended_unix: f64,
    /// Simulated seconds at the end.
    pub sim_seconds: f64,
    /// Why it ended.
    pub reason: String,
}

/// Why the records database cannot be written now, or `None` while it can (shared with the
/// handlers: new sessions are refused while it is down).
type DbDown = Arc<Mutex<Option<String>>>;

/// How often the recorder checks that the records database can be written
/// ([`crate::db::Db::probe`]): a failure shows on every live session within this plus a
/// flush (issue 29: "within 5 s").
pub const HEALTH_INTERVAL: Duration = Duration::from_secs(2);

/// The recorder: its thread and the data directory.
pub struct Recorder {
    sender: RecordSender,
    db: Db,
    dir: PathBuf,
    config: RecordConfig,
    failed: FailedSet,
    db_down: DbDown,
    unstored_ends: UnstoredEnds,
    metrics: Arc<Metrics>,
    thread: Mutex<Option<JoinHandle<()>>>,
}

/// True for ids this server generates (16 lowercase hex digits), so paths stay inside the
/// data directory.
pub fn valid_id(id: &str) -> bool {
    id.len() == 16
        && id
            .bytes()
            .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b))
}

/// Free bytes for unprivileged users on the file system holding `dir` (None where unknown).
pub fn free_disk_bytes(dir: &Path) -> Option<u64> {
    #[cfg(unix)]
    {
        let s = rustix::fs::statvfs(dir).ok()?;
        Some(s.f_bavail.saturating_mul(s.f_frsize))
    }
    #[cfg(not(unix))]
    {
        let _ = dir;
        None
    }
}

impl Recorder {
    /// Creates the records folder and starts the recorder thread, which first repairs the
    /// records a crash cut off, marks them interrupted and applies retention; returns once
    /// that is done (blocking: call at start-up).
    pub fn open(
        dir: &Path,
        db: Db,
        metrics: Arc<Metrics>,
        config: RecordConfig,
    ) -> anyhow::Result<Recorder> {
        std::fs::create_dir_all(dir.join("sessions"))?;
        let failed: FailedSet = Arc::default();
        let db_down: DbDown = Arc::default();
        let unstored_ends: UnstoredEnds = Arc::default();
        let mut state = RecorderState::new(
            dir,
            db.clone(),
            metrics.clone(),
            config,
            failed.clone(),
            db_down.clone(),
        );
        state.unstored_ends = unstored_ends.clone();
        let (tx, rx) = sync_channel(QUEUE_CAPACITY);
        let (ready_tx, ready_rx) = sync_channel(1);
        let thread = std::thread::Builder::new()
            .name("recorder".into())
            .spawn(move || {
                let started = state.start();
                let ok = started.is_ok();
                let _ = ready_tx.send(started);
                if ok {
                    state.run(rx);
                }
            })?;
        match ready_rx.recv() {
            Ok(Ok(())) => {}
            Ok(Err(e)) => return Err(e.context("opening the session records")),
            Err(_) => anyhow::bail!("the recorder thread died at start-up"),
        }
        Ok(Recorder {
            sender: RecordSender {
                tx,
                metrics: metrics.clone(),
            },
            db,
            dir: dir.to_path_buf(),
            config,
            failed,
            db_down,
            unstored_ends,
            metrics,
            thread: Mutex::new(Some(thread)),
        })
    }

    /// The records database.
    pub fn db(&self) -> &Db {
        &self.db
    }

    /// A sending handle.
    pub fn sender(&self) -> RecordSender {
        self.sender.clone()
    }

    /// Queues a record.
    pub fn send(&self, msg: RecordMsg) {
        self.sender.send(msg);
    }

    /// Whether a new session can be recorded now: the data disk has at least the configured
    /// free space and a file can be created in the records folder. Blocking (file system).
    pub fn admit(&self) -> Result<(), String> {
        let down = self
            .db_down
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .is_some();
        if down {
            // Asked again now, not at the recorder's next check: back, it admits at once.
            match self.db.block_on(self.db.probe()) {
                Ok(()) => *self.db_down.lock().unwrap_or_else(|e| e.into_inner()) = None,
                Err(why) => {
                    return Err(format!(
                        "the records database cannot be written ({why:#}); no new session is \
                         started until it can"
                    ));
                }
            }
        }
        let sessions = self.dir.join("sessions");
        if let Some(free) = free_disk_bytes(&self.dir) {
            self.metrics
                .data_disk_free_bytes
                .store(free, Ordering::Relaxed);
            if free < self.config.min_free_disk_bytes {
                return Err(format!(
                    "the data disk is nearly full ({} MB free, the floor is {} MB, \
                     --min-free-disk-mb); session records could not be written, so no new \
                     session is started until space is freed",
                    free >> 20,
                    self.config.min_free_disk_bytes >> 20
                ));
            }
        }
        let probe = sessions.join(format!(".probe-{}", crate::ids::random_hex(4)));
        match File::create(&probe) {
            Ok(_) => {
                let _ = std::fs::remove_file(&probe);
                Ok(())
            }
            Err(e) => Err(format!(
                "session records cannot be written in {} ({e}); no new session is started",
                sessions.display()
            )),
        }
    }

    /// Session `id`'s end if the database has not stored it yet (it is kept for retry, or
    /// was lost with the rest of a failed batch), else None.
    pub fn unstored_end(&self, id: &str) -> Option<UnstoredEnd> {
        self.unstored_ends
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .get(id)
            .cloned()
    }

    /// The sessions whose ends the database has not stored yet ([`Recorder::unstored_end`]).
    pub fn unstored_end_ids(&self) -> Vec<String> {
        self.unstored_ends
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .keys()
            .cloned()
            .collect()
    }

    /// `"failed"` when part of session `id`'s record could not be written in this run,
    /// else `"ok"`.
    pub fn recording(&self, id: &str) -> &'static str {
        if self
            .failed
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .contains_key(id)
        {
            "failed"
        } else {
            "ok"
        }
    }

    /// Flushes every buffer to disk and waits (blocking: call off the reactor).
    pub fn flush(&self) {
        let (tx, rx) = sync_channel(1);
        if self.sender.tx.send(RecordMsg::Flush(tx)).is_ok() {
            let _ = rx.recv_timeout(Duration::from_secs(5));
        }
    }

    /// Flushes and stops the thread.
    pub fn shutdown(&self) {
        let (tx, rx) = sync_channel(1);
        if self.sender.tx.send(RecordMsg::Shutdown(tx)).is_ok() {
            let _ = rx.recv_timeout(Duration::from_secs(10));
        }
        if let Some(t) = self.thread.lock().unwrap_or_else(|e| e.into_inner()).take() {
            let _ = t.join();
        }
    }

    /// Path of a session's CSV (None for an id this server cannot have made).
    pub fn log_path(&self, id: &str) -> Option<PathBuf> {
        valid_id(id).then(|| csv_path(&self.dir, id))
    }
}

fn csv_path(dir: &Path, id: &str) -> PathBuf {
    dir.join("sessions").join(format!("{id}.csv"))
}

/// Cuts a file after its last newline (a line cut by a crash). Missing files are fine. Only
/// the tail is read (a row is far shorter than [`REPAIR_TAIL_BYTES`]).
fn cut_to_last_line(path: &Path) -> io::Result<()> {
    let mut file = match OpenOptions::new().read(true).write(true).open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(e),
    };
    let len = file.metadata()?.len();
    let start = len.saturating_sub(REPAIR_TAIL_BYTES);
    file.seek(SeekFrom::Start(start))?;
    let mut tail = Vec::new();
    file.read_to_end(&mut tail)?;
    let keep = crate::csv_out::complete_lines(&tail).len() as u64;
    if keep == 0 && start > 0 {
        tracing::warn!(
            "{}: no line end in its last {REPAIR_TAIL_BYTES} bytes; left alone",
            path.display()
        );
    } else if start + keep < len {
        file.set_len(start + keep)?;
        tracing::info!("cut {} back to its last whole line", path.display());
    }
    Ok(())
}

/// A file written in whole pieces: `len` is its length after the last piece that was
/// written completely.
#[derive(Debug)]
struct WholeFile<F> {
    file: F,
    len: u64,
}

/// What a record file needs besides writing: cutting back.
trait Truncate {
    fn truncate_to(&mut self, len: u64) -> io::Result<()>;
}

impl Truncate for File {
    fn truncate_to(&mut self, len: u64) -> io::Result<()> {
        self.set_len(len)
    }
}

impl<F: Write + Truncate> WholeFile<F> {
    /// Appends `bytes` (whole rows) in one piece; on failure cuts the file back to the last
    /// whole piece so no reader ever sees part of a row, and returns the error.
    fn append(&mut self, bytes: &[u8]) -> io::Result<()> {
        if bytes.is_empty() {
            return Ok(());
        }
        match self.file.write_all(bytes) {
            Ok(()) => {
                self.len += bytes.len() as u64;
                Ok(())
            }
            Err(e) => {
                if let Err(t) = self.file.truncate_to(self.len) {
                    tracing::error!("cannot cut a record back to its last whole row: {t}");
                }
                Err(e)
            }
        }
    }
}

fn open_whole(path: &Path) -> io::Result<WholeFile<File>> {
    let file = OpenOptions::new().create(true).append(true).open(path)?;
    let len = file.metadata()?.len();
    Ok(WholeFile { file, len })
}

/// The recorder thread's files and counters of one live session (its CSV, rows not yet
/// written, figures, next event number); not the session's live state, [`super::Live`].
struct SessionRecording {
    csv: Option<WholeFile<File>>,
    /// Rows formatted since the last write (whole rows only).
    rows: CsvOut<Vec<u8>>,
    pending_rows: u64,
    /// Figures of the last pending row, of the last row on disk, and as last stored.
    pending_figures: Option<(f64, u64)>,
    written_figures: Option<(f64, u64)>,
    stored_figures: Option<(f64, u64)>,
    failed: bool,
    failure_stored: bool,
    /// Sequence number of the session's next event.
    next_event: i64,
}

impl SessionRecording {
    fn open(dir: &Path, id: &str) -> (SessionRecording, Option<io::Error>) {
        let mut err = None;
        let csv = match open_whole(&csv_path(dir, id)) {
            Ok(mut f) => {
                if f.len == 0 {
                    let mut head = CsvOut::new(Vec::new());
                    let header = head
                        .header(&SessionRow::header())
                        .and_then(|()| head.into_inner())
                        .and_then(|bytes| f.append(&bytes));
                    if let Err(e) = header {
                        err = Some(e);
                    }
                }
                Some(f)
            }
            Err(e) => {
                err = Some(e);
                None
            }
        };
        let failed = err.is_some();
        (
            SessionRecording {
                csv: csv.filter(|_| !failed),
                rows: CsvOut::new(Vec::new()),
                pending_rows: 0,
                pending_figures: None,
                written_figures: None,
                stored_figures: None,
                failed,
                failure_stored: false,
                next_event: 0,
            },
            err,
        )
    }
}

/// The recorder thread's state.
struct RecorderState {
    dir: PathBuf,
    db: Db,
    metrics: Arc<Metrics>,
    config: RecordConfig,
    failed: FailedSet,
    db_down: DbDown,
    unstored_ends: UnstoredEnds,
    last_probe: Instant,
    live: HashMap<String, SessionRecording>,
    /// Database writes since the last commit, in arrival order.
    writes: Vec<DbWrite>,
    /// Sequence number of each running attempt's next input piece.
    next_piece: HashMap<String, i64>,
    last_maintenance: Instant,
}

impl RecorderState {
    fn new(
        dir: &Path,
        db: Db,
        metrics: Arc<Metrics>,
        config: RecordConfig,
        failed: FailedSet,
        db_down: DbDown,
    ) -> RecorderState {
        RecorderState {
            dir: dir.to_path_buf(),
            db,
            metrics,
            config,
            failed,
            db_down,
            unstored_ends: Arc::default(),
            last_probe: Instant::now(),
            live: HashMap::new(),
            writes: Vec::new(),
            next_piece: HashMap::new(),
            last_maintenance: Instant::now(),
        }
    }

    /// Start-up, before anything is live: repairs the CSVs of sessions a crash cut off,
    /// marks them and their attempts interrupted, and applies retention.
    fn start(&mut self) -> anyhow::Result<()> {
        let unfinished = self.db.block_on(self.db.unfinished_sessions())?;
        for id in &unfinished {
            if !valid_id(id) {
                continue;
            }
            let path = csv_path(&self.dir, id);
            if let Err(e) = cut_to_last_line(&path) {
                tracing::warn!(%id, "cannot repair {}: {e}", path.display());
            }
        }
        let (sessions, attempts) = self.db.block_on(self.db.mark_interrupted())?;
        if sessions + attempts > 0 {
            tracing::info!(
                sessions,
                attempts,
                "records cut off by a stop marked interrupted"
            );
        }
        self.maintain();
        Ok(())
    }

    fn mark_failed(&self, id: &str, what: &str, e: &dyn std::fmt::Display) {
        self.metrics
            .record_write_errors
            .fetch_add(1, Ordering::Relaxed);
        tracing::error!(%id, "session record {what} failed: {e}");
        self.failed
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .entry(id.to_string())
            .or_insert_with(|| format!("{what}: {e}"));
    }

    /// The records database cannot be written (`why`): it is marked down (new sessions are
    /// refused), counted, and every live session's record is marked failed — what it sent
    /// since may never reach the database (a deleted file takes it all).
    fn database_down(&mut self, why: &anyhow::Error) {
        self.metrics
            .records_database_failures
            .fetch_add(1, Ordering::Relaxed);
        let was_up = self
            .db_down
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .replace(format!("{why:#}"))
            .is_none();
        if was_up {
            tracing::error!("the records database cannot be written: {why:#}");
        }
        let ids: Vec<String> = self
            .live
            .iter()
            .filter(|(_, l)| !l.failed)
            .map(|(id, _)| id.clone())
            .collect();
        for id in ids {
            if let Some(l) = self.live.get_mut(&id) {
                l.failed = true;
            }
            self.mark_failed(&id, "records database", why);
        }
    }

    /// Checks the records database ([`Db::probe`]); marks it down or back up.
    fn check_database(&mut self) {
        self.last_probe = Instant::now();
        match self.db.block_on(self.db.probe()) {
            Ok(()) => {
                let was_down = self
                    .db_down
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .take()
                    .is_some();
                if was_down {
                    tracing::info!("the records database can be written again");
                }
            }
            Err(e) => self.database_down(&e),
        }
    }

    fn dropped(&self, n: u64) {
        self.metrics.records_dropped.fetch_add(n, Ordering::Relaxed);
    }

    /// Writes a session's pending rows to its CSV; on failure marks it failed.
    fn write_pending(&mut self, id: &str) {
        let Some(live) = self.live.get_mut(id) else {
            return;
        };
        let rows = std::mem::replace(&mut live.rows, CsvOut::new(Vec::new()))
            .into_inner()
            .unwrap_or_default();
        let n_rows = std::mem::take(&mut live.pending_rows);
        if live.failed {
            return;
        }
        let Some(f) = live.csv.as_mut() else {
            return;
        };
        match f.append(&rows) {
            Ok(()) => live.written_figures = live.pending_figures.or(live.written_figures),
            Err(e) => {
                live.failed = true;
                self.mark_failed(id, "CSV write", &e);
                self.dropped(n_rows);
            }
        }
    }

    /// Commits the pending database writes in one transaction. On failure they are kept for
    /// the next commit (the transaction left nothing), up to [`MAX_PENDING_WRITES`].
    fn commit(&mut self) {
        if self.writes.is_empty() {
            return;
        }
        let result = self.db.block_on(self.db.write_batch(&self.writes));
        match result {
            Ok(()) => {
                // every end queued so far is stored now
                self.unstored_ends
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .clear();
                self.writes.clear();
            }
            Err(e) => {
                self.metrics
                    .record_write_errors
                    .fetch_add(1, Ordering::Relaxed);
                tracing::error!(
                    pending = self.writes.len(),
                    "records database write failed (kept for retry): {e:#}"
                );
                self.database_down(&e);
                if self.writes.len() > MAX_PENDING_WRITES {
                    let lost = std::mem::take(&mut self.writes);
                    self.dropped(lost.len() as u64);
                    let ids: HashSet<&str> = lost.iter().filter_map(write_session).collect();
                    for id in ids {
                        self.mark_failed(id, "database write", &e);
                    }
                }
            }
        }
    }

    /// Writes every pending CSV row, then commits the batch with one progress write per
    /// session whose figures changed.
    fn flush_all(&mut self) {
        let ids: Vec<String> = self.live.keys().cloned().collect();
        for id in &ids {
            self.write_pending(id);
        }
        let failed_now = self
            .failed
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clone();
        for (id, live) in &mut self.live {
            live.failed |= failed_now.contains_key(id);
            let changed = live.written_figures != live.stored_figures
                || (live.failed && !live.failure_stored);
            if changed {
                // Only a failure before any row leaves no figures: 0 s recorded.
                let (t, overloads) = live.written_figures.unwrap_or((0.0, 0));
                self.writes.push(DbWrite::Progress {
                    id: id.clone(),
                    sim_seconds: t,
                    overloads,
                    recording_failed: live.failed,
                });
                live.stored_figures = live.written_figures;
                live.failure_stored = live.failed;
            }
        }
        self.commit();
    }

    fn handle(&mut self, msg: RecordMsg) {
        match msg {
            RecordMsg::Created {
                id,
                label,
                group,
                scenario,
                created_unix,
                token_sha256,
            } => {
                let (live, err) = SessionRecording::open(&self.dir, &id);
                if let Some(e) = &err {
                    self.mark_failed(&id, "opening the record", e);
                }
                self.live.insert(id.clone(), live);
                self.writes.push(DbWrite::Session {
                    id,
                    trainee: label,
                    group,
                    scenario,
                    created_unix,
                    token_sha256,
                });
            }
            RecordMsg::Row { id, row, overloads } => {
                let Some(live) = self.live.get_mut(&id) else {
                    return;
                };
                if live.failed {
                    self.dropped(1);
                    return;
                }
                if let Err(e) = row.write(&mut live.rows) {
                    // Formatting into memory does not fail; count it if it ever does.
                    self.dropped(1);
                    tracing::error!(%id, "formatting a record row failed: {e}");
                    return;
                }
                live.pending_rows += 1;
                live.pending_figures = Some((row.t_s, overloads));
            }
            RecordMsg::Event(event) => {
                let EventRecord {
                    session,
                    attempt,
                    t,
                    kind,
                    actor,
                    detail,
                } = *event;
                let Some(live) = self.live.get_mut(&session) else {
                    return;
                };
                let seq = live.next_event;
                live.next_event += 1;
                self.writes.push(DbWrite::Event {
                    session,
                    seq,
                    attempt,
                    t,
                    unix: crate::clock::unix_now(),
                    kind,
                    actor,
                    detail: detail.to_string(),
                });
            }
            RecordMsg::AttemptStarted(start) => {
                self.next_piece.insert(start.id.clone(), 0);
                self.writes.push(DbWrite::AttemptStart(start));
            }
            RecordMsg::AttemptInputs {
                id,
                bytes,
                sim_seconds,
            } => {
                let next = self.next_piece.entry(id.clone()).or_insert(0);
                let seq = *next;
                *next += i64::from(!bytes.is_empty());
                self.writes.push(DbWrite::AttemptInputs {
                    id,
                    seq,
                    data: bytes,
                    sim_seconds,
                });
            }
            RecordMsg::AttemptEnded(end) => {
                self.next_piece.remove(&end.id);
                let attempt = end.id.clone();
                self.writes.push(DbWrite::AttemptEnd(end));
                if self.config.xapi {
                    // In the same transaction as the attempt's row: only stored results are
                    // sent, and none is lost while the LRS is down.
                    self.writes.push(DbWrite::XapiQueue {
                        attempt,
                        queued_unix: crate::clock::unix_now(),
                    });
                }
            }
            RecordMsg::Ended {
                id,
                ended_unix,
                sim_seconds,
                reason,
                overloads,
            } => {
                self.write_pending(&id);
                let failed = self.live.remove(&id).is_some_and(|l| l.failed)
                    || self
                        .failed
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .contains_key(&id);
                self.unstored_ends
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .insert(
                        id.clone(),
                        UnstoredEnd {
                            ended_unix,
                            sim_seconds,
                            reason: reason.clone(),
                        },
                    );
                self.writes.push(DbWrite::SessionEnd {
                    id,
                    ended_unix,
                    sim_seconds,
                    reason,
                    overloads,
                    recording_failed: failed,
                });
                // Ends are rare: stored at once, so the list shows the session ended.
                self.commit();
            }
            RecordMsg::Flush(done) => {
                self.flush_all();
                let _ = done.send(());
            }
            RecordMsg::Shutdown(_) => {}
        }
    }

    fn run(mut self, rx: Receiver<RecordMsg>) {
        let mut last_flush = Instant::now();
        loop {
            let wait = FLUSH_INTERVAL.saturating_sub(last_flush.elapsed());
            match rx.recv_timeout(wait) {
                Ok(RecordMsg::Shutdown(done)) => {
                    self.flush_all();
                    let _ = done.send(());
                    return;
                }
                Ok(msg) => self.handle(msg),
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => {
                    self.flush_all();
                    return;
                }
            }
            if last_flush.elapsed() >= FLUSH_INTERVAL {
                self.flush_all();
                last_flush = Instant::now();
            }
            if self.last_probe.elapsed() >= HEALTH_INTERVAL {
                self.check_database();
            }
            if self.last_maintenance.elapsed() >= self.config.retention_interval {
                self.maintain();
            }
        }
    }

    /// Retention: deletes the CSVs and database rows of the records it selects.
    fn maintain(&mut self) {
        self.last_maintenance = Instant::now();
        if let Some(free) = free_disk_bytes(&self.dir) {
            self.metrics
                .data_disk_free_bytes
                .store(free, Ordering::Relaxed);
        }
        // The database first holds everything received so far.
        self.flush_all();
        let stored = match self.db.block_on(self.db.sessions_with_bytes()) {
            Ok(s) => s,
            Err(e) => {
                tracing::error!("retention cannot read the records database: {e:#}");
                return;
            }
        };
        let sized: Vec<(SessionRecord, u64)> = stored
            .into_iter()
            .map(|(r, db_bytes)| {
                let csv = if valid_id(&r.id) {
                    std::fs::metadata(csv_path(&self.dir, &r.id)).map_or(0, |m| m.len())
                } else {
                    0
                };
                (r, csv + db_bytes)
            })
            .collect();
        let live: HashSet<String> = self.live.keys().cloned().collect();
        let prune = retention::select(
            &sized,
            &live,
            self.config.retention,
            crate::clock::unix_now(),
        );
        let mut deleted = Vec::new();
        for id in prune {
            if valid_id(&id) {
                let p = csv_path(&self.dir, &id);
                if let Err(e) = std::fs::remove_file(&p) {
                    if e.kind() != io::ErrorKind::NotFound {
                        tracing::error!(%id, "retention cannot delete {}: {e}", p.display());
                        continue;
                    }
                }
            }
            deleted.push(id);
        }
        if deleted.is_empty() {
            return;
        }
        match self.db.block_on(self.db.delete_sessions(&deleted)) {
            Ok(()) => {
                for id in &deleted {
                    tracing::info!(%id, "session record deleted by retention");
                }
                self.metrics
                    .records_pruned
                    .fetch_add(deleted.len() as u64, Ordering::Relaxed);
            }
            Err(e) => tracing::error!("retention cannot delete database rows: {e:#}"),
        }
    }
}

/// The session a database write belongs to (None for attempt writes, which name only their
/// attempt).
fn write_session(w: &DbWrite) -> Option<&str> {
    match w {
        DbWrite::Session { id, .. }
        | DbWrite::Progress { id, .. }
        | DbWrite::SessionEnd { id, .. } => Some(id),
        DbWrite::Event { session, .. } => Some(session),
        DbWrite::AttemptStart(a) => Some(&a.session),
        DbWrite::AttemptInputs { .. } | DbWrite::AttemptEnd(_) | DbWrite::XapiQueue { .. } => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file on a disk with `room` bytes left: a write beyond it stores what fits, then
    /// fails with "no space" (what `write(2)` does on a full disk).
    struct FullDisk {
        data: Vec<u8>,
        room: usize,
    }

    impl Write for FullDisk {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            let n = buf.len().min(self.room.saturating_sub(self.data.len()));
            if n == 0 {
                return Err(io::Error::from(io::ErrorKind::StorageFull));
            }
            self.data.extend_from_slice(&buf[..n]);
            Ok(n)
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }

    impl Truncate for FullDisk {
        fn truncate_to(&mut self, len: u64) -> io::Result<()> {
            self.data.truncate(len as usize);
            Ok(())
        }
    }

    /// A write that runs out of room part-way through a row is cut back to the last whole
    /// row: the file never holds part of a row.
    #[test]
    fn a_full_disk_leaves_only_whole_rows() {
        let mut f = WholeFile {
            file: FullDisk {
                data: Vec::new(),
                room: 25,
            },
            len: 0,
        };
        f.append(b"t,x\n0,1\n").expect("fits");
        let err = f
            .append(b"0.01,2\n0.02,3\n0.03,4\n")
            .expect_err("disk full");
        assert_eq!(err.kind(), io::ErrorKind::StorageFull);
        assert_eq!(f.file.data, b"t,x\n0,1\n");
        assert_eq!(f.len, 8);
    }

    /// Start-up repair cuts a row left half-written by a killed process, reading only the
    /// tail of a long file, and leaves a whole file alone.
    #[test]
    fn repair_cuts_a_half_row() {
        let dir =
            std::env::temp_dir().join(format!("seaarms-repair-{}", crate::ids::random_hex(6)));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("x.csv");
        let mut whole = b"t,x\n".to_vec();
        for i in 0..20_000 {
            whole.extend_from_slice(format!("{i},{}\n", i * 7).as_bytes());
        }
        assert!(whole.len() as u64 > REPAIR_TAIL_BYTES);
        let mut cut = whole.clone();
        cut.extend_from_slice(b"20000,14");
        std::fs::write(&path, &cut).expect("write");
        cut_to_last_line(&path).expect("repair");
        assert_eq!(std::fs::read(&path).expect("read"), whole);
        cut_to_last_line(&path).expect("repair again");
        assert_eq!(std::fs::read(&path).expect("read"), whole);
        cut_to_last_line(&dir.join("missing.csv")).expect("a missing file is fine");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
