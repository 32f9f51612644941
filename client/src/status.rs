//! [`StatusReader`]: the health of a running daemon, read from what it publishes
//! ([`Diagnostics`] every diagnostics period, the latest [`BiasSample`]), for `corridor status`.

use crate::{ClientError, Subscriber};
use corridor_shared::wire::{BiasSample, Diagnostics, FLAG_END_OF_STREAM, FLAG_SHUTDOWN, phase};
use std::fmt::Write as _;
use std::time::{Duration, Instant};

/// One view of the daemon's health.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Status {
    /// The latest diagnostics.
    pub diagnostics: Diagnostics,
    /// The diagnostics before them, when two were seen (for rates).
    pub previous: Option<Diagnostics>,
    /// The latest bias estimate, when the daemon has published one.
    pub bias: Option<BiasSample>,
    /// Diagnostics this reader missed (seq gaps).
    pub missed: u64,
}

impl Status {
    /// True when the daemon answered and is not shutting down.
    pub fn healthy(&self) -> bool {
        self.diagnostics.flags & FLAG_SHUTDOWN == 0
    }

    /// Accepted samples per second of sensor time between the last two diagnostics; `None`
    /// when idle (sensor time did not advance), with one diagnostics only, or across a daemon
    /// restart (its count starts again: the difference wrapped, and `--watch` showed 8e17 Hz).
    pub fn sample_rate_hz(&self) -> Option<f64> {
        let p = self
            .previous
            .filter(|p| p.lives == self.diagnostics.lives)?;
        let d = &self.diagnostics;
        let dt_s = d.t_s - p.t_s;
        let accepted = d.accepted.checked_sub(p.accepted)?;
        (dt_s.is_finite() && dt_s > 0.0).then(|| accepted as f64 / dt_s)
    }

