//! Latency, CPU, memory and throughput of the daemon over iceoryx2 (prints figures; not a
//! criterion bench).
//!
//! ```text
//! cargo bench -p corridor-service --bench ipc_latency [-- --delivery live|lossless] [--seconds S]
//! ```
//!
//! 1. End to end: this process publishes IMU samples (exp36, paced at 200 Hz then 1 kHz) with
//!    the client `Producer`, a `corridor serve` process (the real binary) estimates, and a
//!    consumer thread here receives the matching `AttitudeSample`. Latency = receipt time minus
//!    the producer's send stamp (`ImuSample::sent_ns`, carried in
//!    `AttitudeSample::imu_sent_ns`), both `CLOCK_MONOTONIC`.
//! 2. Raw iceoryx2 one-way latency of `ImuSample` in the same delivery mode and the same run:
//!    the same `Producer` and an event-driven `Subscriber<ImuSample>` (what the daemon's receive
//!    thread does), no daemon.
//! 3. At 1 kHz: the daemon's CPU per thread (`/proc/<pid>/task/*/schedstat`, ns on CPU) and
//!    its RSS (`/proc/<pid>/status`).
//! 4. Maximum sustained input rate without loss: a lossless daemon fed as fast as the
//!    backpressure allows, every attitude received and checked.

use corridor_client::{Delivery, Domain, Producer, Subscriber};
use corridor_shared::imu_csv::{ImuCsvOptions, ImuRow, read_imu_csv};
use corridor_shared::wire::{AttitudeSample, Diagnostics, ImuSample, monotonic_ns};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

const WAIT: Duration = Duration::from_secs(15);

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn rows() -> Vec<ImuRow> {
    let path = root().join("tests/data/gdins_exp36_corridor_out_and_back/imu.csv");
    read_imu_csv(&path, &ImuCsvOptions::default())
        .expect("exp36 reads")
        .rows
}

/// Sample `i` of the log played in a loop, the clock continuing across loops.
fn looped(rows: &[ImuRow], i: usize) -> ImuSample {
    let n = rows.len();
    let span = rows[n - 1].t_s - rows[0].t_s + 0.005;
    let r = &rows[i % n];
    let mut s = ImuSample::from(r);
    s.t_s += (i / n) as f64 * span;
    s
}

