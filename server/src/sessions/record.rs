//! Session records on disk, written by one recorder thread so no physics worker ever waits
//! on a file:
//!
//! * `DATA/sessions.jsonl` — the session index: a line when a session is created, a
//!   `progress` line about every second for each session whose record grew (simulated
//!   seconds and overloads of the rows written so far, so a killed server leaves true
//!   figures), and a line when it ends. The last line of a session wins when reading. An
//!   append-only index was chosen over an embedded database: it needs no C dependency, a
//!   crash can at most cut the last line (which the reader skips), and replaying it on
//!   start-up lists every finished session. It is compacted (one `record` line per
//!   session, written to a temporary file and renamed) at start-up and by each retention
//!   pass.
//! * `DATA/sessions/<id>.csv` — the time series at 100 Hz ([`SessionRow`], written by
//!   [`crate::csv_out`]); `DATA/sessions/<id>.events.jsonl` — every event and instructor
//!   action. Rows are formatted in memory and appended whole about every second; a write
//!   that fails (disk full, I/O error) is cut back to the last whole row, the session's
//!   recording is marked `failed`, and its later rows are dropped and counted. A process
//!   killed inside a write can leave part of a row; readers take
//!   [`crate::csv_out::complete_lines`], and start-up cuts the records of interrupted
//!   sessions back to their last whole line.
//! * New sessions are refused while the data disk has less free space than the configured
//!   floor or the records folder cannot be written ([`Recorder::admit`]).
//! * Retention ([`Retention`]): at start-up and periodically, records older than the
//!   retention age, then the oldest ended records beyond the size cap, are deleted — never
//!   a live session's.

mod attempt;
mod index;
mod retention;
mod row;

pub use attempt::{AttemptEnd, AttemptStart, EventRecord};
use index::IndexLine;
pub use index::{SessionRecord, read_index};
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
use crate::metrics::Metrics;

/// Longest time a record stays in memory before it is written.
pub const FLUSH_INTERVAL: Duration = Duration::from_secs(1);
/// Messages queued for the recorder before new ones are dropped (counted in /metrics).
pub const QUEUE_CAPACITY: usize = 65_536;
/// Start-up repair reads this much of the end of an interrupted record.
const REPAIR_TAIL_BYTES: u64 = 64 << 10;
/// The index is compacted by a retention pass once it is larger than this.
const COMPACT_INDEX_BYTES: u64 = 4 << 20;

