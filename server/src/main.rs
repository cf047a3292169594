//! The `seaarms` binary: parses the command line and hands over to the library.

use clap::Parser;
use seaarms::config::{Cli, Command};

#[tokio::main]
async fn main() -> anyhow::Result<()> {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into()),
        )
        .with_writer(std::io::stderr)
        .init();
    let cli = Cli::parse();
    match cli.command {
        None | Some(Command::Serve) => serve(cli.serve).await,
        Some(Command::Scenario { name, out }) => {
            let (summary, csv) =
                tokio::task::spawn_blocking(move || seaarms::scenarios::run_scenario(&name))
                    .await??;
            if let Some(path) = out {
                std::fs::write(&path, csv)?;
            }
            println!("{}", serde_json::to_string_pretty(&summary)?);
            Ok(())
        }
        Some(Command::Exercise {
            id,
            autopilot,
            human,
            idle: _,
            seed,
            reaction,
            jitter,
            misjudge,
        }) => {
            let spec = seaarms::catalogue::EXERCISES.get(&id).ok_or_else(|| {
                anyhow::anyhow!(
                    "unknown exercise `{id}` (known: {})",
                    seaarms::catalogue::EXERCISES
                        .all()
                        .iter()
                        .map(|s| s.id.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })?;
            let robots = seaarms::robots::Robots::load()?;
            let magnum = robots
                .get("magnum")
                .ok_or_else(|| anyhow::anyhow!("no magnum model"))?;
            let driver = if autopilot {
                seaarms::exercises::Driver::Autopilot
            } else if human && (reaction, jitter, misjudge) != (None, None, None) {
                seaarms::exercises::Driver::Noisy(seaarms::exercises::HumanNoise {
                    reaction: reaction.unwrap_or(1.0),
                    jitter: jitter.unwrap_or(0.0),
                    misjudge: misjudge.unwrap_or(0.0),
                    seed,
                })
            } else if human {
                seaarms::exercises::Driver::HumanPaced
            } else {
                seaarms::exercises::Driver::Idle
            };
            let assessment = tokio::task::spawn_blocking(move || {
                seaarms::exercises::run_headless(spec, &[magnum.clone(), magnum], driver, seed)
            })
            .await??;
            println!("{}", serde_json::to_string_pretty(&assessment)?);
            Ok(())
        }
        Some(Command::OptimalPosture {
            robot,
            target,
            alpha,
            starts,
        }) => {
            let robots = seaarms::robots::Robots::load()?;
            let model = robots
                .get(&robot)
                .ok_or_else(|| anyhow::anyhow!("unknown robot `{robot}`"))?;
            anyhow::ensure!(target.len() == 3, "--target takes x,y,z");
            let req = seaarms::posture::PostureRequest {
                robot: robot.into(),
                target_position: [target[0], target[1], target[2]],
                alpha,
                rows: None,
                starts: Some(starts),
            };
            let result = seaarms::posture::optimal_posture(&model, &req)
                .map_err(|e| anyhow::anyhow!(e.error))?;
            println!("{}", serde_json::to_string_pretty(&result)?);
            Ok(())
        }
        Some(Command::Study { name, params, out }) => {
            let params: serde_json::Value = match params {
                Some(p) => serde_json::from_str(&p)?,
                None => serde_json::Value::Null,
            };
            let plan =
                seaarms::studies::plan(&name, &params).map_err(|e| anyhow::anyhow!(e.error))?;
            let study = plan.run(&seaarms::compute::Cancel::never())?;
            if let Some(path) = out {
                std::fs::write(&path, study.csv())?;
            }
            println!("{}", String::from_utf8_lossy(&study.json(true)?));
            Ok(())
        }
        Some(Command::Healthcheck { url }) => {
            let url = url.unwrap_or_else(|| {
                let mut addr = cli.serve.bind;
                if addr.ip().is_unspecified() {
                    addr.set_ip(std::net::Ipv4Addr::LOCALHOST.into());
                }
                format!("http://{addr}/healthz")
            });
            let resp = reqwest::Client::builder()
                .timeout(std::time::Duration::from_secs(2))
                .build()?
                .get(&url)
                .send()
                .await?;
            anyhow::ensure!(
                resp.status().is_success(),
                "{url} answered {}",
                resp.status()
            );
            Ok(())
        }
        Some(Command::Load(args)) => {
            let report = seaarms::load::run(args, cli.serve.instructor_token).await?;
            println!("{}", serde_json::to_string_pretty(&report)?);
            Ok(())
        }
    }
}

async fn serve(config: seaarms::config::ServeConfig) -> anyhow::Result<()> {
    let state = seaarms::app::AppState::new(&config)?;
    let listener = tokio::net::TcpListener::bind(config.bind).await?;
    let addr = listener.local_addr()?;
    // A configured token is the operator's secret and is never printed; a generated one is
    // printed once, to stderr (not to stdout, which is often collected into shared logs),
    // before the address lines so it is out by the time anyone reads them.
    if config.instructor_token.as_deref().is_none_or(str::is_empty) {
        eprintln!(
            "instructor token (generated for this run; set --instructor-token or SEAARMS_INSTRUCTOR_TOKEN to keep one): {}",
            state.instructor_token
        );
    }
    println!("seaarms serving on http://{addr}");
    println!("instructor dashboard: http://{addr}/instructor");
    tracing::info!(%addr, data_dir = %config.data_dir.display(), "listening");
    // SIGTERM/Ctrl-C: drain first (--drain-seconds; none by default), a second signal
    // stops at once.
    let drained = state.clone();
    let shutdown = async move {
        shutdown_signal().await;
        tokio::select! {
            _ = seaarms::cluster::drain(&drained) => {},
            _ = shutdown_signal() => {},
        }
    };
    seaarms::run(listener, state, shutdown).await?;
    tracing::info!("stopped; records flushed");
    Ok(())
}

async fn shutdown_signal() {
    let ctrl_c = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let term = async {
        if let Ok(mut s) = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate())
        {
            s.recv().await;
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! {
        _ = ctrl_c => {},
        _ = term => {},
    }
}
