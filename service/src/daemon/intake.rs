//! The IMU input's bookkeeping, sample by sample: which producer's samples are taken (one at a
//! time: [`super::producers`]), where the followed producer's numbering stands, and what each
//! sample counts in the daemon's accounting file ([`super::state::Record`]): received, repeated,
//! late, refused as another producer's, and the samples missing before it (at a stream's head,
//! in a gap, across a restart of the daemon).
//!
//! Pure: no ports, no clock, no channel. The receive thread (`receive.rs`) reads a sample and
//! passes it with its producer, the time and whether a producer is still connected; it then
//! does what the [`Verdict`] says (acknowledge the producer, tell the estimator of a new
//! producer, forward the sample). Every sample a producer numbered is received or counted
//! missing once, whichever daemon life or producer was followed when (the tests below check
//! the sums), but where a replacement producer that numbers afresh is taken for one that
//! continues the old numbering (docs/known-issues.md).

use super::producers::{Admit, Missing, OtherNumbering, ProducerLock, TakeOverReason};
use super::receive::RxCounters;
use super::state::{load_opt, store_opt};
use corridor_shared::wire::ImuSample;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Producer changes per stream that are logged as warnings (the rest at debug level; all
/// counted in `producer_changes`).
const PRODUCER_CHANGE_WARNINGS_PER_STREAM: u64 = 3;

/// Producers refused per stream (another producer while the followed one is live) that are
/// logged as warnings, at their first refused sample (the rest at debug level; every sample
/// counted in `foreign`).
const FOREIGN_WARNINGS_PER_STREAM: u64 = 3;

/// What to do with one IMU sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Verdict {
    /// Acknowledge its producer (`IMU_ACK_SERVICE`): the daemon reads its samples now, so its
    /// close need not wait for it.
    pub(super) ack: bool,
    /// Tell the estimator first that another producer's samples follow mid-stream
    /// (`Msg::NewProducer`, never dropped).
    pub(super) new_producer: bool,
    pub(super) take: Take,
}

/// Whether, and how, a sample goes on to the estimator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Take {
    /// Not forwarded, and counted: another producer's while the followed one is live
    /// (`foreign`), a repeated `seq` (`duplicate`) or an earlier one (`late`).
    Refused,
    /// A data sample: forwarded under the delivery policy.
    Data,
    /// An end-of-stream marker: forwarded, never dropped.
    EndOfStream,
}

/// The receive thread's state of the IMU input (see the module documentation).
#[derive(Debug)]
pub(super) struct Intake<'a> {
    counters: &'a RxCounters,
    /// The producer followed, from an earlier life too.
    lock: ProducerLock,
    /// The numbering of the producer not followed (refused, or followed before), from an
    /// earlier life too.
    other: Option<OtherNumbering>,
    /// The `seq` of the followed producer's last data sample taken in this stream.
    last_seq: Option<u64>,
    /// The `seq` the followed producer's next stream starts with (after its end marker).
    next_stream_seq: Option<u64>,
    /// True between the first data sample of a stream and its end-of-stream marker.
    mid_stream: bool,
    /// The time stamp of the followed producer's last data sample taken (this life), for
    /// telling a replacement that continues its numbering and clock.
    last_t_s: Option<f64>,
    /// True until this life's first sample: a gap before it, in the numbering of the producer
    /// an earlier life was receiving, is counted in `missing_at_restart`.
    first_of_life: bool,
    /// Producer changes warned of in the current stream.
    changes_warned: u64,
    /// Refused producers warned of in the current stream, and the last one.
    foreign_warned: u64,
    warned_of: Option<u128>,
}

impl<'a> Intake<'a> {
    /// Continues from the accounting file (an earlier daemon life, or a new file): the producer
    /// it followed keeps the lock for `takeover_after` from `now` (see
    /// [`ProducerLock::new`]).
    pub(super) fn resume(counters: &'a RxCounters, takeover_after: Duration, now: Instant) -> Self {
        Self {
            counters,
            lock: ProducerLock::new(counters.producer(), takeover_after, now),
            other: counters.other(),
            last_seq: load_opt(&counters.last_seq_plus1),
            next_stream_seq: load_opt(&counters.next_stream_seq_plus1),
            mid_stream: counters.mid_stream.load(Ordering::Relaxed) != 0,
            last_t_s: None,
            first_of_life: true,
            changes_warned: 0,
            foreign_warned: 0,
            warned_of: None,
        }
    }

