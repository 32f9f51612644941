//! Record: the daemon's attitude and bias streams written to `attitude.csv` and `bias.csv`
//! (the rows of [`crate::csv_rows`]) until the end of stream, or, following new streams
//! ([`Recorder::following_new_streams`]), until nothing arrives for the idle timeout. Used by
//! `corridor-log` and by `corridor demo`.
//!
//! [`Recorder::open`] attaches the readers and creates the files; [`Recorder::run`] then
//! records. The split lets a caller say "attached" before the producer starts.

use crate::csv_rows::{ATTITUDE_HEADER, BIAS_HEADER, write_attitude_row, write_bias_row};
use crate::{ClientError, Domain, Subscriber};
use corridor_shared::wire::{AttitudeSample, BiasSample, FLAG_END_OF_STREAM, FLAG_RETRACTS};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// How to record.
#[derive(Debug, Clone)]
pub struct RecordOptions {
    /// Prefix of the readers' iceoryx2 node names (`-attitude`, `-bias` appended).
    pub node_name: String,
    /// How long to wait for the daemon's services.
    pub wait: Duration,
    /// Stop when nothing arrived for this long.
    pub idle_timeout: Duration,
    /// Whether the idle timeout also runs before the first message (else it waits for the first
    /// message for ever, until SIGINT/SIGTERM).
    pub idle_before_first: bool,
    /// Longest single wait, so [`Recorder::run`] sees its `abort` flag.
    pub poll: Duration,
}

/// Why a recording stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RecordStop {
    /// The end-of-stream attitude and bias messages arrived (and the recorder does not follow
    /// new streams).
    EndOfStream,
    /// Nothing arrived for [`RecordOptions::idle_timeout`].
    IdleTimeout,
    /// SIGINT/SIGTERM.
    Interrupted,
    /// The caller's `abort` flag was set.
    Aborted,
}

impl RecordStop {
    /// In words, for the tools' output.
    pub fn describe(self) -> &'static str {
        match self {
            RecordStop::EndOfStream => "end of stream",
            RecordStop::IdleTimeout => "idle timeout",
            RecordStop::Interrupted => "interrupted",
            RecordStop::Aborted => "aborted",
        }
    }
}

/// What a recording received.
#[derive(Debug, Clone)]
pub struct Recorded {
    /// Why it stopped.
    pub stopped: RecordStop,
    /// Streams whose end-of-stream attitude and bias messages both arrived.
    pub streams_ended: u64,
    /// Rows written to `attitude.csv`.
    pub attitude_rows: u64,
    /// Of those, the rows of a stream whose end had not arrived when the recording stopped
    /// (0 when it stopped at or between ends of stream): that stream may have gone on.
    pub open_stream_rows: u64,
    /// Rows written to `bias.csv` (each stream's end-of-stream bias included).
    pub bias_rows: u64,
    /// Attitude rows that retract earlier ones (`retracts` 1: the rows before them with a
    /// later `t_s` came from glitched stamps; [`corridor_shared::wire::FLAG_RETRACTS`]).
    pub retracting_rows: u64,
    /// Attitude messages received (end-of-stream messages included).
    pub attitude_received: u64,
    /// Attitude messages missing from the `seq` numbering after the first one received.
    pub attitude_missed: u64,
    /// Attitude messages published before the first one received (a logger that started late).
    pub attitude_missed_at_start: u64,
    /// The recorder attached between two streams (the bias stream's first message was the end
    /// of a stream that ended before): the messages published before its first one are all of
    /// earlier streams, none of the ones it recorded.
    pub attached_between_streams: bool,
    /// IMU samples (the producer's numbering, `imu_seq`) within a stream for which the daemon
    /// published no attitude, between two rows that were recorded or between the stream's last
    /// row and its end-of-stream attitude (whose `imu_seq` is the producer's end-of-stream
    /// marker's, one past its last sample): samples it refused (implausible, time), dropped (a
    /// full live queue, a gap in the producer's numbering) or never estimated (lost in a daemon
    /// killed and restarted, `corridor status`'s "missing at a restart"). Attitudes this reader
    /// missed (`attitude_missed`) are not counted again. A stream's first attitude and a
    /// renumbered producer start the count afresh. A stream the daemon ended itself (its
    /// producer's clock restarted) carries its last estimated sample's `imu_seq` on its end:
    /// what it refused after that one is not counted. (The samples missing at a stream's end
    /// went uncounted before: 3 refused last samples were not reported, a review.)
    pub imu_without_attitude: u64,
    /// Bias messages received (end-of-stream messages included).
    pub bias_received: u64,
    /// Bias messages missing from the `seq` numbering after the first one received.
    pub bias_missed: u64,
    /// Bias messages published before the first one received.
    pub bias_missed_at_start: u64,
    /// The bias of the last attitude row.
    pub last_attitude_bias_rad_s: [f64; 3],
    /// The bias of the end-of-stream bias message (the daemon's final bias), if it came.
    pub final_bias_rad_s: Option<[f64; 3]>,
    /// The attitude file.
    pub attitude_path: PathBuf,
    /// The bias file.
    pub bias_path: PathBuf,
    /// No attitude was recorded, and the files of an earlier recording in the directory were
    /// left as they were (a logger that received nothing emptied them, a review).
    pub kept_earlier_files: bool,
}

