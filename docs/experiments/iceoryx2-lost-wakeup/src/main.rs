//! Stress of the iceoryx2 0.10 event (UnixDatagramShmCountingBitSet): a notifier thread notifies
//! without pause while "data" is counted in an atomic; a listener thread drains the data then
//! `timed_wait`s. A wait that lasts the full timeout while the notifier kept notifying (data
//! present afterwards) is a lost wake-up.
use iceoryx2::prelude::*;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    set_log_level(LogLevel::Error);
    let secs: u64 = std::env::args()
        .nth(1)
        .map(|s| s.parse().unwrap())
        .unwrap_or(20);
    let timeout = Duration::from_millis(
        std::env::args()
            .nth(2)
            .map(|s| s.parse().unwrap())
            .unwrap_or(1000),
    );
    let name = format!("evrace_{}", std::process::id());
    let produced = Arc::new(AtomicU64::new(0));
    let consumed = Arc::new(AtomicU64::new(0));
    let stop = Arc::new(AtomicBool::new(false));
    let ready = Arc::new(AtomicBool::new(false));

    let l = {
        let (name, produced, consumed, stop, ready) = (
            name.clone(),
            produced.clone(),
            consumed.clone(),
            stop.clone(),
            ready.clone(),
        );
        std::thread::spawn(move || -> (u64, u64) {
            let node = NodeBuilder::new()
                .signal_handling_mode(SignalHandlingMode::Disabled)
                .create::<ipc::Service>()
                .unwrap();
            let ev = node
                .service_builder(&name.as_str().try_into().unwrap())
                .event()
                .open_or_create()
                .unwrap();
            let listener = ev.listener_builder().create().unwrap();
            ready.store(true, Ordering::SeqCst);
            let (mut waits, mut lost) = (0u64, 0u64);
            while !stop.load(Ordering::SeqCst) {
                // "receive until empty"
                let p = produced.load(Ordering::SeqCst);
                consumed.store(p, Ordering::SeqCst);
                let t = Instant::now();
                listener.timed_wait(|_| {}, timeout).unwrap();
                waits += 1;
                let el = t.elapsed();
                if el >= timeout * 9 / 10
                    && produced.load(Ordering::SeqCst) > p
                    && !stop.load(Ordering::SeqCst)
                {
                    lost += 1;
                    eprintln!(
                        "LOST WAKE-UP: waited {el:?} while {} notifications were sent",
                        produced.load(Ordering::SeqCst) - p
                    );
                }
            }
            (waits, lost)
        })
    };
    while !ready.load(Ordering::SeqCst) {
        std::thread::sleep(Duration::from_millis(1));
    }
    let node = NodeBuilder::new()
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()?;
    let ev = node
        .service_builder(&name.as_str().try_into()?)
        .event()
        .open_or_create()?;
    let notifier = ev.notifier_builder().create()?;
    // A little work between samples, as the estimator does (WORK_US, default 20 µs).
    let work = Duration::from_micros(
        std::env::var("WORK_US")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(20),
    );
    let end = Instant::now() + Duration::from_secs(secs);
    let mut notifies = 0u64;
    while Instant::now() < end {
        produced.fetch_add(1, Ordering::SeqCst);
        let _ = notifier.notify();
        notifies += 1;
        let t = Instant::now();
        while t.elapsed() < work {}
    }
    stop.store(true, Ordering::SeqCst);
    let _ = notifier.notify();
    let (waits, lost) = l.join().unwrap();
    println!("notifies {notifies} waits {waits} lost_wakeups {lost}");
    Ok(())
}
