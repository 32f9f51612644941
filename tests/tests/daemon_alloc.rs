//! No heap allocation per sample on the daemon's receive and estimator threads.
//!
//! This test binary installs a counting global allocator that attributes every allocation to
//! the thread making it (by thread name, resolved once per thread).
//!
//! - `estimator_core_does_not_allocate_per_sample`: `Estimator::step` over exp36 on its own
//!   thread; after the warm-up (alignment, calibration, first heading updates) no allocation
//!   over ~9 700 samples (stances, ZUPTs, heading updates).
//! - `daemon_threads_do_not_allocate_per_sample`: the same replay through an in-process daemon.
//!   Over the same window `corridor-rx` allocates nothing, and `corridor-estimator` allocates
//!   exactly once per message it publishes: iceoryx2 0.10's `Publisher::loan_uninit` boxes a
//!   small `Rc` per loan (`ChunkMutSharedState::new`, freed by `send`), which no public API
//!   avoids. Any allocation of the daemon's own code or of the core breaks the equality.
//!
//! `CORRIDOR_ALLOC_TRACE=1` prints a backtrace for each counted allocation in the window, to
//! find where it comes from.

mod daemon_common;

use corridor_client::{Delivery, Domain, Producer, Subscriber};
use corridor_service::core::{Estimator, ImuInput};
use corridor_service::daemon::{ESTIMATOR_THREAD, RX_THREAD};
use corridor_service::runner::heading_aid;
use corridor_shared::imu_csv::ImuRow;
use corridor_shared::wire::{AttitudeSample, BiasSample, FLAG_END_OF_STREAM, ImuSample, NavSample};
use daemon_common::*;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

struct Counting;

static RX_ALLOCS: AtomicU64 = AtomicU64::new(0);
static EST_ALLOCS: AtomicU64 = AtomicU64::new(0);
/// Inside the measured window (for the optional backtraces).
static WINDOW: AtomicBool = AtomicBool::new(false);
static TRACE: AtomicBool = AtomicBool::new(false);

const UNKNOWN: u8 = 0;
const RX: u8 = 1;
const EST: u8 = 2;
const OTHER: u8 = 3;
const CORE: u8 = 5;
static CORE_ALLOCS: AtomicU64 = AtomicU64::new(0);
const CORE_THREAD: &str = "test-core-alloc";
/// Resolving the name, or printing a trace: allocations not counted.
const BUSY: u8 = 4;

thread_local! {
    static KIND: Cell<u8> = const { Cell::new(UNKNOWN) };
}

fn note() {
    let _ = KIND.try_with(|k| {
        let mut kind = k.get();
        if kind == BUSY {
            return;
        }
        if kind == UNKNOWN {
            k.set(BUSY);
            kind = match std::thread::current().name() {
                Some(RX_THREAD) => RX,
                Some(ESTIMATOR_THREAD) => EST,
                Some(CORE_THREAD) => CORE,
                _ => OTHER,
            };
            k.set(kind);
        }
        let counter = match kind {
            RX => &RX_ALLOCS,
            EST => &EST_ALLOCS,
            CORE => &CORE_ALLOCS,
            _ => return,
        };
        counter.fetch_add(1, Ordering::Relaxed);
        if WINDOW.load(Ordering::Relaxed) && TRACE.load(Ordering::Relaxed) {
            k.set(BUSY);
            eprintln!(
                "allocation on {}:\n{}",
                if kind == RX {
                    RX_THREAD
                } else {
                    ESTIMATOR_THREAD
                },
                std::backtrace::Backtrace::force_capture()
            );
            k.set(kind);
        }
    });
}

// SAFETY: forwards to the system allocator; `note` neither allocates on the counted path nor
// touches the memory.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note();
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note();
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

const WARM_UP: usize = 4000;
const TAIL: usize = 300;

fn trace_if_asked() {
    TRACE.store(
        std::env::var_os("CORRIDOR_ALLOC_TRACE").is_some(),
        Ordering::Relaxed,
    );
}

