//! One IMU producer at a time: which producer's samples the receive thread takes when more than
//! one publishes on the domain.
//!
//! The daemon estimates one foot from one numbering and one clock. Two producers at once (a
//! driver started twice, a replay run next to the live driver) interleave two walks sample by
//! sample: before this rule every sample was a "producer change", the loss accounting counted
//! millions of missing samples and the estimator saw the clock jump back and forth. Now the
//! daemon follows one producer and refuses the other's samples, counting each
//! (`foreign_samples`). The other takes over when the followed one
//! - ended its stream (an end-of-stream marker: a new stream may come from anyone),
//! - is no longer connected (its publisher closed, or iceoryx2 cleaned up its dead node, which a
//!   restarted driver's node does when it is created), or
//! - has sent nothing for `daemon.producer_takeover_s` while the input was caught up (a hung
//!   driver replaced by another).
//!
//! Silence is counted from the first time the receive thread found the input empty after the
//! followed producer's last sample, not from its last sample: a receive thread held up (a full
//! channel in lossless delivery) does not make a live producer look silent.
//!
//! The other producer's numbering ([`OtherNumbering`]) is kept as the followed one's is: what
//! was missing before its first read sample, and the gaps between its read samples, refused or
//! not, are counted (`head_missing`, `seq_gaps`, `missing_at_restart`), so every sample a
//! producer sent is received or counted missing once, whichever producer was followed when.
//!
//! Pure: the caller passes the time and whether the followed producer is still connected.

use std::time::{Duration, Instant};

/// What to do with a sample, by its producer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Admit {
    /// From the followed producer (or the first producer seen): take it.
    Followed,
    /// Another producer takes over from the followed one (the reason, for the log): take it.
    TakeOver(TakeOverReason),
    /// Another producer while the followed one is live: refuse it and count it.
    Foreign,
}

/// Why another producer took over.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum TakeOverReason {
    /// The followed producer's stream had ended (or none had started).
    StreamEnded,
    /// The followed producer is no longer connected.
    Gone,
    /// The followed producer sent nothing for the take-over time.
    Silent,
}

impl TakeOverReason {
    /// For the log: "the followed producer …".
    pub(super) fn said(self) -> &'static str {
        match self {
            Self::StreamEnded => "had ended its stream",
            Self::Gone => "is no longer connected",
            Self::Silent => "was silent for daemon.producer_takeover_s",
        }
    }
}

/// The producer followed, and since when it has been silent.
#[derive(Debug)]
pub(super) struct ProducerLock {
    followed: Option<u128>,
    /// The first time the input was found empty after the followed producer's last sample.
    quiet_since: Option<Instant>,
    takeover_after: Duration,
}

impl ProducerLock {
    /// Follows `followed` (the producer an earlier daemon life followed, if any), counting it
    /// as silent from `now`: a producer that is still connected keeps the lock for
    /// `takeover_after` into this life.
    pub(super) fn new(followed: Option<u128>, takeover_after: Duration, now: Instant) -> Self {
        Self {
            followed,
            quiet_since: Some(now),
            takeover_after,
        }
    }

    /// The producer followed.
    pub(super) fn followed(&self) -> Option<u128> {
        self.followed
    }

    /// Whether to take a sample of `producer`. `mid_stream`: the followed producer's stream has
    /// started and not ended; `connected` says whether the followed producer's publisher is
    /// still on the service (asked only when another producer's sample comes mid-stream).
    pub(super) fn admit(
        &mut self,
        producer: u128,
        mid_stream: bool,
        now: impl FnOnce() -> Instant,
        connected: impl FnOnce(u128) -> bool,
    ) -> Admit {
        let Some(followed) = self.followed else {
            self.follow(producer);
            return Admit::Followed;
        };
        if followed == producer {
            self.quiet_since = None;
            return Admit::Followed;
        }
        let reason = if !mid_stream {
            TakeOverReason::StreamEnded
        } else if !connected(followed) {
            TakeOverReason::Gone
        } else if self
            .quiet_since
            .is_some_and(|t| now().saturating_duration_since(t) >= self.takeover_after)
        {
            TakeOverReason::Silent
        } else {
            return Admit::Foreign;
        };
        self.follow(producer);
        Admit::TakeOver(reason)
    }

