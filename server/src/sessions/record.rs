//! Session records on disk, written by one recorder thread so no physics worker ever waits
//! on a file:
//!
//! * `DATA/sessions.jsonl` — the session index: one JSON line when a session is created and
//!   one when it ends, appended and written through at once (rare, small). An append-only
//!   index was chosen over an embedded database: it needs no C dependency, a crash can at
//!   most cut the last line (which the reader skips), and replaying it on start-up lists
//!   every finished session.
//! * `DATA/sessions/<id>.csv` — the time series at 100 Hz; `DATA/sessions/<id>.events.jsonl`
//!   — every event and instructor action. Buffered and flushed at least every second, so a
//!   crash loses at most a second.

use std::collections::HashMap;
use std::fs::{File, OpenOptions};
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender, TrySendError, sync_channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use super::physics::csv_header;
use crate::metrics::Metrics;

/// Longest time a record stays in memory before it is flushed.
pub const FLUSH_INTERVAL: Duration = Duration::from_secs(1);
/// Messages queued for the recorder before new ones are dropped (counted in /metrics).
pub const QUEUE_CAPACITY: usize = 65_536;

/// What the recorder is asked to do.
#[derive(Debug)]
pub enum RecordMsg {
    /// A session started.
    Created {
        /// Id.
        id: String,
        /// Trainee label.
        label: String,
        /// Scenario.
        scenario: String,
        /// Unix seconds.
        created_unix: f64,
    },
    /// One CSV line (with its newline).
    Row {
        /// Session id.
        id: String,
        /// The line.
        line: String,
    },
    /// One JSON event line (without newline).
    Event {
        /// Session id.
        id: String,
        /// The JSON text.
        json: String,
    },
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

/// One line of the index, folded per session.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SessionRecord {
    /// Id.
    pub id: String,
    /// Trainee label.
    #[serde(default)]
    pub label: String,
    /// Scenario.
    #[serde(default)]
    pub scenario: String,
    /// Unix seconds.
    #[serde(default)]
    pub created_unix: f64,
    /// Unix seconds, when ended.
    #[serde(default)]
    pub ended_unix: Option<f64>,
    /// Simulated seconds at the end.
    #[serde(default)]
    pub sim_seconds: Option<f64>,
    /// Why it ended.
    #[serde(default)]
    pub end_reason: Option<String>,
    /// Relief events over the session.
    #[serde(default)]
    pub overloads: Option<u64>,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(tag = "event", rename_all = "snake_case")]
enum IndexLine {
    Created {
        id: String,
        label: String,
        scenario: String,
        created_unix: f64,
    },
    Ended {
        id: String,
        ended_unix: f64,
        sim_seconds: f64,
        reason: String,
        overloads: u64,
    },
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

/// The recorder: its thread and the data directory.
pub struct Recorder {
    sender: RecordSender,
    dir: PathBuf,
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

impl Recorder {
    /// Creates the data directory and starts the recorder thread.
    pub fn open(dir: &Path, metrics: Arc<Metrics>) -> anyhow::Result<Recorder> {
        std::fs::create_dir_all(dir.join("sessions"))?;
        let index = OpenOptions::new()
            .create(true)
            .append(true)
            .open(dir.join("sessions.jsonl"))?;
        let (tx, rx) = sync_channel(QUEUE_CAPACITY);
        let dir2 = dir.to_path_buf();
        let thread = std::thread::Builder::new()
            .name("recorder".into())
            .spawn(move || recorder_loop(&dir2, index, rx))?;
        Ok(Recorder {
            sender: RecordSender { tx, metrics },
            dir: dir.to_path_buf(),
            thread: Mutex::new(Some(thread)),
        })
    }

    /// A sending handle.
    pub fn sender(&self) -> RecordSender {
        self.sender.clone()
    }

    /// Queues a record.
    pub fn send(&self, msg: RecordMsg) {
        self.sender.send(msg);
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
        valid_id(id).then(|| self.dir.join("sessions").join(format!("{id}.csv")))
    }

