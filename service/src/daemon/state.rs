//! The daemon's accounting file: the input counters, the position in the current IMU
//! producer's numbering and the output sequence numbers, kept in a shared file mapping so that
//! they survive the daemon (a clean stop, a crash, SIGKILL) and the next daemon of the domain
//! continues them.
//!
//! Why: a restarted daemon sees the first sample of a producer that kept sending at some `seq`
//! S. Without knowing the last `seq` L its predecessor received, it can only call all of
//! `0..S` missing (double counting what the predecessor received), or nothing (losing what was
//! sent while no daemon was there, and what was left in the killed daemon's input buffer). With
//! L in this file, it counts exactly `S - L - 1` in [`Record::missing_at_restart`]. The same file
//! carries the output `seq`s, so a consumer that stays connected across the restart counts what
//! it missed from one continuous numbering.
//!
//! Every field is an `AtomicU64` in the mapping, written with plain stores on the hot path (no
//! system call, no allocation); the kernel keeps a `MAP_SHARED` page of a file however the
//! process ends. A SIGKILL between two stores of one sample can misplace that one sample (counted
//! twice or not at all): a window of a few instructions per sample.

use super::producers::OtherNumbering;
use std::fs::OpenOptions;
use std::os::fd::AsRawFd;
use std::os::unix::fs::OpenOptionsExt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// "CRDRST01": the layout of [`Record`]; another value (a new file, an older layout) starts
/// from zero.
const MAGIC: u64 = u64::from_le_bytes(*b"CRDRST01");

/// Size of the file and of the mapping, bytes (one page).
const FILE_LEN: usize = 4096;

/// Output indices of [`Record::out_seq`].
pub(super) const OUT_ATTITUDE: usize = 0;
pub(super) const OUT_BIAS: usize = 1;
pub(super) const OUT_NAV: usize = 2;
pub(super) const OUT_DIAGNOSTICS: usize = 3;

/// The content of the accounting file. Counters are cumulative over every daemon life that used
/// the file (see the module documentation).
#[repr(C)]
#[derive(Debug, Default)]
pub(super) struct Record {
    magic: AtomicU64,
    /// Daemon lives that used this file (this one included).
    pub(super) lives: AtomicU64,
    /// Publisher port id of the current IMU producer (high, low 64 bits; both 0: none).
    pub(super) producer_hi: AtomicU64,
    pub(super) producer_lo: AtomicU64,
    /// `seq` of the last IMU sample received from it, plus 1 (0: none in this stream).
    pub(super) last_seq_plus1: AtomicU64,
    /// The `seq` its next stream starts with (after an end-of-stream marker), plus 1 (0: none).
    pub(super) next_stream_seq_plus1: AtomicU64,
    /// 1 between the first data sample of a stream and its end-of-stream marker.
    pub(super) mid_stream: AtomicU64,
    /// IMU messages received over IPC (end-of-stream markers included).
    pub(super) received: AtomicU64,
    /// IMU samples missing according to `seq`, between two samples received by one daemon life.
    pub(super) seq_gaps: AtomicU64,
    /// Samples refused because `seq` repeated the previous one.
    pub(super) duplicate: AtomicU64,
    /// Samples refused because `seq` was older than the previous one.
    pub(super) late: AtomicU64,
    /// Samples received but not handed to the estimator: its channel was full (live), or the
    /// daemon stopped while waiting for room (lossless).
    pub(super) dropped: AtomicU64,
    /// Times the IMU producer changed mid-stream.
    pub(super) producer_changes: AtomicU64,
    /// Samples of a producer's numbering before the first one any daemon received from it.
    pub(super) head_missing: AtomicU64,
    /// Samples of the current producer's numbering between the last one an earlier daemon life
    /// received and the first one this life received: sent while no daemon was there, or left
    /// unread in the input buffer of the daemon that stopped or was killed.
    pub(super) missing_at_restart: AtomicU64,
    /// IMU samples handed to the estimator thread.
    pub(super) forwarded: AtomicU64,
    /// IMU samples the estimator thread took from the channel.
    pub(super) taken: AtomicU64,
    /// IMU samples a daemon life received but neither estimated, refused by `seq` nor dropped:
    /// it was killed with them in its receive thread or its estimator channel. So
    /// `received = taken + dropped + duplicate + late + foreign + lost_in_daemon` whenever no
    /// sample is in flight.
    pub(super) lost_in_daemon: AtomicU64,
    /// The next `seq` of each output ([`OUT_ATTITUDE`], [`OUT_BIAS`], [`OUT_NAV`],
    /// [`OUT_DIAGNOSTICS`]) = messages published so far.
    pub(super) out_seq: [AtomicU64; 4],
    /// Output messages that reached no subscriber.
    pub(super) undelivered: AtomicU64,
    /// Angle observations dropped because the estimator's channel was full (live).
    pub(super) angles_dropped: AtomicU64,
    /// Angle observations carrying roll or pitch, which the daemon does not fuse (their heading,
    /// if any, is used).
    pub(super) angles_ignored: AtomicU64,
    /// IMU messages refused because another producer was followed (one producer at a time,
    /// see `super::producers`). Appended to the layout: a file written before it holds 0 here.
    pub(super) foreign: AtomicU64,
    /// The producer that is not followed (refused, or followed before another took over): its
    /// publisher port id (high, low 64 bits; both 0: none) and the `seq` expected next from it,
    /// plus 1 (0: none read yet), so that the next life counts its numbering on
    /// (`super::producers::OtherNumbering`). Appended, as `foreign`.
    other_hi: AtomicU64,
    other_lo: AtomicU64,
    other_next_seq_plus1: AtomicU64,
}

