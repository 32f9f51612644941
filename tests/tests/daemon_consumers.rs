//! Consumers and producers coming and going around a running daemon (in-process, each test on
//! its own domain).
//!
//! - `consumers_come_and_go_and_a_stalled_one_does_not_stall_the_estimator` (`live`): three
//!   attitude readers and a bias reader at once; one is dropped mid-stream, one never reads.
//!   The reading ones get every message, the producer and the daemon lose nothing, and the
//!   stalled reader finds the newest messages with its losses counted from `seq`.
//! - `producer_restarted_mid_stream_is_counted_and_handled` (`lossless`): a producer vanishes
//!   mid-stream; its successor restarts `seq` and clock (the daemon ends the old stream and the
//!   new one matches the offline run exactly), a third one continues the numbering after a gap
//!   (counted as a gap, same stream).
//! - `client_tools_replay_record_and_track_a_whole_stream` (`lossless`): the client's replay,
//!   record and track loops (the tools' and the demo's) lose nothing and stop at the end of
//!   stream.

mod daemon_common;

use corridor_client::{Delivery, Domain, Producer, Subscriber};
use corridor_service::core::Estimate;
use corridor_service::runner::{heading_aid, run_log};
use corridor_shared::imu_csv::{ImuCsvOptions, ImuLog, read_imu_csv};
use corridor_shared::injection::BiasInjection;
use corridor_shared::services::Topic;
use corridor_shared::wire::{
    AttitudeSample, BiasSample, Diagnostics, FLAG_END_OF_STREAM, ImuSample,
};
use daemon_common::*;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Reads attitude on its own thread (ports are `!Send`): until the end-of-stream marker, or
/// until `limit` messages then drops the reader. Returns the messages and `missed()`.
fn reader(
    domain: &Domain,
    name: &'static str,
    limit: Option<usize>,
    progress: Arc<AtomicU64>,
) -> std::thread::JoinHandle<(Vec<AttitudeSample>, u64)> {
    let domain = domain.clone();
    let (tx, rx) = std::sync::mpsc::sync_channel(1);
    let h = std::thread::Builder::new()
        .name(name.into())
        .spawn(move || {
            let sub = Subscriber::<AttitudeSample>::open(&domain, name, WAIT).unwrap();
            tx.send(()).unwrap();
            let mut v = Vec::new();
            loop {
                let a = sub
                    .recv_timeout(WAIT)
                    .unwrap()
                    .unwrap_or_else(|| panic!("{name}: timeout after {}", v.len()));
                v.push(a);
                progress.store(a.imu_seq, Ordering::Relaxed);
                if a.flags & FLAG_END_OF_STREAM != 0 || limit.is_some_and(|l| v.len() >= l) {
                    return (v, sub.missed());
                }
            }
        })
        .unwrap();
    rx.recv_timeout(WAIT).expect("reader connected");
    h
}

fn assert_contiguous(name: &str, v: &[AttitudeSample]) {
    for (i, a) in v.iter().enumerate() {
        assert_eq!(a.seq, i as u64, "{name}: attitude seq at {i}");
    }
}