/// The count of [`Recorded::imu_without_attitude`], attitude message by attitude message (pure:
/// unit-tested).
#[derive(Debug, Clone, Copy, Default)]
struct ImuCoverage {
    /// The `imu_seq` and `seq` of the stream's last attitude row.
    last_row: Option<(u64, u64)>,
    /// IMU samples without an attitude so far.
    without: u64,
}

impl ImuCoverage {
    /// An attitude row: counts the samples between the last row and it.
    fn row(&mut self, imu_seq: u64, seq: u64) {
        self.count_to(imu_seq, seq);
        self.last_row = Some((imu_seq, seq));
    }

    /// The stream's end-of-stream attitude: counts the samples between the last row and the
    /// producer's end-of-stream marker (its `imu_seq`), then starts afresh for the next stream.
    fn end_of_stream(&mut self, imu_seq: u64, seq: u64) {
        self.count_to(imu_seq, seq);
        self.last_row = None;
    }

    /// The IMU samples strictly between the last row and `imu_seq` had no attitude, except
    /// those whose attitude this reader missed (the `seq` gap before `seq`: published, only not
    /// received). A producer renumbered at or below the last row counts nothing.
    fn count_to(&mut self, imu_seq: u64, seq: u64) {
        if let Some((last_imu_seq, last_seq)) = self.last_row
            && imu_seq > last_imu_seq
        {
            let imu_gap = imu_seq - last_imu_seq - 1;
            let missed = seq.saturating_sub(last_seq).saturating_sub(1);
            self.without += imu_gap.saturating_sub(missed);
        }
    }
}

/// The readers and the open files of a recording.
#[derive(Debug)]
pub struct Recorder {
    attitude: Subscriber<AttitudeSample>,
    bias: Subscriber<BiasSample>,
    att_w: BufWriter<File>,
    bias_w: BufWriter<File>,
    /// Where the rows go while recording (`NAME.partial`), renamed to the final names at the
    /// end of [`Recorder::run`].
    att_partial: PathBuf,
    bias_partial: PathBuf,
    opts: RecordOptions,
    got: Recorded,
    follow: bool,
}

fn create(path: &Path) -> Result<BufWriter<File>, ClientError> {
    File::create(path)
        .map(BufWriter::new)
        .map_err(|source| ClientError::File {
            path: path.to_owned(),
            source,
        })
}

fn file_err(path: &Path) -> impl FnOnce(std::io::Error) -> ClientError + '_ {
    move |source| ClientError::File {
        path: path.to_owned(),
        source,
    }
}

