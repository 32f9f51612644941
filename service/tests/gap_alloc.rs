//! Gaps and glitched stamps allocate nothing once the estimator has seen one of each: the copy
//! of the estimator kept before a sample that came after a gap (so that a glitched stamp can be
//! dropped after the fact) lives in one buffer, reused. Before, each gap cloned the estimator
//! (seven allocations, about 160 KB), and a producer slower than 1 / `estimator.max_dt_s`
//! cloned it at every sample.
//!
//! This test binary counts the allocations made on the heap (a counting global allocator) while
//! the estimator runs over exp36 with a bridged gap every 50 samples, a stamp glitched 0.5 s
//! ahead every 500 samples and a stretch at 14 Hz, where every step is a gap.
//!
//! One test in this binary, so that no other test's allocations are counted.

use corridor_service::core::{Estimator, ImuInput};
use corridor_service::runner::heading_aid;
use corridor_shared::config::Config;
use corridor_shared::imu_csv::{ImuCsvOptions, read_imu_csv};
use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Allocations (and reallocations) made so far.
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

struct Counting;

// SAFETY: every call is forwarded to the system allocator unchanged; only a counter is added.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

/// A gap's length: beyond `estimator.max_dt_s` (0.05 s), within `max_bridge_s` (0.16 s).
const GAP_S: f64 = 0.06;
/// The samples kept one in this many over the slow stretch (200 Hz → 14 Hz: 0.07 s steps).
const SLOW_KEEP_ONE_IN: usize = 14;
/// Samples run before the allocations are counted: the alignment, the first stances, gaps and
/// glitches (the buffers are made there).
const WARM_UP: usize = 3000;

#[test]
fn gaps_and_glitched_stamps_allocate_nothing_after_the_first() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/gdins_exp36_corridor_out_and_back");
    let log = read_imu_csv(&data.join("imu.csv"), &ImuCsvOptions::default()).unwrap();
    let cfg = Config::from_file(&data.join("../../../configs/gdins.toml")).unwrap();
    assert_eq!(cfg.max_dt_s.get(), 0.05, "the gaps below are sized for it");
    // (a gap every, a glitch every) so many samples. The dense one puts glitches next to long
    // stances, where a copy whose rest blocks had less room than the original's grew them.
    for (gap_every, glitch_every) in [(50, 500), (23, 61)] {
        // 20–24 s: a producer at 14 Hz.
        let slow = |k: usize| (4000..4800).contains(&k);
        // The stream, and the same without its glitched samples.
        let (mut stream, mut clean) = (Vec::new(), Vec::new());
        let mut shift_s = 0.0;
        let mut glitches = 0;
        for (k, r) in log.rows.iter().enumerate() {
            if slow(k) && k % SLOW_KEEP_ONE_IN != 0 {
                continue;
            }
            if k % gap_every == 0 {
                shift_s += GAP_S;
            }
            let s = ImuInput {
                t_s: r.t_s + shift_s,
                gyro_rad_s: r.gyro_rad_s,
                accel_m_s2: r.accel_m_s2,
            };
            // Away from the gaps, the slow stretch and the end: a glitch's next sample must
            // follow the one before it.
            let clear = k % gap_every != 0
                && (k + 1) % gap_every != 0
                && !slow(k)
                && !slow(k + 1)
                && k + 1 < log.rows.len();
            if k % glitch_every == glitch_every / 2 && clear {
                stream.push(ImuInput {
                    t_s: s.t_s + 0.5,
                    ..s
                });
                glitches += 1;
            } else {
                stream.push(s);
                clean.push(s);
            }
        }
        let mut reference = Estimator::new(cfg.clone(), heading_aid(&cfg, None).unwrap());
        for s in &clean {
            reference.step(s).unwrap();
        }
        let mut est = Estimator::new(cfg.clone(), heading_aid(&cfg, None).unwrap());
        let (warm_up, rest) = stream.split_at(WARM_UP);
        for s in warm_up {
            est.step(s).unwrap();
        }
        let before = ALLOCATIONS.load(Ordering::Relaxed);
        for s in rest {
            est.step(s).unwrap();
        }
        let allocations = ALLOCATIONS.load(Ordering::Relaxed) - before;
        // What ran: every gap (the slow stretch's steps among them), every glitch dropped.
        let c = *est.counters();
        assert!(c.gaps > 200, "{c:?}");
        assert_eq!(c.rejected_time_jump, glitches, "{c:?}");
        assert!(c.stances > 40, "{c:?}");
        // Each glitched sample was dropped after the fact, from a copy in the reused buffer:
        // the walk ends as without them, bit for bit.
        assert_eq!(est.last_estimate(), reference.last_estimate());
        assert_eq!(est.bias_state(), reference.bias_state());
        let mut r = *reference.counters();
        r.rejected_time_jump = glitches;
        assert_eq!(c, r);
        assert_eq!(
            allocations,
            0,
            "every {gap_every} / {glitch_every}: {allocations} allocations over {} samples with \
             {} gaps",
            rest.len(),
            c.gaps
        );
    }
}