#[test]
fn consumers_come_and_go_and_a_stalled_one_does_not_stall_the_estimator() {
    let _one = one_daemon_at_a_time();
    let name = "test_daemon_consumers";
    cleanup_domain(name);
    let domain = Domain::new(name).unwrap();
    let daemon = Running::start(daemon_config(&domain, Delivery::Live));

    let rows = exp36_rows();
    let n = rows.len();
    let progress = Arc::new(AtomicU64::new(0));
    let a = reader(&domain, "test-reader-a", None, Arc::clone(&progress));
    let b = reader(
        &domain,
        "test-reader-b",
        Some(3000),
        Arc::new(AtomicU64::new(0)),
    );
    let stalled = Subscriber::<AttitudeSample>::open(&domain, "test-stalled", WAIT).unwrap();
    let bias = Subscriber::<BiasSample>::open(&domain, "test-bias", WAIT).unwrap();
    let diag = Subscriber::<Diagnostics>::open(&domain, "test-diag", WAIT).unwrap();

    // 20× real time (4 kHz), beyond a reader's 4096-sample buffer within a second, but never
    // more than 1024 samples ahead of what the reading consumer got: a debug build on a loaded
    // machine estimates slower than 4 kHz, and the live input would drop what it cannot take.
    let start = Instant::now();
    let producer = {
        let domain = domain.clone();
        let progress = Arc::clone(&progress);
        std::thread::spawn(move || {
            let mut p = Producer::new(&domain, "test-sensor", Delivery::Live).unwrap();
            p.wait_for_daemon(WAIT).unwrap();
            let t0 = rows[0].t_s;
            let start = Instant::now();
            for (k, r) in rows.iter().enumerate() {
                let due = start + Duration::from_secs_f64((r.t_s - t0) / 20.0);
                std::thread::sleep(due.saturating_duration_since(Instant::now()));
                let deadline = Instant::now() + WAIT;
                while k as u64 > progress.load(Ordering::Relaxed) + 1024 {
                    assert!(Instant::now() < deadline, "the daemon stopped estimating");
                    std::thread::sleep(Duration::from_millis(1));
                }
                p.send_imu(ImuSample::from(r)).unwrap();
            }
            p.finish().unwrap();
            p.stats()
        })
    };
    // The stalled reader takes one message (the first, unless this thread was late enough for
    // its buffer to turn over: then the ones before are counted as missed at its start), then
    // nothing until the end.
    let first = stalled.recv_timeout(WAIT).unwrap().expect("first attitude");
    let stats = producer.join().unwrap();
    let (got_a, missed_a) = a.join().unwrap();
    let elapsed = start.elapsed();
    let (got_b, missed_b) = b.join().unwrap();
    assert_eq!(stats.imu_undelivered, 0);

    // The reading consumer got everything, in order, whatever the others did.
    assert_eq!(got_a.len(), n + 1, "every attitude and the marker");
    assert_contiguous("a", &got_a);
    assert_eq!(missed_a, 0);
    assert_eq!(got_b.len(), 3000, "b read 3000 then went away");
    assert_contiguous("b", &got_b);
    assert_eq!(missed_b, 0);
    // Not stalled: the estimator finished the stream while the stalled reader held its first
    // message and read nothing more (under lossless delivery this would never finish). The
    // bound is a deadlock guard only, generous for a loaded machine; speed is benchmarked in
    // benches/ipc_latency.rs, not asserted here.
    assert!(
        elapsed < Duration::from_secs(120),
        "took {elapsed:?}: the stalled reader stalled the daemon"
    );

    // The stalled reader finds the newest messages (its buffer), the rest counted lost.
    let mut kept = Vec::new();
    while let Some(x) = stalled.try_recv().unwrap() {
        kept.push(x);
    }
    assert_eq!(kept.len(), AttitudeSample::QOS.buffer_size);
    assert!(kept.last().unwrap().flags & FLAG_END_OF_STREAM != 0);
    assert_eq!(kept[0].seq, (n + 1 - kept.len()) as u64, "oldest dropped");
    assert_eq!(
        stalled.missed(),
        (n + 1 - kept.len() - 1) as u64 - first.seq,
        "losses counted"
    );

    // The bias reader and diagnostics: nothing lost on the input side.
    let biases = until_end(&bias, |b| b.flags);
    assert!(biases.len() > 60, "{}", biases.len());
    assert_eq!(bias.missed(), 0);
    // Each bias sample says how much of a start error it still carries: it falls as the walk
    // goes on, and the flag is set only below the configured 5 %.
    let carried: Vec<f64> = biases
        .iter()
        .map(|b| b.bias_unabsorbed)
        .filter(|u| u.is_finite())
        .collect();
    assert!(
        carried.len() > 60 && carried[carried.len() - 1] < 0.5 * carried[0],
        "{carried:?}"
    );
    for b in &biases {
        assert!(b.converged == 0 || b.bias_unabsorbed < 0.05, "{b:?}");
    }
    let all = until_end(&diag, |d| d.flags);
    let d = all.last().unwrap();
    assert_eq!(d.accepted, n as u64);
    assert_eq!((d.seq_gaps, d.dropped_overflow, d.late), (0, 0, 0));
    assert_eq!(d.producer_changes, 0);
    // Latency is measured (a value, not a target: see benches/ipc_latency.rs), in a periodic
    // diagnostics message (the end-of-stream one may come right after a periodic one, with
    // no sample in its window).
    assert!(
        all.iter()
            .any(|x| x.latency_p50_s > 0.0 && x.latency_p99_s >= x.latency_p50_s),
        "{all:?}"
    );
    // Between streams the periodic diagnostics say so too (a review found `corridor status`
    // showing the next stream's aligning estimator beside the ended stream's convergence).
    let next = diag
        .recv_timeout(WAIT)
        .unwrap()
        .expect("a periodic diagnostics message");
    assert!(next.flags & FLAG_END_OF_STREAM != 0, "{next:?}");
    drop((stalled, bias, diag));
    let report = daemon.stop();
    assert_eq!(report.streams_finished, 1);
    cleanup_domain(name);
}