    /// The status as a screen of text.
    pub fn render(&self, domain: &str) -> String {
        let d = &self.diagnostics;
        let mut s = String::new();
        let state = if d.flags & FLAG_SHUTDOWN != 0 {
            "shutting down"
        } else if d.flags & FLAG_END_OF_STREAM != 0 {
            "running, stream ended"
        } else {
            "running"
        };
        let _ = writeln!(s, "corridor daemon, domain {domain:?}: {state}");
        if d.flags & FLAG_END_OF_STREAM != 0 {
            // The estimator is already the next stream's, aligning and without a time yet: its
            // phase beside the ended stream's bias read as a contradiction.
            let _ = writeln!(
                s,
                "phase:            between streams (the next one starts with its alignment)"
            );
        } else {
            let _ = writeln!(
                s,
                "phase:            {} (sensor time {})",
                phase::name(d.phase),
                fmt_opt(d.t_s, 3, " s")
            );
        }
        let rate = self
            .sample_rate_hz()
            .map_or("idle".to_owned(), |r| format!("{r:.1} Hz (sensor clock)"));
        let _ = writeln!(s, "IMU rate:         {rate}");
        let _ = writeln!(
            s,
            "samples:          received {}, accepted {}, stances {}, heading updates {} (last NIS {})",
            d.received,
            d.accepted,
            d.stances,
            d.heading_used,
            fmt_opt(d.last_nis, 2, "")
        );
        let _ = writeln!(
            s,
            "clipped:          samples at a rail {} (gyro peaks put back {}, not put back {})",
            d.clipped_samples, d.clipped_peaks_restored, d.clipped_peaks_not_restored
        );
        let _ = writeln!(
            s,
            "losses:           seq gaps {}, overflow drops {}; consumers stalled {} (outputs \
             discarded for them {})",
            d.seq_gaps, d.dropped_overflow, d.stalled_consumers, d.discarded_for_stalled
        );
        // `undelivered` counts the outputs that reached no subscriber, which is every output
        // while nobody subscribes (the diagnostics of an idle daemon, one a second): said apart
        // from the losses, under which a fresh daemon without consumers showed "undelivered
        // outputs 2". What a connected consumer missed is the stalled consumers' count.
        let _ = writeln!(
            s,
            "no subscriber:    outputs published while none was subscribed {} (not a loss; \
             a failed publish is warned in the daemon's log)",
            d.undelivered
        );
        let _ = writeln!(
            s,
            "rejected:         non-finite {}, implausible {}, time not increasing {}, time jump {}, duplicate seq {}, late {}",
            d.rejected_non_finite,
            d.rejected_implausible,
            d.rejected_time,
            d.rejected_time_jump,
            d.rejected_duplicate_seq,
            d.late
        );
        let _ = writeln!(
            s,
            "not received:     before the daemon's first message {}, missing at a restart {}, lost in a killed life {}",
            d.head_missing, d.missing_at_restart, d.lost_in_daemon
        );
        let _ = writeln!(
            s,
            "producers:        changes {}, samples of a second producer refused {}, daemon life {}",
            d.producer_changes, d.foreign_samples, d.lives
        );
        if d.lives > 1 {
            // A restarted daemon continues its input counters from its accounting file, and
            // starts its estimator's afresh: "received 25193, accepted 3000", with the losses
            // of an earlier life, read as counts that do not add up (a review).
            let _ = writeln!(
                s,
                "                  (received, losses but the stalled consumers, no subscriber, \
                 duplicate seq, late, not received, producers and angles count over all {} \
                 daemon lives of this \
                 domain; accepted, stances, heading updates, clipped, the stalled consumers, the \
                 other rejections and external headings over this life)",
                d.lives
            );
        }
        let _ = writeln!(
            s,
            "angles:           dropped {}, with roll or pitch (not fused) {}; external headings \
             refused {}, superseded {}, outside the gate {}, expired {}, undone {}",
            d.angles_dropped,
            d.angles_ignored,
            d.headings_refused,
            d.headings_superseded,
            d.headings_outside_gate,
            d.headings_expired,
            d.headings_undone
        );
        let _ = writeln!(
            s,
            "latency:          p50 {}, p99 {}",
            fmt_opt(d.latency_p50_s * 1e6, 0, " µs"),
            fmt_opt(d.latency_p99_s * 1e6, 0, " µs")
        );
        match &self.bias {
            Some(b) => {
                let v = |x: [f64; 3]| {
                    format!("[{:+.6}, {:+.6}, {:+.6}]", x[0], x[1], x[2]).replace("NaN", "nan")
                };
                let _ = writeln!(
                    s,
                    "gyro bias:        {} rad/s at t = {}",
                    v(b.gyro_bias_rad_s),
                    fmt_opt(b.t_s, 3, " s")
                );
                if b.gyro_bias_sd_rad_s.iter().all(|x| x.is_nan()) {
                    let _ = writeln!(s, "bias σ:           none before the alignment");
                } else {
                    let _ = writeln!(s, "bias σ:           {} rad/s", v(b.gyro_bias_sd_rad_s));
                }
                let _ = writeln!(
                    s,
                    "converged:        {} ({})",
                    if b.converged != 0 { "yes" } else { "no" },
                    if b.bias_unabsorbed.is_finite() {
                        format!("{:.0} % of a start error left", 100.0 * b.bias_unabsorbed)
                    } else {
                        "not aligned yet".to_string()
                    }
                );
            }
            None => {
                let _ = writeln!(s, "gyro bias:        none published yet");
            }
        }
        let _ = writeln!(s, "diagnostics seq:  {}", d.seq);
        s
    }
}

/// Why a checkpoint path cannot be the daemon's checkpoint (its message names the path: the
/// status's `last checkpoint:` line, or its error before any wait for the daemon).
#[derive(Debug, thiserror::Error)]
pub enum CheckpointPathError {
    /// The path holds something other than a file.
    #[error("{} is not a file (a directory?)", path.display())]
    NotAFile {
        /// The path.
        path: std::path::PathBuf,
    },
    /// The file is there but cannot be read by this user.
    #[error("{} not readable ({source})", path.display())]
    Unreadable {
        /// The path.
        path: std::path::PathBuf,
        /// What reading it said.
        source: std::io::Error,
    },
}

