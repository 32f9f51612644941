//! `corridor-pdr`: prints the daemon's stride-by-stride positions (one line per stance) until
//! the producer finishes or Ctrl-C.

use anyhow::Result;
use clap::Parser;
use corridor_client::{ClientError, Domain, Subscriber};
use corridor_shared::services::DEFAULT_DOMAIN;
use corridor_shared::wire::{FLAG_END_OF_STREAM, NavSample};
use std::time::Duration;

#[derive(Parser, Debug)]
#[command(
    name = "corridor-pdr",
    version,
    about = "Print stride-by-stride positions from the corridor daemon"
)]
struct Args {
    /// iceoryx2 domain of the daemon.
    #[arg(long, default_value = DEFAULT_DOMAIN)]
    domain: String,
    /// How long to wait for the daemon, s.
    #[arg(long, default_value_t = 30.0)]
    wait_s: f64,
    /// Keep going after an end of stream (follow the next producer).
    #[arg(long)]
    follow: bool,
}

fn main() -> Result<()> {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn")),
        )
        .with_writer(std::io::stderr)
        .init();
    let a = Args::parse();
    let domain = Domain::new(&a.domain)?;
    let nav = Subscriber::<NavSample>::open(
        &domain,
        "corridor-pdr",
        Duration::from_secs_f64(a.wait_s.max(0.0)),
    )?;
    println!(
        "{:>6} {:>10} {:>9} {:>9} {:>9} {:>8} {:>9}",
        "stride", "t_s", "x_m", "y_m", "z_m", "yaw_deg", "step_m"
    );
    let mut prev: Option<[f64; 3]> = None;
    let mut path_m = 0.0;
    loop {
        let n = match nav.recv_timeout(Duration::from_millis(500)) {
            Ok(Some(n)) => n,
            Ok(None) => continue,
            Err(ClientError::Interrupted) => break,
            Err(e) => return Err(e.into()),
        };
        if n.flags & FLAG_END_OF_STREAM != 0 {
            println!("end of stream: {} strides, path {path_m:.2} m", n.stance);
            if a.follow {
                prev = None;
                path_m = 0.0;
                continue;
            }
            break;
        }
        let p = n.p_m;
        let step = prev.map_or(0.0, |q| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt()
        });
        path_m += step;
        prev = Some(p);
        println!(
            "{:>6} {:>10.3} {:>9.3} {:>9.3} {:>9.3} {:>8.1} {:>9.3}",
            n.stance,
            n.t_s,
            p[0],
            p[1],
            p[2],
            n.yaw_rad.to_degrees(),
            step
        );
    }
    Ok(())
}
