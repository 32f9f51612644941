//! `corridor-log`: writes the daemon's attitude and bias streams to CSV until the producer
//! finishes (end-of-stream marker) or nothing arrives for `--idle-timeout-s`.
//!
//! `attitude.csv` reuses the `estimates.csv` column names of `corridor run` where they apply
//! (no position or velocity: those are in the nav stream), preceded by `seq,imu_seq`.
//! `bias.csv` has the bias rows (at heading observations and at the daemon's bias rate).

use anyhow::{Context, Result};
use clap::Parser;
use corridor_client::csv_rows::{ATTITUDE_HEADER, BIAS_HEADER, write_attitude_row, write_bias_row};
use corridor_client::{Domain, Subscriber};
use corridor_shared::services::DEFAULT_DOMAIN;
use corridor_shared::wire::{AttitudeSample, BiasSample, FLAG_END_OF_STREAM};
use std::io::Write;
use std::path::PathBuf;
use std::time::{Duration, Instant};

#[derive(Parser, Debug)]
#[command(
    name = "corridor-log",
    version,
    about = "Record the corridor daemon's attitude and bias streams to CSV"
)]
struct Args {
    /// iceoryx2 domain of the daemon.
    #[arg(long, default_value = DEFAULT_DOMAIN)]
    domain: String,
    /// Output directory (attitude.csv, bias.csv).
    #[arg(long)]
    out: PathBuf,
    /// Stop when nothing arrived for this long after the first sample, s.
    #[arg(long, default_value_t = 5.0)]
    idle_timeout_s: f64,
    /// How long to wait for the daemon, s.
    #[arg(long, default_value_t = 30.0)]
    wait_s: f64,
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
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let att_path = a.out.join("attitude.csv");
    let bias_path = a.out.join("bias.csv");
    let create = |p: &PathBuf| -> Result<std::io::BufWriter<std::fs::File>> {
        Ok(std::io::BufWriter::new(
            std::fs::File::create(p).with_context(|| format!("creating {}", p.display()))?,
        ))
    };
    let mut att_w = create(&att_path)?;
    let mut bias_w = create(&bias_path)?;
    writeln!(att_w, "{ATTITUDE_HEADER}")?;
    writeln!(bias_w, "{BIAS_HEADER}")?;

    let wait = Duration::from_secs_f64(a.wait_s.max(0.0));
    let attitude = Subscriber::<AttitudeSample>::open(&domain, "corridor-log-attitude", wait)?;
    let bias = Subscriber::<BiasSample>::open(&domain, "corridor-log-bias", wait)?;
    eprintln!(
        "recording domain {:?} into {}",
        domain.name(),
        a.out.display()
    );

    let idle = Duration::from_secs_f64(a.idle_timeout_s.max(0.0));
    let (mut rows, mut bias_rows, mut gaps) = (0u64, 0u64, 0u64);
    let mut last_seq: Option<u64> = None;
    let mut last_rx = Instant::now();
    let reason = loop {
        let got = match attitude.recv_timeout(Duration::from_millis(200)) {
            Ok(x) => x,
            Err(corridor_client::ClientError::Interrupted) => break "interrupted",
            Err(e) => return Err(e.into()),
        };
        while let Some(b) = bias.try_recv()? {
            write_bias_row(&mut bias_w, &b)
                .with_context(|| format!("writing {}", bias_path.display()))?;
            bias_rows += 1;
        }
        let Some(x) = got else {
            if rows > 0 && last_rx.elapsed() >= idle {
                break "idle timeout";
            }
            continue;
        };
        last_rx = Instant::now();
        if let Some(l) = last_seq {
            gaps += x.seq.saturating_sub(l + 1);
        }
        last_seq = Some(x.seq);
        if x.flags & FLAG_END_OF_STREAM != 0 {
            break "end of stream";
        }
        write_attitude_row(&mut att_w, &x)
            .with_context(|| format!("writing {}", att_path.display()))?;
        rows += 1;
    };
    att_w
        .flush()
        .with_context(|| format!("writing {}", att_path.display()))?;
    bias_w
        .flush()
        .with_context(|| format!("writing {}", bias_path.display()))?;
    println!("stopped: {reason}");
    println!("attitude rows: {rows} ({})", att_path.display());
    println!("bias rows: {bias_rows} ({})", bias_path.display());
    println!("attitude samples missing (seq gaps): {gaps}");
    Ok(())
}
