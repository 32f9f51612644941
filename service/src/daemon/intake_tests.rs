//! The intake's counts, without ports: every sample a producer numbered is received or counted
//! missing once, across losses, repeats, end markers, daemon restarts and two producers.

use super::*;
use crate::daemon::state::Record;
use corridor_shared::wire::FLAG_END_OF_STREAM;

const A: u128 = 1;
const B: u128 = 2;
const WAIT: Duration = Duration::from_secs(1);
const ALWAYS: fn(u128) -> bool = |_| true;

fn data(seq: u64) -> ImuSample {
    ImuSample {
        seq,
        t_s: seq as f64 * 0.01,
        ..ImuSample::default()
    }
}

fn marker(seq: u64) -> ImuSample {
    ImuSample {
        seq,
        flags: FLAG_END_OF_STREAM,
        ..ImuSample::default()
    }
}

fn get(a: &AtomicU64) -> u64 {
    a.load(Ordering::Relaxed)
}

/// The samples counted missing, wherever.
fn missing(r: &Record) -> u64 {
    get(&r.head_missing) + get(&r.seq_gaps) + get(&r.missing_at_restart)
}

/// The verdicts' takes of `samples` from `producer`, at `t0`, every producer connected.
fn takes(intake: &mut Intake, producer: u128, samples: &[ImuSample], t0: Instant) -> Vec<Take> {
    samples
        .iter()
        .map(|s| intake.take(s, producer, || t0, ALWAYS).take)
        .collect()
}

#[test]
fn a_stream_with_losses_counts_each_lost_sample_once_where_it_was_lost() {
    let r = Record::default();
    let t0 = Instant::now();
    let mut intake = Intake::resume(&r, WAIT, t0);
    // 0..=999 and the marker 1000; lost: the first three, every 7th, and 300..350.
    let lost = |q: u64| q < 3 || q.is_multiple_of(7) || (300..350).contains(&q);
    let sent: Vec<ImuSample> = (0..1000).map(data).chain([marker(1000)]).collect();
    let read: Vec<ImuSample> = sent.iter().copied().filter(|s| !lost(s.seq)).collect();
    let mut acks = 0;
    for (k, s) in read.iter().enumerate() {
        let v = intake.take(s, A, || t0, ALWAYS);
        acks += usize::from(v.ack);
        assert!(!v.new_producer);
        let want = if k + 1 == read.len() {
            Take::EndOfStream
        } else {
            Take::Data
        };
        assert_eq!(v.take, want, "sample {}", s.seq);
    }
    assert_eq!(acks, 1, "acknowledged once, at its first sample");
    assert_eq!(get(&r.received), read.len() as u64);
    assert_eq!(get(&r.head_missing), 3);
    assert_eq!(get(&r.seq_gaps), (1001 - read.len() - 3) as u64);
    assert_eq!(get(&r.missing_at_restart), 0);
    assert_eq!(get(&r.received) + missing(&r), sent.len() as u64);
}

#[test]
fn repeated_and_late_samples_are_refused_and_counted_not_forwarded() {
    let r = Record::default();
    let t0 = Instant::now();
    let mut intake = Intake::resume(&r, WAIT, t0);
    let seqs = [0, 1, 2, 2, 5, 3, 6];
    let got = takes(&mut intake, A, &seqs.map(data), t0);
    use Take::{Data as D, Refused as R};
    assert_eq!(got, [D, D, D, R, D, R, D]);
    assert_eq!(get(&r.duplicate), 1);
    assert_eq!(get(&r.late), 1);
    // 3 and 4 were missing when 5 came; 3 came late after all (counted in both).
    assert_eq!(get(&r.seq_gaps), 2);
    assert_eq!(get(&r.received), 7);
}

#[test]
fn a_sample_numbered_before_an_end_marker_and_read_after_it_is_late() {
    let r = Record::default();
    let t0 = Instant::now();
    let mut intake = Intake::resume(&r, WAIT, t0);
    let read = [data(275), data(276), marker(278), data(277), data(279)];
    let got = takes(&mut intake, A, &read, t0);
    use Take::{Data as D, EndOfStream as E, Refused as R};
    assert_eq!(got, [D, D, E, R, D]);
    assert_eq!(get(&r.late), 1);
    // 277 counted missing at the marker, received late; 278 not missing.
    assert_eq!((get(&r.head_missing), get(&r.seq_gaps)), (275, 1));
}

