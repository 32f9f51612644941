//! The daemon section of `corridor demo`: the injected exp25 run replayed through an
//! in-process daemon to a logger and a PDR consumer, checked against the offline run.

use anyhow::{Context, Result, bail};
use corridor_client::record::{RecordOptions, RecordStop, Recorded, Recorder};
use corridor_client::replay::{ReplayOptions, Speed, replay};
use corridor_client::track::{Track, TrackStop, Tracker};
use corridor_client::{ClientError, Delivery, Domain, ProducerStats};
use corridor_service::runner::{self, RunOptions};
use corridor_shared::imu_csv::ImuLog;
use corridor_shared::injection::BiasInjection;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// How long the demo's daemon section waits for a peer or for the next message.
const DEMO_WAIT: Duration = Duration::from_secs(10);
/// Longest single wait of the demo's consumers, so they see an abort.
const DEMO_POLL: Duration = Duration::from_millis(50);
/// Largest accepted difference between the daemon's final bias and the offline run's, rad/s.
const DEMO_BIAS_TOLERANCE_RAD_S: f64 = 1e-12;

/// Runs the daemon in-process on a domain of this process, opens a logger and a PDR consumer,
/// replays `exp25` (its log, configuration and injection) through the client [`Producer`] at
/// full speed with lossless delivery, and checks the daemon's final bias against `offline`
/// (the `corridor run` of the same options). Fails when anything was lost or the biases differ.
///
/// [`Producer`]: corridor_client::Producer
pub(super) fn demo_daemon(out: &Path, exp25: &RunOptions, offline: &runner::Summary) -> Result<()> {
    use corridor_service::daemon::{self, DaemonConfig};

    let started = Instant::now();
    let log = corridor_shared::imu_csv::read_imu_csv(&exp25.imu, &exp25.csv)?;
    let domain = Domain::new(&format!("demo_{}", std::process::id()))?;
    let aid = runner::heading_aid(&exp25.config, exp25.map.as_deref())?;
    let mut cfg = DaemonConfig::new(domain.clone(), exp25.config.clone(), aid);
    cfg.delivery = Delivery::Lossless;
    cfg.checkpoint = None;
    let dir = out.join("daemon");
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;

    let shutdown = Arc::new(AtomicBool::new(false));
    let daemon = {
        let flag = Arc::clone(&shutdown);
        std::thread::Builder::new()
            .name("corridor-demo-daemon".into())
            .spawn(move || daemon::run(cfg, flag))
            .context("starting the daemon thread")?
    };
    // The consumers open their ports on their own threads (iceoryx2 ports are !Send) and say
    // when they are attached; the replay starts after both.
    let abort = Arc::new(AtomicBool::new(false));
    // One message from each of the two consumers (bounded, as every channel of the project).
    let (ready_tx, ready_rx) = std::sync::mpsc::sync_channel::<()>(2);
    let logger = {
        let (domain, dir, ready, abort) = (
            domain.clone(),
            dir.clone(),
            ready_tx.clone(),
            Arc::clone(&abort),
        );
        std::thread::Builder::new()
            .name("corridor-demo-log".into())
            .spawn(move || demo_logger(&domain, &dir, &ready, &abort))
            .context("starting the logger thread")?
    };
    let pdr = {
        let (domain, ready, abort) = (domain.clone(), ready_tx, Arc::clone(&abort));
        std::thread::Builder::new()
            .name("corridor-demo-pdr".into())
            .spawn(move || demo_pdr(&domain, &ready, &abort))
            .context("starting the PDR thread")?
    };
    let replay_started = Instant::now();
    let replay = (|| -> Result<ProducerStats> {
        let mut ready = 0;
        let waiting = Instant::now();
        while ready < 2 {
            match ready_rx.recv_timeout(DEMO_POLL) {
                Ok(()) => ready += 1,
                Err(_) if daemon.is_finished() => bail!("the daemon stopped before the replay"),
                Err(_) if logger.is_finished() || pdr.is_finished() => {
                    bail!("a consumer stopped before the replay")
                }
                Err(_) if waiting.elapsed() >= DEMO_WAIT => {
                    bail!("the consumers did not attach within {DEMO_WAIT:?}")
                }
                Err(_) => {}
            }
        }
        demo_replay(&domain, &log, &exp25.injection)
    })();
    let replay_s = replay_started.elapsed().as_secs_f64();
    if replay.is_err() {
        abort.store(true, Ordering::Relaxed);
    }
    let joined = |name: &str| anyhow::anyhow!("the {name} thread panicked");
    let logged = logger.join().map_err(|_| joined("logger"))?;
    let tracked = pdr.join().map_err(|_| joined("PDR"))?;
    shutdown.store(true, Ordering::Relaxed);
    let report = daemon.join().map_err(|_| joined("daemon"))?;
    // The daemon's clean shutdown removed its services; what is left of the domain is the
    // node counter iceoryx2 keeps across runs (`<prefix>…node.<version>.global_mgmt`), which a
    // domain of one process does not need.
    // SAFETY: no other process uses this domain (it is named after this process's id) and
    // every thread of this process that used it has ended, its ports and nodes dropped.
    let removed = unsafe {
        iceoryx2::testing::remove_global_mgmt_segment::<iceoryx2::prelude::ipc::Service>(
            domain.config(),
        )
    };
    // The daemon's accounting file (kept for a restarted daemon of the domain): this domain
    // ends with this process.
    let state_path = domain.daemon_state_path();
    std::fs::remove_file(&state_path)
        .with_context(|| format!("removing {}", state_path.display()))?;
    let stats = replay.context("replaying through the daemon")?;
    let logged = logged.context("logger consumer")?;
    let tracked = tracked.context("PDR consumer")?;
    let report = report.context("daemon")?;
    removed.map_err(|e| anyhow::anyhow!("removing the iceoryx2 node counter: {e:?}"))?;
    let left = demo_leftovers(&domain);

    let d = &report.diagnostics;
    let sent = stats.imu_sent.saturating_sub(1);
    let lost_daemon = stats.imu_undelivered
        + stats.imu_sent.saturating_sub(d.received)
        + d.seq_gaps
        + d.dropped_overflow;
    let logged_missed = logged.attitude_missed + logged.bias_missed;
    let lost_logger = d.accepted.saturating_sub(logged.attitude_rows) + logged_missed;
    let lost_pdr = tracked
        .end_stances
        .unwrap_or(0)
        .saturating_sub(tracked.strides)
        + tracked.missed;
    let lost = lost_daemon + lost_logger + lost_pdr;
    let rejected = d.rejected_non_finite + d.rejected_time + d.rejected_duplicate_seq + d.late;
    let last = tracked.last.unwrap_or_default();
    let path_m = tracked.path_m;
    let daemon_bias = logged.final_bias_rad_s.unwrap_or([f64::NAN; 3]);
    let diff: [f64; 3] = std::array::from_fn(|k| (daemon_bias[k] - offline.bias_rad_s[k]).abs());
    let max_diff = diff
        .iter()
        .copied()
        .fold(0.0, |m: f64, d| if d > m || d.is_nan() { d } else { m });

    corridor_client::say!(
        "\n# The same run through the daemon: iceoryx2 domain {:?}, lossless, replay at full speed with the injected bias, logger and PDR consumers\n",
        domain.name()
    );
    corridor_client::say!(
        "replay: {sent} samples sent (+1 end-of-stream marker) in {replay_s:.2} s ({:.0} samples/s), {} reached no subscriber",
        sent as f64 / replay_s.max(1e-9),
        stats.imu_undelivered
    );
    corridor_client::say!(
        "daemon: received {} (marker included), accepted {}, rejected {rejected}, sequence gaps {}, overflow drops {}",
        d.received,
        d.accepted,
        d.seq_gaps,
        d.dropped_overflow
    );
    corridor_client::say!(
        "logger: {} attitude rows, {} bias rows, {} missed ({}, {})",
        logged.attitude_rows,
        logged.bias_rows,
        logged_missed,
        dir.join("attitude.csv").display(),
        dir.join("bias.csv").display()
    );
    corridor_client::say!(
        "pdr: {} strides ({} stances offline), {} missed; last at t = {:.2} s: x = {:.3} m, y = {:.3} m, z = {:.3} m, yaw = {:.1}°; path {:.2} m",
        tracked.strides,
        offline.stances,
        tracked.missed,
        last.t_s,
        last.p_m[0],
        last.p_m[1],
        last.p_m[2],
        last.yaw_rad.to_degrees(),
        path_m
    );
    corridor_client::say!(
        "lost: {lost} (daemon {lost_daemon}, logger {lost_logger}, pdr {lost_pdr})"
    );
    corridor_client::say!(
        "\nfinal gyro bias, rad/s   {:>22} {:>22} {:>22}",
        "x",
        "y",
        "z"
    );
    let row = |name: &str, v: [f64; 3]| {
        corridor_client::say!(
            "{name:<24} {:>22.15e} {:>22.15e} {:>22.15e}",
            v[0],
            v[1],
            v[2]
        );
    };
    row("daemon", daemon_bias);
    row("corridor run (offline)", offline.bias_rad_s);
    row("|difference|", diff);
    // Each warning was logged as it came (stderr): counted here, not printed a second time.
    corridor_client::say!("daemon warnings: {} (in the log)", report.warnings.len());
    corridor_client::say!(
        "iceoryx2 files left for the domain: {}",
        if left.is_empty() {
            "none".to_owned()
        } else {
            left.join(", ")
        }
    );
    corridor_client::say!(
        "daemon section: {:.2} s wall time",
        started.elapsed().as_secs_f64()
    );

    if lost > 0 {
        bail!("{lost} samples lost with lossless delivery");
    }
    if logged.last_attitude_bias_rad_s != daemon_bias {
        bail!(
            "the daemon's end-of-stream bias {daemon_bias:?} is not the bias of its last attitude {:?}",
            logged.last_attitude_bias_rad_s
        );
    }
    // NaN never compares below the tolerance.
    if !diff.iter().all(|&d| d <= DEMO_BIAS_TOLERANCE_RAD_S) {
        bail!(
            "the daemon's final bias differs from the offline run's by {max_diff:e} rad/s on its worst axis (tolerance {DEMO_BIAS_TOLERANCE_RAD_S:e})"
        );
    }
    if tracked.strides != offline.stances {
        bail!(
            "the PDR consumer saw {} strides, the offline run {} stances",
            tracked.strides,
            offline.stances
        );
    }
    if !left.is_empty() {
        bail!("iceoryx2 files left behind: {}", left.join(", "));
    }
    Ok(())
}

