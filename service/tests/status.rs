//! `corridor status` against a real `corridor serve` process (domains `eco_status*`): the
//! one-screen health after a replayed stream, `--watch` refreshing, and exit code 3 when no
//! daemon answers (2 is a usage error's).

use corridor_client::{Delivery, Domain, Producer};
use corridor_service::runner::{heading_aid, run_log};
use corridor_shared::config::ConfigFile;
use corridor_shared::imu_csv::{ImuCsvOptions, read_imu_csv};
use corridor_shared::injection::BiasInjection;
use corridor_shared::wire::ImuSample;
use std::io::BufRead;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::Duration;

const WAIT: Duration = Duration::from_secs(60);

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn corridor() -> Command {
    Command::new(env!("CARGO_BIN_EXE_corridor"))
}

fn status(domain: &str, timeout_s: &str, extra: &[&str]) -> Output {
    corridor()
        .args(["status", "--domain", domain, "--timeout-s", timeout_s])
        .args(extra)
        .output()
        .unwrap()
}

/// A lossless daemon on `domain` checkpointing into `checkpoint`, killed when dropped.
struct Daemon(Child);

impl Daemon {
    fn start(domain: &str, checkpoint: &Path) -> Self {
        for dir in ["/dev/shm", "/tmp/iceoryx2", "/tmp/iceoryx2/services"] {
            for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
                if e.file_name()
                    .to_string_lossy()
                    .starts_with(&format!("corridor_{domain}_"))
                {
                    let _ = std::fs::remove_file(e.path());
                }
            }
        }
        let config = root().join("configs/gdins.toml");
        Daemon(
            corridor()
                .args(["serve", "--delivery", "lossless", "--domain", domain])
                .arg("--config")
                .arg(config)
                .arg("--checkpoint")
                .arg(checkpoint)
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .unwrap(),
        )
    }
}