/// The `last checkpoint:` line for the daemon's checkpoint file (`daemon.checkpoint_path` or
/// `corridor serve --checkpoint`): the daemon does not publish its checkpoints, but it writes
/// the file atomically at each save, so its modification time is the last save. An error (naming the
/// path) when the path holds something that cannot be the daemon's
/// checkpoint: a directory, a file this user cannot read (it said "saved 3.0 s ago" of a
/// directory, and the status exited 0 whatever it said). A file not there is not an error: a
/// daemon has none before its first save.
pub fn checkpoint_line(path: &std::path::Path) -> Result<String, CheckpointPathError> {
    let shown = path.display();
    let saved = std::fs::File::open(path)
        .and_then(|f| f.metadata())
        .and_then(|m| Ok((m.is_file(), m.len(), m.modified()?)));
    match saved {
        Ok((true, bytes, modified)) => {
            let age_s = modified.elapsed().map_or(0.0, |d| d.as_secs_f64());
            Ok(format!(
                "last checkpoint:  {shown} ({bytes} B), saved {age_s:.1} s ago\n"
            ))
        }
        Ok((false, ..)) => Err(CheckpointPathError::NotAFile {
            path: path.to_owned(),
        }),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(format!(
            "last checkpoint:  none at {shown} (not saved yet: the daemon saves every \
             daemon.checkpoint_period_s, at each end of stream and at shutdown)\n"
        )),
        Err(source) => Err(CheckpointPathError::Unreadable {
            path: path.to_owned(),
            source,
        }),
    }
}

fn fmt_opt(x: f64, decimals: usize, unit: &str) -> String {
    if x.is_finite() {
        format!("{x:.decimals$}{unit}")
    } else {
        "n/a".to_owned()
    }
}

/// What the daemon did with the samples it was sent between two of its diagnostics (of one
/// daemon life): a producer sees only its side, and its summary said nothing of a daemon that
/// dropped 41 % of a replay on a full queue (a review).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DaemonAccount {
    /// IMU messages received (end-of-stream markers included).
    pub received: u64,
    /// Samples missing from the producers' numbering (overwritten in the live input buffer,
    /// or never sent).
    pub seq_gaps: u64,
    /// Samples a producer numbered before the daemon's first read of it (sent before its
    /// connection was up, or overwritten in its live input buffer before that read).
    pub head_missing: u64,
    /// Samples dropped on a full estimator queue (live delivery).
    pub dropped_overflow: u64,
    /// Samples the estimator refused (any reason) or refused as duplicates or late.
    pub refused: u64,
    /// Samples the estimator accepted.
    pub accepted: u64,
    /// Producer changes (another producer took over).
    pub producer_changes: u64,
    /// Samples refused because another producer was followed (this stream's, when it was not
    /// the one followed; or a second producer's while it was).
    pub foreign: u64,
}

impl DaemonAccount {
    /// Every one of `sent` samples (the end-of-stream marker not included) estimated, refused,
    /// dropped or known missing: the estimator's side has taken them all (the receive side
    /// alone can run ahead of it).
    pub fn accounts_for(&self, sent: u64) -> bool {
        self.accepted
            + self.refused
            + self.dropped_overflow
            + self.seq_gaps
            + self.head_missing
            + self.foreign
            >= sent
    }

    /// Samples sent that the estimator never saw: missing from the numbering, sent before the
    /// daemon's connection, dropped on a full queue.
    pub fn lost(&self) -> u64 {
        self.seq_gaps + self.head_missing + self.dropped_overflow
    }

    /// The counts from `before` to `after`; `None` across a daemon restart (the estimator's
    /// counts start again) or when a count went back.
    pub fn between(before: &Diagnostics, after: &Diagnostics) -> Option<Self> {
        if before.lives != after.lives {
            return None;
        }
        let d = |a: u64, b: u64| b.checked_sub(a);
        let refused = |x: &Diagnostics| {
            x.rejected_duplicate_seq
                + x.late
                + x.rejected_non_finite
                + x.rejected_time
                + x.rejected_implausible
                + x.rejected_time_jump
        };
        Some(Self {
            received: d(before.received, after.received)?,
            seq_gaps: d(before.seq_gaps, after.seq_gaps)?,
            head_missing: d(before.head_missing, after.head_missing)?,
            dropped_overflow: d(before.dropped_overflow, after.dropped_overflow)?,
            refused: d(refused(before), refused(after))?,
            accepted: d(before.accepted, after.accepted)?,
            producer_changes: d(before.producer_changes, after.producer_changes)?,
            foreign: d(before.foreign_samples, after.foreign_samples)?,
        })
    }
}

