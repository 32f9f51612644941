//! Helpers shared by the `daemon_*` tests: the bundled log, the config, an in-process daemon
//! and the per-test domain cleanup. Each test binary uses part of it.
#![allow(dead_code)]

use corridor_client::{Delivery, Domain, Producer, Subscriber};
use corridor_service::daemon::{self, DaemonConfig, DaemonError, DaemonReport};
use corridor_service::runner::heading_aid;
use corridor_shared::config::{Config, ConfigFile};
use corridor_shared::imu_csv::{ImuCsvOptions, ImuRow, read_imu_csv};
use corridor_shared::services::Topic;
use corridor_shared::wire::{FLAG_END_OF_STREAM, ImuSample};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

/// Longest wait for anything in these tests.
pub const WAIT: Duration = Duration::from_secs(60);

/// The tests crate's directory.
pub fn manifest() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// `configs/gdins.toml`, validated.
pub fn config() -> Config {
    let path = manifest().join("../configs/gdins.toml");
    ConfigFile::read(&path)
        .expect("config reads")
        .validate()
        .expect("config is valid")
}

/// The rows of the bundled exp36 recording (200 Hz, 14 000 samples).
pub fn exp36_rows() -> Vec<ImuRow> {
    let path = manifest().join("data/gdins_exp36_corridor_out_and_back/imu.csv");
    read_imu_csv(&path, &ImuCsvOptions::default())
        .expect("exp36 reads")
        .rows
}

/// A daemon config for `domain` with the gdins config and its grid heading aid.
pub fn daemon_config(domain: &Domain, delivery: Delivery) -> DaemonConfig {
    let cfg = config();
    let aid = heading_aid(&cfg, None).unwrap();
    let mut d = DaemonConfig::new(domain.clone(), cfg, aid);
    d.delivery = delivery;
    // A lossless consumer counts as stalled after this long without reading: the default 1 s
    // can pass for a reading test thread on a loaded machine. Tests of stalls set their own.
    d.stall_timeout = std::time::Duration::from_secs(10);
    d
}

/// A daemon running in-process on its own thread.
pub struct Running {
    shutdown: Arc<AtomicBool>,
    handle: JoinHandle<Result<DaemonReport, DaemonError>>,
}

impl Running {
    /// Starts [`daemon::run`] on a thread named `test-daemon`.
    pub fn start(cfg: DaemonConfig) -> Self {
        let shutdown = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&shutdown);
        let handle = std::thread::Builder::new()
            .name("test-daemon".into())
            .spawn(move || daemon::run(cfg, flag))
            .unwrap();
        Self { shutdown, handle }
    }

    /// Sets the shutdown flag and returns the report.
    pub fn stop(self) -> DaemonReport {
        self.shutdown.store(true, Ordering::Relaxed);
        self.handle.join().unwrap().expect("daemon ran cleanly")
    }
}

/// Removes the domain's shared-memory files (a clean exit leaves only the 16-byte
/// `global_mgmt` file of the prefix; a killed process leaves more). Call at the start and at
/// the end of a test.
pub fn cleanup_domain(domain: &str) {
    let prefix = format!("corridor_{domain}_");
    // Shared memory, and the event sockets / service files iceoryx2 keeps under /tmp/iceoryx2
    // (left behind when a failed test exits with its daemon still running).
    for root in ["/dev/shm", "/tmp/iceoryx2", "/tmp/iceoryx2/services"] {
        if let Ok(dir) = std::fs::read_dir(root) {
            for e in dir.flatten() {
                if e.file_name().to_string_lossy().starts_with(&prefix) {
                    let _ = std::fs::remove_file(e.path());
                }
            }
        }
    }
}

