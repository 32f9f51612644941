//! Track: the daemon's stride-by-stride positions (one nav sample per stance) followed until
//! the end of stream. Used by `corridor-pdr` and by `corridor demo`.
//!
//! [`Tracker::open`] attaches the reader; [`Tracker::run`] then follows one stream, handing
//! each stride to a callback. The split lets a caller say "attached" before the producer
//! starts, and follow several streams with one reader.

use crate::{ClientError, Domain, Subscriber};
use corridor_shared::services::Topic;
use corridor_shared::wire::{FLAG_END_OF_STREAM, FLAG_FRAME_SET, NavSample};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// One stride: the nav sample of a stance and the horizontal distance from the previous one.
#[derive(Debug, Clone, Copy)]
pub struct Stride {
    /// The daemon's nav sample.
    pub nav: NavSample,
    /// Horizontal distance from the previous stride of the stream, m (0 for the first).
    pub step_m: f64,
    /// The daemon sent this stance again, and this stride replaces the previous one (the same
    /// `stance`, a later `imu_seq`; or earlier ones, when a run of glitched stamps held
    /// several stances); it is not counted again. Either the sample that began it carried a
    /// glitched stamp and was dropped after the fact, or ([`Stride::frame_set`]) the start
    /// heading set the map frame during it.
    pub replaces_previous: bool,
    /// The start heading set the map frame on this stride's sample ([`FLAG_FRAME_SET`]): the
    /// stance sent again in that frame, replacing its first sending, which was in the frame
    /// before (the first stride, on a walk that starts along its start heading; see the flag
    /// for when it comes again).
    pub frame_set: bool,
    /// The daemon's estimator started again (its stance count went back to 1: a daemon that
    /// restarted within the stream): this stride starts a new track from the new origin (it
    /// was joined to the last one, a step of tens of metres that never happened: a review).
    pub new_track: bool,
}

/// Strides remembered to be replaced when the daemon sends earlier stances again.
const STRIDES_KEPT: usize = 8;

/// The strides of one stream so far: their count, the path over them, and the last few with
/// the step to each (a stance sent again replaces them from that stance on).
#[derive(Debug, Clone, Default)]
struct Strides {
    count: u64,
    path_m: f64,
    recent: std::collections::VecDeque<(NavSample, f64)>,
}

/// Horizontal distance from `from` to `to`, m (0 from nothing).
fn step_m(from: Option<NavSample>, to: &NavSample) -> f64 {
    from.map_or(0.0, |q| (to.p_m[0] - q.p_m[0]).hypot(to.p_m[1] - q.p_m[1]))
}

impl Strides {
    /// The last stride's nav sample.
    fn last(&self) -> Option<NavSample> {
        self.recent.back().map(|&(q, _)| q)
    }

    fn add(&mut self, n: NavSample) -> Stride {
        // The stance sent again in the frame the start heading set replaces its first sending
        // (the same stance, a later time: without the flag, an estimator started again).
        let frame_set = n.flags & FLAG_FRAME_SET != 0;
        let resent = frame_set && self.last().is_some_and(|q| q.stance == n.stance);
        if resent && let Some((_, step)) = self.recent.pop_back() {
            self.path_m -= step;
            self.count -= 1;
        }
        // A stance count that does not go on: stances sent again after glitched stamps, which
        // the dropped samples had stamped ahead of this one, or else an estimator that started
        // again (a daemon restarted within the stream), whose times go on (a review: telling
        // them apart by the count alone took a glitched run over stances 1 and 2 for a
        // restart, and a restart whose stance 1 was missed for a glitch).
        let last = self.last();
        let goes_back = last.is_some_and(|q| n.stance <= q.stance);
        let new_track = goes_back && last.is_some_and(|q| q.t_s <= n.t_s);
        if new_track {
            self.recent.clear();
        }
        // Strides from this stance on, sent before with a later time, are replaced (not
        // counted again).
        let mut replaced = resent;
        while let Some(&(q, step)) = self.recent.back()
            && q.stance >= n.stance
            && q.t_s > n.t_s
        {
            self.recent.pop_back();
            self.path_m -= step;
            self.count -= 1;
            replaced = true;
        }
        self.count += 1;
        let step_m = step_m(self.last(), &n);
        self.path_m += step_m;
        if self.recent.len() == STRIDES_KEPT {
            self.recent.pop_front();
        }
        self.recent.push_back((n, step_m));
        Stride {
            nav: n,
            step_m,
            replaces_previous: replaced,
            new_track,
            frame_set,
        }
    }
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
    /// The daemon stopped within the stream and no daemon came back within the wait given to
    /// [`Tracker::open`]: its nav publisher left the service (a clean stop; a killed daemon's
    /// stays until iceoryx2 cleans up its node). `corridor-pdr` waited on for ever, saying
    /// nothing (a review). A daemon back within the wait is followed (a new track).
    DaemonStopped,
}

