//! The `seaarms` binary: parses the command line and hands over to the library.

use clap::Parser;
use seaarms::config::{Cli, Command};

#[tokio::main]
async fn main() -> anyhow::Result<()> {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into()),
        )
        .init();
    let cli = Cli::parse();
    match cli.command {
        None | Some(Command::Serve) => {
            let state = seaarms::app::AppState::new()?;
            let listener = tokio::net::TcpListener::bind(cli.serve.bind).await?;
            let addr = listener.local_addr()?;
            println!("seaarms serving on http://{addr}");
            tracing::info!(%addr, "listening");
            seaarms::run(listener, state, async {
                let _ = tokio::signal::ctrl_c().await;
            })
            .await?;
        }
    }
    Ok(())
}
