//! Counters exported at `GET /metrics` in the Prometheus text format.

use std::fmt::Write as _;
use std::sync::atomic::{AtomicU64, Ordering};

/// Server-wide counters and gauges (relaxed atomics: monotonic counts, no ordering needed).
#[derive(Debug, Default)]
pub struct Metrics {
    /// HTTP requests answered.
    pub http_requests: AtomicU64,
    /// Sessions created since start.
    pub sessions_created: AtomicU64,
    /// Live sessions now.
    pub sessions_live: AtomicU64,
    /// Simulation steps run.
    pub steps: AtomicU64,
    /// Steps dropped because a session fell more than the catch-up cap behind real time.
    pub step_overruns: AtomicU64,
    /// State frames published (once per session per frame).
    pub frames_published: AtomicU64,
    /// Frames sent to clients.
    pub frames_sent: AtomicU64,
    /// Frames a slow client skipped (latest state wins).
    pub frames_skipped: AtomicU64,
    /// WebSocket clients connected now.
    pub ws_clients: AtomicU64,
    /// Client messages refused (malformed, out of range, over the rate).
    pub ws_messages_rejected: AtomicU64,
    /// Records (rows, events) dropped: the recorder queue was full or the record could not
    /// be written.
    pub records_dropped: AtomicU64,
    /// Failed writes of session records: CSV rows or database batches (disk full, I/O
    /// errors, database unreachable).
    pub record_write_errors: AtomicU64,
    /// Times the records database was found not writable (a failed check or commit).
    pub records_database_failures: AtomicU64,
    /// Session records deleted by retention.
    pub records_pruned: AtomicU64,
    /// Free bytes on the data disk at the last check.
    pub data_disk_free_bytes: AtomicU64,
    /// Compute-pool jobs finished (any outcome).
    pub compute_jobs: AtomicU64,
    /// Compute requests running or queued now.
    pub compute_in_flight: AtomicU64,
    /// Compute requests refused with 503 (queue full).
    pub compute_busy: AtomicU64,
    /// Compute requests answered 504 (deadline passed).
    pub compute_deadline_exceeded: AtomicU64,
    /// 1 while this replica drains (SIGTERM: no new sessions), else 0.
    pub draining: AtomicU64,
    /// xAPI statements the Learning Record Store accepted ([`crate::xapi`]).
    pub xapi_statements_sent: AtomicU64,
    /// Finished attempts whose xAPI statements wait in the outbox (at the sender's last look).
    pub xapi_pending: AtomicU64,
    /// Failed tries to send an attempt's xAPI statements (LRS down or erring; retried).
    pub xapi_send_failures: AtomicU64,
    /// Attempts whose xAPI statements the LRS refused for good (400 or 409; not retried).
    pub xapi_refused: AtomicU64,
}

impl Metrics {
    /// The Prometheus text exposition, with the info gauge naming this replica.
    pub fn render(&self, replica: &str) -> String {
        let mut out = String::new();
        let rows: [(&str, &str, &str, &AtomicU64); 24] = [
            (
                "seaarms_http_requests_total",
                "counter",
                "HTTP requests answered",
                &self.http_requests,
            ),
            (
                "seaarms_sessions_created_total",
                "counter",
                "Sessions created since start",
                &self.sessions_created,
            ),
            (
                "seaarms_sessions",
                "gauge",
                "Live sessions",
                &self.sessions_live,
            ),
            (
                "seaarms_steps_total",
                "counter",
                "Simulation steps (1 ms each)",
                &self.steps,
            ),
            (
                "seaarms_step_overruns_total",
                "counter",
                "Steps dropped to stay real time",
                &self.step_overruns,
            ),
            (
                "seaarms_frames_published_total",
                "counter",
                "State frames published",
                &self.frames_published,
            ),
            (
                "seaarms_frames_sent_total",
                "counter",
                "State frames sent to clients",
                &self.frames_sent,
            ),
            (
                "seaarms_frames_skipped_total",
                "counter",
                "State frames skipped by slow clients",
                &self.frames_skipped,
            ),
            (
                "seaarms_websocket_clients",
                "gauge",
                "WebSocket clients connected",
                &self.ws_clients,
            ),
            (
                "seaarms_ws_messages_rejected_total",
                "counter",
                "Client messages refused",
                &self.ws_messages_rejected,
            ),
            (
                "seaarms_records_dropped_total",
                "counter",
                "Record rows and events dropped (recorder queue full or record not writable)",
                &self.records_dropped,
            ),
            (
                "seaarms_record_write_errors_total",
                "counter",
                "Failed writes of session records or the session index",
                &self.record_write_errors,
            ),
            (
                "seaarms_records_database_failures_total",
                "counter",
                "Times the records database was found not writable (a failed check or commit)",
                &self.records_database_failures,
            ),
            (
                "seaarms_records_pruned_total",
                "counter",
                "Session records deleted by retention",
                &self.records_pruned,
            ),
            (
                "seaarms_data_disk_free_bytes",
                "gauge",
                "Free bytes on the data disk at the last check",
                &self.data_disk_free_bytes,
            ),
            (
                "seaarms_compute_jobs_total",
                "counter",
                "Compute-pool jobs finished",
                &self.compute_jobs,
            ),
            (
                "seaarms_compute_in_flight",
                "gauge",
                "Compute requests running or queued",
                &self.compute_in_flight,
            ),
            (
                "seaarms_compute_busy_total",
                "counter",
                "Compute requests refused (queue full, 503)",
                &self.compute_busy,
            ),
            (
                "seaarms_compute_deadline_exceeded_total",
                "counter",
                "Compute requests past their deadline (504)",
                &self.compute_deadline_exceeded,
            ),
            (
                "seaarms_draining",
                "gauge",
                "1 while the replica drains (SIGTERM: no new sessions)",
                &self.draining,
            ),
            (
                "seaarms_xapi_statements_sent_total",
                "counter",
                "xAPI statements accepted by the Learning Record Store",
                &self.xapi_statements_sent,
            ),
            (
                "seaarms_xapi_pending",
                "gauge",
                "Finished attempts whose xAPI statements wait to be sent",
                &self.xapi_pending,
            ),
            (
                "seaarms_xapi_send_failures_total",
                "counter",
                "Failed tries to send xAPI statements (retried with back-off)",
                &self.xapi_send_failures,
            ),
            (
                "seaarms_xapi_refused_total",
                "counter",
                "Attempts whose xAPI statements the LRS refused (400 or 409; not retried)",
                &self.xapi_refused,
            ),
        ];
        for (name, kind, help, v) in rows {
            let _ = writeln!(
                out,
                "# HELP {name} {help}\n# TYPE {name} {kind}\n{name} {}",
                v.load(Ordering::Relaxed)
            );
        }
        let _ = writeln!(
            out,
            "# HELP seaarms_replica_info This replica's name\n# TYPE seaarms_replica_info gauge\nseaarms_replica_info{{replica=\"{replica}\"}} 1"
        );
        out
    }
}