    /// Every session of the index, created order, with end data when ended. A session with
    /// no end line was cut off by a crash: it is reported with `end_reason: "interrupted"`
    /// unless it is live now (the caller merges live ones).
    pub fn index(&self) -> Vec<SessionRecord> {
        read_index(&self.dir.join("sessions.jsonl"))
    }
}

/// Reads and folds an index file; unparsable lines (a line cut by a crash) are skipped.
pub fn read_index(path: &Path) -> Vec<SessionRecord> {
    let Ok(file) = File::open(path) else {
        return Vec::new();
    };
    let mut order: Vec<String> = Vec::new();
    let mut by_id: HashMap<String, SessionRecord> = HashMap::new();
    for line in BufReader::new(file).lines().map_while(Result::ok) {
        match serde_json::from_str::<IndexLine>(&line) {
            Ok(IndexLine::Created {
                id,
                label,
                scenario,
                created_unix,
            }) => {
                order.push(id.clone());
                by_id.insert(
                    id.clone(),
                    SessionRecord {
                        id,
                        label,
                        scenario,
                        created_unix,
                        ended_unix: None,
                        sim_seconds: None,
                        end_reason: None,
                        overloads: None,
                    },
                );
            }
            Ok(IndexLine::Ended {
                id,
                ended_unix,
                sim_seconds,
                reason,
                overloads,
            }) => {
                if let Some(r) = by_id.get_mut(&id) {
                    r.ended_unix = Some(ended_unix);
                    r.sim_seconds = Some(sim_seconds);
                    r.end_reason = Some(reason);
                    r.overloads = Some(overloads);
                }
            }
            Err(_) => continue,
        }
    }
    order
        .into_iter()
        .filter_map(|id| by_id.remove(&id))
        .collect()
}

struct Files {
    csv: BufWriter<File>,
    events: BufWriter<File>,
}

fn open_files(dir: &Path, id: &str) -> std::io::Result<Files> {
    let base = dir.join("sessions");
    let csv_path = base.join(format!("{id}.csv"));
    let fresh = !csv_path.exists();
    let mut csv = BufWriter::new(
        OpenOptions::new()
            .create(true)
            .append(true)
            .open(&csv_path)?,
    );
    if fresh {
        csv.write_all(csv_header().as_bytes())?;
    }
    let events = BufWriter::new(
        OpenOptions::new()
            .create(true)
            .append(true)
            .open(base.join(format!("{id}.events.jsonl")))?,
    );
    Ok(Files { csv, events })
}

fn write_index(index: &mut File, line: &IndexLine) {
    if let Ok(mut text) = serde_json::to_string(line) {
        text.push('\n');
        if let Err(e) = index
            .write_all(text.as_bytes())
            .and_then(|_| index.sync_data())
        {
            tracing::error!("session index write failed: {e}");
        }
    }
}

fn recorder_loop(dir: &Path, mut index: File, rx: Receiver<RecordMsg>) {
    let mut files: HashMap<String, Files> = HashMap::new();
    let mut last_flush = Instant::now();
    let flush_all = |files: &mut HashMap<String, Files>| {
        for (id, f) in files.iter_mut() {
            if let Err(e) = f.csv.flush().and_then(|_| f.events.flush()) {
                tracing::error!(%id, "record flush failed: {e}");
            }
        }
    };
    loop {
        let wait = FLUSH_INTERVAL.saturating_sub(last_flush.elapsed());
        let msg = match rx.recv_timeout(wait) {
            Ok(m) => Some(m),
            Err(RecvTimeoutError::Timeout) => None,
            Err(RecvTimeoutError::Disconnected) => {
                flush_all(&mut files);
                return;
            }
        };
        match msg {
            None => {}
            Some(RecordMsg::Created {
                id,
                label,
                scenario,
                created_unix,
            }) => {
                match open_files(dir, &id) {
                    Ok(f) => {
                        files.insert(id.clone(), f);
                    }
                    Err(e) => tracing::error!(%id, "cannot open session record: {e}"),
                }
                write_index(
                    &mut index,
                    &IndexLine::Created {
                        id,
                        label,
                        scenario,
                        created_unix,
                    },
                );
            }
            Some(RecordMsg::Row { id, line }) => {
                if let Some(f) = files.get_mut(&id) {
                    let _ = f.csv.write_all(line.as_bytes());
                }
            }
            Some(RecordMsg::Event { id, json }) => {
                if let Some(f) = files.get_mut(&id) {
                    let _ = f.events.write_all(json.as_bytes());
                    let _ = f.events.write_all(b"\n");
                }
            }
            Some(RecordMsg::Ended {
                id,
                ended_unix,
                sim_seconds,
                reason,
                overloads,
            }) => {
                if let Some(mut f) = files.remove(&id) {
                    let _ = f.csv.flush();
                    let _ = f.events.flush();
                }
                write_index(
                    &mut index,
                    &IndexLine::Ended {
                        id,
                        ended_unix,
                        sim_seconds,
                        reason,
                        overloads,
                    },
                );
            }
            Some(RecordMsg::Flush(done)) => {
                flush_all(&mut files);
                last_flush = Instant::now();
                let _ = done.send(());
            }
            Some(RecordMsg::Shutdown(done)) => {
                flush_all(&mut files);
                let _ = done.send(());
                return;
            }
        }
        if last_flush.elapsed() >= FLUSH_INTERVAL {
            flush_all(&mut files);
            last_flush = Instant::now();
        }
    }
}
