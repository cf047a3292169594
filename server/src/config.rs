//! Command line and environment configuration: one `clap` struct, defaults that make a bare
//! `seaarms` serve on http://127.0.0.1:8080.

use std::net::SocketAddr;

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
}

impl Default for ServeConfig {
    fn default() -> Self {
        ServeConfig {
            bind: SocketAddr::from(([127, 0, 0, 1], 8080)),
        }
    }
}