    /// The input was found empty at `now`: from here the followed producer is silent until its
    /// next sample (a review: this was marked after every forwarded sample instead, so a
    /// producer whose last sample before it hung was a repeated one never went silent).
    pub(super) fn drained(&mut self, now: Instant) {
        self.lock.drained(now);
    }

    /// Sample `s` of `producer` was read: counts it, and says what to do with it. `now` is
    /// asked only when another producer's sample comes mid-stream; `connected` says whether a
    /// producer's publisher is still on the IMU service (asked then, and at a take-over).
    pub(super) fn take(
        &mut self,
        s: &ImuSample,
        producer: u128,
        now: impl FnOnce() -> Instant,
        connected: impl Fn(u128) -> bool,
    ) -> Verdict {
        let c = self.counters;
        let last_producer = self.lock.followed();
        let admit = self.lock.admit(producer, self.mid_stream, now, &connected);
        if admit == Admit::Foreign {
            let ack = self.refuse(s, producer);
            return Verdict {
                ack,
                new_producer: false,
                take: Take::Refused,
            };
        }
        if let Admit::TakeOver(reason) = admit {
            self.log_take_over(s.seq, producer, reason);
        }
        let new_producer = last_producer != Some(producer);
        // The daemon's side of this producer's connection is attached now: its queued samples
        // survive the producer (`Producer::close` waits for the acknowledgement).
        let ack = new_producer || self.first_of_life;
        // Gaps in the numbering of the producer an earlier daemon life was receiving, up to
        // this life's first sample of it, are the restart's.
        let first_taken_of_life = std::mem::take(&mut self.first_of_life);
        let gaps = if first_taken_of_life && !new_producer {
            &c.missing_at_restart
        } else {
            &c.seq_gaps
        };
        // Where the numbering of the producer taken over from stood.
        let (last_seq_before, next_stream_seq_before) = (self.last_seq, self.next_stream_seq);
        if new_producer {
            self.next_stream_seq = None;
        }
        let changed_mid_stream = last_producer.is_some_and(|p| p != producer) && self.mid_stream;
        if changed_mid_stream {
            self.producer_changed(s, admit);
        }
        if new_producer {
            // The producer taken over from becomes the other one, with where its numbering
            // stands.
            let taken_over = last_producer.map(|p| OtherNumbering {
                producer: p,
                next_seq: if self.mid_stream {
                    last_seq_before.map(|l| l.wrapping_add(1))
                } else {
                    next_stream_seq_before
                },
                // Not when this life's first sample is the new one's: the producer taken over
                // from is an earlier life's.
                seen_this_life: !first_taken_of_life,
            });
            self.follow(producer, s.seq, taken_over, &connected);
        }
        let take = if s.is_end_of_stream() {
            self.end_stream(s.seq, gaps);
            Take::EndOfStream
        } else {
            self.number(s, gaps)
        };
        Verdict {
            ack,
            new_producer: changed_mid_stream,
            take,
        }
    }

    /// Another producer's sample while the followed one is live: counted, its numbering
    /// followed, the first of each producer per stream warned of. True for the first sample
    /// of it this life (acknowledge it: its close need not wait for the daemon).
    fn refuse(&mut self, s: &ImuSample, producer: u128) -> bool {
        let c = self.counters;
        c.received.fetch_add(1, Ordering::Relaxed);
        c.foreign.fetch_add(1, Ordering::Relaxed);
        let o = match self.other.as_mut() {
            Some(o) if o.producer == producer => o,
            _ => self.other.insert(OtherNumbering::new(producer)),
        };
        let first_this_life = !o.seen_this_life;
        count_missing(c, o.read(s.seq));
        c.set_other(o);
        if self.warned_of != Some(producer) {
            self.warned_of = Some(producer);
            self.foreign_warned += 1;
            if self.foreign_warned <= FOREIGN_WARNINGS_PER_STREAM {
                tracing::warn!(
                    seq = s.seq,
                    "IMU samples from a second producer while the followed one sends: refused, \
                     counted in foreign_samples (one producer at a time; another takes over \
                     after daemon.producer_takeover_s of silence, an end of stream or a close)"
                );
            } else {
                tracing::debug!(seq = s.seq, "IMU samples from a second producer refused");
            }
        }
        first_this_life
    }

