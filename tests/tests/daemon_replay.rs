//! End-to-end: the daemon in-process on its own iceoryx2 domain, fed over IPC by the client
//! [`Producer`], read back with [`Subscriber`]s.
//!
//! - `replay_matches_offline_run_sample_by_sample`: the exp36 log at full speed with the lossless
//!   policy gives exactly the estimates of the offline `run_log`, with no sample lost;
//!   `a_gap_filled_from_the_stride_before_is_the_same_through_the_daemon` the same with 0.3 s cut
//!   out of a swing; `late_footfalls_are_the_same_through_the_daemon` the same on the fast exp38,
//!   whose missed footfalls are updated late (the filter propagated again from the stride
//!   memory inside one step); `a_start_in_fast_gait_that_goes_back_is_the_same_through_the_daemon`
//!   the same on exp38 started mid-walk, whose start goes back to an earlier stance and runs
//!   the filter over the samples kept while aligning.
//! - `bad_samples_over_ipc_are_rejected_and_counted`: NaN, time going backwards, a duplicate and a
//!   late `seq` are refused and counted in `Diagnostics`; a second daemon on the domain is
//!   refused.
//!
//! Each test has its own domain (stable name, so no per-run shared-memory files pile up).

use corridor_client::{Delivery, Domain, Producer, Subscriber};
use corridor_service::core::Estimate;
use corridor_service::daemon::{self, DaemonConfig, DaemonReport};
use corridor_service::runner::{heading_aid, run_log};
use corridor_shared::config::{Config, ConfigFile};
use corridor_shared::imu_csv::{ImuCsvOptions, ImuLog, read_imu_csv};
use corridor_shared::injection::BiasInjection;
use corridor_shared::services::ServiceError;
use corridor_shared::wire::{
    AttitudeSample, Diagnostics, FLAG_CONVERGED, FLAG_END_OF_STREAM, ImuSample,
};
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

const WAIT: Duration = Duration::from_secs(60);

/// A bundled recording's IMU log.
fn bundled_walk(name: &str) -> ImuLog {
    let path = manifest().join("data").join(name).join("imu.csv");
    read_imu_csv(&path, &ImuCsvOptions::default()).unwrap()
}

fn manifest() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn config() -> Config {
    let path = manifest().join("../configs/gdins.toml");
    ConfigFile::read(&path)
        .expect("config reads")
        .validate()
        .expect("config is valid")
}

struct Running {
    shutdown: Arc<AtomicBool>,
    handle: JoinHandle<Result<DaemonReport, daemon::DaemonError>>,
}

impl Running {
    fn start(cfg: DaemonConfig) -> Self {
        let shutdown = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&shutdown);
        let handle = std::thread::Builder::new()
            .name("test-daemon".into())
            .spawn(move || daemon::run(cfg, flag))
            .unwrap();
        Self { shutdown, handle }
    }

    fn stop(self) -> DaemonReport {
        self.shutdown.store(true, Ordering::Relaxed);
        self.handle.join().unwrap().expect("daemon ran cleanly")
    }
}

/// Reads diagnostics until the end-of-stream one.
fn diagnostics_at_end(sub: &Subscriber<Diagnostics>) -> Diagnostics {
    loop {
        let d = sub
            .recv_timeout(WAIT)
            .unwrap()
            .expect("diagnostics before timeout");
        if d.flags & FLAG_END_OF_STREAM != 0 {
            return d;
        }
    }
}

#[test]
fn replay_matches_offline_run_sample_by_sample() {
    let _one = one_daemon_at_a_time();
    let log = bundled_walk("gdins_exp36_corridor_out_and_back");
    let (offline, counters, report) = replay_and_compare(&log, "test_daemon_replay");
    // The walk is long enough for the flag to rise (the estimate has absorbed 95 % of an error
    // in the rest-mean bias): the comparison covered both states.
    assert!(offline.iter().any(|e| e.converged) && !offline[0].converged);
    assert_eq!(counters.gaps, 0);
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
}

#[test]
fn a_gap_filled_from_the_stride_before_is_the_same_through_the_daemon() {
    // 0.3 s cut out of a swing (issue 9; `estimator.max_fill_s`): the daemon fills it from its
    // own memory of the stride before, exactly as the offline run does.
    let _one = one_daemon_at_a_time();
    let mut log = bundled_walk("gdins_exp36_corridor_out_and_back");
    log.rows.drain(9000..9060);
    let (_, counters, _) = replay_and_compare(&log, "test_daemon_replay_gap");
    assert_eq!((counters.gaps, counters.gaps_filled), (1, 1));
}

