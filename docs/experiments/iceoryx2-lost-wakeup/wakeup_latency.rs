//! Wake-up latency of `Subscriber::recv_timeout` (verification of the EVENT_WAIT_SLICE fix).
//!
//! The main thread opens the attitude service the way the daemon does (service/src/daemon/
//! outputs.rs: `Domain::open::<T>(Access::Owner(delivery))` + publisher, `Domain::open_event(..,
//! true)` + notifier), and publishes AttitudeSample with increasing `seq`, the publish time
//! (`monotonic_ns`) in `imu_sent_ns`, notifying after each, with WORK_US of busy work between.
//! A second thread creates a `Subscriber::<AttitudeSample>` and loops on
//! `recv_timeout(2 s)`, recording the gap between successive receives and the latency from
//! publish to receive.
//!
//! usage: wakeup_latency DOMAIN [SECS=15] [WORK_US=20]
use corridor_client::subscriber::Subscriber;
use corridor_shared::services::{Access, Delivery, Domain, Topic};
use corridor_shared::wire::{AttitudeSample, monotonic_ns};
use iceoryx2::prelude::*;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

const END: u32 = 0xDEAD_BEEF;
const TIMEOUT: Duration = Duration::from_secs(2);

struct SubStats {
    received: u64,
    missed: u64,
    timeouts: u64,
    gaps_us: Vec<u64>,
    lat_us: Vec<u64>,
    worst: Vec<(u64, u64, u64)>, // (gap_us, seq, latency_us)
}

fn pct(v: &[u64], p: f64) -> u64 {
    if v.is_empty() {
        return 0;
    }
    let i = ((v.len() - 1) as f64 * p).round() as usize;
    v[i]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    set_log_level(LogLevel::Error);
    let args: Vec<String> = std::env::args().collect();
    let domain_name = args
        .get(1)
        .cloned()
        .expect("usage: wakeup_latency DOMAIN [SECS] [WORK_US]");
    let secs: u64 = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(15);
    let work_us: u64 = args.get(3).map(|s| s.parse().unwrap()).unwrap_or(20);
    let domain = Domain::unsecured(&domain_name)?;
    let delivery = Delivery::Live;

    // Publisher side, as in service/src/daemon/outputs.rs (Out::new).
    let node = domain.node("wakeup-pub", SignalHandlingMode::Disabled)?;
    let publisher = domain
        .open::<AttitudeSample>(&node, Access::Owner(delivery))?
        .publisher_builder()
        .backpressure_strategy(delivery.backpressure())
        .max_loaned_samples(2)
        .create()?;
    let notifier = domain
        .open_event(&node, AttitudeSample::SERVICE, true)?
        .notifier_builder()
        .create()?;

    let ready = Arc::new(AtomicBool::new(false));
    let sub_thread = {
        let (domain, ready) = (domain.clone(), ready.clone());
        std::thread::spawn(move || -> SubStats {
            let sub =
                Subscriber::<AttitudeSample>::open(&domain, "wakeup-sub", Duration::from_secs(10))
                    .expect("subscriber");
            ready.store(true, Ordering::SeqCst);
            let mut st = SubStats {
                received: 0,
                missed: 0,
                timeouts: 0,
                gaps_us: Vec::with_capacity(1 << 20),
                lat_us: Vec::with_capacity(1 << 20),
                worst: Vec::new(),
            };
            let mut prev: Option<Instant> = None;
            loop {
                match sub.recv_timeout(TIMEOUT).expect("recv") {
                    Some(m) => {
                        let now = Instant::now();
                        let now_ns = monotonic_ns();
                        if m.flags == END {
                            break;
                        }
                        let lat = now_ns.saturating_sub(m.imu_sent_ns) / 1000;
                        st.lat_us.push(lat);
                        if let Some(p) = prev {
                            let g = (now - p).as_micros() as u64;
                            st.gaps_us.push(g);
                            if g > 100_000 {
                                st.worst.push((g, m.seq, lat));
                            }
                        }
                        prev = Some(now);
                    }
                    None => {
                        st.timeouts += 1;
                        eprintln!("recv_timeout returned None (timeout {TIMEOUT:?})");
                    }
                }
            }
            st.received = sub.received() - 1; // without the END marker
            st.missed = sub.missed();
            st
        })
    };
    while !ready.load(Ordering::SeqCst) {
        std::thread::sleep(Duration::from_millis(1));
    }
    {
        use iceoryx2::port::update_connections::UpdateConnections;
        let _ = publisher.update_connections();
    }

    let end = Instant::now() + Duration::from_secs(secs);
    let mut seq = 0u64;
    let publish = |seq: u64, flags: u32| {
        let v = AttitudeSample {
            seq,
            flags,
            imu_sent_ns: monotonic_ns(),
            ..Default::default()
        };
        if let Ok(slot) = publisher.loan_uninit() {
            let _ = slot.write_payload(v).send();
        }
        let _ = notifier.notify();
    };
    while Instant::now() < end {
        publish(seq, 0);
        seq += 1;
        let t = Instant::now();
        while t.elapsed() < Duration::from_micros(work_us) {
            std::hint::spin_loop();
        }
    }
    publish(seq, END);
    let mut st = sub_thread.join().expect("subscriber thread");

    st.gaps_us.sort_unstable();
    st.lat_us.sort_unstable();
    let over = |v: &[u64], us: u64| v.iter().filter(|&&g| g > us).count();
    println!(
        "domain {domain_name} secs {secs} work_us {work_us} notify_delay_us {:?} drain_delay_us {:?}",
        std::env::var("IOX2_NOTIFY_DELAY_US").ok(),
        std::env::var("IOX2_DRAIN_DELAY_US").ok()
    );
    println!(
        "published {seq} received {} missed {} timeouts {}",
        st.received, st.missed, st.timeouts
    );
    println!(
        "gap_between_receives_us: p50 {} p99 {} p99.9 {} max {} | >50ms {} >60ms {} >100ms {} >1s {} >1.9s {}",
        pct(&st.gaps_us, 0.5),
        pct(&st.gaps_us, 0.99),
        pct(&st.gaps_us, 0.999),
        st.gaps_us.last().copied().unwrap_or(0),
        over(&st.gaps_us, 50_000),
        over(&st.gaps_us, 60_000),
        over(&st.gaps_us, 100_000),
        over(&st.gaps_us, 1_000_000),
        over(&st.gaps_us, 1_900_000),
    );
    println!(
        "publish_to_receive_us: p50 {} p99 {} p99.9 {} max {} | >50ms {} >60ms {} >100ms {} >1s {}",
        pct(&st.lat_us, 0.5),
        pct(&st.lat_us, 0.99),
        pct(&st.lat_us, 0.999),
        st.lat_us.last().copied().unwrap_or(0),
        over(&st.lat_us, 50_000),
        over(&st.lat_us, 60_000),
        over(&st.lat_us, 100_000),
        over(&st.lat_us, 1_000_000),
    );
    st.worst.sort_unstable_by(|a, b| b.0.cmp(&a.0));
    for (g, s, l) in st.worst.iter().take(10) {
        println!("  gap {g} us before seq {s} (publish->receive {l} us)");
    }
    Ok(())
}