impl TrackStop {
    /// In words, for the tools' output (as [`crate::record::RecordStop::describe`]: a pdr
    /// stopped by Ctrl-C said only "stopped", where the README says every tool says
    /// "interrupted").
    pub fn describe(self) -> &'static str {
        match self {
            TrackStop::EndOfStream => "end of stream",
            TrackStop::IdleTimeout => "idle timeout",
            TrackStop::Interrupted => "interrupted",
            TrackStop::Aborted => "aborted",
            TrackStop::DaemonStopped => "daemon stopped",
        }
    }
}

/// What following one stream got.
#[derive(Debug, Clone, Copy)]
pub struct Track {
    /// Why it stopped.
    pub stopped: TrackStop,
    /// Strides received (a stance sent again counted once).
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
    /// How long a daemon that stopped may take to come back.
    wait: Duration,
    /// The domain's name, for the error of a daemon gone before a stream began.
    domain: String,
}

impl Tracker {
    /// Attaches to the daemon's nav stream in `domain`, waiting up to `wait` for it (and as
    /// long for a daemon that stopped within a stream to come back).
    pub fn open(domain: &Domain, node_name: &str, wait: Duration) -> Result<Self, ClientError> {
        Ok(Self {
            nav: Subscriber::open(domain, node_name, wait)?,
            wait,
            domain: domain.name().to_owned(),
        })
    }