#[test]
fn estimator_core_does_not_allocate_per_sample() {
    trace_if_asked();
    let h = std::thread::Builder::new()
        .name(CORE_THREAD.into())
        .spawn(|| {
            let cfg = config();
            let aid = heading_aid(&cfg, None).unwrap();
            let rows = exp36_rows();
            let mut est = Estimator::new(cfg, aid);
            let step = |est: &mut Estimator, r: &ImuRow| {
                est.step(&ImuInput::from(r))
                    .map(|e| e.heading.is_some())
                    .unwrap()
            };
            for r in &rows[..WARM_UP] {
                step(&mut est, r);
            }
            let before = CORE_ALLOCS.load(Ordering::Relaxed);
            WINDOW.store(true, Ordering::Relaxed);
            let mut headings = 0;
            for r in &rows[WARM_UP..rows.len() - TAIL] {
                headings += usize::from(step(&mut est, r));
            }
            (before, CORE_ALLOCS.load(Ordering::Relaxed), headings)
        })
        .unwrap();
    let (before, after, headings) = h.join().unwrap();
    assert!(before > 0, "the counter sees the thread");
    assert!(headings > 10, "the window covers heading observations");
    assert_eq!(
        after - before,
        0,
        "allocations by Estimator::step after warm-up"
    );
}

/// Reads attitude until the end-of-stream marker, counting; returns `missed()`.
fn attitude_reader(domain: &Domain, received: Arc<AtomicU64>) -> std::thread::JoinHandle<u64> {
    let domain = domain.clone();
    let (tx, rx) = std::sync::mpsc::sync_channel(1);
    let h = std::thread::spawn(move || {
        let sub = Subscriber::<AttitudeSample>::open(&domain, "test-att", WAIT).unwrap();
        tx.send(()).unwrap();
        loop {
            let a = sub.recv_timeout(WAIT).unwrap().expect("attitude");
            received.fetch_add(1, Ordering::Relaxed);
            if a.flags & FLAG_END_OF_STREAM != 0 {
                return sub.missed();
            }
        }
    });
    rx.recv_timeout(WAIT).unwrap();
    h
}

/// Reads bias and nav messages until both end-of-stream markers, counting them and keeping the
/// `imu_seq` of each; returns the sum of their `missed()` and the `imu_seq`s.
fn bias_nav_reader(
    domain: &Domain,
    count: Arc<AtomicU64>,
) -> std::thread::JoinHandle<(u64, Vec<u64>)> {
    let domain = domain.clone();
    let (tx, rx) = std::sync::mpsc::sync_channel(1);
    let h = std::thread::spawn(move || {
        let bias = Subscriber::<BiasSample>::open(&domain, "test-bias", WAIT).unwrap();
        let nav = Subscriber::<NavSample>::open(&domain, "test-nav", WAIT).unwrap();
        tx.send(()).unwrap();
        let (mut b_end, mut n_end) = (false, false);
        let mut seqs = Vec::new();
        while !(b_end && n_end) {
            let mut any = false;
            while let Some(b) = bias.try_recv().unwrap() {
                count.fetch_add(1, Ordering::Relaxed);
                b_end |= b.flags & FLAG_END_OF_STREAM != 0;
                seqs.push(b.imu_seq);
                any = true;
            }
            while let Some(n) = nav.try_recv().unwrap() {
                count.fetch_add(1, Ordering::Relaxed);
                n_end |= n.flags & FLAG_END_OF_STREAM != 0;
                seqs.push(n.imu_seq);
                any = true;
            }
            if !any {
                std::thread::sleep(Duration::from_micros(200));
            }
        }
        (bias.missed() + nav.missed(), seqs)
    });
    rx.recv_timeout(WAIT).unwrap();
    h
}