#[test]
fn a_gap_before_a_lifes_first_sample_from_a_producer_taking_over_is_the_restarts() {
    // Life 1 follows A and has read B's 0..10, refused; A ends. Life 2's first sample is B's
    // 20, taking over: 10..20 went while no daemon ran.
    let r = Record::default();
    let t0 = Instant::now();
    {
        let mut life = Intake::resume(&r, WAIT, t0);
        takes(&mut life, A, &(0..50).map(data).collect::<Vec<_>>(), t0);
        let got = takes(&mut life, B, &(0..10).map(data).collect::<Vec<_>>(), t0);
        assert!(got.iter().all(|t| *t == Take::Refused));
        takes(&mut life, A, &[marker(50)], t0);
    }
    let mut life = Intake::resume(&r, WAIT, t0);
    assert_eq!(life.take(&data(20), B, || t0, ALWAYS).take, Take::Data);
    assert_eq!(get(&r.missing_at_restart), 10);
    assert_eq!(get(&r.seq_gaps), 0);
    assert_eq!(get(&r.head_missing), 0);

    // The producer taken over from at a life's first sample is an earlier life's: its gap up
    // to its next read sample is the restart's too. Life 1 reads A's 0..50 mid-stream; life 2's
    // first sample is B's (A gone), then A comes back at 60, refused.
    let r = Record::default();
    {
        let mut life = Intake::resume(&r, WAIT, t0);
        takes(&mut life, A, &(0..50).map(data).collect::<Vec<_>>(), t0);
    }
    let mut life = Intake::resume(&r, WAIT, t0);
    let v = life.take(&data(0), B, || t0, |p| p != A);
    assert_eq!(v.take, Take::Data);
    assert!(v.new_producer);
    assert_eq!(life.take(&data(1), B, || t0, ALWAYS).take, Take::Data);
    assert_eq!(life.take(&data(60), A, || t0, ALWAYS).take, Take::Refused);
    assert_eq!(get(&r.missing_at_restart), 10);
    assert_eq!(get(&r.seq_gaps), 0);
}

#[test]
fn a_restarted_daemon_counts_what_it_missed_at_the_restart_once() {
    let r = Record::default();
    let t0 = Instant::now();
    {
        let mut life = Intake::resume(&r, WAIT, t0);
        let got = takes(&mut life, A, &(0..100).map(data).collect::<Vec<_>>(), t0);
        assert!(got.iter().all(|t| *t == Take::Data));
    }
    // The next life reads on from 130 (100..130 were sent while no daemon ran), with a gap of
    // its own at 150..160.
    let mut life = Intake::resume(&r, WAIT, t0);
    let read: Vec<ImuSample> = (130..200)
        .filter(|q| !(150..160).contains(q))
        .map(data)
        .chain([marker(200)])
        .collect();
    let first = life.take(&read[0], A, || t0, ALWAYS);
    assert!(
        first.ack,
        "a new life acknowledges the producer it goes on with"
    );
    assert!(!first.new_producer, "the same producer, not a change");
    takes(&mut life, A, &read[1..], t0);
    assert_eq!(get(&r.missing_at_restart), 30);
    assert_eq!(get(&r.seq_gaps), 10);
    assert_eq!(get(&r.head_missing), 0);
    assert_eq!(get(&r.received) + missing(&r), 201);
}

