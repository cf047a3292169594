//! The compute pool: where CPU-heavy requests (polytopes, optimal posture, studies, workspace
//! maps, scenario runs) run, away from tokio's async workers (which carry every live
//! session's frames) and from the physics threads.
//!
//! * A fixed number of threads (`--compute-threads`, default 1) in a [`rayon::ThreadPool`],
//!   at the lowest OS priority by default (`--compute-priority idle`: Linux `SCHED_IDLE`,
//!   which runs only when no normal thread wants the core, so the physics threads keep their
//!   timing on a 2-core machine; `low` = nice 19; `normal` leaves it).
//! * A queue limit: at most threads + `--compute-queue` requests running or waiting; one
//!   more is refused at once with 503, a `Retry-After` header and a JSON body
//!   ([`ComputeError::Busy`]).
//! * A deadline per request (`--compute-deadline-secs`, from the moment it is queued): past
//!   it the client gets a 504 JSON body ([`ComputeError::Deadline`]) and the job's
//!   [`Cancel`] reports cancellation, so a job that checks it between rows / series stops
//!   consuming CPU. A client that disconnects cancels its job the same way; a job still
//!   waiting in the queue when cancelled never starts.

use std::fmt;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde_json::json;
use tokio::sync::{OwnedSemaphorePermit, Semaphore, oneshot};

use crate::error::ApiError;
use crate::limits::RETRY_AFTER_SECS;
use crate::metrics::Metrics;

/// OS priority of the compute threads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ComputePriority {
    /// Linux `SCHED_IDLE` (elsewhere: the lowest nice value): runs only on otherwise idle cores.
    Idle,
    /// Nice 19.
    Low,
    /// Unchanged (the server's own priority).
    Normal,
}

/// Size, queue, deadline and priority of the pool.
#[derive(Debug, Clone)]
pub struct ComputeSettings {
    /// Compute threads (≥ 1).
    pub threads: usize,
    /// Requests that may wait beyond the running ones.
    pub queue: usize,
    /// Deadline of one request, queueing included.
    pub deadline: Duration,
    /// OS priority of the threads.
    pub priority: ComputePriority,
}

/// Why a compute request did not produce its answer.
#[derive(Debug)]
pub enum ComputeError {
    /// A client error (validation, limits) or a core error, answered as usual.
    Api(ApiError),
    /// The queue is full: 503 + `Retry-After`.
    Busy {
        /// Requests running or waiting.
        capacity: usize,
    },
    /// The deadline passed (504).
    Deadline {
        /// The deadline (s).
        seconds: f64,
    },
    /// The job panicked (500); the pool keeps running.
    Failed,
}

impl From<ApiError> for ComputeError {
    fn from(e: ApiError) -> Self {
        ComputeError::Api(e)
    }
}

impl From<seaarms_core::Error> for ComputeError {
    fn from(e: seaarms_core::Error) -> Self {
        ComputeError::Api(e.into())
    }
}

impl ComputeError {
    /// The JSON error this becomes (status, message, detail).
    pub fn api_error(&self) -> ApiError {
        match self {
            ComputeError::Api(e) => e.clone(),
            ComputeError::Busy { capacity } => ApiError {
                status: StatusCode::SERVICE_UNAVAILABLE,
                error: format!(
                    "the server is busy: {capacity} compute requests are running or queued (limit compute_queue); retry in {RETRY_AFTER_SECS} s"
                ),
                detail: None,
            }
            .with_detail(json!({
                "limit": "compute_queue",
                "value": capacity,
                "retry_after_s": RETRY_AFTER_SECS,
            })),
            ComputeError::Deadline { seconds } => ApiError {
                status: StatusCode::GATEWAY_TIMEOUT,
                error: format!(
                    "the request was not done within its deadline of {seconds} s (limit compute_deadline_secs)"
                ),
                detail: None,
            }
            .with_detail(json!({ "limit": "compute_deadline_secs", "value": seconds })),
            ComputeError::Failed => ApiError {
                status: StatusCode::INTERNAL_SERVER_ERROR,
                error: "the computation failed (internal error)".into(),
                detail: None,
            },
        }
    }
}

impl fmt::Display for ComputeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.api_error().error)
    }
}

impl std::error::Error for ComputeError {}

impl IntoResponse for ComputeError {
    fn into_response(self) -> Response {
        let busy = matches!(self, ComputeError::Busy { .. });
        let mut resp = self.api_error().into_response();
        if busy {
            resp.headers_mut()
                .insert(header::RETRY_AFTER, HeaderValue::from(RETRY_AFTER_SECS));
        }
        resp
    }
}

/// A job's deadline and cancellation flag; jobs call [`Cancel::check`] between units of work
/// (rows, series, starts).
#[derive(Debug, Clone)]
pub struct Cancel {
    at: Option<Instant>,
    limit: Duration,
    flag: Arc<AtomicBool>,
}