fn exp36_log() -> ImuLog {
    let path = manifest().join("data/gdins_exp36_corridor_out_and_back/imu.csv");
    read_imu_csv(&path, &ImuCsvOptions::default()).unwrap()
}

#[test]
fn producer_restarted_mid_stream_is_counted_and_handled() {
    let _one = one_daemon_at_a_time();
    let name = "test_daemon_producer_restart";
    cleanup_domain(name);
    let domain = Domain::new(name).unwrap();
    let daemon = Running::start(daemon_config(&domain, Delivery::Lossless));
    let log = exp36_log();
    let cfg = config();
    let aid = heading_aid(&cfg, None).unwrap();
    let mut offline: Vec<Estimate> = Vec::new();
    run_log(&log, &cfg, &aid, &BiasInjection::default(), |_, e| {
        offline.push(*e)
    });
    let rows = log.rows;
    let (k1, k2, gap, k3) = (6000usize, 5000usize, 10usize, 3000usize);

    let a = AttitudeReader::start(&domain, 2);
    let diag = Subscriber::<Diagnostics>::open(&domain, "test-diag", WAIT).unwrap();

    // P1 sends part of the log and vanishes (no end-of-stream marker).
    {
        let mut p = Producer::new(&domain, "test-p1", Delivery::Lossless).unwrap();
        p.wait_for_daemon(WAIT).unwrap();
        for r in &rows[..k1] {
            p.send_imu(ImuSample::from(r)).unwrap();
        }
        a.wait_for(k1 as u64);
    }
    // P2: a restarted driver, seq and clock from the start.
    {
        let mut p = Producer::new(&domain, "test-p2", Delivery::Lossless).unwrap();
        p.wait_for_daemon(WAIT).unwrap();
        for r in &rows[..k2] {
            p.send_imu(ImuSample::from(r)).unwrap();
        }
        a.wait_for((k1 + 1 + k2) as u64);
    }
    // P3: continues P2's numbering and clock after `gap` lost samples.
    {
        let mut p = Producer::new(&domain, "test-p3", Delivery::Lossless).unwrap();
        p.wait_for_daemon(WAIT).unwrap();
        for (i, r) in rows[k2 + gap..k2 + gap + k3].iter().enumerate() {
            let mut s = ImuSample::from(r);
            s.seq = (k2 + gap + i) as u64;
            p.send_imu_raw(s).unwrap();
        }
        p.finish().unwrap();
        // P3 stays until its stream was taken: a publisher dropped before the daemon attached
        // its side of the connection takes its queued samples with it.
        a.wait_for((k1 + 1 + k2 + k3 + 1) as u64);
    }
    let got = a.join();
    assert_eq!(got.len(), k1 + 1 + k2 + k3 + 1);
    // P1's stream, ended by the daemon when P2's clock went back.
    let end1 = &got[k1];
    assert!(
        end1.flags & FLAG_END_OF_STREAM != 0,
        "implicit end of stream"
    );
    assert_eq!(end1.imu_seq, (k1 - 1) as u64);
    // P2's stream starts afresh: exactly the offline run (cold start, no checkpoint), and P3's
    // samples continue it.
    let second = &got[k1 + 1..got.len() - 1];
    let expect_idx = (0..k2).chain(k2 + gap..k2 + gap + k3);
    let mut checked = 0;
    for (a, i) in second.iter().zip(expect_idx) {
        assert_eq!(a.imu_seq, i as u64);
        assert_eq!(a.t_s, rows[i].t_s);
        if i < k2 {
            assert_eq!(a.nav_from_body_wxyz, offline[i].nav_from_body, "sample {i}");
            assert_eq!(a.gyro_bias_rad_s, offline[i].gyro_bias_rad_s, "sample {i}");
            checked += 1;
        }
    }
    assert_eq!(checked, k2);

    let d = until_end(&diag, |d| d.flags);
    // The first end-of-stream diagnostics is the implicit one; read to the second.
    let d = if d.last().unwrap().accepted == (k1 + k2 + k3) as u64 {
        *d.last().unwrap()
    } else {
        *until_end(&diag, |d| d.flags).last().unwrap()
    };
    assert_eq!(d.producer_changes, 2);
    assert_eq!(d.seq_gaps, gap as u64, "P3's gap counted");
    assert_eq!(
        (d.late, d.rejected_duplicate_seq, d.rejected_time),
        (0, 0, 0)
    );
    assert_eq!(d.accepted, (k1 + k2 + k3) as u64);
    drop(diag);
    let report = daemon.stop();
    assert_eq!(report.streams_finished, 2);
    cleanup_domain(name);
}