    /// The input was found empty at `now`: the followed producer is silent from here unless
    /// it was already.
    pub(super) fn drained(&mut self, now: Instant) {
        self.quiet_since.get_or_insert(now);
    }

    fn follow(&mut self, producer: u128) {
        self.followed = Some(producer);
        self.quiet_since = None;
    }
}

/// The numbering of the producer that is not followed: refused now, or followed before another
/// took over. One is kept (the IMU service takes two publishers at a time).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct OtherNumbering {
    pub(super) producer: u128,
    /// The `seq` expected next from it; `None` before any of its samples was read (its head is
    /// unknown).
    pub(super) next_seq: Option<u64>,
    /// This daemon life has read one of its samples: a gap before the first one of a life is the
    /// restart's.
    pub(super) seen_this_life: bool,
}

/// Samples of a numbering missing before one that was read, by where they are counted.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(super) struct Missing {
    /// Before the first sample ever read of it (`head_missing`).
    pub(super) head: u64,
    /// Between two samples read by one daemon life (`seq_gaps`).
    pub(super) gap: u64,
    /// Between the last sample an earlier life read and the first this life read
    /// (`missing_at_restart`).
    pub(super) at_restart: u64,
}

impl OtherNumbering {
    /// A producer none of whose samples was read yet.
    pub(super) fn new(producer: u128) -> Self {
        Self {
            producer,
            next_seq: None,
            seen_this_life: false,
        }
    }

    fn missing_before(&self, n: u64, seq: u64) -> Missing {
        if self.seen_this_life {
            Missing {
                gap: seq - n,
                ..Missing::default()
            }
        } else {
            Missing {
                at_restart: seq - n,
                ..Missing::default()
            }
        }
    }

    /// A refused sample `seq` of it was read: what is missing before it. A `seq` that does not
    /// go forward (a repeated or late sample) changes nothing (a review: it was taken for a
    /// restarted numbering, and the whole refused run was counted as a head missing).
    pub(super) fn read(&mut self, seq: u64) -> Missing {
        let missing = match self.next_seq {
            None => Missing {
                head: seq,
                ..Missing::default()
            },
            Some(n) if seq >= n => self.missing_before(n, seq),
            Some(_) => {
                self.seen_this_life = true;
                return Missing::default();
            }
        };
        self.next_seq = Some(seq.wrapping_add(1));
        self.seen_this_life = true;
        missing
    }