impl Cancel {
    /// No deadline (the command line).
    pub fn never() -> Cancel {
        Cancel {
            at: None,
            limit: Duration::MAX,
            flag: Arc::default(),
        }
    }

    /// A deadline `limit` from now.
    pub(crate) fn until(limit: Duration) -> Cancel {
        Cancel {
            at: Instant::now().checked_add(limit),
            limit,
            flag: Arc::default(),
        }
    }

    /// `Err(Deadline)` once the deadline has passed or the request was abandoned.
    pub fn check(&self) -> Result<(), ComputeError> {
        let late = self.at.is_some_and(|at| Instant::now() >= at);
        if late || self.flag.load(Ordering::Relaxed) {
            Err(ComputeError::Deadline {
                seconds: self.limit.as_secs_f64(),
            })
        } else {
            Ok(())
        }
    }
}

/// Sets the flag when the waiting request goes away (answered, timed out or disconnected).
struct CancelOnDrop(Arc<AtomicBool>);

impl Drop for CancelOnDrop {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Relaxed);
    }
}

/// A queue slot: released (and the gauge lowered) when the job ends, however it ends.
struct Slot {
    _permit: OwnedSemaphorePermit,
    metrics: Arc<Metrics>,
}

impl Drop for Slot {
    fn drop(&mut self) {
        self.metrics
            .compute_in_flight
            .fetch_sub(1, Ordering::Relaxed);
    }
}

/// The bounded pool (see the module doc).
pub struct ComputePool {
    pool: rayon::ThreadPool,
    slots: Arc<Semaphore>,
    capacity: usize,
    deadline: Duration,
    metrics: Arc<Metrics>,
}

impl ComputePool {
    /// Starts the threads.
    pub fn new(settings: &ComputeSettings, metrics: Arc<Metrics>) -> anyhow::Result<ComputePool> {
        let threads = settings.threads.max(1);
        let priority = settings.priority;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("seaarms-compute-{i}"))
            .start_handler(move |_| lower_priority(priority))
            .panic_handler(|_| tracing::error!("a compute job panicked"))
            .build()?;
        let capacity = threads + settings.queue;
        Ok(ComputePool {
            pool,
            slots: Arc::new(Semaphore::new(capacity)),
            capacity,
            deadline: settings.deadline,
            metrics,
        })
    }

    /// Runs `job` on the pool and waits for it (see the module doc for the 503 and 504 cases).
    pub async fn run<T, F>(&self, job: F) -> Result<T, ComputeError>
    where
        T: Send + 'static,
        F: FnOnce(&Cancel) -> Result<T, ComputeError> + Send + 'static,
    {
        let Ok(permit) = self.slots.clone().try_acquire_owned() else {
            self.metrics.compute_busy.fetch_add(1, Ordering::Relaxed);
            return Err(ComputeError::Busy {
                capacity: self.capacity,
            });
        };
        self.metrics
            .compute_in_flight
            .fetch_add(1, Ordering::Relaxed);
        let slot = Slot {
            _permit: permit,
            metrics: self.metrics.clone(),
        };
        let cancel = Cancel::until(self.deadline);
        let _abandon = CancelOnDrop(cancel.flag.clone());
        let (tx, rx) = oneshot::channel();
        let metrics = self.metrics.clone();
        self.pool.spawn(move || {
            let result = cancel.check().and_then(|()| job(&cancel));
            metrics.compute_jobs.fetch_add(1, Ordering::Relaxed);
            drop(slot);
            let _ = tx.send(result);
        });
        let result = match tokio::time::timeout(self.deadline, rx).await {
            Ok(Ok(result)) => result,
            Ok(Err(_)) => Err(ComputeError::Failed),
            Err(_) => Err(ComputeError::Deadline {
                seconds: self.deadline.as_secs_f64(),
            }),
        };
        if matches!(result, Err(ComputeError::Deadline { .. })) {
            self.metrics
                .compute_deadline_exceeded
                .fetch_add(1, Ordering::Relaxed);
        }
        result
    }
}