impl Recorder {
    /// Attaches to the daemon's attitude and bias streams in `domain`, then creates `dir` (if
    /// needed) with `attitude.csv.partial` and `bias.csv.partial` and their headers (in that
    /// order: a logger that could not attach used to leave an earlier recording's files
    /// emptied). [`Recorder::run`] renames them to `attitude.csv` and `bias.csv` at its end, or,
    /// when nothing was recorded and an earlier recording's files are there, removes them.
    pub fn open(domain: &Domain, dir: &Path, opts: &RecordOptions) -> Result<Self, ClientError> {
        // Said as such (it read "File exists (os error 17)"), and before waiting for a daemon
        // (it was said after `--wait-s`, a review).
        if dir.exists() && !dir.is_dir() {
            return Err(ClientError::File {
                path: dir.to_owned(),
                source: std::io::Error::other(
                    "exists and is not a directory (the output is a directory for \
                     attitude.csv and bias.csv)",
                ),
            });
        }
        let name = &opts.node_name;
        let attitude = Subscriber::open(domain, &format!("{name}-attitude"), opts.wait)?;
        let bias = Subscriber::open(domain, &format!("{name}-bias"), opts.wait)?;
        std::fs::create_dir_all(dir).map_err(file_err(dir))?;
        let attitude_path = dir.join("attitude.csv");
        let bias_path = dir.join("bias.csv");
        let att_partial = dir.join("attitude.csv.partial");
        let bias_partial = dir.join("bias.csv.partial");
        let mut att_w = create(&att_partial)?;
        let mut bias_w = create(&bias_partial)?;
        writeln!(att_w, "{ATTITUDE_HEADER}").map_err(file_err(&att_partial))?;
        writeln!(bias_w, "{BIAS_HEADER}").map_err(file_err(&bias_partial))?;
        Ok(Self {
            attitude,
            bias,
            att_w,
            bias_w,
            att_partial,
            bias_partial,
            opts: opts.clone(),
            follow: false,
            got: Recorded {
                stopped: RecordStop::EndOfStream,
                streams_ended: 0,
                attitude_rows: 0,
                open_stream_rows: 0,
                bias_rows: 0,
                retracting_rows: 0,
                attitude_received: 0,
                attitude_missed: 0,
                attitude_missed_at_start: 0,
                attached_between_streams: false,
                imu_without_attitude: 0,
                bias_received: 0,
                bias_missed: 0,
                bias_missed_at_start: 0,
                last_attitude_bias_rad_s: [0.0; 3],
                final_bias_rad_s: None,
                attitude_path,
                bias_path,
                kept_earlier_files: false,
            },
        })
    }

    /// Goes on after an end of stream: the rows of the next stream (a restarted producer, the
    /// next replay; the loops of one replay are one stream) are appended to the same files, and only the idle timeout,
    /// SIGINT/SIGTERM or `abort` stop the recording. Before, a producer restart ended the
    /// recording and the new stream went unlogged.
    pub fn following_new_streams(mut self) -> Self {
        self.follow = true;
        self
    }

    /// Records until the end-of-stream attitude and bias messages (unless
    /// [`Recorder::following_new_streams`]), the idle timeout,
    /// SIGINT/SIGTERM or `abort`; flushes the files, gives them their final names and says
    /// what it got. The end-of-stream attitude is not written as a row; the end-of-stream bias
    /// is, marked (`end_of_stream`). An end of stream as the bias reader's first message is
    /// the daemon's history (the bias stream keeps its last message for late readers) of a
    /// stream that ended before the recorder attached: it is passed over (it ended the
    /// recording of a logger started between two streams, and the next stream went unlogged).
    pub fn run(mut self, abort: &AtomicBool) -> Result<Recorded, ClientError> {
        let poll = self.opts.poll;
        let (mut attitude_done, mut bias_done) = (false, false);
        let mut first_bias = true;
        let mut any = false;
        let mut coverage = ImuCoverage::default();
        let mut last_rx = Instant::now();
        let stopped = loop {
            if attitude_done && bias_done {
                self.got.streams_ended += 1;
                if !self.follow {
                    break RecordStop::EndOfStream;
                }
                (attitude_done, bias_done) = (false, false);
            }
            if abort.load(Ordering::Relaxed) {
                break RecordStop::Aborted;
            }
            // The bias stream first, without waiting while attitudes still come.
            let b = if attitude_done {
                self.bias.recv_timeout(poll)
            } else {
                self.bias.try_recv()
            };
            let b = match b {
                Err(ClientError::Interrupted) => break RecordStop::Interrupted,
                b => b?,
            };
            if let Some(b) = b {
                let end = b.flags & FLAG_END_OF_STREAM != 0;
                if std::mem::take(&mut first_bias) && end {
                    // a stream that ended before the recorder attached
                    self.got.attached_between_streams = true;
                    continue;
                }
                (last_rx, any) = (Instant::now(), true);
                if end {
                    self.got.final_bias_rad_s = Some(b.gyro_bias_rad_s);
                    bias_done = true;
                }
                write_bias_row(&mut self.bias_w, &b).map_err(file_err(&self.bias_partial))?;
                self.got.bias_rows += 1;
                continue;
            }
            if !attitude_done {
                let x = match self.attitude.recv_timeout(poll) {
                    Err(ClientError::Interrupted) => break RecordStop::Interrupted,
                    x => x?,
                };
                if let Some(x) = x {
                    (last_rx, any) = (Instant::now(), true);
                    if x.flags & FLAG_END_OF_STREAM != 0 {
                        attitude_done = true;
                        self.got.open_stream_rows = 0;
                        // The samples after the last row (refused, dropped) count too.
                        coverage.end_of_stream(x.imu_seq, x.seq);
                    } else {
                        coverage.row(x.imu_seq, x.seq);
                        write_attitude_row(&mut self.att_w, &x)
                            .map_err(file_err(&self.att_partial))?;
                        self.got.attitude_rows += 1;
                        self.got.open_stream_rows += 1;
                        self.got.retracting_rows += u64::from(x.flags & FLAG_RETRACTS != 0);
                        self.got.last_attitude_bias_rad_s = x.gyro_bias_rad_s;
                    }
                    continue;
                }
            }
            if (any || self.opts.idle_before_first) && last_rx.elapsed() >= self.opts.idle_timeout {
                break RecordStop::IdleTimeout;
            }
        };
        self.att_w.flush().map_err(file_err(&self.att_partial))?;
        self.bias_w.flush().map_err(file_err(&self.bias_partial))?;
        self.finish_files()?;
        self.got.stopped = stopped;
        self.got.imu_without_attitude = coverage.without;
        self.got.attitude_received = self.attitude.received();
        self.got.attitude_missed = self.attitude.missed();
        self.got.attitude_missed_at_start = self.attitude.missed_at_start();
        self.got.bias_received = self.bias.received();
        self.got.bias_missed = self.bias.missed();
        self.got.bias_missed_at_start = self.bias.missed_at_start();
        Ok(self.got)
    }