/// A reader of the daemon's diagnostics on its own thread, for the account of one producer's
/// stream ([`DaemonAccount`]): started before the first sample, it keeps the first
/// diagnostics it gets (the daemon's latest before the stream, from the stream's history) and
/// reads on, so that it never fills (a reader left unread stalled a lossless daemon: a
/// review), until [`DaemonWatch::finish`] says how many samples were sent.
#[derive(Debug)]
pub struct DaemonWatch {
    sent: std::sync::mpsc::SyncSender<u64>,
    thread: std::thread::JoinHandle<Option<(DaemonAccount, bool)>>,
}

/// Longest single wait of [`DaemonWatch`]'s reader.
const WATCH_POLL: Duration = Duration::from_millis(50);

impl DaemonWatch {
    /// Attaches to the diagnostics of `domain`'s daemon (waiting up to `open_wait` for it, and
    /// up to `open_wait` more for its latest diagnostics); `None` when it is not there (no
    /// daemon yet, a stand-in without diagnostics).
    pub fn start(
        domain: &crate::Domain,
        open_wait: Duration,
        finish_wait: Duration,
    ) -> Option<Self> {
        // One message each (bounded, as every channel of the project).
        let (attached_tx, attached) = std::sync::mpsc::sync_channel(1);
        let (sent, sent_rx) = std::sync::mpsc::sync_channel::<u64>(1);
        let domain = domain.clone();
        let thread = std::thread::Builder::new()
            .name("daemon-watch".into())
            .spawn(move || {
                let sub = Subscriber::<Diagnostics>::open(&domain, "corridor-watch", open_wait);
                let Ok(sub) = sub else {
                    let _ = attached_tx.send(false);
                    return None;
                };
                // The daemon's latest diagnostics before the first sample goes: from the
                // service's history, or the first one a daemon just started publishes (at once,
                // then every period). Without it, the first one read would be from within the
                // stream, and the account would miss what came before (a replay started within
                // a diagnostics period of a fresh daemon said "not finished").
                let mut before = sub.recv_timeout(open_wait).ok().flatten();
                let _ = attached_tx.send(true);
                let mut last = before;
                let mut until: Option<(u64, Instant)> = None;
                loop {
                    while let Ok(Some(d)) = sub.recv_timeout(WATCH_POLL) {
                        before.get_or_insert(d);
                        last = Some(d);
                    }
                    if until.is_none() {
                        match sent_rx.try_recv() {
                            Ok(n) => until = Some((n, Instant::now() + finish_wait)),
                            Err(std::sync::mpsc::TryRecvError::Disconnected) => return None,
                            Err(std::sync::mpsc::TryRecvError::Empty) => {}
                        }
                    }
                    let Some((n, deadline)) = until else { continue };
                    let account = before
                        .zip(last)
                        .map(|(b, l)| (DaemonAccount::between(&b, &l), l.flags));
                    match account {
                        Some((None, _)) => return None, // the daemon restarted
                        Some((Some(a), flags))
                            if flags & FLAG_END_OF_STREAM != 0 && a.accounts_for(n) =>
                        {
                            return Some((a, true));
                        }
                        _ if Instant::now() >= deadline => {
                            return account.and_then(|(a, _)| a).map(|a| (a, false));
                        }
                        _ => {}
                    }
                }
            })
            .ok()?;
        // Attached, and the daemon's diagnostics from before the first sample read (or
        // `open_wait` passed without any), before the first sample goes.
        attached.recv().ok()?.then_some(Self { sent, thread })
    }

    /// The account of the `samples` sent since [`Self::start`]: once the daemon's diagnostics
    /// at the end of the stream account for them all (`true`), or what it had counted when
    /// `finish_wait` ran out (`false`); `None` without diagnostics or across a restart.
    pub fn finish(self, samples: u64) -> Option<(DaemonAccount, bool)> {
        self.sent.send(samples).ok()?;
        self.thread.join().ok()?
    }
}

/// Reads the daemon's diagnostics and bias streams of a domain.
#[derive(Debug)]
pub struct StatusReader {
    diagnostics: Subscriber<Diagnostics>,
    bias: Subscriber<BiasSample>,
    last: Option<Diagnostics>,
    latest_bias: Option<BiasSample>,
}

