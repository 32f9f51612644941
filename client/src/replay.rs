//! Replay: a recorded IMU log sent to the daemon as if it were a live sensor, paced at a chosen
//! speed, optionally looped and with a synthetic gyro bias added. Used by `corridor-replay` and
//! by `corridor demo`.

use crate::{ClientError, Delivery, Domain, Producer, ProducerStats};
use corridor_shared::imu_csv::ImuRow;
use corridor_shared::injection::BiasInjection;
use corridor_shared::wire::ImuSample;
use std::str::FromStr;
use std::time::{Duration, Instant};

/// Replay speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Speed {
    /// As fast as the daemon takes it.
    Max,
    /// Sensor time × factor (1 = real time).
    Factor(f64),
}

/// The slowest replay factor (a minute of log in about 17 hours).
pub const MIN_SPEED_FACTOR: f64 = 1e-3;
/// The fastest replay factor short of `max`.
pub const MAX_SPEED_FACTOR: f64 = 1e6;

impl FromStr for Speed {
    type Err = String;

    /// `max`, `realtime` or a speed-up factor > 0 (`2` = twice real time).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "max" => Ok(Speed::Max),
            "realtime" => Ok(Speed::Factor(1.0)),
            _ => s
                .parse::<f64>()
                .ok()
                // A factor so small that the log's times overflow the clock was taken for
                // `max`, silently (a review): refused, as one a clock cannot follow.
                .filter(|f| (MIN_SPEED_FACTOR..=MAX_SPEED_FACTOR).contains(f))
                .map(Speed::Factor)
                .ok_or_else(|| {
                    format!(
                        "speed {s:?}: expected realtime, max or a factor in \
                         [{MIN_SPEED_FACTOR}, {MAX_SPEED_FACTOR:e}]"
                    )
                }),
        }
    }
}

/// How to replay a log.
#[derive(Debug, Clone)]
pub struct ReplayOptions {
    /// Name of the producer's iceoryx2 node.
    pub node_name: String,
    /// Delivery policy: `None` takes the daemon's; `Some` asserts it (another policy fails).
    pub delivery: Option<Delivery>,
    /// Pacing.
    pub speed: Speed,
    /// Times the log is sent; the clock continues across loops (shifted by the log's span plus
    /// one mean period).
    pub loops: u32,
    /// Synthetic gyro bias added to every sample, at the (shifted) sample time.
    pub injection: BiasInjection,
    /// How long to wait for the daemon's subscriber.
    pub wait: Duration,
}

/// What a replay sent.
#[derive(Debug, Clone, Copy)]
pub struct Replayed {
    /// The delivery policy used (the daemon's).
    pub delivery: Delivery,
    /// Data samples sent (the end-of-stream marker not included).
    pub samples: u64,
    /// The producer's counters (the marker included).
    pub stats: ProducerStats,
    /// Stopped early by SIGINT/SIGTERM (the marker is still sent).
    pub interrupted: bool,
    /// Wall time from the first sample to the marker, s.
    pub elapsed_s: f64,
}

/// Longest single sleep of the pacing: SIGINT/SIGTERM are seen within it during a gap of the
/// log (they used to wait for the gap's end: a 60 s gap held a Ctrl-C for 59 s).
const PACING_SLICE: Duration = Duration::from_millis(100);

/// Sleeps until `offset_s` after `start`, in slices that ask `interrupted` (SIGINT/SIGTERM);
/// true when it said so. A time beyond what the clock can hold (a replay speed of 1e-300
/// panicked) is not waited for.
fn wait_until_due(start: Instant, offset_s: f64, interrupted: impl Fn() -> bool) -> bool {
    let Some(due) = Duration::try_from_secs_f64(offset_s.max(0.0))
        .ok()
        .and_then(|d| start.checked_add(d))
    else {
        return false;
    };
    loop {
        let now = Instant::now();
        if due <= now {
            return false;
        }
        std::thread::sleep((due - now).min(PACING_SLICE));
        if Instant::now() < due && interrupted() {
            return true;
        }
    }
}