    fn log_take_over(&self, seq: u64, producer: u128, reason: TakeOverReason) {
        let known = self.other.is_some_and(|o| o.producer == producer);
        if self.mid_stream {
            tracing::warn!(
                seq,
                "IMU producer taken over mid-stream: the followed one {}",
                reason.said()
            );
        } else if known && reason == TakeOverReason::StreamEnded {
            tracing::info!(
                seq,
                "IMU producer whose samples were refused (or that was followed before) takes \
                 over: the followed one had ended its stream"
            );
        }
    }

    /// A restarted or replaced producer mid-stream: counted and warned of; its numbering
    /// starts afresh unless it continues the old one (then the gap is real and counted).
    fn producer_changed(&mut self, s: &ImuSample, admit: Admit) {
        self.counters
            .producer_changes
            .fetch_add(1, Ordering::Relaxed);
        // Two producers at once change at every sample: a warning each flooded the log (a
        // review: one per sample); the count is `producer_changes`.
        self.changes_warned += 1;
        if self.changes_warned <= PRODUCER_CHANGE_WARNINGS_PER_STREAM {
            tracing::warn!(
                seq = s.seq,
                last_seq = ?self.last_seq,
                "IMU producer changed mid-stream{}",
                if self.changes_warned == PRODUCER_CHANGE_WARNINGS_PER_STREAM {
                    " (further changes in this stream are counted in producer_changes, not \
                     logged: two producers at once?)"
                } else {
                    ""
                }
            );
        } else {
            tracing::debug!(seq = s.seq, "IMU producer changed mid-stream");
        }
        // The new producer continues the old numbering only when the old one is gone (not
        // silent: still connected, it is a second producer) and both its `seq` and its clock
        // run on from the old one's: a restarted driver that keeps its counter and its
        // sensor's clock. Otherwise its numbering is its own, and its head is counted as such
        // (reviews: a producer at seq 100,000 after 2,000 had its head counted as gaps in the
        // old numbering, 2,000 short in the sum). After an end of stream (not mid-stream) a
        // new producer always starts its own.
        let continues = admit != Admit::TakeOver(TakeOverReason::Silent)
            && self.last_seq.is_some_and(|l| s.seq > l)
            && self.last_t_s.is_some_and(|t| s.t_s >= t);
        if !continues {
            self.last_seq = None;
        }
    }

    /// `producer` is followed from its sample `seq` on; `taken_over` is where the numbering of
    /// the producer followed before stands.
    fn follow(
        &mut self,
        producer: u128,
        seq: u64,
        taken_over: Option<OtherNumbering>,
        connected: impl Fn(u128) -> bool,
    ) {
        let c = self.counters;
        c.set_producer(producer);
        // One whose samples were read before (refused, or followed before) goes on from its
        // own numbering: its head was counted when it was first read.
        if let Some(o) = self.other.filter(|o| o.producer == producer) {
            let (missing, from) = o.take_over(seq);
            count_missing(c, missing);
            self.last_seq = from;
            self.next_stream_seq = None;
            self.other = None;
        }
        // One slot (the service takes two publishers): a producer refused while still
        // connected keeps it over the one taken over from, which then is gone (a review: a
        // driver restarted after its end of stream next to a refused producer overwrote the
        // refused one's numbering, and its head was counted again).
        let keep = self.other.is_some_and(|o| connected(o.producer));
        if !keep {
            self.other = taken_over;
        }
        if let Some(o) = &self.other {
            c.set_other(o);
        }
        // Where the new producer's numbering stands, at once (the sample may still be refused
        // as repeated or late, before the store of its position).
        store_opt(&c.last_seq_plus1, self.last_seq);
        store_opt(&c.next_stream_seq_plus1, self.next_stream_seq);
    }