/// The client tools' loops ([`replay`], [`Recorder`], [`Tracker`]: what `corridor-replay`,
/// `corridor-log`, `corridor-pdr` and `corridor demo` run) around a daemon, lossless at full
/// speed: nothing is lost, the logger's files hold every accepted sample and stop at the end of
/// stream, the tracker reports one stride per stance with its path.
#[test]
fn client_tools_replay_record_and_track_a_whole_stream() {
    use corridor_client::csv_rows::{ATTITUDE_HEADER, BIAS_HEADER};
    use corridor_client::record::{RecordOptions, RecordStop, Recorder};
    use corridor_client::replay::replay;
    use corridor_client::track::{TrackStop, Tracker};
    use std::sync::atomic::AtomicBool;

    let _one = one_daemon_at_a_time();
    let name = "test_daemon_tools";
    cleanup_domain(name);
    let domain = Domain::new(name).unwrap();
    let poll = Duration::from_millis(50);
    let record_opts = |node: &str| RecordOptions {
        node_name: node.into(),
        wait: WAIT,
        idle_timeout: WAIT,
        idle_before_first: true,
        poll,
    };
    // A logger that cannot attach leaves an earlier recording as it was (it emptied it).
    let earlier = temp_dir("test-daemon-tools-earlier");
    std::fs::write(earlier.join("attitude.csv"), "an earlier recording\n").unwrap();
    let no_daemon = RecordOptions {
        wait: Duration::from_millis(200),
        ..record_opts("test-log-early")
    };
    assert!(Recorder::open(&domain, &earlier, &no_daemon).is_err());
    assert_eq!(
        std::fs::read_to_string(earlier.join("attitude.csv")).unwrap(),
        "an earlier recording\n"
    );
    let dir = temp_dir("test-daemon-tools");
    // With a checkpoint path the second stream starts from the bias the first left.
    let mut dcfg = daemon_config(&domain, Delivery::Lossless);
    dcfg.checkpoint = Some(dir.join("checkpoint.bin"));
    let daemon = Running::start(dcfg);
    // A logger that attaches and receives nothing (here: no stream yet, a short idle timeout)
    // leaves the earlier recording as it was too (it emptied it: a review), and no partial file.
    let idle = RecordOptions {
        idle_timeout: Duration::from_millis(300),
        ..record_opts("test-log-idle")
    };
    let got = Recorder::open(&domain, &earlier, &idle)
        .unwrap()
        .run(&AtomicBool::new(false))
        .unwrap();
    assert_eq!(got.stopped, RecordStop::IdleTimeout);
    assert!(got.kept_earlier_files);
    assert_eq!(
        std::fs::read_to_string(earlier.join("attitude.csv")).unwrap(),
        "an earlier recording\n"
    );
    assert!(!earlier.join("attitude.csv.partial").exists());
    assert!(!earlier.join("bias.csv.partial").exists());
    let rows = exp36_rows();
    let never = Arc::new(AtomicBool::new(false));
    let (ready_tx, ready_rx) = std::sync::mpsc::channel();

    let recorder = {
        let (domain, dir, ready, never) = (
            domain.clone(),
            dir.to_path_buf(),
            ready_tx.clone(),
            Arc::clone(&never),
        );
        let opts = record_opts("test-log");
        std::thread::spawn(move || {
            let r = Recorder::open(&domain, &dir, &opts).unwrap();
            ready.send(()).unwrap();
            r.run(&never).unwrap()
        })
    };
    let tracker = {
        let (domain, ready, never) = (domain.clone(), ready_tx, Arc::clone(&never));
        std::thread::spawn(move || {
            let t = Tracker::open(&domain, "test-pdr", WAIT).unwrap();
            ready.send(()).unwrap();
            let mut strides = Vec::new();
            let track = t
                .run(poll, Some(WAIT), &never, |s| strides.push(*s))
                .unwrap();
            (track, strides)
        })
    };
    for _ in 0..2 {
        ready_rx.recv_timeout(WAIT).expect("consumer attached");
    }
    let sent = replay(&domain, &rows, &lossless_at_full_speed()).unwrap();
    let rec = recorder.join().unwrap();
    let (track, strides) = tracker.join().unwrap();

    // A logger and a tracker started between two streams record the next one. The bias and
    // nav streams keep their last message, the first stream's end, for late readers: it ended
    // both at once (a review: "end of stream: 58 strides" for a tracker started after it, and
    // a logger that then stopped idle with 0 rows while the next stream went unlogged).
    let dir2 = temp_dir("test-daemon-tools-2");
    let (rec2, track2) = std::thread::scope(|scope| {
        let (ready, attached) = std::sync::mpsc::channel();
        let ready2 = ready.clone();
        let (domain, dir2, never) = (&domain, &dir2, &never);
        // As `corridor-log` runs by default: the idle timeout only after a first message.
        let opts2 = RecordOptions {
            idle_timeout: Duration::from_secs(1),
            idle_before_first: false,
            ..record_opts("test-log-2")
        };
        let rec2 = scope.spawn(move || {
            let r = Recorder::open(domain, dir2, &opts2).unwrap();
            ready.send(()).unwrap();
            r.run(never).unwrap()
        });
        let track2 = scope.spawn(move || {
            let t = Tracker::open(domain, "test-pdr-2", WAIT).unwrap();
            ready2.send(()).unwrap();
            t.run(poll, Some(WAIT), never, |_| {}).unwrap()
        });
        for _ in 0..2 {
            attached.recv_timeout(WAIT).expect("consumer attached");
        }
        // The next stream comes later: after the daemon's idle refresh of its readers (every
        // diagnostics period, 1 s), which hands them the history, and the idle timeout.
        std::thread::sleep(Duration::from_millis(3000));
        replay(domain, &rows[..4000], &lossless_at_full_speed()).unwrap();
        (rec2.join().unwrap(), track2.join().unwrap())
    });

    let report = daemon.stop();
    assert_eq!(report.streams_warm_started, 1, "the second stream, warm");
    let both = report.diagnostics;
    assert_eq!(rec2.stopped, RecordStop::EndOfStream);
    assert_eq!(track2.stopped, TrackStop::EndOfStream);
    assert!(rec2.attitude_rows > 3900, "{} rows", rec2.attitude_rows);
    // What was published before its first message is all the first stream's, and it says so
    // (a review read the count as this stream's); the first logger attached before any stream.
    assert!(rec2.attached_between_streams && !rec.attached_between_streams);
    assert_eq!(rec2.attitude_missed_at_start, rec.attitude_received);
    assert_eq!(
        (rec.imu_without_attitude, rec2.imu_without_attitude),
        (0, 0)
    );
    assert!(track2.strides > 0 && Some(track2.strides) == track2.end_stances);
    assert_eq!((rec.open_stream_rows, rec2.open_stream_rows), (0, 0));
    assert_eq!((rec.retracting_rows, rec2.retracting_rows), (0, 0));
    // The daemon's counts are the two streams'; the first stream's are checked below.
    let d = Diagnostics {
        accepted: both.accepted - rec2.attitude_rows,
        stances: both.stances - track2.strides,
        ..both
    };

    assert_eq!(sent.samples, rows.len() as u64);
    assert_eq!(sent.stats.imu_sent, rows.len() as u64 + 1, "and the marker");
    assert_eq!(sent.stats.imu_undelivered, 0);
    assert!(!sent.interrupted);
    assert_eq!(d.accepted, rows.len() as u64);

    assert_eq!(rec.stopped, RecordStop::EndOfStream);
    assert_eq!(rec.attitude_rows, d.accepted);
    assert_eq!((rec.attitude_missed, rec.bias_missed), (0, 0));
    assert!(rec.bias_rows > 0);
    assert_eq!(rec.final_bias_rad_s, Some(rec.last_attitude_bias_rad_s));
    let att = std::fs::read_to_string(&rec.attitude_path).unwrap();
    assert_eq!(att.lines().next(), Some(ATTITUDE_HEADER));
    assert_eq!(att.lines().count() as u64, rec.attitude_rows + 1);
    let bias = std::fs::read_to_string(&rec.bias_path).unwrap();
    assert_eq!(bias.lines().next(), Some(BIAS_HEADER));
    assert_eq!(bias.lines().count() as u64, rec.bias_rows + 1);
    // The stream's end is its last row: the final bias, marked (it was left out).
    let last: Vec<&str> = bias.lines().last().unwrap().split(',').collect();
    assert_eq!(last.last(), Some(&"1"), "{last:?}");
    let final_bias = rec.final_bias_rad_s.unwrap();
    for (axis, b) in final_bias.iter().enumerate() {
        assert_eq!(last[3 + axis].parse::<f64>().unwrap(), *b);
    }
    let ends = bias.lines().filter(|l| l.ends_with(",1")).count();
    assert_eq!(ends, 1, "one stream, one end");

    assert_eq!(track.stopped, TrackStop::EndOfStream);
    assert!(d.stances > 0);
    assert_eq!(track.end_stances, Some(d.stances));
    assert_eq!(track.strides, d.stances);
    // Stance 1 comes twice: as it began, and again in the map frame the start heading set
    // during it (before, it stayed in the frame before: 1.5 m off, and the step to stance 2
    // 2.99 m, a review).
    let again: Vec<_> = strides.iter().filter(|s| s.replaces_previous).collect();
    assert_eq!(again.len(), 1, "{again:?}");
    assert!(again[0].frame_set && again[0].nav.stance == 1, "{again:?}");
    assert_eq!(strides.len() as u64, track.strides + 1);
    let longest = strides.iter().map(|s| s.step_m).fold(0.0, f64::max);
    assert!(longest < 2.0, "a step no foot takes: {longest} m");
    assert_eq!(track.missed, 0);
    assert_eq!(strides.first().map(|s| s.step_m), Some(0.0));
    assert_eq!(track.path_m, strides.iter().map(|s| s.step_m).sum::<f64>());
    assert_eq!(track.last.map(|n| n.stance), Some(d.stances));
    cleanup_domain(name);
}