    /// Follows one stream until its end-of-stream nav sample, SIGINT/SIGTERM, `abort`, the
    /// daemon's stop (not back within the wait of [`Tracker::open`]), or (when `idle_timeout`
    /// is set) nothing for that long; calls `on_stride` for every stride. A daemon gone before
    /// the stream's first stride, and not back within the wait, is [`ClientError::NoPeer`]: no
    /// stream was cut (it was said as a daemon stopped within the stream: a review).
    /// A stream that had ended before the reader attached is not followed.
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
        let mut strides = Strides::default();
        let mut last_rx = Instant::now();
        let mut first = true;
        let mut gone_since: Option<Instant> = None;
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
                    // (Nothing was waiting: whatever it sent before it left has been read.)
                    if self.nav.publishers() > 0 {
                        gone_since = None;
                    } else if gone_since.get_or_insert_with(Instant::now).elapsed() >= self.wait {
                        if strides.count == 0 {
                            return Err(ClientError::NoPeer {
                                service: NavSample::SERVICE,
                                domain: self.domain.clone(),
                                peer: "publisher",
                                waited: self.wait,
                            });
                        }
                        break TrackStop::DaemonStopped;
                    }
                    continue;
                }
                Err(ClientError::Interrupted) => break TrackStop::Interrupted,
                Err(e) => return Err(e),
            };
            (last_rx, gone_since) = (Instant::now(), None);
            // An end of stream as the first message is the daemon's history (the nav stream
            // keeps its last message for late readers) of a stream that ended before this
            // reader attached: passed over (it ended a track started between two streams at
            // once, with the previous stream's stride count).
            if std::mem::take(&mut first) && n.flags & FLAG_END_OF_STREAM != 0 {
                continue;
            }
            if n.flags & FLAG_END_OF_STREAM != 0 {
                t.end_stances = Some(n.stance);
                break TrackStop::EndOfStream;
            }
            let stride = strides.add(n);
            (t.strides, t.path_m, t.last) = (strides.count, strides.path_m, strides.last());
            on_stride(&stride);
        };
        t.missed = self.nav.missed();
        Ok(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The nav sample of `stance` at `x_m`, sent for IMU sample `imu_seq` at `t_s`.
    fn nav_at(stance: u64, x_m: f64, imu_seq: u64, t_s: f64) -> NavSample {
        NavSample {
            stance,
            p_m: [x_m, 0.0, 0.0],
            imu_seq,
            t_s,
            ..NavSample::default()
        }
    }

    /// [`nav_at`] at 0.01 s per IMU sample.
    fn nav(stance: u64, x_m: f64, imu_seq: u64) -> NavSample {
        nav_at(stance, x_m, imu_seq, imu_seq as f64 * 0.01)
    }

    #[test]
    fn a_stance_sent_again_replaces_the_last_stride() {
        let mut s = Strides::default();
        let got: Vec<(f64, bool)> = [
            nav(1, 0.0, 10),
            nav_at(2, 1.0, 20, 0.30), // its sample stamped 0.1 s ahead, dropped after it
            nav(2, 1.2, 21),
            nav(3, 2.0, 30),
        ]
        .into_iter()
        .map(|n| {
            let stride = s.add(n);
            (stride.step_m, stride.replaces_previous)
        })
        .collect();
        // The stance 2 sent again (its first sample's stamp was a glitch) is measured from
        // stance 1, not from the stance it replaces, and not counted twice.
        let steps: Vec<f64> = got.iter().map(|g| g.0).collect();
        assert!(
            (steps[2] - 1.2).abs() < 1e-12 && (steps[3] - 0.8).abs() < 1e-12,
            "{steps:?}"
        );
        assert_eq!(
            got.iter().map(|g| g.1).collect::<Vec<_>>(),
            [false, false, true, false]
        );
        assert_eq!(s.count, 3);
        assert!((s.path_m - 2.0).abs() < 1e-12, "{}", s.path_m);
        assert_eq!(s.last().map(|n| n.imu_seq), Some(30));
        // A run of glitched stamps (975 s ahead) that held two stances: both are replaced from
        // the first.
        s.add(nav_at(4, 3.0, 40, 975.4));
        s.add(nav_at(5, 4.0, 50, 975.5));
        let again = s.add(nav(4, 2.9, 60));
        assert!(again.replaces_previous && !again.new_track);
        assert!((again.step_m - 0.9).abs() < 1e-12);
        assert_eq!(s.count, 4);
        assert!((s.path_m - 2.9).abs() < 1e-12, "{}", s.path_m);
        // ... also over stances 1 and 2 (a review: taken for a restart).
        let mut s = Strides::default();
        s.add(nav_at(1, 0.0, 10, 975.1));
        s.add(nav_at(2, 0.7, 20, 975.2));
        let again = s.add(nav(1, 0.1, 30));
        assert!(again.replaces_previous && !again.new_track);
        assert_eq!((s.count, s.path_m), (1, 0.0));
    }

    #[test]
    fn the_first_stance_sent_again_in_the_frame_the_start_heading_set_replaces_it() {
        // As exp36 through the daemon: stance 1 published as it began, in the frame before
        // the start heading (2.99 m to stance 2 in a review), then again 0.01 s later in it.
        let mut s = Strides::default();
        s.add(nav_at(1, -0.691, 309, 3.09));
        let set = NavSample {
            flags: FLAG_FRAME_SET,
            ..nav_at(1, 0.763, 310, 3.10)
        };
        let again = s.add(set);
        assert!(again.frame_set && again.replaces_previous && !again.new_track);
        assert_eq!((again.step_m, s.count, s.path_m), (0.0, 1, 0.0));
        let second = s.add(nav_at(2, 2.251, 432, 4.315));
        assert!((second.step_m - 1.488).abs() < 1e-9, "{}", second.step_m);
        assert_eq!(s.count, 2);
        assert!((s.path_m - 1.488).abs() < 1e-9, "{}", s.path_m);
        // Without the flag the same stance at a later time is an estimator started again.
        let mut s = Strides::default();
        s.add(nav_at(1, -0.691, 309, 3.09));
        let unflagged = s.add(nav_at(1, 0.763, 310, 3.10));
        assert!(unflagged.new_track && !unflagged.frame_set);
        // The flag on a stance not sent before (the frame set as it began) replaces nothing.
        let mut s = Strides::default();
        s.add(nav_at(1, 0.0, 10, 0.1));
        let first_in_frame = s.add(NavSample {
            flags: FLAG_FRAME_SET,
            ..nav_at(2, 1.4, 20, 0.2)
        });
        assert!(first_in_frame.frame_set && !first_in_frame.replaces_previous);
        assert_eq!(s.count, 2);
    }

    #[test]
    fn a_daemon_that_restarted_within_the_stream_starts_a_new_track() {
        // The new daemon life's estimator counts stances from 1 again, from its own origin,
        // while the times go on: before, its first stride was joined to the last one (a 24 m
        // step in a review).
        let mut s = Strides::default();
        for (k, x) in [(1, 0.0), (2, 1.0), (44, 40.0)] {
            s.add(nav(k, x, k * 10));
        }
        let path_before = s.path_m;
        let first = s.add(nav(1, 0.0, 500));
        assert!(first.new_track && !first.replaces_previous);
        assert_eq!(first.step_m, 0.0);
        let second = s.add(nav(2, 0.7, 510));
        assert!(!second.new_track && (second.step_m - 0.7).abs() < 1e-12);
        assert_eq!(s.count, 5);
        assert!((s.path_m - path_before - 0.7).abs() < 1e-12);
        // A restart whose stance 1 was missed: a new track too, nothing replaced (a review:
        // seven real strides were taken back).
        let (count, path) = (s.count, s.path_m);
        let after = s.add(nav(2, 0.5, 900));
        assert!(after.new_track && !after.replaces_previous);
        assert_eq!((s.count, s.path_m), (count + 1, path));
    }
}
