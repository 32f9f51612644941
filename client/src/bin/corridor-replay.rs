//! `corridor-replay`: publishes a CSV IMU log to the daemon as if it were a live sensor.
//!
//! Reports what it sent and how many samples reached no subscriber.

use anyhow::{Context, Result, bail};
use clap::Parser;
use corridor_client::{Delivery, Domain, Producer};
use corridor_shared::imu_csv::{ImuCsvOptions, read_imu_csv};
use corridor_shared::injection::{BiasInjection, parse_vec3};
use corridor_shared::services::DEFAULT_DOMAIN;
use corridor_shared::wire::ImuSample;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Replay speed.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Speed {
    /// As fast as the daemon takes it.
    Max,
    /// Sensor time × factor (1 = real time).
    Factor(f64),
}

fn parse_speed(s: &str) -> Result<Speed, String> {
    match s {
        "max" => Ok(Speed::Max),
        "realtime" => Ok(Speed::Factor(1.0)),
        _ => s
            .parse::<f64>()
            .ok()
            .filter(|f| f.is_finite() && *f > 0.0)
            .map(Speed::Factor)
            .ok_or_else(|| format!("speed {s:?}: expected realtime, max or a factor > 0")),
    }
}

#[derive(Parser, Debug)]
#[command(
    name = "corridor-replay",
    version,
    about = "Replay an IMU CSV log to the corridor daemon"
)]
struct Args {
    /// IMU log (CSV: t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2,...).
    #[arg(long)]
    imu: PathBuf,
    /// realtime, max, or a speed-up factor (2 = twice real time).
    #[arg(long, default_value = "realtime", value_parser = parse_speed)]
    speed: Speed,
    /// Send the log this many times (time continues across loops).
    #[arg(long = "loop", default_value_t = 1)]
    loops: u32,
    /// iceoryx2 domain of the daemon.
    #[arg(long, default_value = DEFAULT_DOMAIN)]
    domain: String,
    /// Delivery policy: live or lossless (must match the daemon's).
    #[arg(long, default_value = "live")]
    delivery: Delivery,
    /// Constant gyro bias to add, X,Y,Z in rad/s.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    inject_gyro_bias: Option<[f64; 3]>,
    /// Start the injection at this sensor time, s.
    #[arg(long, default_value_t = 0.0)]
    inject_after_s: f64,
    /// How long to wait for the daemon, s.
    #[arg(long, default_value_t = 10.0)]
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
    if a.loops == 0 {
        bail!("--loop 0: nothing to send");
    }
    let log = read_imu_csv(&a.imu, &ImuCsvOptions::default())
        .with_context(|| format!("reading {}", a.imu.display()))?;
    let (Some(first), Some(last)) = (log.rows.first(), log.rows.last()) else {
        bail!("{}: no samples", a.imu.display());
    };
    let injection = BiasInjection {
        constant_rad_s: a.inject_gyro_bias.unwrap_or_default(),
        after_s: a.inject_after_s,
        ..BiasInjection::default()
    };
    // Each loop continues the clock: shift by the log's span plus one mean period.
    let n = log.rows.len();
    let period = if n > 1 {
        (last.t_s - first.t_s) / (n - 1) as f64
    } else {
        0.01
    };
    let loop_shift_s = last.t_s - first.t_s + period;

    let domain = Domain::new(&a.domain)?;
    let mut p = Producer::new(&domain, "corridor-replay", a.delivery)?;
    p.wait_for_daemon(Duration::from_secs_f64(a.wait_s.max(0.0)))?;
    let start = Instant::now();
    let mut interrupted = false;
    'outer: for k in 0..a.loops {
        let shift = f64::from(k) * loop_shift_s;
        for (i, r) in log.rows.iter().enumerate() {
            let t_s = r.t_s + shift;
            if let Speed::Factor(f) = a.speed {
                let due = start + Duration::from_secs_f64(((t_s - first.t_s) / f).max(0.0));
                let now = Instant::now();
                if due > now {
                    std::thread::sleep(due - now);
                }
            }
            if i % 64 == 0 && p.termination_requested() {
                interrupted = true;
                break 'outer;
            }
            let mut gyro = r.gyro_rad_s;
            injection.apply(t_s, &mut gyro);
            p.send_imu(ImuSample {
                t_s,
                gyro_rad_s: gyro,
                accel_m_s2: r.accel_m_s2,
                temp_c: r.temp_c.unwrap_or(f64::NAN),
                ..ImuSample::default()
            })?;
        }
    }
    p.finish()?;
    let s = p.stats();
    let elapsed = start.elapsed().as_secs_f64();
    let samples = s.imu_sent - 1;
    let rate = if elapsed > 0.0 {
        samples as f64 / elapsed
    } else {
        0.0
    };
    println!("imu: {}", a.imu.display());
    println!("domain: {} (delivery {})", domain.name(), a.delivery.name());
    println!(
        "loops: {}{}",
        a.loops,
        if interrupted { " (interrupted)" } else { "" }
    );
    println!("samples sent: {samples} (+1 end-of-stream marker)");
    println!("samples nobody received: {}", s.imu_undelivered);
    println!("lossless retries: {}", s.retries);
    println!("rows rejected by the CSV reader: {}", log.rejected.len());
    println!("elapsed: {elapsed:.3} s ({rate:.0} samples/s)");
    if s.imu_undelivered > 0 {
        eprintln!(
            "warning: {} of {} messages reached no subscriber (is the daemon running on domain {:?}?)",
            s.imu_undelivered,
            s.imu_sent,
            domain.name()
        );
    }
    Ok(())
}