    /// An end-of-stream marker `seq`: the samples missing before it, and the next stream
    /// starts after it.
    fn end_stream(&mut self, seq: u64, gaps: &AtomicU64) {
        let c = self.counters;
        self.changes_warned = 0;
        self.foreign_warned = 0;
        self.warned_of = None;
        match (self.last_seq, self.next_stream_seq) {
            (Some(l), _) if seq > l => {
                gaps.fetch_add(seq - l - 1, Ordering::Relaxed);
            }
            (Some(_), _) => {}
            // A marker at the head of a stream (all its data lost, or sent while no daemon
            // ran): what was numbered before it is missing, as before a stream's first sample
            // (a review: it was counted nowhere).
            (None, Some(first)) => {
                gaps.fetch_add(seq.saturating_sub(first), Ordering::Relaxed);
            }
            (None, None) => {
                c.head_missing.fetch_add(seq, Ordering::Relaxed);
            }
        }
        self.next_stream_seq = Some(seq.wrapping_add(1));
        self.last_seq = None;
        self.mid_stream = false;
        store_opt(&c.next_stream_seq_plus1, self.next_stream_seq);
        c.mid_stream.store(0, Ordering::Relaxed);
        store_opt(&c.last_seq_plus1, None);
        c.received.fetch_add(1, Ordering::Relaxed);
    }

    /// A data sample of the followed producer: where it stands in the numbering.
    fn number(&mut self, s: &ImuSample, gaps: &AtomicU64) -> Take {
        let c = self.counters;
        if self.last_seq.is_none() && self.next_stream_seq.is_some_and(|first| s.seq < first) {
            // Numbered before the end marker just read: a late sample of the stream that ended,
            // not the head of a new one (a review: it started one, and the marker's own `seq`
            // was then counted missing).
            c.received.fetch_add(1, Ordering::Relaxed);
            c.late.fetch_add(1, Ordering::Relaxed);
            return Take::Refused;
        }
        if !self.mid_stream {
            self.mid_stream = true;
            c.mid_stream.store(1, Ordering::Relaxed);
        }
        match self.last_seq {
            // The head of a stream: what the producer numbered before this sample.
            None => {
                match self.next_stream_seq.take() {
                    Some(first) => gaps.fetch_add(s.seq.saturating_sub(first), Ordering::Relaxed),
                    None => c.head_missing.fetch_add(s.seq, Ordering::Relaxed),
                };
                store_opt(&c.next_stream_seq_plus1, None);
            }
            Some(l) if s.seq == l => {
                c.received.fetch_add(1, Ordering::Relaxed);
                c.duplicate.fetch_add(1, Ordering::Relaxed);
                return Take::Refused;
            }
            Some(l) if s.seq < l => {
                c.received.fetch_add(1, Ordering::Relaxed);
                c.late.fetch_add(1, Ordering::Relaxed);
                return Take::Refused;
            }
            Some(l) => {
                gaps.fetch_add(s.seq - l - 1, Ordering::Relaxed);
            }
        }
        self.last_seq = Some(s.seq);
        self.last_t_s = Some(s.t_s);
        // `received` is counted next to the store of the position (`last_seq_plus1`), so a
        // SIGKILL can misplace at most the one sample between the two stores.
        store_opt(&c.last_seq_plus1, self.last_seq);
        c.received.fetch_add(1, Ordering::Relaxed);
        Take::Data
    }
}

/// Adds the samples missing before one that was read to their counters.
fn count_missing(c: &RxCounters, m: Missing) {
    for (n, counter) in [
        (m.head, &c.head_missing),
        (m.gap, &c.seq_gaps),
        (m.at_restart, &c.missing_at_restart),
    ] {
        if n > 0 {
            counter.fetch_add(n, Ordering::Relaxed);
        }
    }
}

#[cfg(test)]
#[path = "intake_tests.rs"]
mod tests;