#[test]
fn late_footfalls_are_the_same_through_the_daemon() {
    // Fast gait (issue 9; `detector.late_stance_min_s`, `detector.overdue_stride_factor`): the
    // step that updates a missed footfall late propagates the filter again through the samples
    // since, from the stride memory, in the daemon as offline.
    let _one = one_daemon_at_a_time();
    let log = bundled_walk("gdins_exp38_zigzag_extreme");
    let (offline, counters, _) = replay_and_compare(&log, "test_daemon_replay_late");
    assert!(counters.late_footfalls >= 2, "{counters:?}");
    let late = offline
        .iter()
        .filter(|e| e.late_footfall_t_s.is_some())
        .count();
    assert_eq!(late as u64, counters.late_footfalls);
}

#[test]
fn a_start_in_fast_gait_that_goes_back_is_the_same_through_the_daemon() {
    // A daemon started while the wearer walks fast (issue 9; `alignment.fast_gait_replay_s`):
    // the start goes back to the first stance the fast-gait rule takes, and the filter runs
    // over the samples kept since inside one step, in the daemon as offline.
    let _one = one_daemon_at_a_time();
    let mut log = bundled_walk("gdins_exp38_zigzag_extreme");
    log.rows.retain(|r| r.t_s >= 19.084);
    let (offline, counters, _) = replay_and_compare(&log, "test_daemon_replay_fast_start");
    assert!(counters.start_replayed_ms > 500, "{counters:?}");
    // The first estimate already holds the strides walked since the stance it started on.
    let first = offline
        .iter()
        .find(|e| e.phase != corridor_service::core::estimator::Phase::Aligning)
        .unwrap();
    assert!(first.p_m[0].hypot(first.p_m[1]) > 1.0, "{first:?}");
}

