//! `corridor-pdr`: prints the daemon's stride-by-stride positions (one line per stance,
//! [`corridor_client::track`]) until the producer finishes, the daemon stops and does not
//! come back within `--wait-s` (an error: the walk's end was not received) or Ctrl-C. `sensor_yaw_deg` is the
//! sensor's yaw in the map frame, not the walking direction: a sensor sits turned on the shoe
//! (the bundled walks' by about 180°; a review read it as the direction walked).

use anyhow::{Result, bail};
use clap::Parser;
use corridor_client::Domain;
use corridor_client::track::{TrackStop, Tracker};
use corridor_shared::injection::parse_time_s;
use corridor_shared::services::DEFAULT_DOMAIN;
use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

#[derive(Parser, Debug)]
#[command(
    name = "corridor-pdr",
    version,
    about = "Print stride-by-stride positions from the corridor daemon (sensor_yaw_deg: the sensor's yaw in the map frame, not the walking direction)",
    after_help = "Examples:\n  corridor-pdr --domain lab\n  corridor-pdr --domain lab --follow\nExit code: 0 success, 1 error, 2 usage error, 3 no daemon answered within --wait-s; stopped by Ctrl-C (SIGTERM), it ends as the signal does: 130 (143) in a shell."
)]
struct Args {
    /// iceoryx2 domain of the daemon.
    #[arg(long, default_value = DEFAULT_DOMAIN, value_parser = Domain::parse_name)]
    domain: String,
    /// How long to wait for the daemon, s: at the start, and for one that stopped within a
    /// stream to come back.
    #[arg(long, default_value_t = 30.0, value_parser = parse_time_s)]
    wait_s: f64,
    /// Keep going after an end of stream (follow the next producer).
    #[arg(long)]
    follow: bool,
}

fn main() -> std::process::ExitCode {
    corridor_client::init_tracing("warn");
    corridor_client::exit(run())
}

fn run() -> Result<()> {
    let a = Args::parse();
    let domain = Domain::new(&a.domain)?;
    let tracker = Tracker::open(&domain, "corridor-pdr", Duration::from_secs_f64(a.wait_s))?;
    // Standard output closed (a pipe whose reader left, `| head`): stop quietly, as a filter
    // does (`println!` panicked with a backtrace).
    let mut out = std::io::stdout().lock();
    let closed = AtomicBool::new(false);
    let say = |out: &mut std::io::StdoutLock, line: std::fmt::Arguments| {
        if writeln!(out, "{line}").is_err() {
            closed.store(true, Ordering::Relaxed);
        }
    };
    say(
        &mut out,
        format_args!(
            "{:>6} {:>10} {:>9} {:>9} {:>9} {:>14} {:>9}",
            "stride", "t_s", "x_m", "y_m", "z_m", "sensor_yaw_deg", "step_m"
        ),
    );
    loop {
        let t = tracker.run(Duration::from_millis(500), None, &closed, |s| {
            let (n, p) = (s.nav, s.nav.p_m);
            say(
                &mut out,
                format_args!(
                    "{:>6} {:>10.3} {:>9.3} {:>9.3} {:>9.3} {:>14.1} {:>9.3}{}",
                    n.stance,
                    n.t_s,
                    p[0],
                    p[1],
                    p[2],
                    n.yaw_rad.to_degrees(),
                    s.step_m,
                    if s.frame_set && s.replaces_previous {
                        "  (again, in the map frame the start heading set on it: replaces the line above)"
                    } else if s.replaces_previous {
                        "  (again: replaces the lines above from this stride on, whose samples had glitched stamps)"
                    } else if s.new_track {
                        "  (the daemon's estimator started again: a new track from its own origin)"
                    } else {
                        ""
                    }
                ),
            );
        })?;
        if closed.load(Ordering::Relaxed) {
            return Ok(());
        }
        // What was received, and what was not: the daemon's count at the end of stream, the
        // nav messages this reader missed (it fell behind; before, neither was said, and the
        // daemon's count was printed as if every stride had been received).
        let ended = t.stopped == TrackStop::EndOfStream;
        let daemon_stopped = t.stopped == TrackStop::DaemonStopped;
        let daemon = match t.end_stances {
            Some(n) if n != t.strides => format!(" of the daemon's {n}"),
            _ => String::new(),
        };
        let missed = match t.missed {
            0 => String::new(),
            n => format!(", {n} nav messages missed (this reader fell behind)"),
        };
        say(
            &mut out,
            format_args!(
                "{}: {} strides received{daemon}, path {:.2} m over them{missed}",
                t.stopped.describe(),
                t.strides,
                t.path_m
            ),
        );
        if daemon_stopped {
            bail!(
                "the daemon of domain {:?} stopped within the stream and did not come back \
                 within --wait-s ({} s): the strides after the last one above were not received",
                a.domain,
                a.wait_s
            );
        }
        if !ended || !a.follow {
            break;
        }
    }
    Ok(())
}