/// SIGTERM (a clean exit removes the shared memory), SIGKILL if that takes over a minute.
fn terminate(child: &mut Child) {
    let pid = i32::try_from(child.id()).unwrap();
    // SAFETY: plain kill(2) on our own child.
    unsafe { libc::kill(pid, libc::SIGTERM) };
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > WAIT {
            let _ = child.kill();
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

impl Drop for Daemon {
    fn drop(&mut self) {
        terminate(&mut self.0);
    }
}

#[test]
fn status_shows_the_daemons_counters_and_final_bias() {
    let name = "eco_status";
    let checkpoint =
        std::env::temp_dir().join(format!("corridor-eco-status-{}.bin", std::process::id()));
    let _ = std::fs::remove_file(&checkpoint);
    let daemon = Daemon::start(name, &checkpoint);
    let log = read_imu_csv(
        // exp26: 144 samples at the gyro's rail, and peaks put back (the clipping line).
        &root().join("tests/data/gdins_exp26_narrow_out_and_back/imu.csv"),
        &ImuCsvOptions::default(),
    )
    .unwrap();
    let domain = Domain::new(name).unwrap();
    let mut p = Producer::new(&domain, "eco-status-producer", Delivery::Lossless).unwrap();
    p.wait_for_daemon(WAIT).unwrap();
    for r in &log.rows {
        assert_eq!(p.send_imu(ImuSample::from(r)).unwrap(), 1);
    }
    p.finish().unwrap();

    let cfg = ConfigFile::read(&root().join("configs/gdins.toml"))
        .unwrap()
        .validate()
        .unwrap();
    let aid = heading_aid(&cfg, None).unwrap();
    let mut last = None;
    let offline = run_log(&log, &cfg, &aid, &BiasInjection::default(), |_, e| {
        last = Some(*e)
    })
    .counters;
    assert!(offline.clipped_samples > 0 && offline.clipped_peaks_restored > 0);
    let rows = log.rows.len();
    let b = last.unwrap().gyro_bias_rad_s;
    let bias = format!("[{:+.6}, {:+.6}, {:+.6}]", b[0], b[1], b[2]);

    // The daemon counts the marker (and saves its checkpoint) a moment after it was sent;
    // poll until it has.
    let mut screen = String::new();
    for _ in 0..30 {
        let o = status(name, "20", &["--checkpoint", checkpoint.to_str().unwrap()]);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        screen = String::from_utf8_lossy(&o.stdout).into_owned();
        // The final bias is published at the end of the stream, after the count: under load
        // it can come a moment later than the marker's count.
        if screen.contains(&format!("received {}", rows + 1))
            && screen.contains("s ago")
            && !screen.contains("none published yet")
        {
            break;
        }
    }
    for want in [
        "domain \"eco_status\": running",
        &format!("received {}, accepted {rows}", rows + 1),
        "seq gaps 0, overflow drops 0",
        "consumers stalled 0 (outputs discarded for them 0)",
        &format!(
            "clipped:          samples at a rail {} (gyro peaks put back {}, not put back {})",
            offline.clipped_samples,
            offline.clipped_peaks_restored,
            offline.clipped_peaks_not_restored
        ),
        "not received:     before the daemon's first message 0, missing at a restart 0, lost in a killed life 0",
        "producers:        changes 0, samples of a second producer refused 0, daemon life 1",
        "angles:           dropped 0, with roll or pitch (not fused) 0; external headings refused 0, superseded 0, outside the gate 0, expired 0, undone 0",
        "latency:",
        &format!("gyro bias:        {bias} rad/s"),
        "bias σ:",
        "converged:",
        "% of a start error left",
        &format!("last checkpoint:  {}", checkpoint.display()),
        "s ago",
    ] {
        assert!(screen.contains(want), "missing {want:?} in\n{screen}");
    }

    // A checkpoint path that cannot be the daemon's checkpoint (here a directory) is said, and
    // the status, healthy otherwise, exits 1 (it exited 0 and said "saved 0.0 s ago").
    let dir = std::env::temp_dir();
    let o = status(name, "20", &["--checkpoint", dir.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(&format!(
            "error: --checkpoint: {} is not a file",
            dir.display()
        )),
        "{err}"
    );

    // A file that is not a checkpoint (a config file) is said as such, exit 1.
    let not_one = root().join("configs/gdins.toml");
    let o = status(name, "20", &["--checkpoint", not_one.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("error: --checkpoint: not a checkpoint the daemon can start from")
            && err.contains("gdins.toml"),
        "{err}"
    );

    // --watch redraws at every diagnostics.
    let mut watch = corridor()
        .args(["status", "--watch", "--domain", name])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let out = watch.stdout.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::BufReader::new(out).lines() {
            let Ok(line) = line else { break };
            if line.starts_with("diagnostics seq:") && tx.send(line).is_err() {
                break;
            }
        }
    });
    let first = rx.recv_timeout(WAIT).expect("a first screen");
    let second = rx.recv_timeout(WAIT).expect("a refreshed screen");
    assert_ne!(first, second);
    // A watch stopped by SIGTERM says so (it said nothing) and ends by the signal, as every
    // tool does (it exited with 0).
    let mut stopped = corridor()
        .args(["status", "--watch", "--domain", name])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = std::io::BufReader::new(stopped.stdout.take().unwrap()).lines();
    assert!(
        lines.any(|l| l.is_ok_and(|l| l.starts_with("diagnostics seq:"))),
        "a first screen"
    );
    terminate(&mut stopped);
    assert_eq!(
        std::os::unix::process::ExitStatusExt::signal(&stopped.wait().unwrap()),
        Some(libc::SIGTERM)
    );
    let rest: Vec<String> = lines.map_while(Result::ok).collect();
    assert_eq!(
        rest.last().map(String::as_str),
        Some("stopped: interrupted")
    );
    // The daemon stopping ends the watch with exit code 3, said as a daemon shutting down,
    // without the hint on a secured domain's runtime directory (the daemon was found: the
    // hint sent its reader looking for a directory that had nothing to do with it).
    drop(daemon);
    let start = std::time::Instant::now();
    while watch.try_wait().unwrap().is_none() && start.elapsed() < WAIT {
        std::thread::sleep(Duration::from_millis(20));
    }
    terminate(&mut watch);
    let o = watch.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(
        err.contains("the daemon is shutting down") && !err.contains("--runtime-dir"),
        "{err}"
    );
    let _ = std::fs::remove_file(&checkpoint);
}

#[test]
fn status_exits_3_when_no_daemon_answers_and_2_on_a_usage_error() {
    let o = status("eco_status_nobody", "0.5", &[]);
    assert_eq!(o.status.code(), Some(3));
    // Not the code of a usage error: a script could not tell a mistyped flag from a daemon
    // that is down (both were 2).
    let usage = status("eco_status_nobody", "0.5", &["--no-such-flag"]);
    assert_eq!(usage.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("no corridor daemon answers on domain \"eco_status_nobody\""),
        "{err}"
    );
    // A --checkpoint path that cannot be a checkpoint is said before any wait for a daemon,
    // exit 1: it waited out the timeout and exited 3, as if only the daemon were missing.
    let dir = std::env::temp_dir();
    let start = std::time::Instant::now();
    let o = status(
        "eco_status_nobody",
        "30",
        &["--checkpoint", dir.to_str().unwrap()],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(start.elapsed() < Duration::from_secs(20), "{err}");
    assert!(
        err.contains(&format!(
            "error: --checkpoint: {} is not a file",
            dir.display()
        )),
        "{err}"
    );
    // Without the runtime directory a secured domain's daemon cannot be found: said.
    let o = corridor()
        .args([
            "status",
            "--domain",
            "eco_status_nobody",
            "--timeout-s",
            "0.5",
        ])
        .env_remove("CORRIDOR_RUNTIME_DIR")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--runtime-dir DIR") && err.contains("CORRIDOR_RUNTIME_DIR=DIR"),
        "{err}"
    );
}