/// Lists the domain's files in /dev/shm.
pub fn shm_files(domain: &str) -> Vec<String> {
    let prefix = format!("corridor_{domain}_");
    let mut v: Vec<String> = std::fs::read_dir("/dev/shm")
        .map(|d| {
            d.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.starts_with(&prefix))
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// A fresh, empty temporary directory, removed when dropped (also when the test fails).
pub struct TempDir(PathBuf);

impl std::ops::Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A fresh, empty temporary directory for `tag` (`corridor-{tag}`), removed when dropped.
pub fn temp_dir(tag: &str) -> TempDir {
    let d = std::env::temp_dir().join(format!("corridor-{tag}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    TempDir(d)
}

/// A producer on its own thread (from [`produce`]). It stays alive after its last send until
/// [`Produced::join`]: iceoryx2 0.10 attaches the daemon's side of a new connection only when the
/// daemon's receive thread next runs, and a publisher dropped before that takes every sample still
/// queued with it (the sends had reported a receiver). Join once the daemon has taken the stream
/// (its end-of-stream outputs arrived).
pub struct Produced {
    handle: JoinHandle<corridor_client::ProducerStats>,
    release: std::sync::mpsc::Sender<()>,
}

impl Produced {
    /// Lets the producer go and returns its stats.
    pub fn join(self) -> corridor_client::ProducerStats {
        let _ = self.release.send(());
        self.handle.join().unwrap()
    }
}

/// Sends `rows` (then, if `finish`, the end-of-stream marker) from a producer created on a new
/// thread (iceoryx2 ports are `!Send`); [`Produced::join`] returns the producer's stats.
pub fn produce(
    domain: &Domain,
    node: &'static str,
    delivery: Delivery,
    rows: Vec<ImuRow>,
    finish: bool,
) -> Produced {
    let domain = domain.clone();
    let (release, released) = std::sync::mpsc::channel::<()>();
    let handle = std::thread::Builder::new()
        .name(node.into())
        .spawn(move || {
            let mut p = Producer::new(&domain, node, delivery).unwrap();
            p.wait_for_daemon(WAIT).unwrap();
            for r in &rows {
                p.send_imu(ImuSample::from(r)).unwrap();
            }
            if finish {
                p.finish().unwrap();
            }
            let _ = released.recv_timeout(WAIT);
            p.stats()
        })
        .unwrap();
    Produced { handle, release }
}

/// Reads attitude on its own thread (ports are `!Send`) until `ends` end-of-stream markers, and
/// counts what it read and the ends. Connected when this returns.
pub struct AttitudeReader {
    handle: JoinHandle<Vec<corridor_shared::wire::AttitudeSample>>,
    progress: Arc<std::sync::atomic::AtomicU64>,
    ends: Arc<std::sync::atomic::AtomicU64>,
}

impl AttitudeReader {
    pub fn start(domain: &Domain, ends: usize) -> Self {
        use corridor_shared::wire::AttitudeSample;
        let progress = Arc::new(std::sync::atomic::AtomicU64::new(0));
        let ends_read = Arc::new(std::sync::atomic::AtomicU64::new(0));
        let (ready_tx, ready) = std::sync::mpsc::sync_channel(1);
        let handle = {
            let domain = domain.clone();
            let progress = Arc::clone(&progress);
            let ends_read = Arc::clone(&ends_read);
            std::thread::spawn(move || {
                let sub = Subscriber::<AttitudeSample>::open(&domain, "test-att", WAIT).unwrap();
                ready_tx.send(()).unwrap();
                let mut v = Vec::new();
                let mut seen = 0;
                loop {
                    let a = sub.recv_timeout(WAIT).unwrap().expect("attitude");
                    v.push(a);
                    progress.fetch_add(1, Ordering::Relaxed);
                    if a.flags & FLAG_END_OF_STREAM != 0 {
                        seen += 1;
                        ends_read.fetch_add(1, Ordering::Relaxed);
                        if seen == ends {
                            return v;
                        }
                    }
                }
            })
        };
        ready.recv_timeout(WAIT).expect("reader connected");
        Self {
            handle,
            progress,
            ends: ends_read,
        }
    }

    /// Waits until `count` end-of-stream markers were read (panics after [`WAIT`]).
    pub fn wait_for_ends(&self, count: u64) {
        let deadline = std::time::Instant::now() + WAIT;
        while self.ends.load(Ordering::Relaxed) < count {
            assert!(std::time::Instant::now() < deadline, "daemon stuck");
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    /// Waits until `count` messages were read (panics after [`WAIT`]).
    pub fn wait_for(&self, count: u64) {
        let deadline = std::time::Instant::now() + WAIT;
        while self.progress.load(Ordering::Relaxed) < count {
            assert!(std::time::Instant::now() < deadline, "daemon stuck");
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    /// The messages, once the last end-of-stream marker was read.
    pub fn join(self) -> Vec<corridor_shared::wire::AttitudeSample> {
        self.handle.join().unwrap()
    }
}

/// Receives until a message carrying [`FLAG_END_OF_STREAM`] (included in the result).
pub fn until_end<T: Topic>(sub: &Subscriber<T>, flags: impl Fn(&T) -> u32) -> Vec<T> {
    let mut v = Vec::new();
    loop {
        let m = sub
            .recv_timeout(WAIT)
            .unwrap()
            .unwrap_or_else(|| panic!("{} timed out after {} messages", T::SERVICE, v.len()));
        let end = flags(&m) & FLAG_END_OF_STREAM != 0;
        v.push(m);
        if end {
            return v;
        }
    }
}

/// Serialises the daemon tests of one test binary. Two daemons (on different domains) started
/// concurrently in one process sometimes never take up the producer's IMU connection: the
/// producer's sends report a receiver, the daemon's subscriber receives nothing (seen about once
/// in six runs of `daemon_checkpoint`, never in 14 runs one test at a time; iceoryx2 0.10, cause
/// not found). The product runs one daemon per process; the tests do the same.
pub fn one_daemon_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    static ONE: std::sync::Mutex<()> = std::sync::Mutex::new(());
    ONE.lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// The offline estimates of exp36 from an estimator that `prepare` set up first (a queued
/// heading, a warm start), sample by sample as the daemon runs it.
pub fn offline_exp36_with(
    prepare: impl FnOnce(&mut corridor_service::core::Estimator),
) -> Vec<corridor_service::core::Estimate> {
    let cfg = config();
    let aid = heading_aid(&cfg, None).unwrap();
    let mut est = corridor_service::core::Estimator::new(cfg, aid);
    prepare(&mut est);
    exp36_rows()
        .iter()
        .map(|r| *est.step(&r.into()).unwrap())
        .collect()
}

/// The offline estimates of exp36 and the index of the first aligned sample.
pub fn offline_exp36() -> (Vec<corridor_service::core::Estimate>, usize) {
    let cfg = config();
    let aid = heading_aid(&cfg, None).unwrap();
    let path = manifest().join("data/gdins_exp36_corridor_out_and_back/imu.csv");
    let log = read_imu_csv(&path, &ImuCsvOptions::default()).unwrap();
    let mut est = Vec::with_capacity(log.rows.len());
    corridor_service::runner::run_log(
        &log,
        &cfg,
        &aid,
        &corridor_shared::injection::BiasInjection::default(),
        |_, e| est.push(*e),
    );
    let first = est
        .iter()
        .position(|e| e.phase != corridor_service::core::Phase::Aligning)
        .expect("exp36 aligns");
    (est, first)
}

/// Replays the first `n` rows of exp36 (then the end-of-stream marker) and returns the first
/// bias sample with a finite σ (published at the end of alignment) and the report.
pub fn first_aligned_bias(
    domain: &Domain,
    ckpt: &std::path::Path,
    n: usize,
) -> (
    corridor_shared::wire::BiasSample,
    corridor_service::daemon::DaemonReport,
) {
    let mut dcfg = daemon_config(domain, Delivery::Lossless);
    dcfg.checkpoint = Some(ckpt.to_owned());
    let daemon = Running::start(dcfg);
    let bias =
        Subscriber::<corridor_shared::wire::BiasSample>::open(domain, "test-bias", WAIT).unwrap();
    let rows = exp36_rows()[..n].to_vec();
    let producer = produce(domain, "test-replay", Delivery::Lossless, rows, true);
    let got = until_end(&bias, |b| b.flags);
    producer.join();
    let report = daemon.stop();
    let first = *got
        .iter()
        .find(|b| b.gyro_bias_sd_rad_s[0].is_finite())
        .expect("a bias sample after alignment");
    (first, report)
}

pub fn max_abs_diff(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f64::max)
}
