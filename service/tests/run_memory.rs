//! `corridor run` holds nothing per sample (issue 10, finding 6: "5 M rows took 1.07 GiB").
//!
//! This test binary counts the bytes allocated on the heap (a counting global allocator) and
//! runs the offline runner over a long log made of exp36 repeated, at N and 4 N rows: the peak
//! heap must not grow with the length and must stay under a bound. Before the runner streamed,
//! it held the file's text, its parsed rows and a per-sample trace (about 300 bytes a row): the
//! 60 000 rows more would have added some 18 MB. The figure for 5 M rows as a process's peak RSS is printed by
//! `cargo bench -p corridor-service --bench run_memory`.
//!
//! One test in this binary, so that no other test's allocations are counted.

mod common;

use common::{TempDir, repeat_log};
use corridor_service::runner::{RunOptions, run};
use corridor_shared::config::Config;
use corridor_shared::imu_csv::ImuCsvOptions;
use corridor_shared::injection::BiasInjection;
use std::alloc::{GlobalAlloc, Layout, System};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Bytes allocated now, and the largest value since the last reset.
static NOW: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

struct Counting;

fn grew(bytes: usize) {
    let now = NOW.fetch_add(bytes, Ordering::Relaxed) + bytes;
    PEAK.fetch_max(now, Ordering::Relaxed);
}

// SAFETY: every call is forwarded to the system allocator unchanged; only counters are added.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        NOW.fetch_sub(layout.size(), Ordering::Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            NOW.fetch_sub(layout.size(), Ordering::Relaxed);
            grew(new_size);
        }
        p
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Rows of the shorter log (past the units check's exact-median buffer of 16 384 rows).
const N: u64 = 20_000;
/// A plain run: the reader's and writers' buffers, the estimator, the summary, and the log's first
/// 10 s read ahead for the units check (measured 0.70 MiB; 0.42 before the read-ahead).
const PLAIN_BOUND_BYTES: usize = 1 << 20;
/// With `--plots` and truth: two traces of at most 32 768 samples and the figures' text
/// (measured 7.6 MiB).
const PLOTS_BOUND_BYTES: usize = 12 << 20;
/// What the peak may differ between lengths (the figures' text, decimated differently).
const SLACK_BYTES: usize = 256 << 10;

/// Peak heap above the start while `run` streams `imu`, bytes.
fn peak_of_run(imu: &Path, out: &Path, plots: bool) -> usize {
    let data = root().join("tests/data/gdins_exp36_corridor_out_and_back");
    let opts = RunOptions {
        imu: imu.to_owned(),
        config: Config::from_file(&root().join("configs/gdins.toml")).unwrap(),
        map: None,
        truth: plots.then(|| data.join("ground_truth.csv")),
        injection: BiasInjection::default(),
        plots,
        out_dir: out.to_owned(),
        csv: ImuCsvOptions::default(),
        warm_start: None,
    };
    let start = NOW.load(Ordering::Relaxed);
    PEAK.store(start, Ordering::Relaxed);
    let summary = run(&opts).unwrap();
    assert!(summary.samples > 0);
    PEAK.load(Ordering::Relaxed) - start
}

#[test]
fn the_runners_peak_heap_does_not_grow_with_the_log() {
    let dir = TempDir::new(&format!("run-memory-{}", std::process::id()));
    let src = root().join("tests/data/gdins_exp36_corridor_out_and_back/imu.csv");
    let (short, long) = (dir.join("short.csv"), dir.join("long.csv"));
    repeat_log(&src, N, &short);
    repeat_log(&src, 4 * N, &long);
    for (plots, bound) in [(false, PLAIN_BOUND_BYTES), (true, PLOTS_BOUND_BYTES)] {
        let p1 = peak_of_run(&short, &dir.join("o1"), plots);
        let p4 = peak_of_run(&long, &dir.join("o4"), plots);
        println!(
            "plots {plots}: peak heap {:.2} MiB at {N} rows, {:.2} MiB at {} rows",
            p1 as f64 / 1048576.0,
            p4 as f64 / 1048576.0,
            4 * N
        );
        assert!(
            p4 <= p1 + SLACK_BYTES,
            "plots {plots}: the peak heap grew with the log: {p1} B at {N} rows, {p4} B at {} rows",
            4 * N
        );
        assert!(
            p4 < bound,
            "plots {plots}: peak heap {p4} B above {bound} B"
        );
    }
}