/// Sends `rows` to the daemon of `domain` as `opts` says, then the end-of-stream marker.
/// SIGINT/SIGTERM end the replay early (checked every 64 samples, and during the pacing's
/// waits), still with the marker.
pub fn replay(
    domain: &Domain,
    rows: &[ImuRow],
    opts: &ReplayOptions,
) -> Result<Replayed, ClientError> {
    replay_with(domain, rows, opts, || {})
}

/// [`replay`], calling `daemon_found` once the daemon reads the IMU service, before the first
/// sample goes (`corridor-replay` starts its watch of the daemon's diagnostics there: started
/// before, it gave up on a daemon that came up during `opts.wait`, and the replay said nothing
/// of the samples that daemon lost).
pub fn replay_with(
    domain: &Domain,
    rows: &[ImuRow],
    opts: &ReplayOptions,
    daemon_found: impl FnOnce(),
) -> Result<Replayed, ClientError> {
    let mut p = Producer::open(domain, &opts.node_name, opts.delivery)?;
    p.wait_for_daemon(opts.wait)?;
    daemon_found();
    let (first_t_s, loop_shift_s) = match (rows.first(), rows.last()) {
        (Some(first), Some(last)) => {
            let n = rows.len();
            let period = if n > 1 {
                (last.t_s - first.t_s) / (n - 1) as f64
            } else {
                0.01
            };
            (first.t_s, last.t_s - first.t_s + period)
        }
        _ => (0.0, 0.0),
    };
    let start = Instant::now();
    let mut interrupted = false;
    'outer: for k in 0..opts.loops {
        let shift = f64::from(k) * loop_shift_s;
        for (i, r) in rows.iter().enumerate() {
            let t_s = r.t_s + shift;
            if let Speed::Factor(f) = opts.speed
                && wait_until_due(start, (t_s - first_t_s) / f, || p.termination_requested())
            {
                interrupted = true;
                break 'outer;
            }
            if i % 64 == 0 && p.termination_requested() {
                interrupted = true;
                break 'outer;
            }
            let mut s = ImuSample::from(r);
            s.t_s = t_s;
            opts.injection.apply(t_s - first_t_s, &mut s.gyro_rad_s);
            p.send_imu(s)?;
        }
    }
    p.finish()?;
    let delivery = p.delivery();
    // Waits until the daemon has taken the stream (see `Producer::close`).
    let stats = p.close()?;
    Ok(Replayed {
        delivery,
        samples: stats.imu_sent.saturating_sub(1),
        stats,
        interrupted,
        elapsed_s: start.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pacing_sees_an_interruption_within_a_slice_and_never_waits_for_the_impossible() {
        // A gap of 60 s in the log: a Ctrl-C is seen within a slice (it waited the whole gap).
        let start = Instant::now();
        assert!(wait_until_due(start, 60.0, || true));
        assert!(start.elapsed() < Duration::from_secs(30));
        // A due time the clock cannot hold (speed 1e-300: it panicked) is not waited for.
        assert!(!wait_until_due(start, f64::INFINITY, || true));
        assert!(!wait_until_due(start, 1e300, || true));
        // Otherwise it waits until the due time.
        assert!(!wait_until_due(start, 0.25, || false));
        assert!(start.elapsed() >= Duration::from_millis(250));
    }

    #[test]
    fn speeds_parse() {
        assert_eq!("max".parse::<Speed>(), Ok(Speed::Max));
        assert_eq!("realtime".parse::<Speed>(), Ok(Speed::Factor(1.0)));
        assert_eq!("2.5".parse::<Speed>(), Ok(Speed::Factor(2.5)));
        for bad in ["0", "-1", "inf", "NaN", "fast", "1e-300", "1e-4", "1e7"] {
            assert!(bad.parse::<Speed>().is_err(), "{bad}");
        }
    }
}