    /// It takes over with sample `seq`: what is missing before it, and the `last_seq` the
    /// followed numbering goes on from (`None`: its head is unknown, and is counted as a
    /// stream's head).
    pub(super) fn take_over(&self, seq: u64) -> (Missing, Option<u64>) {
        match self.next_seq {
            None => (Missing::default(), None),
            Some(n) if seq >= n => (self.missing_before(n, seq), seq.checked_sub(1)),
            // Its own repeated or late sample: the followed numbering counts it so.
            Some(n) => (Missing::default(), n.checked_sub(1)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: u128 = 1;
    const B: u128 = 2;
    const WAIT: Duration = Duration::from_secs(1);

    fn ms(t0: Instant, ms: u64) -> Instant {
        t0 + Duration::from_millis(ms)
    }

    #[test]
    fn a_second_producer_is_refused_while_the_first_sends_and_takes_over_when_it_is_silent() {
        let t0 = Instant::now();
        let mut lock = ProducerLock::new(None, WAIT, t0);
        let connected = |_| true;
        assert_eq!(lock.admit(A, false, || t0, connected), Admit::Followed);
        // Interleaved, with the input drained between: A keeps the lock for as long as it sends.
        for k in 0..100 {
            let t = ms(t0, 5 * k);
            assert_eq!(lock.admit(A, true, || t, connected), Admit::Followed);
            assert_eq!(lock.admit(B, true, || t, connected), Admit::Foreign);
            lock.drained(t);
        }
        // A goes silent (still connected: hung); B is refused until A has been silent for WAIT.
        let last = ms(t0, 500);
        lock.drained(last);
        assert_eq!(
            lock.admit(B, true, || ms(t0, 1400), connected),
            Admit::Foreign
        );
        assert_eq!(
            lock.admit(B, true, || ms(t0, 1495), connected),
            Admit::TakeOver(TakeOverReason::Silent)
        );
        assert_eq!(lock.followed(), Some(B));
        // Now A is the foreign one.
        assert_eq!(
            lock.admit(A, true, || ms(t0, 1500), connected),
            Admit::Foreign
        );
        assert_eq!(
            lock.admit(B, true, || ms(t0, 1500), connected),
            Admit::Followed
        );
    }

    #[test]
    fn silence_counts_only_from_an_empty_input() {
        // The receive thread was held up for 5 s (a full channel) with A's samples still queued:
        // A is not silent, whatever the time since its last sample was taken.
        let t0 = Instant::now();
        let mut lock = ProducerLock::new(None, WAIT, t0);
        assert_eq!(lock.admit(A, true, || t0, |_| true), Admit::Followed);
        assert_eq!(
            lock.admit(B, true, || ms(t0, 5000), |_| true),
            Admit::Foreign
        );
        // Once found empty, the silence runs from then.
        lock.drained(ms(t0, 5000));
        lock.drained(ms(t0, 5900)); // a later drain does not move its start
        assert_eq!(
            lock.admit(B, true, || ms(t0, 5999), |_| true),
            Admit::Foreign
        );
        assert!(matches!(
            lock.admit(B, true, || ms(t0, 6000), |_| true),
            Admit::TakeOver(_)
        ));
    }

    #[test]
    fn another_producer_takes_over_at_once_after_an_end_of_stream_or_when_the_first_is_gone() {
        let t0 = Instant::now();
        let mut lock = ProducerLock::new(Some(A), WAIT, t0);
        assert_eq!(
            lock.admit(B, false, || t0, |_| true),
            Admit::TakeOver(TakeOverReason::StreamEnded)
        );
        let mut asked = None;
        assert_eq!(
            lock.admit(
                A,
                true,
                || t0,
                |p| {
                    asked = Some(p);
                    false
                }
            ),
            Admit::TakeOver(TakeOverReason::Gone)
        );
        assert_eq!(asked, Some(B), "asks about the followed producer");
    }

    #[test]
    fn the_other_producers_numbering_counts_its_head_and_gaps_once() {
        let mut o = OtherNumbering::new(B);
        // Its first read sample is seq 40: 40 were sent before any was read.
        assert_eq!(
            o.read(40),
            Missing {
                head: 40,
                ..Missing::default()
            }
        );
        assert_eq!(o.read(41), Missing::default());
        // 42..45 overwritten in a live buffer.
        assert_eq!(
            o.read(46),
            Missing {
                gap: 4,
                ..Missing::default()
            }
        );
        // Repeated and late samples change nothing (they restarted the numbering once).
        assert_eq!(o.read(46), Missing::default());
        assert_eq!(o.read(10), Missing::default());
        assert_eq!(o.next_seq, Some(47));
        // It takes over at 50: 3 missing, the followed numbering goes on from 49.
        assert_eq!(
            o.take_over(50),
            (
                Missing {
                    gap: 3,
                    ..Missing::default()
                },
                Some(49)
            )
        );
        assert_eq!(o.take_over(47), (Missing::default(), Some(46)));
        // In a new daemon life the first gap is the restart's.
        let mut later = OtherNumbering {
            seen_this_life: false,
            ..o
        };
        assert_eq!(
            later.read(60),
            Missing {
                at_restart: 13,
                ..Missing::default()
            }
        );
        // Nothing read of it yet: a take-over's head is the caller's to count.
        assert_eq!(
            OtherNumbering::new(A).take_over(7),
            (Missing::default(), None)
        );
    }

    #[test]
    fn a_restarted_daemon_keeps_the_producer_of_its_last_life_for_the_take_over_time() {
        let t0 = Instant::now();
        let mut lock = ProducerLock::new(Some(A), WAIT, t0);
        assert_eq!(lock.admit(B, true, || ms(t0, 10), |_| true), Admit::Foreign);
        assert_eq!(
            lock.admit(A, true, || ms(t0, 20), |_| true),
            Admit::Followed
        );
        // A producer of the last life that never comes back: B after the take-over time.
        let mut lock = ProducerLock::new(Some(A), WAIT, t0);
        assert_eq!(
            lock.admit(B, true, || ms(t0, 1000), |_| true),
            Admit::TakeOver(TakeOverReason::Silent)
        );
    }
}
