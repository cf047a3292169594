//! Command line and environment configuration: one `clap` struct, defaults that make a bare
//! `seaarms` serve on http://127.0.0.1:8080.

use std::net::{IpAddr, SocketAddr};
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
    /// Run a training exercise headless (`exercises/<id>.json`) and print its assessment JSON:
    /// `--autopilot` drives it with the exercise's scripted controller through the trainee's
    /// controls, `--human` with a human-paced operator following the script's intent (a
    /// decision every 0.25 s, two axes at most, rest / slow / full), `--idle` gives no input.
    Exercise {
        /// Exercise id (see `GET /api/exercises`).
        id: String,
        /// Drive with the exercise's autopilot script.
        #[arg(long, conflicts_with_all = ["idle", "human"])]
        autopilot: bool,
        /// Drive with a human-paced operator (`exercises::Driver::HumanPaced`).
        #[arg(long, conflicts_with = "idle")]
        human: bool,
        /// Give no input (the default).
        #[arg(long)]
        idle: bool,
        /// Seed of the attempt's random draws (the fault drill's fault and time).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// With `--human`: the operator's mean decision interval as a multiple of 0.25 s
        /// (`exercises::HumanNoise`; with any of these three the operator varies, seeded by
        /// `--seed`).
        #[arg(long, requires = "human")]
        reaction: Option<f64>,
        /// With `--human`: largest extra share of the decision interval, drawn per decision.
        #[arg(long, requires = "human")]
        jitter: Option<f64>,
        /// With `--human`: largest relative misjudgement of an axis's intent, per decision.
        #[arg(long, requires = "human")]
        misjudge: Option<f64>,
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
    /// Instructor token; when not set, one is generated and printed once to stderr (a
    /// configured token is never printed).
    #[arg(
        long,
        env = "SEAARMS_INSTRUCTOR_TOKEN",
        hide_env_values = true,
        global = true
    )]
    pub instructor_token: Option<String>,
    /// Directory of session records (CSVs) and of the default SQLite records database.
    #[arg(
        long,
        env = "SEAARMS_DATA_DIR",
        default_value = "./data",
        global = true
    )]
    pub data_dir: PathBuf,
    /// Training records database: `sqlite://PATH?mode=rwc` or `postgres://user@host/db`;
    /// `sqlite://DATA_DIR/seaarms.db?mode=rwc` when not given.
    #[arg(
        long,
        env = "SEAARMS_DATABASE_URL",
        hide_env_values = true,
        global = true
    )]
    pub database_url: Option<String>,
    /// Most live sessions at once (503 beyond).
    #[arg(
        long,
        env = "SEAARMS_MAX_SESSIONS",
        default_value_t = 64,
        global = true
    )]
    pub max_sessions: usize,
    /// A session whose trainee gives no input for this many seconds ends (connected or not).
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

    // --- Admission and browser security (docs/operations.md) ---
    /// Sessions one client may create at once before the rate limit applies (429 beyond).
    #[arg(
        long,
        env = "SEAARMS_SESSION_BURST",
        default_value_t = 10,
        global = true
    )]
    pub session_burst: u32,
    /// Sessions one client may create per minute after its burst (token-bucket refill).
    #[arg(
        long,
        env = "SEAARMS_SESSIONS_PER_MINUTE",
        default_value_t = 6.0,
        global = true
    )]
    pub sessions_per_minute: f64,
    /// Most live sessions created by one client at once (429 beyond).
    #[arg(
        long,
        env = "SEAARMS_MAX_SESSIONS_PER_CLIENT",
        default_value_t = 16,
        global = true
    )]
    pub max_sessions_per_client: usize,
    /// A session no trainee has connected to ends after this many seconds.
    #[arg(
        long,
        env = "SEAARMS_UNJOINED_GRACE_SECS",
        default_value_t = 60,
        global = true
    )]
    pub unjoined_grace_secs: u64,
    /// A session whose trainee left (its last trainee connection closed) ends after this many
    /// seconds unless a trainee connects again (end reason `abandoned`).
    #[arg(
        long,
        env = "SEAARMS_ABANDON_GRACE_SECONDS",
        default_value_t = 30,
        global = true
    )]
    pub abandon_grace_seconds: u64,
    /// Reverse proxies (IP addresses, comma-separated) whose `X-Forwarded-For` and
    /// `X-Forwarded-Proto` are believed; none by default (the headers are ignored).
    #[arg(
        long,
        env = "SEAARMS_TRUSTED_PROXIES",
        value_delimiter = ',',
        global = true
    )]
    pub trusted_proxies: Vec<IpAddr>,
    /// Class code that `POST /api/sessions` must present (`join_code` field or `X-Join-Code`
    /// header; 403 otherwise); none by default. The instructor token needs none.
    #[arg(long, env = "SEAARMS_JOIN_CODE", hide_env_values = true, global = true)]
    pub join_code: Option<String>,
    /// Progression (docs/exercises.md "Progression"): `on`, a trainee starts an exercise only
    /// once proficient in those it `requires` (or unlocked by the instructor); `off`, every
    /// exercise is open to everyone (free practice, and tests not about progression).
    #[arg(
        long,
        env = "SEAARMS_PROGRESSION",
        value_enum,
        default_value = "on",
        global = true
    )]
    pub progression: Progression,
    /// Further origins (e.g. `https://sim.example.org`, comma-separated) allowed to open
    /// WebSockets and send POST/DELETE, besides the served host itself.
    #[arg(
        long,
        env = "SEAARMS_ALLOWED_ORIGINS",
        value_delimiter = ',',
        global = true
    )]
    pub allowed_origins: Vec<String>,
    /// Host names the server answers for (comma-separated; `*` for any); other `Host`
    /// headers get 421 (DNS rebinding). Default: the bind address (and `localhost` when it is
    /// a loopback one) and the hosts of `--public-url` and `--allowed-origins`; any when bound
    /// to every interface (`0.0.0.0`).
    #[arg(
        long,
        env = "SEAARMS_ALLOWED_HOSTS",
        value_delimiter = ',',
        global = true
    )]
    pub allowed_hosts: Vec<String>,
    /// Public base URL (`https://sim.example.org`); `ws_url` is built from it instead of the
    /// request's Host header, and its origin is allowed.
    #[arg(long, env = "SEAARMS_PUBLIC_URL", global = true)]
    pub public_url: Option<String>,

    // --- Session records: free-space floor and retention (see sessions::record). ---
    /// New sessions are refused (503) while the data disk has less free space than this (MB).
    #[arg(
        long,
        env = "SEAARMS_MIN_FREE_DISK_MB",
        default_value_t = 256,
        global = true
    )]
    pub min_free_disk_mb: u64,
    /// Session records that ended more than this many days ago are deleted (0 = kept however
    /// old; fractions allowed).
    #[arg(long, env = "SEAARMS_RETENTION_DAYS", default_value_t = 0.0, value_parser = non_negative, global = true)]
    pub retention_days: f64,
    /// Session records are kept below this many MB by deleting the oldest ended ones
    /// (live sessions never; 0 = no cap; fractions allowed).
    #[arg(long, env = "SEAARMS_RETENTION_MAX_MB", default_value_t = 10240.0, value_parser = non_negative, global = true)]
    pub retention_max_mb: f64,
    /// Seconds between retention passes (one also runs at start-up).
    #[arg(
        long,
        env = "SEAARMS_RETENTION_CHECK_SECS",
        default_value_t = 60,
        value_parser = clap::value_parser!(u64).range(1..),
        global = true
    )]
    pub retention_check_secs: u64,
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

    // --- Several replicas behind a proxy (docs/api.md "Replicas", docs/operations.md) ---
    /// This replica's name (a DNS label: lowercase letters, digits, `-`; at most 63): session
    /// URLs carry it as `/r/<name>/…` when the database is shared (PostgreSQL). Default: the
    /// host name (a Kubernetes StatefulSet pod's name).
    #[arg(long, env = "SEAARMS_REPLICA_NAME", global = true)]
    pub replica_name: Option<String>,
    /// On SIGTERM, keep serving live sessions for up to this many seconds (new ones get 503,
    /// `/healthz` 503) before ending them as interrupted; 0 (the default) stops at once.
    #[arg(
        long,
        env = "SEAARMS_DRAIN_SECONDS",
        default_value_t = 0,
        global = true
    )]
    pub drain_seconds: u64,

    // --- Results to a Learning Record Store (docs/xapi.md) ---
    /// xAPI endpoint of a Learning Record Store (`https://lrs.example.org/xAPI/`): every
    /// finished exercise attempt's statements are queued in the records database and sent
    /// there. Off when unset. Credentials (HTTP Basic) by environment only:
    /// `SEAARMS_XAPI_USERNAME`, `SEAARMS_XAPI_PASSWORD`.
    #[arg(long, env = "SEAARMS_XAPI_ENDPOINT", global = true)]
    pub xapi_endpoint: Option<String>,
}