const _: () = assert!(size_of::<Record>() <= FILE_LEN);

impl Record {
    /// The IMU producer recorded, if any.
    pub(super) fn producer(&self) -> Option<u128> {
        let hi = self.producer_hi.load(Ordering::Relaxed);
        let lo = self.producer_lo.load(Ordering::Relaxed);
        ((hi, lo) != (0, 0)).then_some((u128::from(hi) << 64) | u128::from(lo))
    }

    /// Records the IMU producer.
    pub(super) fn set_producer(&self, id: u128) {
        self.producer_hi.store((id >> 64) as u64, Ordering::Relaxed);
        self.producer_lo.store(id as u64, Ordering::Relaxed);
    }

    /// The other producer's numbering recorded, if any (as not yet seen by this life).
    pub(super) fn other(&self) -> Option<OtherNumbering> {
        let hi = self.other_hi.load(Ordering::Relaxed);
        let lo = self.other_lo.load(Ordering::Relaxed);
        ((hi, lo) != (0, 0)).then(|| OtherNumbering {
            producer: (u128::from(hi) << 64) | u128::from(lo),
            next_seq: load_opt(&self.other_next_seq_plus1),
            seen_this_life: false,
        })
    }

    /// Records the other producer's numbering.
    pub(super) fn set_other(&self, o: &OtherNumbering) {
        self.other_hi
            .store((o.producer >> 64) as u64, Ordering::Relaxed);
        self.other_lo.store(o.producer as u64, Ordering::Relaxed);
        store_opt(&self.other_next_seq_plus1, o.next_seq);
    }

    fn reset(&self) {
        // Field by field: the record is shared memory, not to be replaced wholesale.
        let fields = [
            &self.lives,
            &self.producer_hi,
            &self.producer_lo,
            &self.last_seq_plus1,
            &self.next_stream_seq_plus1,
            &self.mid_stream,
            &self.received,
            &self.seq_gaps,
            &self.duplicate,
            &self.late,
            &self.dropped,
            &self.producer_changes,
            &self.head_missing,
            &self.missing_at_restart,
            &self.forwarded,
            &self.taken,
            &self.lost_in_daemon,
            &self.undelivered,
            &self.angles_dropped,
            &self.angles_ignored,
            &self.foreign,
            &self.other_hi,
            &self.other_lo,
            &self.other_next_seq_plus1,
        ];
        for f in fields.into_iter().chain(&self.out_seq) {
            f.store(0, Ordering::Relaxed);
        }
        self.magic.store(MAGIC, Ordering::Release);
    }
}

/// Stores `x` as "value plus 1" (0 for `None`).
pub(super) fn store_opt(a: &AtomicU64, x: Option<u64>) {
    a.store(x.map_or(0, |v| v.wrapping_add(1)), Ordering::Relaxed);
}

/// Loads a "value plus 1" field.
pub(super) fn load_opt(a: &AtomicU64) -> Option<u64> {
    a.load(Ordering::Relaxed).checked_sub(1)
}

/// A failure to open the accounting file.
#[derive(Debug, thiserror::Error)]
#[error("daemon accounting file {}: {what}: {source}", path.display())]
pub struct StateFileError {
    /// The file.
    pub path: PathBuf,
    /// What was attempted.
    pub what: &'static str,
    /// The OS error.
    pub source: std::io::Error,
}

/// The mapped accounting file of one daemon life.
#[derive(Debug)]
pub(super) struct StateFile {
    record: *const Record,
    path: PathBuf,
}

// SAFETY: the mapping is only accessed through the `AtomicU64`s of `Record` (Sync), it lives
// until `drop`, and `StateFile` is shared by reference (`Arc`) only.
unsafe impl Send for StateFile {}
// SAFETY: see `Send`.
unsafe impl Sync for StateFile {}

impl std::ops::Deref for StateFile {
    type Target = Record;
    fn deref(&self) -> &Record {
        // SAFETY: `record` points to a live, page-aligned mapping of FILE_LEN >= size_of::<Record>()
        // bytes (checked at compile time) until `drop`; every field is an atomic.
        unsafe { &*self.record }
    }
}

