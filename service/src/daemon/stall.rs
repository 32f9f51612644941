//! Lossless without stalls: a consumer that dies or stops reading must not hold the daemon's
//! publishers for longer than `daemon.stall_timeout_s`.
//!
//! iceoryx2 0.10 calls a publisher's backpressure handler (`set_backpressure_handler`) while a
//! `RetryUntilDelivered` send waits on one receiver's full buffer, with that receiver's port id
//! and the time waited so far. The handler here lets the wait go on up to the bound, then
//! discards the sample for that receiver only (the others still get it) and marks the receiver
//! as stalled: from then on a sample that does not fit its buffer is discarded at once. A
//! stalled consumer that reads again gets the samples that fit, so it is served like a `live`
//! consumer; every sample it did not get is counted. Once nothing has been discarded for it for
//! [`RECOVERED_AFTER`], it has caught up and is lossless again: a later full buffer is waited on
//! up to the bound, as the first time (before, a consumer that stalled once stayed lossy for the
//! daemon's life, and the list of stalled consumers only grew). A dead consumer's connection
//! goes away when iceoryx2 cleans up its node; until then it counts as stalled, and on an output
//! published less often than [`RECOVERED_AFTER`] it costs one wait of the bound per sample.

use iceoryx2::port::{BackpressureAction, BackpressureInfo};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

/// A stalled consumer for which nothing was discarded for this long has caught up: it is waited
/// on again. Longer than the period of every periodic output (the bias's, 1 s by default), so
/// a consumer that stays stalled is not waited on at each of its samples.
pub(super) const RECOVERED_AFTER: Duration = Duration::from_secs(60);

/// Counts of one publisher's stalled consumers.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StallCounts {
    /// Times a consumer stalled the publisher for longer than the bound (a consumer that
    /// recovered and stalled again counts again).
    pub stalled_consumers: u64,
    /// Samples discarded for stalled consumers.
    pub discarded: u64,
}

#[derive(Debug, Default)]
struct State {
    /// Port ids of the stalled receivers, with when a sample was last discarded for each (those
    /// quiet for [`RECOVERED_AFTER`] leave it).
    stalled: Vec<(u128, Instant)>,
    counts: StallCounts,
    /// Stalls not reported yet.
    unreported: Vec<u128>,
}

/// The shared state between a publisher's backpressure handler and the daemon.
#[derive(Debug, Clone)]
pub(super) struct StallGuard {
    bound: Duration,
    state: Arc<Mutex<State>>,
}

impl StallGuard {
    /// A guard that lets a send wait at most `bound` on one consumer.
    pub(super) fn new(bound: Duration) -> Self {
        Self {
            bound,
            state: Arc::default(),
        }
    }

    /// The handler for `set_backpressure_handler`.
    pub(super) fn handler(
        &self,
    ) -> impl Fn(&BackpressureInfo) -> BackpressureAction + Send + 'static {
        let guard = self.clone();
        move |info: &BackpressureInfo| {
            guard.decide(info.receiver_port_id, info.elapsed_time, Instant::now())
        }
    }

    fn decide(&self, receiver: u128, waited: Duration, now: Instant) -> BackpressureAction {
        let mut s = self.state.lock().unwrap_or_else(PoisonError::into_inner);
        // Consumers quiet for long enough have caught up.
        s.stalled
            .retain(|&(_, last)| now.saturating_duration_since(last) < RECOVERED_AFTER);
        if let Some(entry) = s.stalled.iter_mut().find(|(r, _)| *r == receiver) {
            entry.1 = now;
            s.counts.discarded += 1;
            return BackpressureAction::DiscardData;
        }
        if waited < self.bound {
            return BackpressureAction::Retry;
        }
        s.stalled.push((receiver, now));
        s.unreported.push(receiver);
        s.counts.stalled_consumers += 1;
        s.counts.discarded += 1;
        BackpressureAction::DiscardData
    }

    /// The counts so far.
    pub(super) fn counts(&self) -> StallCounts {
        self.state
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .counts
    }

    /// Port ids of consumers that stalled since the last call (for the log), and the samples
    /// discarded so far (one lock, taken after each send).
    pub(super) fn take_new_stalls(&self) -> (Vec<u128>, u64) {
        let mut s = self.state.lock().unwrap_or_else(PoisonError::into_inner);
        (std::mem::take(&mut s.unreported), s.counts.discarded)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_periodic_output_comes_more_often_than_a_stall_is_forgotten() {
        // The longest `daemon.bias_period_s` and `daemon.diagnostics_period_s` the
        // configuration takes: a consumer that stays stalled is not waited on at each sample.
        let longest = corridor_shared::config::defaults::DAEMON_OUTPUT_PERIOD_MAX_S;
        assert!(RECOVERED_AFTER.as_secs_f64() >= longest);
    }

    #[test]
    fn a_consumer_waits_up_to_the_bound_then_is_discarded_at_once() {
        let g = StallGuard::new(Duration::from_millis(100));
        let ms = Duration::from_millis;
        let t0 = Instant::now();
        assert_eq!(g.decide(7, ms(50), t0), BackpressureAction::Retry);
        assert_eq!(g.decide(7, ms(100), t0), BackpressureAction::DiscardData);
        // The next sample that does not fit: no wait at all.
        assert_eq!(
            g.decide(7, ms(0), t0 + ms(5)),
            BackpressureAction::DiscardData
        );
        // Another consumer is not affected.
        assert_eq!(g.decide(8, ms(0), t0 + ms(5)), BackpressureAction::Retry);
        assert_eq!(
            g.counts(),
            StallCounts {
                stalled_consumers: 1,
                discarded: 2
            }
        );
        assert_eq!(g.take_new_stalls().0, vec![7]);
        assert!(g.take_new_stalls().0.is_empty());
    }

    #[test]
    fn a_stalled_consumer_that_caught_up_is_waited_on_again() {
        let g = StallGuard::new(Duration::from_millis(100));
        let ms = Duration::from_millis;
        let t0 = Instant::now();
        assert_eq!(g.decide(7, ms(100), t0), BackpressureAction::DiscardData);
        // Still stalled: each sample that does not fit is discarded at once, and each discard
        // keeps it stalled, however long it lasts.
        let mut t = t0;
        for _ in 0..100 {
            t += ms(1000);
            assert_eq!(g.decide(7, ms(0), t), BackpressureAction::DiscardData);
        }
        // It read again and nothing was discarded for it for RECOVERED_AFTER: lossless again.
        let later = t + RECOVERED_AFTER;
        assert_eq!(g.decide(7, ms(0), later), BackpressureAction::Retry);
        assert_eq!(g.decide(7, ms(100), later), BackpressureAction::DiscardData);
        assert_eq!(
            g.counts(),
            StallCounts {
                stalled_consumers: 2,
                discarded: 102
            }
        );
        // The list holds the consumers stalled now, not every one that ever stalled.
        for r in 10..20 {
            assert_eq!(g.decide(r, ms(100), later), BackpressureAction::DiscardData);
        }
        let quiet = later + RECOVERED_AFTER;
        assert_eq!(g.decide(99, ms(0), quiet), BackpressureAction::Retry);
        assert!(g.state.lock().unwrap().stalled.is_empty());
    }
}