/// Recorder settings (from [`crate::config::ServeConfig`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecordConfig {
    /// New sessions are refused while the data disk has less free space (bytes).
    pub min_free_disk_bytes: u64,
    /// What to delete.
    pub retention: Retention,
    /// How often retention runs (it also runs at start-up).
    pub retention_interval: Duration,
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
    /// The next piece of an attempt's compressed input stream ([`crate::replay::log`]):
    /// appended in order; the pieces so far always decode.
    AttemptInputs {
        /// Attempt id.
        id: String,
        /// Bytes to append.
        bytes: Vec<u8>,
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

/// The recorder: its thread and the data directory.
pub struct Recorder {
    sender: RecordSender,
    dir: PathBuf,
    config: RecordConfig,
    failed: FailedSet,
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
    /// Creates the data directory, repairs records cut by a crash, compacts the index,
    /// applies retention and starts the recorder thread.
    pub fn open(
        dir: &Path,
        metrics: Arc<Metrics>,
        config: RecordConfig,
    ) -> anyhow::Result<Recorder> {
        std::fs::create_dir_all(dir.join("sessions"))?;
        let index_path = dir.join("sessions.jsonl");
        // Nothing is live yet: every session without an end line was interrupted.
        for r in read_index(&index_path) {
            if r.ended_unix.is_none() {
                for path in [csv_path(dir, &r.id), events_path(dir, &r.id)] {
                    if let Err(e) = cut_to_last_line(&path) {
                        tracing::warn!(id = %r.id, "cannot repair {}: {e}", path.display());
                    }
                }
            }
        }
        let failed: FailedSet = Arc::default();
        let mut state = RecorderState::new(dir, metrics.clone(), config, failed.clone())?;
        state.maintain(true);
        let (tx, rx) = sync_channel(QUEUE_CAPACITY);
        let thread = std::thread::Builder::new()
            .name("recorder".into())
            .spawn(move || state.run(rx))?;
        let recorder = Recorder {
            sender: RecordSender {
                tx,
                metrics: metrics.clone(),
            },
            dir: dir.to_path_buf(),
            config,
            failed,
            metrics,
            thread: Mutex::new(Some(thread)),
        };
        Ok(recorder)
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
        let probe = sessions.join(format!(".probe-{}", super::random_hex(4)));
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

    /// Every session of the index, created order, with end data when ended. A session with
    /// no end line was cut off by a crash: it is reported with `end_reason: "interrupted"`
    /// unless it is live now (the caller merges live ones).
    pub fn index(&self) -> Vec<SessionRecord> {
        let mut v = read_index(&self.dir.join("sessions.jsonl"));
        let failed = self.failed.lock().unwrap_or_else(|e| e.into_inner());
        for r in &mut v {
            r.recording_failed |= failed.contains_key(&r.id);
        }
        v
    }
}

fn csv_path(dir: &Path, id: &str) -> PathBuf {
    dir.join("sessions").join(format!("{id}.csv"))
}

fn events_path(dir: &Path, id: &str) -> PathBuf {
    dir.join("sessions").join(format!("{id}.events.jsonl"))
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

/// One live session in the recorder thread.
struct Live {
    csv: Option<WholeFile<File>>,
    events: Option<WholeFile<File>>,
    /// Rows formatted since the last write (whole rows only).
    rows: CsvOut<Vec<u8>>,
    pending_rows: u64,
    pending_events: Vec<u8>,
    pending_event_count: u64,
    /// Figures of the last pending row, and of the last row on disk / in the index.
    pending_figures: Option<(f64, u64)>,
    written_figures: Option<(f64, u64)>,
    indexed_figures: Option<(f64, u64)>,
    failed: bool,
    failure_indexed: bool,
}

impl Live {
    fn open(dir: &Path, id: &str) -> (Live, Option<io::Error>) {
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
        let events = match open_whole(&events_path(dir, id)) {
            Ok(f) => Some(f),
            Err(e) => {
                err.get_or_insert(e);
                None
            }
        };
        let failed = err.is_some();
        (
            Live {
                csv: csv.filter(|_| !failed),
                events: events.filter(|_| !failed),
                rows: CsvOut::new(Vec::new()),
                pending_rows: 0,
                pending_events: Vec::new(),
                pending_event_count: 0,
                pending_figures: None,
                written_figures: None,
                indexed_figures: None,
                failed,
                failure_indexed: false,
            },
            err,
        )
    }
}

/// The recorder thread's state.
struct RecorderState {
    dir: PathBuf,
    index: WholeFile<File>,
    metrics: Arc<Metrics>,
    config: RecordConfig,
    failed: FailedSet,
    live: HashMap<String, Live>,
    last_maintenance: Instant,
}

impl RecorderState {
    fn new(
        dir: &Path,
        metrics: Arc<Metrics>,
        config: RecordConfig,
        failed: FailedSet,
    ) -> io::Result<RecorderState> {
        Ok(RecorderState {
            dir: dir.to_path_buf(),
            index: open_whole(&dir.join("sessions.jsonl"))?,
            metrics,
            config,
            failed,
            live: HashMap::new(),
            last_maintenance: Instant::now(),
        })
    }

    fn write_error(&self, id: &str, what: &str, e: &io::Error) {
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

    fn dropped(&self, n: u64) {
        self.metrics.records_dropped.fetch_add(n, Ordering::Relaxed);
    }

    /// Appends index lines in one piece (synced: they are few and small).
    fn write_index(&mut self, lines: &[IndexLine]) {
        let mut text = String::new();
        for line in lines {
            if let Ok(l) = serde_json::to_string(line) {
                text.push_str(&l);
                text.push('\n');
            }
        }
        if let Err(e) = self
            .index
            .append(text.as_bytes())
            .and_then(|()| self.index.file.sync_data())
        {
            self.metrics
                .record_write_errors
                .fetch_add(1, Ordering::Relaxed);
            tracing::error!("session index write failed: {e}");
        }
    }

    /// Writes a session's pending rows and events; on failure marks it failed.
    fn write_pending(&mut self, id: &str) {
        let Some(live) = self.live.get_mut(id) else {
            return;
        };
        let rows = std::mem::replace(&mut live.rows, CsvOut::new(Vec::new()))
            .into_inner()
            .unwrap_or_default();
        let (n_rows, n_events) = (live.pending_rows, live.pending_event_count);
        live.pending_rows = 0;
        live.pending_event_count = 0;
        let events = std::mem::take(&mut live.pending_events);
        let mut errors = Vec::new();
        if !live.failed {
            if let Some(f) = live.csv.as_mut() {
                match f.append(&rows) {
                    Ok(()) => live.written_figures = live.pending_figures.or(live.written_figures),
                    Err(e) => errors.push(("CSV write", e, n_rows + n_events)),
                }
            }
        }
        if !live.failed && errors.is_empty() {
            if let Some(f) = live.events.as_mut() {
                if let Err(e) = f.append(&events) {
                    errors.push(("events write", e, n_events));
                }
            }
        }
        if !errors.is_empty() {
            live.failed = true;
        }
        for (what, e, lost) in &errors {
            self.write_error(id, what, e);
            self.dropped(*lost);
        }
    }

    /// Writes every pending record, then one index line per session whose figures changed.
    fn flush_all(&mut self) {
        let ids: Vec<String> = self.live.keys().cloned().collect();
        for id in &ids {
            self.write_pending(id);
        }
        let mut lines = Vec::new();
        for (id, live) in &mut self.live {
            let changed = live.written_figures != live.indexed_figures
                || (live.failed && !live.failure_indexed);
            if changed {
                // Only a failure before any row leaves no figures: 0 s recorded.
                let (t, overloads) = live.written_figures.unwrap_or((0.0, 0));
                lines.push(IndexLine::Progress {
                    id: id.clone(),
                    sim_seconds: t,
                    overloads,
                    recording_failed: live.failed,
                });
                live.indexed_figures = live.written_figures;
                live.failure_indexed = live.failed;
            }
        }
        if !lines.is_empty() {
            self.write_index(&lines);
        }
    }

    fn handle(&mut self, msg: RecordMsg) {
        match msg {
            RecordMsg::Created {
                id,
                label,
                scenario,
                created_unix,
                ..
            } => {
                let (live, err) = Live::open(&self.dir, &id);
                if let Some(e) = &err {
                    self.write_error(&id, "opening the record", e);
                }
                let failed = live.failed;
                self.live.insert(id.clone(), live);
                let mut lines = vec![IndexLine::Created {
                    id: id.clone(),
                    label,
                    scenario,
                    created_unix,
                }];
                if failed {
                    lines.push(IndexLine::Progress {
                        id,
                        sim_seconds: 0.0,
                        overloads: 0,
                        recording_failed: true,
                    });
                }
                self.write_index(&lines);
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
                let id = event.session.clone();
                let mut json = event.detail.clone();
                if !json.is_object() {
                    json = serde_json::json!({"detail": json});
                }
                json["t"] = serde_json::json!(event.t);
                json["event"] = serde_json::json!(event.kind);
                if let Some(by) = event.actor {
                    json["by"] = serde_json::json!(by);
                }
                let json = json.to_string();
                let Some(live) = self.live.get_mut(&id) else {
                    return;
                };
                if live.failed {
                    self.dropped(1);
                    return;
                }
                live.pending_events.extend_from_slice(json.as_bytes());
                live.pending_events.push(b'\n');
                live.pending_event_count += 1;
            }
            RecordMsg::Ended {
                id,
                ended_unix,
                sim_seconds,
                reason,
                overloads,
            } => {
                self.write_pending(&id);
                let failed = self.live.remove(&id).is_some_and(|l| l.failed);
                self.write_index(&[IndexLine::Ended {
                    id,
                    ended_unix,
                    sim_seconds,
                    reason,
                    overloads,
                    recording_failed: failed,
                }]);
            }
            RecordMsg::Flush(done) => {
                self.flush_all();
                let _ = done.send(());
            }
            RecordMsg::AttemptStarted(_)
            | RecordMsg::AttemptInputs { .. }
            | RecordMsg::AttemptEnded(_) => {}
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
            if self.last_maintenance.elapsed() >= self.config.retention_interval {
                self.maintain(false);
            }
        }
    }

    /// Retention, then index compaction when something was deleted, the index has grown
    /// large, or `compact` is set (start-up).
    fn maintain(&mut self, compact: bool) {
        self.last_maintenance = Instant::now();
        if let Some(free) = free_disk_bytes(&self.dir) {
            self.metrics
                .data_disk_free_bytes
                .store(free, Ordering::Relaxed);
        }
        let index_path = self.dir.join("sessions.jsonl");
        let records = read_index(&index_path);
        let sized: Vec<(SessionRecord, u64)> = records
            .iter()
            .map(|r| {
                let size = [csv_path(&self.dir, &r.id), events_path(&self.dir, &r.id)]
                    .iter()
                    .filter_map(|p| std::fs::metadata(p).ok())
                    .map(|m| m.len())
                    .sum();
                (r.clone(), size)
            })
            .collect();
        let live: HashSet<String> = self.live.keys().cloned().collect();
        let prune = retention::select(&sized, &live, self.config.retention, super::unix_now());
        let mut deleted: HashSet<String> = HashSet::new();
        for id in prune {
            let mut ok = true;
            for p in [csv_path(&self.dir, &id), events_path(&self.dir, &id)] {
                if let Err(e) = std::fs::remove_file(&p) {
                    if e.kind() != io::ErrorKind::NotFound {
                        tracing::error!(%id, "retention cannot delete {}: {e}", p.display());
                        ok = false;
                    }
                }
            }
            if ok {
                tracing::info!(%id, "session record deleted by retention");
                deleted.insert(id);
            }
        }
        self.metrics
            .records_pruned
            .fetch_add(deleted.len() as u64, Ordering::Relaxed);
        if compact || !deleted.is_empty() || self.index.len > COMPACT_INDEX_BYTES {
            let kept: Vec<SessionRecord> = records
                .into_iter()
                .filter(|r| !deleted.contains(&r.id))
                .collect();
            if let Err(e) = self.compact(&kept) {
                self.metrics
                    .record_write_errors
                    .fetch_add(1, Ordering::Relaxed);
                tracing::error!("session index compaction failed: {e}");
            }
        }
    }

    /// Rewrites the index as one line per record (temporary file, synced, renamed).
    fn compact(&mut self, records: &[SessionRecord]) -> io::Result<()> {
        let path = self.dir.join("sessions.jsonl");
        let tmp = self.dir.join("sessions.jsonl.tmp");
        let mut text = String::new();
        for r in records {
            text.push_str(&serde_json::to_string(&IndexLine::Record(r.clone()))?);
            text.push('\n');
        }
        let result = (|| {
            let mut f = File::create(&tmp)?;
            f.write_all(text.as_bytes())?;
            f.sync_all()?;
            std::fs::rename(&tmp, &path)?;
            self.index = open_whole(&path)?;
            Ok(())
        })();
        if result.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        result
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
            std::env::temp_dir().join(format!("seaarms-repair-{}", super::super::random_hex(6)));
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