impl StatusReader {
    /// Opens the two streams, waiting up to `timeout` for the daemon's services.
    pub fn open(domain: &crate::Domain, timeout: Duration) -> Result<Self, ClientError> {
        let diagnostics = Subscriber::open(domain, "corridor-status", timeout)?;
        let bias = Subscriber::open(domain, "corridor-status-bias", timeout)?;
        Ok(Self {
            diagnostics,
            bias,
            last: None,
            latest_bias: None,
        })
    }

    /// The next status: waits up to `timeout` for the next diagnostics (the daemon publishes
    /// them every diagnostics period, idle or not). `want_rate`: on the first call, also wait
    /// (within `timeout`) for a second diagnostics, so the rates can be computed. `Ok(None)`
    /// when the daemon did not answer in time.
    pub fn next(
        &mut self,
        timeout: Duration,
        want_rate: bool,
    ) -> Result<Option<Status>, ClientError> {
        let deadline = Instant::now() + timeout;
        let left = || deadline.saturating_duration_since(Instant::now());
        let Some(mut d) = self.diagnostics.recv_timeout(left())? else {
            return Ok(None);
        };
        // Take everything already queued: the newest diagnostics wins.
        let mut previous = self.last;
        while let Some(next) = self.diagnostics.try_recv()? {
            previous = Some(d);
            d = next;
        }
        if previous.is_none()
            && want_rate
            && let Some(next) = self.diagnostics.recv_timeout(left())?
        {
            previous = Some(d);
            d = next;
        }
        // The daemon hands a late reader the latest bias right after its diagnostics.
        if self.latest_bias.is_none() {
            self.latest_bias = self
                .bias
                .recv_timeout(left().min(Duration::from_millis(200)))?;
        }
        while let Some(b) = self.bias.try_recv()? {
            self.latest_bias = Some(b);
        }
        self.last = Some(d);
        Ok(Some(Status {
            diagnostics: d,
            previous,
            bias: self.latest_bias,
            missed: self.diagnostics.missed(),
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_checkpoint_path_that_cannot_be_a_checkpoint_is_an_error_and_a_missing_one_is_not() {
        let dir = std::env::temp_dir().join(format!("corridor-ckpt-line-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let err = checkpoint_line(&dir).unwrap_err();
        assert!(
            matches!(&err, CheckpointPathError::NotAFile { path } if *path == dir),
            "{err:?}"
        );
        assert!(err.to_string().contains("is not a file"), "{err}");
        let missing = dir.join("checkpoint.bin");
        let line = checkpoint_line(&missing).unwrap();
        assert!(
            line.contains("none at") && line.contains("not saved yet"),
            "{line}"
        );
        std::fs::write(&missing, [0u8; 12]).unwrap();
        let line = checkpoint_line(&missing).unwrap();
        assert!(line.contains("(12 B), saved"), "{line}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_daemon_account_is_the_difference_within_one_life() {
        let before = Diagnostics {
            received: 100,
            seq_gaps: 3,
            accepted: 90,
            rejected_time: 2,
            lives: 1,
            ..Diagnostics::default()
        };
        let after = Diagnostics {
            received: 14101,
            seq_gaps: 4793,
            dropped_overflow: 1019,
            accepted: 8280,
            rejected_time: 2,
            rejected_time_jump: 1,
            lives: 1,
            ..Diagnostics::default()
        };
        assert_eq!(
            DaemonAccount::between(&before, &after),
            Some(DaemonAccount {
                received: 14001,
                seq_gaps: 4790,
                head_missing: 0,
                dropped_overflow: 1019,
                refused: 1,
                accepted: 8190,
                producer_changes: 0,
                foreign: 0,
            })
        );
        let account = DaemonAccount::between(&before, &after).unwrap();
        assert_eq!(account.lost(), 4790 + 1019);
        // 8190 estimated, 1 refused, 1019 dropped, 4790 missing.
        assert!(account.accounts_for(14000) && !account.accounts_for(14001));
        let restarted = Diagnostics { lives: 2, ..after };
        assert_eq!(DaemonAccount::between(&before, &restarted), None);
        assert_eq!(DaemonAccount::between(&after, &before), None);
    }

    #[test]
    fn the_sample_rate_is_not_made_up_across_a_daemon_restart() {
        let diag = |t_s: f64, accepted: u64| Diagnostics {
            t_s,
            accepted,
            ..Diagnostics::default()
        };
        let status = |previous, now| Status {
            diagnostics: now,
            previous: Some(previous),
            bias: None,
            missed: 0,
        };
        assert_eq!(
            status(diag(10.0, 1000), diag(11.0, 1200)).sample_rate_hz(),
            Some(200.0)
        );
        // The new daemon life counts from 0 (the difference wrapped: 8e17 Hz in `--watch`),
        // also once its count has passed the old one's (a review).
        assert_eq!(
            status(diag(10.0, 1000), diag(11.0, 150)).sample_rate_hz(),
            None
        );
        let next_life = Diagnostics {
            lives: 2,
            ..diag(11.0, 1600)
        };
        assert_eq!(status(diag(10.0, 1000), next_life).sample_rate_hz(), None);
        assert_eq!(
            status(diag(10.0, 1000), diag(10.0, 1000)).sample_rate_hz(),
            None
        );
    }

    #[test]
    fn a_screen_between_streams_says_so_and_no_nan_sigma() {
        // After a stream's end the estimator is the next stream's (aligning, no time yet), and
        // a bias published before the alignment has no σ: the screen used to say
        // "aligning (sensor time n/a)" beside the ended stream's bias, and "[nan, nan, nan]".
        let status = Status {
            diagnostics: Diagnostics {
                t_s: f64::NAN,
                phase: phase::ALIGNING,
                flags: FLAG_END_OF_STREAM,
                ..Diagnostics::default()
            },
            previous: None,
            bias: Some(BiasSample {
                gyro_bias_sd_rad_s: [f64::NAN; 3],
                ..BiasSample::default()
            }),
            missed: 0,
        };
        let screen = status.render("d");
        assert!(screen.contains("running, stream ended"), "{screen}");
        assert!(screen.contains("between streams"), "{screen}");
        assert!(!screen.contains("aligning"), "{screen}");
        assert!(
            screen.contains("bias σ:           none before the alignment"),
            "{screen}"
        );
        assert!(!screen.contains("nan"), "{screen}");
        // Within a stream: its phase and time.
        let mut running = status;
        running.diagnostics.flags = 0;
        running.diagnostics.phase = phase::TRACKING;
        running.diagnostics.t_s = 12.5;
        let screen = running.render("d");
        assert!(
            screen.contains("tracking (sensor time 12.500 s)"),
            "{screen}"
        );
    }

    #[test]
    fn outputs_nobody_subscribed_to_are_not_shown_as_losses() {
        // A fresh daemon without consumers: its diagnostics reached no subscriber until this
        // status subscribed. The screen said "losses: … undelivered outputs 2".
        let status = Status {
            diagnostics: Diagnostics {
                undelivered: 2,
                lives: 1,
                ..Diagnostics::default()
            },
            previous: None,
            bias: None,
            missed: 0,
        };
        let screen = status.render("d");
        let losses = screen.lines().find(|l| l.starts_with("losses:")).unwrap();
        assert!(!losses.contains('2'), "{screen}");
        assert!(
            screen.contains(
                "no subscriber:    outputs published while none was subscribed 2 (not a loss; \
                 a failed publish is warned in the daemon's log)"
            ),
            "{screen}"
        );
    }

    #[test]
    fn a_restarted_daemons_screen_says_which_counts_span_its_lives() {
        let mut status = Status {
            diagnostics: Diagnostics {
                received: 25193,
                accepted: 3000,
                lives: 1,
                ..Diagnostics::default()
            },
            previous: None,
            bias: None,
            missed: 0,
        };
        assert!(!status.render("d").contains("daemon lives"));
        status.diagnostics.lives = 3;
        let screen = status.render("d");
        // The stalled consumers (on the losses line) and the clipping counts are this life's
        // (the publishers' stall guards and the estimator start again with each life): the
        // note said every loss spanned the lives.
        assert!(
            screen.contains("received, losses but the stalled consumers, no subscriber, duplicate seq, late, not received, producers and angles count over all 3 daemon lives of this domain; accepted, stances, heading updates, clipped, the stalled consumers, the other rejections and external headings over this life"),
            "{screen}"
        );
    }
}