fn cleanup_domain(domain: &str) {
    let prefix = format!("corridor_{domain}_");
    if let Ok(dir) = std::fs::read_dir("/dev/shm") {
        for e in dir.flatten() {
            if e.file_name().to_string_lossy().starts_with(&prefix) {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
}

fn serve(domain: &str, delivery: Delivery) -> Child {
    Command::new(env!("CARGO_BIN_EXE_corridor"))
        .args(["serve", "--domain", domain, "--delivery", delivery.name()])
        .arg("--config")
        .arg(root().join("configs/gdins.toml"))
        .env("RUST_LOG", "warn")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .spawn()
        .expect("corridor serve starts")
}

fn terminate(mut child: Child) {
    let pid = i32::try_from(child.id()).expect("pid");
    // SAFETY: kill(2) on our own child.
    unsafe { libc::kill(pid, libc::SIGTERM) };
    let _ = child.wait();
}

/// Percentiles of latencies in ns, printed in µs.
struct Stats {
    n: usize,
    p50: f64,
    p99: f64,
    p999: f64,
    max: f64,
}

impl Stats {
    fn of(mut v: Vec<u64>) -> Stats {
        assert!(!v.is_empty(), "no latency samples");
        v.sort_unstable();
        let q = |p: f64| v[((p * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1] as f64;
        Stats {
            n: v.len(),
            p50: q(0.5) / 1e3,
            p99: q(0.99) / 1e3,
            p999: q(0.999) / 1e3,
            max: *v.last().unwrap() as f64 / 1e3,
        }
    }
}

impl std::fmt::Display for Stats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "p50 {:7.1} µs  p99 {:7.1} µs  p99.9 {:7.1} µs  max {:8.1} µs  (n = {})",
            self.p50, self.p99, self.p999, self.max, self.n
        )
    }
}

/// Sends `count` samples paced at `rate_hz` (absolute schedule); returns the samples sent.
fn pace(p: &mut Producer, rows: &[ImuRow], first: usize, count: usize, rate_hz: f64) {
    let start = Instant::now();
    for k in 0..count {
        let due = start + Duration::from_secs_f64(k as f64 / rate_hz);
        let now = Instant::now();
        if due > now {
            std::thread::sleep(due - now);
        }
        p.send_imu(looped(rows, first + k)).expect("send");
    }
}

/// Receives `T` on a thread until `stop`, returning the latency of each message.
fn collect<T: corridor_shared::services::Topic>(
    domain: &Domain,
    node: &'static str,
    stop: Arc<AtomicBool>,
    sent_ns: fn(&T) -> u64,
) -> std::thread::JoinHandle<Vec<u64>> {
    let domain = domain.clone();
    let (tx, rx) = std::sync::mpsc::sync_channel(1);
    let h = std::thread::Builder::new()
        .name(node.into())
        .spawn(move || {
            let sub = Subscriber::<T>::open(&domain, node, WAIT).expect("subscriber");
            tx.send(()).unwrap();
            let mut lat = Vec::with_capacity(1 << 16);
            while !stop.load(Ordering::Relaxed) {
                if let Some(m) = sub
                    .recv_timeout(Duration::from_millis(50))
                    .expect("receive")
                {
                    let now = monotonic_ns();
                    let s = sent_ns(&m);
                    if s != 0 && now >= s {
                        lat.push(now - s);
                    }
                }
            }
            lat
        })
        .unwrap();
    rx.recv_timeout(WAIT).expect("subscriber ready");
    h
}

/// CPU time on the daemon's threads, ns, by thread name.
fn thread_cpu_ns(pid: u32) -> Vec<(String, u64)> {
    let mut v = Vec::new();
    if let Ok(dir) = std::fs::read_dir(format!("/proc/{pid}/task")) {
        for t in dir.flatten() {
            let comm = std::fs::read_to_string(t.path().join("comm")).unwrap_or_default();
            let sched = std::fs::read_to_string(t.path().join("schedstat")).unwrap_or_default();
            let ns = sched
                .split_whitespace()
                .next()
                .and_then(|x| x.parse::<u64>().ok())
                .unwrap_or(0);
            v.push((comm.trim().to_owned(), ns));
        }
    }
    v
}

fn status_kib(pid: u32, key: &str) -> u64 {
    std::fs::read_to_string(format!("/proc/{pid}/status"))
        .unwrap_or_default()
        .lines()
        .find_map(|l| l.strip_prefix(key))
        .and_then(|r| r.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}

/// End-to-end latency through a daemon process at each rate; CPU and RSS at the last rate.
fn end_to_end(rows: &[ImuRow], delivery: Delivery, phases: &[(f64, f64)]) -> Vec<Stats> {
    let name = "bench_e2e";
    cleanup_domain(name);
    let domain = Domain::new(name).unwrap();
    let daemon = serve(name, delivery);
    let pid = daemon.id();
    let mut out = Vec::new();
    let mut p = None;
    let mut next = 0;
    for (i, &(rate, secs)) in phases.iter().enumerate() {
        let p = p.get_or_insert_with(|| {
            let p = Producer::new(&domain, "bench-producer", delivery).expect("producer");
            p.wait_for_daemon(WAIT).expect("daemon");
            p
        });
        // Warm-up (alignment, connections), not measured.
        pace(p, rows, next, 200, rate);
        next += 200;
        let stop = Arc::new(AtomicBool::new(false));
        let h = collect::<AttitudeSample>(&domain, "bench-consumer", Arc::clone(&stop), |a| {
            a.imu_sent_ns
        });
        let count = (rate * secs) as usize;
        let cpu0 = thread_cpu_ns(pid);
        let t0 = Instant::now();
        pace(p, rows, next, count, rate);
        next += count;
        let wall = t0.elapsed().as_secs_f64();
        let cpu1 = thread_cpu_ns(pid);
        std::thread::sleep(Duration::from_millis(50));
        stop.store(true, Ordering::Relaxed);
        let lat = h.join().unwrap();
        let stats = Stats::of(lat);
        println!(
            "  end to end, {rate:6.0} Hz, {delivery:>8}: {stats}",
            delivery = delivery.name()
        );
        if i + 1 == phases.len() {
            let mut total = 0;
            for (name, ns1) in &cpu1 {
                let ns0 = cpu0
                    .iter()
                    .find(|(n, _)| n == name)
                    .map_or(0, |(_, ns)| *ns);
                let d = ns1.saturating_sub(ns0);
                total += d;
                if name.starts_with("corridor") {
                    println!(
                        "    daemon thread {name:<16} CPU {:5.2} % of a core",
                        d as f64 / 1e9 / wall * 100.0
                    );
                }
            }
            println!(
                "    daemon process total        CPU {:5.2} % of a core over {wall:.1} s at {rate:.0} Hz",
                total as f64 / 1e9 / wall * 100.0
            );
            println!(
                "    daemon RSS {:.1} MiB (peak {:.1} MiB)",
                status_kib(pid, "VmRSS:") as f64 / 1024.0,
                status_kib(pid, "VmHWM:") as f64 / 1024.0
            );
        }
        out.push(stats);
    }
    drop(p);
    terminate(daemon);
    cleanup_domain(name);
    out
}

/// Raw iceoryx2 one-way latency of `ImuSample`: producer → event-driven subscriber.
fn raw(rows: &[ImuRow], delivery: Delivery, rate: f64, secs: f64) -> Stats {
    let name = "bench_raw";
    cleanup_domain(name);
    let domain = Domain::new(name).unwrap();
    let p = Producer::new(&domain, "bench-raw-producer", delivery).expect("producer");
    let stop = Arc::new(AtomicBool::new(false));
    let h = collect::<ImuSample>(&domain, "bench-raw-consumer", Arc::clone(&stop), |s| {
        s.sent_ns
    });
    let mut p = p;
    p.wait_for_daemon(WAIT).expect("subscriber");
    pace(&mut p, rows, 0, (rate * secs) as usize, rate);
    std::thread::sleep(Duration::from_millis(50));
    stop.store(true, Ordering::Relaxed);
    let mut lat = h.join().unwrap();
    lat.drain(..lat.len().min(20)); // connection set-up
    drop(p);
    cleanup_domain(name);
    let stats = Stats::of(lat);
    println!(
        "  raw iceoryx2, {rate:6.0} Hz, {:>8}: {stats}",
        delivery.name()
    );
    stats
}

/// Lossless daemon fed as fast as it takes; every attitude must arrive.
fn max_rate(rows: &[ImuRow], count: usize) -> f64 {
    let name = "bench_rate";
    cleanup_domain(name);
    let domain = Domain::new(name).unwrap();
    let daemon = serve(name, Delivery::Lossless);
    let (tx, rx) = std::sync::mpsc::sync_channel(1);
    let consumer = {
        let domain = domain.clone();
        std::thread::spawn(move || {
            let sub = Subscriber::<AttitudeSample>::open(&domain, "bench-rate", WAIT).unwrap();
            let diag = Subscriber::<Diagnostics>::open(&domain, "bench-diag", WAIT).unwrap();
            tx.send(()).unwrap();
            let mut got = 0usize;
            let mut first = None;
            while got < count {
                let a = sub.recv_timeout(WAIT).unwrap().expect("attitude in time");
                first.get_or_insert_with(Instant::now);
                got += 1;
                assert_eq!(a.imu_seq as usize, got - 1, "lossless: contiguous");
            }
            let mut last_d = None;
            while let Some(d) = diag.try_recv().unwrap() {
                last_d = Some(d);
            }
            (got, sub.missed(), last_d)
        })
    };
    rx.recv_timeout(WAIT).unwrap();
    let mut p = Producer::new(&domain, "bench-rate-producer", Delivery::Lossless).unwrap();
    p.wait_for_daemon(WAIT).unwrap();
    let t0 = Instant::now();
    for i in 0..count {
        p.send_imu(looped(rows, i)).unwrap();
    }
    let (got, missed, diag) = consumer.join().unwrap();
    let secs = t0.elapsed().as_secs_f64();
    let undelivered = p.stats().imu_undelivered;
    drop(p);
    terminate(daemon);
    cleanup_domain(name);
    let rate = count as f64 / secs;
    println!(
        "  max sustained input, lossless: {rate:9.0} samples/s ({got} of {count} attitudes received, \
         {missed} missed, {undelivered} IMU undelivered, {secs:.2} s; diagnostics gaps {:?})",
        diag.map(|d| d.seq_gaps + d.dropped_overflow)
    );
    rate
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |key: &str| {
        args.iter()
            .position(|a| a == key)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let delivery: Delivery = arg("--delivery")
        .map(|d| d.parse().expect("--delivery live|lossless"))
        .unwrap_or(Delivery::Live);
    let secs: f64 = arg("--seconds")
        .map(|s| s.parse().expect("--seconds S"))
        .unwrap_or(3.0);
    let rows = rows();
    println!(
        "ipc_latency: delivery {}, {secs} s per rate, exp36 in a loop (release build, {} cores)",
        delivery.name(),
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
    let e2e = end_to_end(&rows, delivery, &[(200.0, secs), (1000.0, secs)]);
    let raw200 = raw(&rows, delivery, 200.0, secs);
    let raw1k = raw(&rows, delivery, 1000.0, secs);
    for (label, e, r) in [("200 Hz", &e2e[0], &raw200), ("1 kHz", &e2e[1], &raw1k)] {
        println!(
            "  {label}: end-to-end p99 / raw p99 = {:.2} (target ≤ 3)",
            e.p99 / r.p99
        );
    }
    max_rate(&rows, 200_000);
}