/// A stream that pauses longer than the logger's idle timeout: the logger says it stopped
/// within a stream, with the rows it has of it (`corridor-log` said nothing and exited with 0:
/// a review).
#[test]
fn a_logger_that_times_out_within_a_stream_says_so() {
    use corridor_client::record::{RecordOptions, RecordStop, Recorder};
    use std::sync::atomic::AtomicBool;

    let _one = one_daemon_at_a_time();
    let name = "test_daemon_log_pause";
    cleanup_domain(name);
    let domain = Domain::new(name).unwrap();
    let daemon = Running::start(daemon_config(&domain, Delivery::Lossless));
    let rows = exp36_rows();
    let dir = temp_dir("test-daemon-log-pause");
    // An output that is a file: said as such (it read "File exists (os error 17)").
    let file = dir.join("a-file");
    std::fs::write(&file, "").unwrap();
    let opts = RecordOptions {
        node_name: "test-log-file".into(),
        wait: WAIT,
        idle_timeout: WAIT,
        idle_before_first: false,
        poll: Duration::from_millis(50),
    };
    let err = Recorder::open(&domain, &file, &opts)
        .unwrap_err()
        .to_string();
    assert!(err.contains("not a directory"), "{err}");
    let never = AtomicBool::new(false);
    let paused = 500;
    let rec = std::thread::scope(|scope| {
        let (ready, attached) = std::sync::mpsc::channel();
        let (domain, dir, never) = (&domain, &dir, &never);
        let opts = RecordOptions {
            node_name: "test-log-pause".into(),
            wait: WAIT,
            idle_timeout: Duration::from_secs(1),
            idle_before_first: false,
            poll: Duration::from_millis(50),
        };
        let rec = scope.spawn(move || {
            let r = Recorder::open(domain, dir, &opts)
                .unwrap()
                .following_new_streams();
            ready.send(()).unwrap();
            r.run(never).unwrap()
        });
        attached.recv_timeout(WAIT).expect("logger attached");
        let mut p = Producer::new(domain, "test-pause", Delivery::Lossless).unwrap();
        p.wait_for_daemon(WAIT).unwrap();
        for r in &rows[..paused] {
            p.send_imu(ImuSample::from(r)).unwrap();
        }
        let rec = rec.join().unwrap();
        p.finish().unwrap();
        rec
    });
    daemon.stop();
    assert_eq!(rec.stopped, RecordStop::IdleTimeout);
    assert_eq!(rec.streams_ended, 0);
    assert_eq!(
        (rec.attitude_rows, rec.open_stream_rows),
        (paused as u64, paused as u64)
    );
    cleanup_domain(name);
}