impl Drop for StateFile {
    fn drop(&mut self) {
        // SAFETY: the mapping made in `open`, unmapped once.
        unsafe {
            libc::munmap(self.record as *mut libc::c_void, FILE_LEN);
        }
    }
}

impl StateFile {
    /// Opens (or creates, mode 0600) the accounting file at `path` and maps it; a file of another
    /// layout, or a new one, starts from zero. Counts one more daemon life, and the samples the
    /// previous life received but never estimated (killed with samples in flight).
    pub(super) fn open(path: &Path) -> Result<Self, StateFileError> {
        let err = |what| {
            move |source| StateFileError {
                path: path.to_owned(),
                what,
                source,
            }
        };
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .mode(0o600)
            .open(path)
            .map_err(err("cannot open"))?;
        let len = file.metadata().map_err(err("cannot stat"))?.len();
        if len < FILE_LEN as u64 {
            file.set_len(FILE_LEN as u64)
                .map_err(err("cannot extend"))?;
        }
        // SAFETY: a shared read-write mapping of FILE_LEN bytes of an open regular file at least
        // that long; the result is checked before use.
        let ptr = unsafe {
            libc::mmap(
                std::ptr::null_mut(),
                FILE_LEN,
                libc::PROT_READ | libc::PROT_WRITE,
                libc::MAP_SHARED,
                file.as_raw_fd(),
                0,
            )
        };
        if ptr == libc::MAP_FAILED {
            return Err(err("cannot map")(std::io::Error::last_os_error()));
        }
        let state = Self {
            record: ptr as *const Record,
            path: path.to_owned(),
        };
        if state.magic.load(Ordering::Acquire) != MAGIC {
            state.reset();
        }
        state.lives.fetch_add(1, Ordering::Relaxed);
        // What the previous life received but neither estimated nor refused by `seq` nor dropped
        // (in its receive thread or its channel when it was killed) is lost in the daemon; the
        // channel of this life starts empty.
        let load = |a: &AtomicU64| a.load(Ordering::Relaxed);
        let accounted = load(&state.taken)
            + load(&state.dropped)
            + load(&state.duplicate)
            + load(&state.late)
            + load(&state.foreign);
        let unestimated =
            load(&state.received).saturating_sub(accounted + load(&state.lost_in_daemon));
        state
            .lost_in_daemon
            .fetch_add(unestimated, Ordering::Relaxed);
        state.forwarded.store(load(&state.taken), Ordering::Relaxed);
        Ok(state)
    }

    /// The file.
    pub(super) fn path(&self) -> &Path {
        &self.path
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counters_survive_the_mapping_and_a_new_life_counts_unestimated_samples() {
        let path = std::env::temp_dir().join(format!("corridor-state-{}", std::process::id()));
        let _ = std::fs::remove_file(&path);
        {
            let s = StateFile::open(&path).unwrap();
            assert_eq!(s.lives.load(Ordering::Relaxed), 1);
            s.received.store(12, Ordering::Relaxed);
            s.forwarded.store(9, Ordering::Relaxed);
            s.taken.store(6, Ordering::Relaxed);
            s.dropped.store(1, Ordering::Relaxed);
            s.foreign.store(2, Ordering::Relaxed);
            s.set_producer(u128::MAX - 5);
            s.set_other(&OtherNumbering {
                producer: 7 << 64 | 9,
                next_seq: Some(120),
                seen_this_life: true,
            });
            store_opt(&s.last_seq_plus1, Some(41));
            s.out_seq[OUT_ATTITUDE].store(7, Ordering::Relaxed);
        }
        let s = StateFile::open(&path).unwrap();
        assert_eq!(s.lives.load(Ordering::Relaxed), 2);
        assert_eq!(s.received.load(Ordering::Relaxed), 12);
        // 12 received = 6 estimated + 1 dropped + 2 foreign + 3 lost (in the channel or the
        // receive thread).
        assert_eq!(s.lost_in_daemon.load(Ordering::Relaxed), 3);
        assert_eq!(s.forwarded.load(Ordering::Relaxed), 6);
        assert_eq!(s.producer(), Some(u128::MAX - 5));
        assert_eq!(
            s.other(),
            Some(OtherNumbering {
                producer: 7 << 64 | 9,
                next_seq: Some(120),
                seen_this_life: false,
            })
        );
        assert_eq!(load_opt(&s.last_seq_plus1), Some(41));
        assert_eq!(load_opt(&s.next_stream_seq_plus1), None);
        assert_eq!(s.out_seq[OUT_ATTITUDE].load(Ordering::Relaxed), 7);
        drop(s);
        // Another layout starts from zero.
        std::fs::write(&path, [0xAB; 64]).unwrap();
        let s = StateFile::open(&path).unwrap();
        assert_eq!(s.lives.load(Ordering::Relaxed), 1);
        assert_eq!(s.received.load(Ordering::Relaxed), 0);
        assert_eq!(s.producer(), None);
        drop(s);
        let _ = std::fs::remove_file(&path);
    }
}
