//! `corridor-log`: writes the daemon's attitude and bias streams to CSV
//! ([`corridor_client::record`]), following one stream after another into the same files, until
//! nothing arrives for `--idle-timeout-s` (or, with `--stop-at-end-of-stream`, until the first
//! end-of-stream marker).
//!
//! `attitude.csv` reuses the `estimates.csv` column names of `corridor run` where they apply
//! (no position or velocity: those are in the nav stream), preceded by `seq,imu_seq`.
//! `bias.csv` has the bias rows (at heading observations and at the daemon's bias rate).

use anyhow::Result;
use clap::Parser;
use corridor_client::Domain;
use corridor_client::record::{RecordOptions, RecordStop, Recorder};
use corridor_shared::injection::parse_time_s;
use corridor_shared::services::DEFAULT_DOMAIN;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

#[derive(Parser, Debug)]
#[command(
    name = "corridor-log",
    version,
    about = "Record the corridor daemon's attitude and bias streams to CSV",
    after_help = "Examples:\n  corridor-log --domain lab --out out/log\n  corridor-log --domain lab --out out/log --idle-timeout-s 1 --wait-s 60\nExit code: 0 success, 1 error, 2 usage error, 3 no daemon answered within --wait-s; stopped by Ctrl-C (SIGTERM), it ends as the signal does: 130 (143) in a shell."
)]
struct Args {
    /// iceoryx2 domain of the daemon.
    #[arg(long, default_value = DEFAULT_DOMAIN, value_parser = Domain::parse_name)]
    domain: String,
    /// Output directory (attitude.csv, bias.csv).
    #[arg(long)]
    out: PathBuf,
    /// Stop when nothing arrived for this long after the first sample, s.
    #[arg(long, default_value_t = 5.0, value_parser = parse_time_s)]
    idle_timeout_s: f64,
    /// How long to wait for the daemon, s.
    #[arg(long, default_value_t = 30.0, value_parser = parse_time_s)]
    wait_s: f64,
    /// Stop at the first end of stream instead of following the next stream (a restarted
    /// producer, the next replay; the loops of one replay are one stream) into the same files.
    #[arg(long)]
    stop_at_end_of_stream: bool,
}

fn main() -> std::process::ExitCode {
    corridor_client::init_tracing("warn");
    corridor_client::exit(run())
}

/// What is said of a stream whose end never arrived: why, as far as this logger can tell. (A
/// logger stopped by Ctrl-C or SIGTERM within a stream was given the causes of an idle timeout,
/// a pause in the data or a stalled logger.)
fn open_stream_note(stopped: RecordStop, rows: u64) -> String {
    let why = match stopped {
        RecordStop::Interrupted | RecordStop::Aborted => {
            "this logger was stopped within the stream"
        }
        _ => {
            "the daemon stopped, a pause in the data longer than --idle-timeout-s, messages the \
             daemon discarded while this logger stalled, or a producer that stopped without its \
             end-of-stream marker (corridor status --domain D says which)"
        }
    };
    format!(
        "open stream: its end never arrived; {rows} attitude rows of it recorded, what the \
         daemon published after them not received ({why})"
    )
}

fn run() -> Result<()> {
    let a = Args::parse();
    let domain = Domain::new(&a.domain)?;
    let opts = RecordOptions {
        node_name: "corridor-log".into(),
        wait: Duration::from_secs_f64(a.wait_s),
        idle_timeout: Duration::from_secs_f64(a.idle_timeout_s),
        idle_before_first: false,
        poll: Duration::from_millis(200),
    };
    let mut recorder = Recorder::open(&domain, &a.out, &opts)?;
    if !a.stop_at_end_of_stream {
        recorder = recorder.following_new_streams();
    }
    corridor_client::say_err!(
        "recording domain {:?} into {}",
        domain.name(),
        a.out.display()
    );
    let r = recorder.run(&AtomicBool::new(false))?;
    corridor_client::say!(
        "stopped: {} ({} streams ended)",
        r.stopped.describe(),
        r.streams_ended
    );
    corridor_client::say!(
        "attitude rows: {} ({})",
        r.attitude_rows,
        r.attitude_path.display()
    );
    corridor_client::say!("bias rows: {} ({})", r.bias_rows, r.bias_path.display());
    if r.kept_earlier_files {
        corridor_client::say!(
            "nothing recorded: the files of an earlier recording in {} were left as they were",
            a.out.display()
        );
    }
    if r.retracting_rows > 0 {
        corridor_client::say!(
            "retracting rows: {} (retracts 1: the rows before each with a later t_s came from \
             glitched stamps the daemon dropped after the fact)",
            r.retracting_rows
        );
    }
    // A stream whose end never came: what followed the last row received is unknown here (it
    // used to stop with exit code 0 and nothing said, after a pause in the data longer than
    // the idle timeout, or after the daemon discarded a stalled logger's messages).
    let open_stream = r.open_stream_rows > 0;
    if open_stream {
        corridor_client::say!("{}", open_stream_note(r.stopped, r.open_stream_rows));
    }
    // Every attitude message the daemon published up to the last one received is here:
    // published = before start + received + missing.
    // (The daemon numbers its messages over its lives: a logger that attached between two
    // streams counts every earlier stream's there, a review read them as this stream's.)
    let earlier = if r.attached_between_streams {
        " (all of earlier streams: this logger attached between two)"
    } else {
        ""
    };
    corridor_client::say!(
        "attitude messages: {} received, {} missing (seq gaps), {} published before the first{earlier}",
        r.attitude_received,
        r.attitude_missed,
        r.attitude_missed_at_start
    );
    corridor_client::say!(
        "bias messages: {} received, {} missing (seq gaps), {} published before the first{earlier}",
        r.bias_received,
        r.bias_missed,
        r.bias_missed_at_start
    );
    if r.imu_without_attitude > 0 {
        // (A daemon killed and restarted mid-stream leaves such a hole with its attitude
        // numbering whole: the logger said "0 missing" over it, a review. The samples after a
        // stream's last row, up to its end-of-stream marker, count too: a review.)
        corridor_client::say!(
            "IMU samples the daemon published no attitude for, between recorded rows or after a stream's last one: {} (refused or dropped by it, missing from the producer's numbering, or lost in a daemon restart: corridor status --domain {} says which)",
            r.imu_without_attitude,
            a.domain
        );
    }
    if open_stream && r.stopped == RecordStop::IdleTimeout {
        anyhow::bail!("the recording is incomplete: it timed out within a stream");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_interrupted_logger_says_it_was_stopped_not_why_the_data_paused() {
        let note = open_stream_note(RecordStop::Interrupted, 1548);
        assert!(
            note.contains("1548 attitude rows") && note.contains("this logger was stopped"),
            "{note}"
        );
        assert!(!note.contains("--idle-timeout-s"), "{note}");
        let note = open_stream_note(RecordStop::IdleTimeout, 7);
        assert!(note.contains("longer than --idle-timeout-s"), "{note}");
        // A daemon stopped within the stream was not among the causes.
        assert!(note.contains("the daemon stopped"), "{note}");
    }
}
