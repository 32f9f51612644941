//! Lossless without stalls: a consumer that dies or stops reading must not hold the daemon's
//! publishers for longer than `daemon.stall_timeout_s`.
//!
//! iceoryx2 0.10 calls a publisher's backpressure handler (`set_backpressure_handler`) while a
//! `RetryUntilDelivered` send waits on one receiver's full buffer, with that receiver's port id
//! and the time waited so far. The handler here lets the wait go on up to the bound, then
//! discards the sample for that receiver only (the others still get it) and marks the receiver
//! as stalled: from then on a sample that does not fit its buffer is discarded at once. A
//! stalled consumer that reads again gets the samples that fit, so it is served like a `live`
//! consumer; every sample it did not get is counted. A dead consumer's connection goes away when
//! iceoryx2 cleans up its node; until then it counts as stalled.

use iceoryx2::port::{BackpressureAction, BackpressureInfo};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

/// Counts of one publisher's stalled consumers.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StallCounts {
    /// Consumers that stalled the publisher for longer than the bound.
    pub stalled_consumers: u64,
    /// Samples discarded for stalled consumers.
    pub discarded: u64,
}

#[derive(Debug, Default)]
struct State {
    /// Port ids of the stalled receivers (grows only when a consumer stalls).
    stalled: Vec<u128>,
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
        move |info: &BackpressureInfo| guard.decide(info.receiver_port_id, info.elapsed_time)
    }

    fn decide(&self, receiver: u128, waited: Duration) -> BackpressureAction {
        let mut s = self.state.lock().unwrap_or_else(PoisonError::into_inner);
        if s.stalled.contains(&receiver) {
            s.counts.discarded += 1;
            return BackpressureAction::DiscardData;
        }
        if waited < self.bound {
            return BackpressureAction::Retry;
        }
        s.stalled.push(receiver);
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

    /// Port ids of consumers that stalled since the last call (for the log).
    pub(super) fn take_new_stalls(&self) -> Vec<u128> {
        let mut s = self.state.lock().unwrap_or_else(PoisonError::into_inner);
        std::mem::take(&mut s.unreported)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_consumer_waits_up_to_the_bound_then_is_discarded_at_once() {
        let g = StallGuard::new(Duration::from_millis(100));
        let ms = Duration::from_millis;
        assert_eq!(g.decide(7, ms(50)), BackpressureAction::Retry);
        assert_eq!(g.decide(7, ms(100)), BackpressureAction::DiscardData);
        // The next sample that does not fit: no wait at all.
        assert_eq!(g.decide(7, ms(0)), BackpressureAction::DiscardData);
        // Another consumer is not affected.
        assert_eq!(g.decide(8, ms(0)), BackpressureAction::Retry);
        assert_eq!(
            g.counts(),
            StallCounts {
                stalled_consumers: 1,
                discarded: 2
            }
        );
        assert_eq!(g.take_new_stalls(), vec![7]);
        assert!(g.take_new_stalls().is_empty());
    }
}
