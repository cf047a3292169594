//! Command line and environment configuration: one `clap` struct, defaults that make a bare
//! `seaarms` serve on http://127.0.0.1:8080.

use std::net::SocketAddr;
use std::path::PathBuf;

use clap::{Parser, Subcommand};

/// seaarms: dual hydraulic subsea manipulator training simulator.
#[derive(Debug, Parser)]
#[command(name = "seaarms", version, about)]
pub struct Cli {
    /// What to do; serving the simulator when omitted.
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Server settings (used by `serve` and by a bare `seaarms`).
    #[command(flatten)]
    pub serve: ServeConfig,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Serve the simulator and the HTTP API (the default).
    Serve,
    /// Run one of Lim's dynamic case studies headless; prints the summary JSON.
    Scenario {
        /// `case1-single-arm`, `case2-single-arm-load`, `case3-dual-open-loop` or `case4-dual-closed-loop`.
        name: String,
        /// Write the post-processing CSV here.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Load-test a running server: N trainee sessions with random sticks plus M observers.
    Load(crate::load::LoadArgs),
    /// Optimal deploy posture (Jun §3): prints {q, tomm, jlm, objective, …} as JSON.
    OptimalPosture {
        /// Built-in robot name.
        #[arg(long, default_value = "magnum")]
        robot: String,
        /// Tool-point target x,y,z in the base frame (m).
        #[arg(
            long,
            value_delimiter = ',',
            allow_negative_numbers = true,
            required = true
        )]
        target: Vec<f64>,
        /// Weight of TOMM against JLM, in [0, 1].
        #[arg(long, default_value_t = 0.8)]
        alpha: f64,
        /// Initial candidates.
        #[arg(long, default_value_t = 8)]
        starts: usize,
    },
    /// Run a manipulability study of Lim §4.3 (or the workspace map); prints JSON.
    Study {
        /// `single-x`, `single-z`, `single-pitch-yaw`, `dual-x`, `dual-pitch-yaw`, `dual-distance`, `workspace-map`.
        name: String,
        /// Parameters as a JSON object.
        #[arg(long)]
        params: Option<String>,
        /// Write the CSV here.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Exit 0 when the server answers `/healthz` (the container's HEALTHCHECK; the runtime
    /// image has no curl).
    Healthcheck {
        /// URL to probe (default: `/healthz` at the configured bind address, 0.0.0.0 → 127.0.0.1).
        #[arg(long)]
        url: Option<String>,
    },
}

/// Settings of the HTTP server.
#[derive(Debug, Clone, clap::Args)]
pub struct ServeConfig {
    /// Address to listen on.
    #[arg(
        long,
        env = "SEAARMS_BIND",
        default_value = "127.0.0.1:8080",
        global = true
    )]
    pub bind: SocketAddr,
    /// Instructor token; generated and printed at start-up when not set.
    #[arg(long, env = "SEAARMS_INSTRUCTOR_TOKEN", global = true)]
    pub instructor_token: Option<String>,
    /// Directory of session records and the session index.
    #[arg(
        long,
        env = "SEAARMS_DATA_DIR",
        default_value = "./data",
        global = true
    )]
    pub data_dir: PathBuf,
    /// Most live sessions at once (503 beyond).
    #[arg(
        long,
        env = "SEAARMS_MAX_SESSIONS",
        default_value_t = 64,
        global = true
    )]
    pub max_sessions: usize,
    /// A session with no trainee connected and no input for this many seconds ends.
    #[arg(
        long,
        env = "SEAARMS_IDLE_TIMEOUT_SECS",
        default_value_t = 900,
        global = true
    )]
    pub idle_timeout_secs: u64,
    /// State frames per second streamed to each client (10–120).
    #[arg(long, env = "SEAARMS_FRAME_HZ", default_value_t = 60, value_parser = clap::value_parser!(u32).range(10..=120), global = true)]
    pub frame_hz: u32,
    /// Client WebSocket messages per second allowed per connection.
    #[arg(
        long,
        env = "SEAARMS_MAX_MESSAGES_PER_SECOND",
        default_value_t = 200,
        global = true
    )]
    pub max_messages_per_second: u32,
    /// Physics worker threads (default: one per CPU).
    #[arg(long, env = "SEAARMS_PHYSICS_THREADS", global = true)]
    pub physics_threads: Option<usize>,
    /// Threads of the compute pool (polytopes, optimal posture, studies, scenario runs).
    #[arg(long, env = "SEAARMS_COMPUTE_THREADS", default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=64), global = true)]
    pub compute_threads: u16,
    /// Compute requests that may wait beyond the running ones (503 + Retry-After beyond).
    #[arg(
        long,
        env = "SEAARMS_COMPUTE_QUEUE",
        default_value_t = 4,
        global = true
    )]
    pub compute_queue: usize,
    /// Deadline of one compute request, queueing included (s; 504 beyond).
    #[arg(long, env = "SEAARMS_COMPUTE_DEADLINE_SECS", default_value_t = 20, value_parser = clap::value_parser!(u64).range(1..=3600), global = true)]
    pub compute_deadline_secs: u64,
    /// OS priority of the compute threads: `idle` (Linux SCHED_IDLE), `low` (nice 19) or `normal`.
    #[arg(
        long,
        env = "SEAARMS_COMPUTE_PRIORITY",
        value_enum,
        default_value = "idle",
        global = true
    )]
    pub compute_priority: crate::compute::ComputePriority,
}

impl Default for ServeConfig {
    fn default() -> Self {
        ServeConfig {
            bind: SocketAddr::from(([127, 0, 0, 1], 8080)),
            instructor_token: None,
            data_dir: PathBuf::from("./data"),
            max_sessions: 64,
            idle_timeout_secs: 900,
            frame_hz: 60,
            max_messages_per_second: 200,
            physics_threads: None,
            compute_threads: 1,
            compute_queue: 4,
            compute_deadline_secs: 20,
            compute_priority: crate::compute::ComputePriority::Idle,
        }
    }
}