/// Runs `log` offline and through an in-process daemon on domain `domain_name` (lossless, at
/// full speed) and checks that every published attitude equals the offline estimate of its
/// sample, with nothing lost. Returns the offline estimates and counters and the daemon's report.
fn replay_and_compare(
    log: &ImuLog,
    domain_name: &str,
) -> (
    Vec<Estimate>,
    corridor_service::core::Counters,
    DaemonReport,
) {
    let cfg = config();
    let aid = heading_aid(&cfg, None).unwrap();
    let mut offline: Vec<Estimate> = Vec::with_capacity(log.rows.len());
    let outcome = run_log(log, &cfg, &aid, &BiasInjection::default(), |_, e| {
        offline.push(*e)
    });
    assert!(outcome.refused.is_empty());
    assert_eq!(offline.len(), log.rows.len());

    let domain = Domain::new(domain_name).unwrap();
    // No accounting file of an earlier run (counters, output seq continue across daemon lives).
    let _ = std::fs::remove_file(domain.daemon_state_path());
    let mut dcfg = DaemonConfig::new(domain.clone(), cfg, aid);
    dcfg.delivery = Delivery::Lossless;
    let daemon = Running::start(dcfg);
    let attitude = Subscriber::<AttitudeSample>::open(&domain, "test-attitude", WAIT).unwrap();
    let diagnostics = Subscriber::<Diagnostics>::open(&domain, "test-diagnostics", WAIT).unwrap();

    // The producer on its own thread: with the lossless policy it blocks while this thread is
    // not reading (iceoryx2 ports are !Send, so it is created there).
    let rows = log.rows.clone();
    let producer = std::thread::spawn(move || {
        let mut p = Producer::new(&domain, "test-replay", Delivery::Lossless).unwrap();
        p.wait_for_daemon(WAIT).unwrap();
        for r in &rows {
            p.send_imu(ImuSample::from(r)).unwrap();
        }
        p.finish().unwrap();
        p.stats()
    });

    let mut got: Vec<AttitudeSample> = Vec::with_capacity(offline.len());
    loop {
        let a = attitude
            .recv_timeout(WAIT)
            .unwrap()
            .unwrap_or_else(|| panic!("attitude timed out after {} samples", got.len()));
        if a.flags & FLAG_END_OF_STREAM != 0 {
            assert_eq!(
                a.imu_seq,
                offline.len() as u64,
                "marker carries the last seq"
            );
            break;
        }
        got.push(a);
    }
    let stats = producer.join().unwrap();
    assert_eq!(stats.imu_sent, offline.len() as u64 + 1);
    assert_eq!(stats.imu_undelivered, 0);

    assert_eq!(
        got.len(),
        offline.len(),
        "every sample reached the subscriber"
    );
    for (i, (a, e)) in got.iter().zip(&offline).enumerate() {
        assert_eq!(a.seq, i as u64, "attitude seq contiguous");
        assert_eq!(a.imu_seq, i as u64, "input seq contiguous");
        assert_eq!(a.t_s.to_bits(), e.t_s.to_bits(), "t_s at {i}");
        let close = |x: f64, y: f64| x == y || (x - y).abs() <= 1e-12;
        for k in 0..3 {
            assert!(
                close(a.gyro_bias_rad_s[k], e.gyro_bias_rad_s[k]),
                "bias[{k}] at sample {i}: {} vs {}",
                a.gyro_bias_rad_s[k],
                e.gyro_bias_rad_s[k]
            );
            assert!(
                close(a.gyro_bias_sd_rad_s[k], e.gyro_bias_sd_rad_s[k])
                    || (a.gyro_bias_sd_rad_s[k].is_nan() && e.gyro_bias_sd_rad_s[k].is_nan()),
                "bias sd[{k}] at sample {i}"
            );
        }
        for k in 0..4 {
            assert!(
                close(a.nav_from_body_wxyz[k], e.nav_from_body[k]),
                "q[{k}] at sample {i}"
            );
        }
        assert!(close(a.roll_rad, e.roll_rad), "roll at {i}");
        assert!(close(a.pitch_rad, e.pitch_rad), "pitch at {i}");
        assert!(close(a.yaw_rad, e.yaw_rad), "yaw at {i}");
        assert_eq!(
            a.flags & FLAG_CONVERGED != 0,
            e.converged,
            "convergence flag at sample {i}"
        );
    }
    let d = diagnostics_at_end(&diagnostics);
    assert_eq!(d.received, offline.len() as u64 + 1);
    assert_eq!(d.accepted, offline.len() as u64);
    assert_eq!(
        (
            d.seq_gaps,
            d.dropped_overflow,
            d.rejected_duplicate_seq,
            d.late
        ),
        (0, 0, 0, 0)
    );
    assert_eq!((d.rejected_non_finite, d.rejected_time), (0, 0));
    assert_eq!(d.stances, outcome.counters.stances);

    let report = daemon.stop();
    assert_eq!(report.streams_finished, 1);
    assert_eq!(report.diagnostics.accepted, offline.len() as u64);
    (offline, outcome.counters, report)
}

/// A lossless daemon on `name`, fresh (no accounting file of an earlier run: counters and output
/// seq continue across daemon lives), with its configuration and a diagnostics subscriber.
fn fresh_daemon(name: &str) -> (Domain, DaemonConfig, Running, Subscriber<Diagnostics>) {
    let cfg = config();
    let aid = heading_aid(&cfg, None).unwrap();
    let domain = Domain::new(name).unwrap();
    let _ = std::fs::remove_file(domain.daemon_state_path());
    let mut dcfg = DaemonConfig::new(domain.clone(), cfg, aid);
    dcfg.delivery = Delivery::Lossless;
    let daemon = Running::start(dcfg.clone());
    let diagnostics = Subscriber::<Diagnostics>::open(&domain, "test-diagnostics", WAIT).unwrap();
    (domain, dcfg, daemon, diagnostics)
}

/// A still sensor's sample.
fn still(seq: u64, t_s: f64) -> ImuSample {
    ImuSample {
        seq,
        t_s,
        gyro_rad_s: [0.001, -0.002, 0.003],
        accel_m_s2: [0.0, 0.0, 9.81],
        temp_c: f64::NAN,
        ..ImuSample::default()
    }
}

