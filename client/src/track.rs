//! Track: the daemon's stride-by-stride positions (one nav sample per stance) followed until
//! the end of stream. Used by `corridor-pdr` and by `corridor demo`.
//!
//! [`Tracker::open`] attaches the reader; [`Tracker::run`] then follows one stream, handing
//! each stride to a callback. The split lets a caller say "attached" before the producer
//! starts, and follow several streams with one reader.

use crate::{ClientError, Domain, Subscriber};
use corridor_shared::wire::{FLAG_END_OF_STREAM, NavSample};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// One stride: the nav sample of a stance and the horizontal distance from the previous one.
#[derive(Debug, Clone, Copy)]
pub struct Stride {
    /// The daemon's nav sample.
    pub nav: NavSample,
    /// Horizontal distance from the previous stride of the stream, m (0 for the first).
    pub step_m: f64,
}

/// Why following a stream stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TrackStop {
    /// The end-of-stream nav sample arrived.
    EndOfStream,
    /// Nothing arrived for the idle timeout.
    IdleTimeout,
    /// SIGINT/SIGTERM.
    Interrupted,
    /// The caller's `abort` flag was set.
    Aborted,
}

/// What following one stream got.
#[derive(Debug, Clone, Copy)]
pub struct Track {
    /// Why it stopped.
    pub stopped: TrackStop,
    /// Strides received.
    pub strides: u64,
    /// The last stride, if any.
    pub last: Option<NavSample>,
    /// Horizontal path length over the strides, m.
    pub path_m: f64,
    /// The stance count carried by the end-of-stream nav sample.
    pub end_stances: Option<u64>,
    /// Nav messages missing from the `seq` numbering so far (cumulative over the reader's
    /// life).
    pub missed: u64,
}

/// The nav reader.
#[derive(Debug)]
pub struct Tracker {
    nav: Subscriber<NavSample>,
}

impl Tracker {
    /// Attaches to the daemon's nav stream in `domain`, waiting up to `wait` for it.
    pub fn open(domain: &Domain, node_name: &str, wait: Duration) -> Result<Self, ClientError> {
        Ok(Self {
            nav: Subscriber::open(domain, node_name, wait)?,
        })
    }

    /// Follows one stream until its end-of-stream nav sample, SIGINT/SIGTERM, `abort`, or
    /// (when `idle_timeout` is set) nothing for that long; calls `on_stride` for every stride.
    /// `poll` is the longest single wait, so it sees `abort`.
    pub fn run(
        &self,
        poll: Duration,
        idle_timeout: Option<Duration>,
        abort: &AtomicBool,
        mut on_stride: impl FnMut(&Stride),
    ) -> Result<Track, ClientError> {
        let mut t = Track {
            stopped: TrackStop::EndOfStream,
            strides: 0,
            last: None,
            path_m: 0.0,
            end_stances: None,
            missed: 0,
        };
        let mut last_rx = Instant::now();
        t.stopped = loop {
            if abort.load(Ordering::Relaxed) {
                break TrackStop::Aborted;
            }
            let n = match self.nav.recv_timeout(poll) {
                Ok(Some(n)) => n,
                Ok(None) => {
                    if idle_timeout.is_some_and(|i| last_rx.elapsed() >= i) {
                        break TrackStop::IdleTimeout;
                    }
                    continue;
                }
                Err(ClientError::Interrupted) => break TrackStop::Interrupted,
                Err(e) => return Err(e),
            };
            last_rx = Instant::now();
            if n.flags & FLAG_END_OF_STREAM != 0 {
                t.end_stances = Some(n.stance);
                break TrackStop::EndOfStream;
            }
            let step_m = t
                .last
                .map_or(0.0, |q| (n.p_m[0] - q.p_m[0]).hypot(n.p_m[1] - q.p_m[1]));
            t.path_m += step_m;
            t.strides += 1;
            t.last = Some(n);
            on_stride(&Stride { nav: n, step_m });
        };
        t.missed = self.nav.missed();
        Ok(t)
    }
}