/// Sends `log` with `injection` added to the gyro through a lossless producer
/// ([`corridor_client::replay()`]), as fast as the daemon takes it, then the end-of-stream marker.
fn demo_replay(domain: &Domain, log: &ImuLog, injection: &BiasInjection) -> Result<ProducerStats> {
    let opts = ReplayOptions {
        node_name: "corridor-demo-replay".into(),
        delivery: Some(Delivery::Lossless),
        speed: Speed::Max,
        loops: 1,
        injection: *injection,
        wait: DEMO_WAIT,
    };
    Ok(replay(domain, &log.rows, &opts)?.stats)
}

/// The demo's logger ([`Recorder`], the `corridor-log` tool's loop): writes the attitude and
/// bias streams to `dir/attitude.csv` and `dir/bias.csv` until the end-of-stream attitude and
/// bias; says `ready` once attached.
fn demo_logger(
    domain: &Domain,
    dir: &Path,
    ready: &std::sync::mpsc::SyncSender<()>,
    abort: &AtomicBool,
) -> Result<Recorded> {
    let opts = RecordOptions {
        node_name: "corridor-demo-log".into(),
        wait: DEMO_WAIT,
        idle_timeout: DEMO_WAIT,
        idle_before_first: true,
        poll: DEMO_POLL,
    };
    let recorder = Recorder::open(domain, dir, &opts)?;
    let _ = ready.send(());
    let got = recorder.run(abort)?;
    match got.stopped {
        RecordStop::EndOfStream => Ok(got),
        RecordStop::Aborted => bail!("stopped: the replay failed"),
        RecordStop::IdleTimeout => bail!("nothing from the daemon for {DEMO_WAIT:?}"),
        RecordStop::Interrupted => Err(ClientError::Interrupted.into()),
    }
}