/// `--progression`: whether exercises' `requires` lock them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Progression {
    /// Exercises open as their requirements are met (the default).
    On,
    /// Every exercise is open.
    Off,
}

fn non_negative(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 0.0 => Ok(x),
        _ => Err(format!("expected a finite number ≥ 0, got `{s}`")),
    }
}

impl ServeConfig {
    /// The records database URL: `--database-url`, else the SQLite file in the data folder.
    pub fn database_url(&self) -> String {
        match &self.database_url {
            Some(url) if !url.is_empty() => url.clone(),
            _ => crate::db::default_url(&self.data_dir),
        }
    }

    /// The recorder's settings.
    pub fn record_config(&self) -> crate::sessions::record::RecordConfig {
        crate::sessions::record::RecordConfig {
            min_free_disk_bytes: self.min_free_disk_mb.saturating_mul(1 << 20),
            retention: crate::sessions::record::Retention {
                max_age_days: self.retention_days,
                max_bytes: (self.retention_max_mb * 1_048_576.0) as u64,
            },
            retention_interval: std::time::Duration::from_secs(self.retention_check_secs),
            xapi: self.xapi_endpoint.as_deref().is_some_and(|e| !e.is_empty()),
        }
    }

    /// The xAPI sender's settings when `--xapi-endpoint` is set: the credentials from the
    /// environment (`SEAARMS_XAPI_USERNAME`, `SEAARMS_XAPI_PASSWORD`), the public URL
    /// (`--public-url`; else, left empty, `run` uses `http://<the address it listens on>`).
    pub fn xapi_config(&self) -> anyhow::Result<Option<crate::xapi::XapiConfig>> {
        let Some(endpoint) = self.xapi_endpoint.as_deref().filter(|e| !e.is_empty()) else {
            return Ok(None);
        };
        let env = |k: &str| std::env::var(k).ok();
        crate::xapi::XapiConfig::new(
            endpoint,
            env("SEAARMS_XAPI_USERNAME").as_deref(),
            env("SEAARMS_XAPI_PASSWORD").as_deref(),
            self.public_url.as_deref().unwrap_or_default(),
        )
        .map(Some)
    }
}

impl Default for ServeConfig {
    fn default() -> Self {
        ServeConfig {
            bind: SocketAddr::from(([127, 0, 0, 1], 8080)),
            instructor_token: None,
            data_dir: PathBuf::from("./data"),
            database_url: None,
            max_sessions: 64,
            idle_timeout_secs: 900,
            frame_hz: 60,
            max_messages_per_second: 200,
            physics_threads: None,
            session_burst: 10,
            sessions_per_minute: 6.0,
            max_sessions_per_client: 16,
            unjoined_grace_secs: 60,
            abandon_grace_seconds: 30,
            trusted_proxies: Vec::new(),
            join_code: None,
            progression: Progression::On,
            allowed_origins: Vec::new(),
            allowed_hosts: Vec::new(),
            public_url: None,
            min_free_disk_mb: 256,
            retention_days: 0.0,
            retention_max_mb: 10240.0,
            retention_check_secs: 60,
            compute_threads: 1,
            compute_queue: 4,
            compute_deadline_secs: 20,
            compute_priority: crate::compute::ComputePriority::Idle,
            replica_name: None,
            drain_seconds: 0,
            xapi_endpoint: None,
        }
    }
}