#[test]
fn a_second_producer_is_refused_while_the_first_sends_and_takes_over_at_its_end() {
    let r = Record::default();
    let t0 = Instant::now();
    let mut intake = Intake::resume(&r, WAIT, t0);
    // A sends 0..50 and its marker; B starts after A's tenth sample, interleaved.
    let mut refused = 0;
    for q in 0..50 {
        assert_eq!(intake.take(&data(q), A, || t0, ALWAYS).take, Take::Data);
        if q >= 10 {
            let v = intake.take(&data(q - 10), B, || t0, ALWAYS);
            assert_eq!(v.take, Take::Refused);
            assert_eq!(
                v.ack,
                q == 10,
                "B acknowledged at its first read sample only"
            );
            refused += 1;
        }
    }
    assert_eq!(
        intake.take(&marker(50), A, || t0, ALWAYS).take,
        Take::EndOfStream
    );
    // B takes over at its next sample and goes on from its own numbering: its refused samples
    // were counted, so nothing is missing.
    let v = intake.take(&data(40), B, || t0, ALWAYS);
    assert_eq!(v.take, Take::Data);
    assert!(
        v.ack && !v.new_producer,
        "after an end of stream: not a change mid-stream"
    );
    let rest = takes(&mut intake, B, &(41..60).map(data).collect::<Vec<_>>(), t0);
    assert!(rest.iter().all(|t| *t == Take::Data));
    assert_eq!(get(&r.foreign), refused);
    assert_eq!(get(&r.producer_changes), 0);
    assert_eq!(missing(&r), 0);
    assert_eq!(get(&r.received), 51 + 60);
}

#[test]
fn a_hung_producer_is_taken_over_after_the_take_over_time_and_both_numberings_kept() {
    let r = Record::default();
    let t0 = Instant::now();
    let at = |ms: u64| t0 + Duration::from_millis(ms);
    let mut intake = Intake::resume(&r, WAIT, t0);
    takes(&mut intake, A, &(0..20).map(data).collect::<Vec<_>>(), t0);
    intake.drained(at(0)); // A hangs mid-stream, still connected
    assert_eq!(
        intake.take(&data(0), B, || at(500), ALWAYS).take,
        Take::Refused
    );
    let v = intake.take(&data(1), B, || at(1000), ALWAYS);
    assert_eq!(v.take, Take::Data);
    assert!(
        v.new_producer,
        "taken over mid-stream: the estimator is told"
    );
    assert_eq!(get(&r.producer_changes), 1);
    // A wakes up while B sends: refused, and its numbering followed.
    for q in 2..10 {
        assert_eq!(
            intake.take(&data(q), B, || at(1000), ALWAYS).take,
            Take::Data
        );
        let a = intake.take(&data(18 + q), A, || at(1000), ALWAYS);
        assert_eq!(a.take, Take::Refused);
    }
    assert_eq!(
        intake.take(&marker(10), B, || at(1000), ALWAYS).take,
        Take::EndOfStream
    );
    // A takes over again after B's end, from its own numbering (27 read last, refused).
    assert_eq!(
        intake.take(&data(28), A, || at(1000), ALWAYS).take,
        Take::Data
    );
    assert_eq!(
        intake.take(&marker(29), A, || at(1000), ALWAYS).take,
        Take::EndOfStream
    );
    assert_eq!(get(&r.foreign), 1 + 8);
    assert_eq!(
        missing(&r),
        0,
        "30 of A and 11 of B, each received or counted once"
    );
    assert_eq!(get(&r.received), 30 + 11);
}

#[test]
fn a_replacement_continues_the_old_numbering_only_when_the_old_producer_is_gone() {
    // A is gone (closed) and B goes on from A's seq and clock: a restarted driver that keeps
    // its counter. The five between are lost.
    let r = Record::default();
    let t0 = Instant::now();
    let mut intake = Intake::resume(&r, WAIT, t0);
    takes(&mut intake, A, &(0..100).map(data).collect::<Vec<_>>(), t0);
    let v = intake.take(&data(105), B, || t0, |p| p != A);
    assert_eq!(v.take, Take::Data);
    assert!(v.new_producer);
    assert_eq!(get(&r.seq_gaps), 5);
    assert_eq!(get(&r.head_missing), 0);

    // A silent one is still connected: B's numbering is its own, its head counted as such.
    let r = Record::default();
    let mut intake = Intake::resume(&r, WAIT, t0);
    takes(&mut intake, A, &(0..100).map(data).collect::<Vec<_>>(), t0);
    intake.drained(t0);
    let v = intake.take(&data(105), B, || t0 + WAIT, ALWAYS);
    assert_eq!(v.take, Take::Data);
    assert_eq!(get(&r.seq_gaps), 0);
    assert_eq!(get(&r.head_missing), 105);
}