/// The demo's PDR consumer ([`Tracker`], the `corridor-pdr` tool's loop): follows the nav
/// stream until its end; says `ready` once attached.
fn demo_pdr(
    domain: &Domain,
    ready: &std::sync::mpsc::SyncSender<()>,
    abort: &AtomicBool,
) -> Result<Track> {
    let tracker = Tracker::open(domain, "corridor-demo-pdr", DEMO_WAIT)?;
    let _ = ready.send(());
    let got = tracker.run(DEMO_POLL, Some(DEMO_WAIT), abort, |_| {})?;
    match got.stopped {
        TrackStop::EndOfStream => Ok(got),
        TrackStop::Aborted => bail!("stopped: the replay failed"),
        TrackStop::IdleTimeout => bail!("nothing from the daemon for {DEMO_WAIT:?}"),
        TrackStop::DaemonStopped => bail!("the daemon stopped within the stream"),
        TrackStop::Interrupted => Err(ClientError::Interrupted.into()),
    }
}

/// Files of `domain` still in the iceoryx2 locations: shared memory (`/dev/shm`) and the
/// iceoryx2 root directory (services, nodes), two levels deep.
fn demo_leftovers(domain: &Domain) -> Vec<String> {
    fn scan(dir: &Path, tag: &str, depth: u32, left: &mut Vec<String>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            if e.file_name().to_string_lossy().contains(tag) {
                left.push(e.path().display().to_string());
            } else if depth > 0 && e.file_type().is_ok_and(|t| t.is_dir()) {
                scan(&e.path(), tag, depth - 1, left);
            }
        }
    }
    let tag = format!("{}_", domain.name());
    let mut left = Vec::new();
    scan(Path::new("/dev/shm"), &tag, 0, &mut left);
    let root = PathBuf::from(domain.config().global.root_path().to_string());
    scan(&root, &tag, 2, &mut left);
    left
}