    /// Renames the partial files to their final names; when no attitude was recorded and an
    /// earlier recording's files are there, removes the partial files instead and keeps those.
    /// (Bias rows alone do not count: the bias stream keeps its last message for late readers,
    /// and a logger started after a stream that never ended got that one row, and emptied an
    /// earlier recording with it: a review.)
    fn finish_files(&mut self) -> Result<(), ClientError> {
        let nothing = self.got.attitude_rows == 0;
        let earlier = self.got.attitude_path.exists() || self.got.bias_path.exists();
        if nothing && earlier {
            for p in [&self.att_partial, &self.bias_partial] {
                std::fs::remove_file(p).map_err(file_err(p))?;
            }
            self.got.kept_earlier_files = true;
            return Ok(());
        }
        for (from, to) in [
            (&self.att_partial, &self.got.attitude_path),
            (&self.bias_partial, &self.got.bias_path),
        ] {
            std::fs::rename(from, to).map_err(file_err(to))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::ImuCoverage;

    /// Attitude rows for IMU samples `imu` numbered from attitude `seq0` on, one each.
    fn rows(c: &mut ImuCoverage, imu: impl IntoIterator<Item = u64>, seq0: u64) -> u64 {
        let mut seq = seq0;
        for i in imu {
            c.row(i, seq);
            seq += 1;
        }
        seq
    }

    #[test]
    fn samples_without_attitude_between_rows() {
        let mut c = ImuCoverage::default();
        // IMU 0..=9, 13..=19 (10, 11, 12 refused), the attitudes numbered on.
        let seq = rows(&mut c, 0..10, 100);
        rows(&mut c, 13..20, seq);
        assert_eq!(c.without, 3);
    }

    #[test]
    fn samples_without_attitude_at_the_end_of_a_stream_count() {
        // The last 3 of 20 samples refused: the producer's marker is IMU 20, the end-of-stream
        // attitude the next one after the row of IMU 16 (a review: not counted).
        let mut c = ImuCoverage::default();
        let seq = rows(&mut c, 0..17, 100);
        c.end_of_stream(20, seq);
        assert_eq!(c.without, 3);
        // Nothing missing at the end: none.
        let mut c = ImuCoverage::default();
        let seq = rows(&mut c, 0..20, 100);
        c.end_of_stream(20, seq);
        assert_eq!(c.without, 0);
        // Attitudes this reader missed at the end (2 of the last 5 rows) were published.
        let mut c = ImuCoverage::default();
        let seq = rows(&mut c, 0..15, 100);
        c.end_of_stream(20, seq + 2);
        assert_eq!(c.without, 3);
    }

    #[test]
    fn each_stream_counts_afresh() {
        let mut c = ImuCoverage::default();
        let seq = rows(&mut c, 0..10, 0);
        c.end_of_stream(12, seq); // IMU 10, 11 without attitude
        // The next stream starts at IMU 0 again, its first row at 5: not counted.
        let seq = rows(&mut c, 5..8, seq + 1);
        c.end_of_stream(8, seq);
        assert_eq!(c.without, 2);
        // An end the daemon made itself (a restarted clock) carries its last sample's imu_seq;
        // an end with no row before it counts nothing.
        let mut c = ImuCoverage::default();
        let seq = rows(&mut c, 0..10, 0);
        c.end_of_stream(9, seq);
        c.end_of_stream(30, seq + 1);
        assert_eq!(c.without, 0);
    }
}