/// Lowers the calling (compute) thread's OS priority; a refusal is logged, not fatal.
fn lower_priority(priority: ComputePriority) {
    use thread_priority::{ThreadPriority, set_current_thread_priority};
    let result = match priority {
        ComputePriority::Normal => return,
        #[cfg(target_os = "linux")]
        ComputePriority::Idle => thread_priority::set_thread_priority_and_policy(
            thread_priority::thread_native_id(),
            ThreadPriority::Min,
            thread_priority::ThreadSchedulePolicy::Normal(
                thread_priority::NormalThreadSchedulePolicy::Idle,
            ),
        ),
        #[cfg(not(target_os = "linux"))]
        ComputePriority::Idle => set_current_thread_priority(ThreadPriority::Min),
        ComputePriority::Low => set_current_thread_priority(ThreadPriority::Min),
    };
    if let Err(e) = result {
        tracing::warn!(
            ?e,
            ?priority,
            "could not lower the compute thread's priority"
        );
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn pool(threads: usize, queue: usize, deadline: Duration) -> (ComputePool, Arc<Metrics>) {
        let metrics = Arc::new(Metrics::default());
        let settings = ComputeSettings {
            threads,
            queue,
            deadline,
            priority: ComputePriority::Idle,
        };
        (
            ComputePool::new(&settings, metrics.clone()).unwrap(),
            metrics,
        )
    }

    #[cfg(target_os = "linux")]
    #[tokio::test]
    async fn compute_threads_run_under_sched_idle() {
        let (p, _) = pool(1, 0, Duration::from_secs(10));
        let policy = p
            .run(|_| Ok(thread_priority::thread_schedule_policy().unwrap()))
            .await
            .unwrap();
        assert_eq!(
            policy,
            thread_priority::ThreadSchedulePolicy::Normal(
                thread_priority::NormalThreadSchedulePolicy::Idle
            )
        );
    }

    #[tokio::test]
    async fn a_full_queue_is_a_503_with_retry_after_and_a_late_job_a_504() {
        let (p, metrics) = pool(1, 1, Duration::from_millis(300));
        let p = Arc::new(p);
        // One job holds the thread until it is cancelled (deadline) and 100 ms more, so the
        // waiting one is past its own deadline when the thread frees: the third is refused
        // at once.
        let (started_tx, started_rx) = std::sync::mpsc::channel();
        let spin = {
            let p = p.clone();
            tokio::spawn(async move {
                p.run(move |c| {
                    let _ = started_tx.send(());
                    while c.check().is_ok() {
                        std::thread::sleep(Duration::from_millis(5));
                    }
                    std::thread::sleep(Duration::from_millis(100));
                    c.check()
                })
                .await
            })
        };
        tokio::task::spawn_blocking(move || started_rx.recv().unwrap())
            .await
            .unwrap();
        let waiting = {
            let p = p.clone();
            tokio::spawn(async move { p.run(|_| Ok(1)).await })
        };
        // Until the waiting job is queued (in flight: the spinning one and it), not a fixed
        // sleep: on a loaded machine the task may take longer than any guess to be polled.
        for _ in 0..1000 {
            if metrics.compute_in_flight.load(Ordering::Relaxed) == 2 {
                break;
            }
            tokio::time::sleep(Duration::from_millis(1)).await;
        }
        assert_eq!(metrics.compute_in_flight.load(Ordering::Relaxed), 2);
        let busy = p.run(|_| Ok(2)).await.unwrap_err();
        assert!(
            matches!(busy, ComputeError::Busy { capacity: 2 }),
            "{busy:?}"
        );
        let resp = busy.into_response();
        assert_eq!(resp.status(), StatusCode::SERVICE_UNAVAILABLE);
        assert_eq!(resp.headers()[header::RETRY_AFTER], "2");
        assert!(matches!(
            spin.await.unwrap(),
            Err(ComputeError::Deadline { .. })
        ));
        // The waiting job was queued as long as the spinning one ran: past its own deadline
        // too, so it never ran.
        assert!(matches!(
            waiting.await.unwrap(),
            Err(ComputeError::Deadline { .. })
        ));
        assert_eq!(metrics.compute_busy.load(Ordering::Relaxed), 1);
        assert_eq!(metrics.compute_deadline_exceeded.load(Ordering::Relaxed), 2);
        // Once the abandoned job has stopped (≤ 10 s even on a loaded machine), the pool is
        // free again.
        for _ in 0..1000 {
            if metrics.compute_in_flight.load(Ordering::Relaxed) == 0 {
                break;
            }
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
        assert_eq!(metrics.compute_in_flight.load(Ordering::Relaxed), 0);
        // Admitted again (not 503). Its answer is 3 — or, when foreign load starves the
        // pool's lowered-priority thread past the 300 ms deadline, a 504: that is the pool
        // yielding to the sessions' physics as designed, not a full queue; the abandoned job
        // then holds its slot until the thread reaches it and sees the cancellation.
        match p.run(|_| Ok(3)).await {
            Ok(v) => assert_eq!(v, 3),
            Err(e) => assert!(matches!(e, ComputeError::Deadline { .. }), "{e:?}"),
        }
        for _ in 0..1000 {
            if metrics.compute_in_flight.load(Ordering::Relaxed) == 0 {
                break;
            }
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
        assert_eq!(metrics.compute_in_flight.load(Ordering::Relaxed), 0);
    }

    #[tokio::test]
    async fn a_panicking_job_is_a_500_and_the_pool_survives() {
        let (p, _) = pool(1, 0, Duration::from_secs(10));
        let e = p
            .run(|_| -> Result<(), ComputeError> { panic!("boom") })
            .await
            .unwrap_err();
        assert_eq!(
            e.into_response().status(),
            StatusCode::INTERNAL_SERVER_ERROR
        );
        assert_eq!(p.run(|_| Ok(7)).await.unwrap(), 7);
    }
}