#[test]
fn bad_samples_over_ipc_are_rejected_and_counted() {
    let _one = one_daemon_at_a_time();
    let (domain, dcfg, daemon, diagnostics) = fresh_daemon("test_daemon_reject");

    // A second daemon on the same domain is refused with a clear error.
    let err = daemon::run(dcfg, Arc::new(AtomicBool::new(true))).unwrap_err();
    assert!(
        matches!(
            &err,
            daemon::DaemonError::Service(ServiceError::DaemonAlreadyRunning { domain, .. })
                if domain == "test_daemon_reject"
        ),
        "{err}"
    );

    let mut p = Producer::new(&domain, "test-bad-producer", Delivery::Lossless).unwrap();
    p.wait_for_daemon(WAIT).unwrap();
    let at = still;
    let dt = 0.005;
    let mut sent = 0u64;
    let mut send = |s: ImuSample| {
        p.send_imu_raw(s).unwrap();
        sent += 1;
    };
    for i in 0..5 {
        send(at(i, i as f64 * dt)); // 0..4 good
    }
    let mut nan = at(5, 5.0 * dt);
    nan.gyro_rad_s[1] = f64::NAN;
    send(nan); // refused by the estimator: non-finite
    send(at(6, 2.0 * dt)); // refused by the estimator: time backwards
    send(at(7, 7.0 * dt)); // good
    send(at(7, 8.0 * dt)); // duplicate seq
    send(at(6, 9.0 * dt)); // late seq
    send(at(10, 10.0 * dt)); // good, after a gap of 2 (seq 8 and 9)
    let mut absurd = at(11, 11.0 * dt);
    absurd.gyro_rad_s[2] = 1e6;
    send(absurd); // refused by the estimator: implausible
    send(at(12, 60.0)); // refused by the estimator: a jump the next sample does not confirm
    send(at(13, 13.0 * dt)); // good
    p.finish().unwrap();
    sent += 1;
    assert_eq!(p.stats().imu_undelivered, 0);

    let d = diagnostics_at_end(&diagnostics);
    assert_eq!(d.received, sent);
    assert_eq!(d.rejected_non_finite, 1);
    assert_eq!(d.rejected_time, 1);
    assert_eq!(d.rejected_duplicate_seq, 1);
    assert_eq!(d.late, 1);
    assert_eq!(d.seq_gaps, 2);
    assert_eq!(d.accepted, 8);
    assert_eq!(d.dropped_overflow, 0);

    let report = daemon.stop();
    assert_eq!(report.diagnostics.rejected_non_finite, 1);
    // On the wire since v4 (before: in the report only).
    assert_eq!((d.rejected_implausible, d.rejected_time_jump), (1, 1));
    assert_eq!(
        (
            report.diagnostics.rejected_implausible,
            report.diagnostics.rejected_time_jump
        ),
        (1, 1)
    );
    assert_eq!(report.streams_finished, 1);
}

#[test]
fn a_device_clock_that_restarts_starts_a_new_stream() {
    // The same producer, its clock reset mid-stream (a device reset, a wrapped counter): the
    // estimator refused every later sample until the new clock passed the old one.
    let _one = one_daemon_at_a_time();
    let (domain, _, daemon, diagnostics) = fresh_daemon("test_daemon_clock_reset");
    let mut p = Producer::new(&domain, "test-reset-producer", Delivery::Lossless).unwrap();
    p.wait_for_daemon(WAIT).unwrap();
    let dt = 0.005;
    let at = still;
    for i in 0..600 {
        p.send_imu_raw(at(i, 1000.0 + i as f64 * dt)).unwrap();
    }
    // A stray earlier stamp and a short replayed burst are refused, not a restart.
    p.send_imu_raw(at(600, 10.0)).unwrap();
    for i in 0..50 {
        p.send_imu_raw(at(601 + i, 1000.0 + i as f64 * dt)).unwrap();
    }
    // The clock restarts at 0 and runs on: 1 s of it is refused, then a new stream.
    for i in 0..600 {
        p.send_imu_raw(at(651 + i, i as f64 * dt)).unwrap();
    }
    p.finish().unwrap();
    // The first end of stream published is the restart's.
    let first = diagnostics_at_end(&diagnostics);
    assert_eq!((first.accepted, first.t_s), (600, 1000.0 + 599.0 * dt));
    let report = daemon.stop();
    assert_eq!(report.streams_finished, 2, "{report:?}");
    let d = report.diagnostics;
    assert_eq!(d.rejected_time, 1 + 50 + 200, "{d:?}");
    assert_eq!(d.accepted, 600 + 400, "{d:?}");
}

/// One daemon per process at a time (see `daemon_common::one_daemon_at_a_time` in the other
/// daemon tests: two concurrent daemons in one process sometimes lose the IMU connection).
fn one_daemon_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    static ONE: std::sync::Mutex<()> = std::sync::Mutex::new(());
    ONE.lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}