#[test]
fn daemon_threads_do_not_allocate_per_sample() {
    let _one = one_daemon_at_a_time();
    trace_if_asked();
    let name = "test_daemon_alloc";
    cleanup_domain(name);
    let domain = Domain::new(name).unwrap();
    let mut dcfg = daemon_config(&domain, Delivery::Lossless);
    // Every message published in the window is counted by a reader below; periodic diagnostics
    // would race with the snapshots.
    dcfg.diagnostics_period = Duration::from_secs(3600);
    dcfg.health_period = Duration::from_secs(3600);
    let daemon = Running::start(dcfg);
    let attitudes = Arc::new(AtomicU64::new(0));
    let others = Arc::new(AtomicU64::new(0));
    let reader = attitude_reader(&domain, Arc::clone(&attitudes));
    let other_reader = bias_nav_reader(&domain, Arc::clone(&others));
    // Waits until `n` attitudes arrived and the bias/nav count settled (usually the window's
    // exact boundary; the count below does not rely on it).
    let wait_for = |n: usize| {
        let deadline = Instant::now() + WAIT;
        while attitudes.load(Ordering::Relaxed) < n as u64 {
            assert!(Instant::now() < deadline, "daemon stuck");
            std::thread::sleep(Duration::from_millis(2));
        }
        let mut last = u64::MAX;
        loop {
            std::thread::sleep(Duration::from_millis(20));
            let now = others.load(Ordering::Relaxed);
            if now == last {
                return;
            }
            last = now;
        }
    };

    let rows = exp36_rows();
    let window_end = rows.len() - TAIL;
    let mut p = Producer::new(&domain, "test-sensor", Delivery::Lossless).unwrap();
    p.wait_for_daemon(WAIT).unwrap();
    for r in &rows[..WARM_UP] {
        p.send_imu(ImuSample::from(r)).unwrap();
    }
    wait_for(WARM_UP);
    let before = (
        RX_ALLOCS.load(Ordering::Relaxed),
        EST_ALLOCS.load(Ordering::Relaxed),
    );
    WINDOW.store(true, Ordering::Relaxed);
    let t = Instant::now();
    for r in &rows[WARM_UP..window_end] {
        p.send_imu(ImuSample::from(r)).unwrap();
    }
    wait_for(window_end);
    WINDOW.store(false, Ordering::Relaxed);
    let window = t.elapsed();
    let after = (
        RX_ALLOCS.load(Ordering::Relaxed),
        EST_ALLOCS.load(Ordering::Relaxed),
    );
    for r in &rows[window_end..] {
        p.send_imu(ImuSample::from(r)).unwrap();
    }
    p.finish().unwrap();
    assert_eq!(reader.join().unwrap(), 0, "no attitude lost");
    let (other_missed, other_seqs) = other_reader.join().unwrap();
    assert_eq!(other_missed, 0, "no bias or nav lost");
    let report = daemon.stop();
    assert_eq!(report.diagnostics.accepted, rows.len() as u64);
    assert!(report.diagnostics.heading_used > 10, "heading updates");
    // The threads were seen allocating during setup, so the counter works.
    assert!(before.0 > 0 && before.1 > 0, "{before:?}");
    let samples = (window_end - WARM_UP) as u64;
    // The bias and nav messages of the window's samples, by the sample they answer (not by when
    // they arrived: a reader descheduled for a moment would move them across the window).
    let others = other_seqs
        .iter()
        .filter(|&&q| (WARM_UP as u64..window_end as u64).contains(&q))
        .count() as u64;
    assert!(others > 0, "bias and nav messages in the window");
    let published = samples + others;
    assert_eq!(
        after.0 - before.0,
        0,
        "allocations on {RX_THREAD} over {samples} samples in {window:?}"
    );
    // The window opens after the last attitude before it arrived and closes after the last one
    // in it: the bias and nav messages of those two samples (at most one each) can be published
    // on either side of the switch.
    let allocs = after.1 - before.1;
    assert!(
        allocs.abs_diff(published) <= 2,
        "allocations on {ESTIMATOR_THREAD} over {samples} samples in {window:?}: {allocs}, \
         expected one per published message ({published}: iceoryx2's loan, ± the 2 boundary \
         messages) and none besides"
    );
    cleanup_domain(name);
}
