//! `corridor-replay`: publishes a CSV IMU log to the daemon as if it were a live sensor
//! ([`corridor_client::replay()`]).
//!
//! Reports what it sent and how many samples reached no subscriber; fails when any did.

use anyhow::{Result, bail};
use clap::Parser;
use corridor_client::replay::{ReplayOptions, Speed, replay_with};
use corridor_client::status::DaemonWatch;
use corridor_client::{Delivery, Domain};
use corridor_shared::imu_csv::{ImuCsvOptions, read_imu_csv};
use corridor_shared::injection::{BiasInjection, parse_injected_bias_rad_s, parse_time_s};
use corridor_shared::services::DEFAULT_DOMAIN;
use std::path::PathBuf;
use std::time::Duration;

#[derive(Parser, Debug)]
#[command(
    name = "corridor-replay",
    version,
    about = "Replay an IMU CSV log to the corridor daemon",
    after_help = "Examples:\n  corridor-replay --imu tests/data/gdins_exp36_corridor_out_and_back/imu.csv --domain lab --speed max\n  corridor-replay --imu imu.csv --domain lab --speed 2 --loop 3 --inject-gyro-bias 0.001,0.001,-0.005\n  corridor-replay --imu imu.csv --domain lab --delivery lossless   (fails unless the daemon is lossless)\nExit code: 0 success, 1 error, 2 usage error, 3 no daemon answered within --wait-s; stopped by Ctrl-C (SIGTERM), it ends as the signal does: 130 (143) in a shell."
)]
struct Args {
    /// IMU log (CSV: t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2,...).
    #[arg(long)]
    imu: PathBuf,
    /// realtime, max, or a speed-up factor in [0.001, 1e6] (2 = twice real time).
    #[arg(long, default_value = "realtime")]
    speed: Speed,
    /// Send the log this many times (time continues across loops).
    #[arg(long = "loop", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    loops: u32,
    /// iceoryx2 domain of the daemon.
    #[arg(long, default_value = DEFAULT_DOMAIN, value_parser = Domain::parse_name)]
    domain: String,
    /// Delivery policy, live or lossless: the daemon's when left out; when given, the replay
    /// fails unless the daemon uses it.
    #[arg(long)]
    delivery: Option<Delivery>,
    /// Constant gyro bias to add, X,Y,Z in rad/s (each within ±0.2).
    #[arg(long, value_parser = parse_injected_bias_rad_s, allow_hyphen_values = true)]
    inject_gyro_bias: Option<[f64; 3]>,
    /// Start the injection this long after the log's first sample instead of at it, s (with
    /// --inject-gyro-bias).
    #[arg(
        long,
        requires = "inject_gyro_bias",
        default_value_t = 0.0,
        allow_negative_numbers = true,
        value_parser = parse_time_s
    )]
    inject_after_s: f64,
    /// How long to wait for the daemon, s.
    #[arg(long, default_value_t = 10.0, value_parser = parse_time_s)]
    wait_s: f64,
}

fn main() -> std::process::ExitCode {
    corridor_client::init_tracing("warn");
    corridor_client::exit(run())
}

/// How long to wait after the replay for the daemon's diagnostics of the stream's end (it
/// publishes them at the end of a stream, and every `daemon.diagnostics_period_s`).
const DIAGNOSTICS_WAIT: Duration = Duration::from_secs(10);

/// How long to wait for the daemon's diagnostics service before the replay (a running daemon
/// has it at once).
const DIAGNOSTICS_OPEN_WAIT: Duration = Duration::from_secs(1);

/// Rejected rows named one by one (the rest are counted).
const REJECTED_ROWS_NAMED: usize = 20;