#[test]
fn an_end_marker_at_a_streams_head_counts_what_was_numbered_before_it() {
    let r = Record::default();
    let t0 = Instant::now();
    let mut intake = Intake::resume(&r, WAIT, t0);
    let mut read: Vec<ImuSample> = (0..10).map(data).collect();
    // The stream 11..=14 lost whole, its marker 15 read; then 16.. read.
    read.extend([marker(10), marker(15)]);
    read.extend((16..20).map(data));
    read.push(marker(20));
    takes(&mut intake, A, &read, t0);
    assert_eq!(get(&r.seq_gaps), 4);
    assert_eq!(get(&r.received) + missing(&r), 21);
}

/// A small deterministic generator (the tests need no crate for it).
struct Lcg(u64);

impl Lcg {
    fn below(&mut self, n: u64) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 33) % n
    }
}

/// A producer that numbers every message it sends, markers included, and loses some.
struct Producer {
    id: u128,
    next_seq: u64,
    in_stream: bool,
    sent: u64,
    /// Whether its last message was read.
    last_read: bool,
}

impl Producer {
    fn new(id: u128) -> Self {
        Self {
            id,
            next_seq: 0,
            in_stream: false,
            sent: 0,
            last_read: true,
        }
    }

    /// Its next message: a data sample, or its stream's end marker when `end`.
    fn send(&mut self, end: bool) -> ImuSample {
        let end = end && self.in_stream;
        let s = if end {
            marker(self.next_seq)
        } else {
            data(self.next_seq)
        };
        self.in_stream = !end;
        self.next_seq += 1;
        self.sent += 1;
        s
    }
}

#[test]
fn two_producers_losses_ends_silences_and_restarts_leave_every_sample_counted_once() {
    let (mut changes, mut at_restart, mut gone) = (0, 0, 0);
    for seed in 0..200 {
        let r = Record::default();
        let t0 = Instant::now();
        let mut now = t0;
        let mut rng = Lcg(seed);
        let mut intake = Intake::resume(&r, WAIT, now);
        let mut producers = [Producer::new(A), Producer::new(B)];
        // Every producer ever started, for the sum; a restarted driver is a new producer.
        let mut sent = 0;
        let mut next_id = 3;
        for _ in 0..3000 {
            let ids = producers.each_ref().map(|p| p.id);
            let connected = move |id: u128| ids.contains(&id);
            match rng.below(200) {
                // The input found empty, time passes (now and then long enough for a
                // take-over).
                0..=9 => {
                    intake.drained(now);
                    now += Duration::from_millis(if rng.below(4) == 0 { 1200 } else { 50 });
                }
                // A daemon restart: a new life from the accounting file.
                10 | 11 => intake = Intake::resume(&r, WAIT, now),
                // A driver restarted: a new producer numbering from 0, the old one gone. Its
                // last message is read first (what it lost after its last read one cannot be
                // known).
                12 => {
                    let k = usize::from(rng.below(2) == 0);
                    if !producers[k].last_read {
                        let s = producers[k].send(false);
                        intake.take(&s, producers[k].id, || now, connected);
                    }
                    sent += producers[k].sent;
                    producers[k] = Producer::new(next_id);
                    next_id += 1;
                    gone += 1;
                }
                _ => {
                    // Mostly the first producer; a second one now and then.
                    let k = usize::from(rng.below(5) == 0);
                    let s = producers[k].send(rng.below(40) == 0);
                    // One in ten lost on the way.
                    producers[k].last_read = rng.below(10) != 0;
                    if producers[k].last_read {
                        intake.take(&s, producers[k].id, || now, connected);
                    }
                }
            }
        }
        // Each producer's last message arrives.
        let ids = producers.each_ref().map(|p| p.id);
        for p in &mut producers {
            let s = p.send(true);
            intake.take(&s, p.id, || now, |id| ids.contains(&id));
        }
        sent += producers.iter().map(|p| p.sent).sum::<u64>();
        assert_eq!(
            get(&r.received) + missing(&r),
            sent,
            "seed {seed}: received {} + head {} + gaps {} + at restart {}",
            get(&r.received),
            get(&r.head_missing),
            get(&r.seq_gaps),
            get(&r.missing_at_restart),
        );
        assert!(
            get(&r.foreign) > 0,
            "seed {seed}: the second producer was refused at times"
        );
        changes += get(&r.producer_changes);
        at_restart += get(&r.missing_at_restart);
    }
    // What the schedules went through.
    assert!(changes > 0 && at_restart > 0 && gone > 0);
}