/// `corridor-replay`'s account of what the daemon did with its samples ([`DaemonWatch`]),
/// against a daemon started just before it: the watch reads the daemon's diagnostics from
/// before the first sample (the daemon publishes its first at once). Before, the first one a
/// fresh daemon published came a period into the stream, and the account said "not finished"
/// with 0 received (3 of 3 replays at `--speed max` right after `corridor serve`).
#[test]
fn the_replays_account_of_a_daemon_started_just_before_it_is_complete() {
    use corridor_client::replay::replay;
    use corridor_client::status::DaemonWatch;

    let _one = one_daemon_at_a_time();
    let name = "test_daemon_fresh_account";
    cleanup_domain(name);
    let domain = Domain::new(name).unwrap();
    let daemon = Running::start(daemon_config(&domain, Delivery::Lossless));
    let watch = DaemonWatch::start(&domain, WAIT, WAIT).expect("the daemon's diagnostics");
    let rows = exp36_rows();
    let sent = replay(&domain, &rows, &lossless_at_full_speed()).unwrap();
    let (account, complete) = watch.finish(sent.samples).expect("an account");
    assert!(complete, "{account:?}");
    assert_eq!(account.received, rows.len() as u64 + 1);
    assert_eq!(account.accepted, rows.len() as u64);
    assert_eq!(account.lost(), 0);
    daemon.stop();
    cleanup_domain(name);
}

/// The replay options of these tests: lossless, as fast as the daemon takes the samples.
fn lossless_at_full_speed() -> corridor_client::replay::ReplayOptions {
    corridor_client::replay::ReplayOptions {
        node_name: "test-replay".into(),
        delivery: Some(Delivery::Lossless),
        speed: corridor_client::replay::Speed::Max,
        loops: 1,
        injection: corridor_shared::injection::BiasInjection::default(),
        wait: WAIT,
    }
}