fn run() -> Result<()> {
    let a = Args::parse();
    // Its errors name the file.
    let log = read_imu_csv(&a.imu, &ImuCsvOptions::default())?;
    if log.rows.is_empty() {
        bail!("{}: no samples", a.imu.display());
    }
    // Rows the reader rejected are not sent: the first named, then counted, as `corridor run`
    // names them.
    log.warn_rejected(REJECTED_ROWS_NAMED, ", not sent");
    let rejected = log.rejected.len();
    let domain = Domain::new(&a.domain)?;
    let opts = ReplayOptions {
        node_name: "corridor-replay".into(),
        delivery: a.delivery,
        speed: a.speed,
        loops: a.loops,
        injection: BiasInjection {
            constant_rad_s: a.inject_gyro_bias.unwrap_or_default(),
            after_s: a.inject_after_s,
            ..BiasInjection::default()
        },
        wait: Duration::from_secs_f64(a.wait_s.max(0.0)),
    };
    // The daemon's counts over the replay: what it did with the samples (a producer sees only
    // its side), from its diagnostics, read on their own thread from before the first sample
    // to those of the stream's end. Not there (a daemon not yet started, a stand-in without
    // diagnostics): not known, and the replay goes on.
    // Started once the daemon is there (a daemon started during --wait-s came up after a
    // watch started first had given up: its losses went unsaid, a review).
    let mut watch = None;
    let r = replay_with(&domain, &log.rows, &opts, || {
        watch = DaemonWatch::start(&domain, DIAGNOSTICS_OPEN_WAIT, DIAGNOSTICS_WAIT);
    })?;
    let (account, complete) = match watch.and_then(|w| w.finish(r.samples)) {
        Some((a, complete)) => (Some(a), complete),
        None => (None, false),
    };
    let s = r.stats;
    let rate = if r.elapsed_s > 0.0 {
        r.samples as f64 / r.elapsed_s
    } else {
        0.0
    };
    corridor_client::say!("imu: {}", a.imu.display());
    corridor_client::say!("domain: {} (delivery {})", domain.name(), r.delivery.name());
    corridor_client::say!(
        "loops: {}{}",
        a.loops,
        if r.interrupted { " (interrupted)" } else { "" }
    );
    corridor_client::say!("samples sent: {} (+1 end-of-stream marker)", r.samples);
    // Also counted by the daemon, from the numbering, when it next receives from this
    // producer (head_missing, missing_at_restart): not an extra loss.
    corridor_client::say!(
        "samples nobody received: {} (sent while no daemon was reading)",
        s.imu_undelivered
    );
    corridor_client::say!("lossless retries: {}", s.retries);
    // (The daemon acknowledges a producer at the first sample it takes: a daemon that came
    // back after a stop acknowledges it although the samples sent while none read them are
    // lost, counted on the line above; a review read the two lines as contradicting.)
    corridor_client::say!(
        "daemon acknowledged this producer: {}",
        if s.closes_unconfirmed == 0 {
            "yes"
        } else {
            "no"
        }
    );
    // What the daemon did with them, from its counters (another producer at the same time is
    // counted in them too: `refused as another producer's`).
    let (mut lost, mut foreign) = (0, 0);
    match account {
        Some(d) => {
            foreign = d.foreign;
            corridor_client::say!(
                "the daemon, over the replay{}: received {}, missing from the numbering {} \
                 (overwritten in its live input buffer), before its first read of them {}, \
                 dropped on a full queue {}, refused {}, accepted by its estimator {}, producer changes {}, \
                 refused as another producer's {}",
                if complete {
                    ""
                } else {
                    " (not finished: it had not taken the whole stream)"
                },
                d.received,
                d.seq_gaps,
                d.head_missing,
                d.dropped_overflow,
                d.refused,
                d.accepted,
                d.producer_changes,
                d.foreign
            );
            lost = d.lost();
        }
        None => corridor_client::say!(
            "the daemon, over the replay: not known (no diagnostics, or the daemon restarted); \
             corridor status --domain {}",
            a.domain
        ),
    }
    corridor_client::say!("rows rejected by the CSV reader: {rejected}");
    corridor_client::say!("elapsed: {:.3} s ({rate:.0} samples/s)", r.elapsed_s);
    if lost > 0 && foreign == 0 {
        corridor_client::say_err!(
            "warning: the daemon lost {lost} of the {} samples sent (live delivery drops what \
             it cannot keep up with: --delivery lossless, or a lower --speed)",
            r.samples
        );
    } else if lost > 0 {
        // With a second producer the counts are both producers' (a review: "lost 59370 of the
        // 42000 samples sent").
        corridor_client::say_err!(
            "warning: the daemon lost {lost} samples during the replay, this replay's and the \
             other producer's together (live delivery drops what it cannot keep up with)"
        );
    }
    if foreign > 0 {
        // Whose they were cannot be told from the daemon's counters, which are the domain's
        // (a review: the first version named the other producer's on both replays).
        corridor_client::say_err!(
            "warning: another producer sent on domain {:?} during the replay, and the daemon \
             follows one producer at a time: it refused {foreign} samples as a second \
             producer's (this replay's or the other's), and its counts above are both \
             producers'",
            domain.name()
        );
    }
    if s.closes_unconfirmed > 0 {
        corridor_client::say_err!(
            "warning: the daemon did not confirm within {} s that it took this replay's \
             samples: the samples still queued when it ended may be lost",
            corridor_client::END_ACK_WAIT.as_secs()
        );
    }
    // The replay's purpose is that the daemon gets the log: samples sent while none read (it
    // stopped or restarted during the replay) are lost, so the replay fails (it exited 0 with a
    // warning, and a script took it for a success).
    if s.imu_undelivered > 0 {
        bail!(
            "{} of {} messages (the end-of-stream marker included) reached no subscriber: no \
             daemon read domain {:?} while they were sent",
            s.imu_undelivered,
            s.imu_sent,
            domain.name()
        );
    }
    Ok(())
}
