//! The daemon as a real process (`corridor serve`), each test on its own domain:
//!
//! - `sigkill_then_restart_cleans_up_and_resumes_from_the_periodic_checkpoint`: a daemon fed at
//!   10× real time is killed with SIGKILL mid-stream (after a periodic checkpoint), leaving its
//!   shared memory behind; a new daemon on the same domain starts (iceoryx2 removes the dead
//!   node's resources), warm-starts from that checkpoint, and a consumer that stayed connected
//!   across the crash receives the new daemon's stream. SIGTERM then stops it cleanly.
//! - `second_daemon_on_the_same_domain_is_refused`: the second `corridor serve` exits with an
//!   error naming the domain.
//! - `sigterm_then_sigcont_stops_the_daemon`: systemd's stop; `ctrl_z_stops_the_daemon_and_fg_resumes_it`.

mod common;

use common::TempDir;
use corridor_client::{Delivery, Domain, Producer, Subscriber};
use corridor_service::checkpoint;
use corridor_service::core::{Estimate, Phase};
use corridor_service::runner::{heading_aid, run_log};
use corridor_shared::config::ConfigFile;
use corridor_shared::imu_csv::{ImuCsvOptions, ImuLog, read_imu_csv};
use corridor_shared::injection::BiasInjection;
use corridor_shared::wire::{AttitudeSample, BiasSample, Diagnostics, ImuSample, phase};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

const WAIT: Duration = Duration::from_secs(60);

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn exp36() -> ImuLog {
    let path = root().join("tests/data/gdins_exp36_corridor_out_and_back/imu.csv");
    read_imu_csv(&path, &ImuCsvOptions::default()).unwrap()
}

/// gdins.toml plus a `[daemon]` section with a fast periodic checkpoint.
fn write_config(dir: &Path) -> PathBuf {
    let mut text = std::fs::read_to_string(root().join("configs/gdins.toml")).unwrap();
    assert!(!text.contains("[daemon]"));
    text.push_str("\n[daemon]\ncheckpoint_period_s = 0.2\nhealth_period_s = 0.5\n");
    let path = dir.join("service.toml");
    std::fs::write(&path, text).unwrap();
    ConfigFile::read(&path).unwrap().validate().unwrap();
    path
}

fn cleanup_domain(domain: &str) {
    for f in shm_files(domain) {
        let _ = std::fs::remove_file(Path::new("/dev/shm").join(f));
    }
    // Event sockets and service files a failed run may leave under /tmp/iceoryx2.
    let prefix = format!("corridor_{domain}_");
    for root in ["/tmp/iceoryx2", "/tmp/iceoryx2/services"] {
        if let Ok(dir) = std::fs::read_dir(root) {
            for e in dir.flatten() {
                if e.file_name().to_string_lossy().starts_with(&prefix) {
                    let _ = std::fs::remove_file(e.path());
                }
            }
        }
    }
}

fn shm_files(domain: &str) -> Vec<String> {
    let prefix = format!("corridor_{domain}_");
    std::fs::read_dir("/dev/shm")
        .map(|d| {
            d.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.starts_with(&prefix))
                .collect()
        })
        .unwrap_or_default()
}

/// The `corridor serve` command, its stderr (the log) in `log`.
fn serve_command(config: &Path, domain: &str, ckpt: &Path, log: &Path) -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_corridor"));
    cmd.args(["serve", "--delivery", "live", "--domain", domain])
        .arg("--config")
        .arg(config)
        .arg("--checkpoint")
        .arg(ckpt)
        .env("RUST_LOG", "info")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(std::fs::File::create(log).unwrap());
    cmd
}

/// `corridor serve` with its stderr (the log) in `log`.
fn serve(config: &Path, domain: &str, ckpt: &Path, log: &Path) -> Child {
    serve_command(config, domain, ckpt, log)
        .spawn()
        .expect("corridor serve starts")
}

/// SIGTERM, then the exit status and stdout (the JSON report).
fn terminate(mut child: Child) -> (std::process::ExitStatus, String) {
    let pid = i32::try_from(child.id()).unwrap();
    // SAFETY: plain kill(2) on our own child.
    assert_eq!(unsafe { libc::kill(pid, libc::SIGTERM) }, 0);
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            let mut out = String::new();
            use std::io::Read;
            child
                .stdout
                .take()
                .unwrap()
                .read_to_string(&mut out)
                .unwrap();
            return (status, out);
        }
        if start.elapsed() > WAIT {
            let _ = child.kill();
            panic!("daemon did not stop on SIGTERM");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// A fresh domain `name` with `corridor serve` on it (log in `daemon.log` of the returned
/// directory), once it publishes.
fn serve_fresh(name: &str) -> (TempDir, Domain, Child) {
    cleanup_domain(name);
    let dir = TempDir::new(&name.replace('_', "-"));
    let config = write_config(&dir);
    let domain = Domain::new(name).unwrap();
    let child = serve(&config, name, &dir.join("c.bin"), &dir.join("daemon.log"));
    let diag = Subscriber::<Diagnostics>::open(&domain, "test-diag", WAIT).unwrap();
    assert!(diag.recv_timeout(WAIT).unwrap().is_some(), "daemon up");
    (dir, domain, child)
}

/// Sends `sig` to the child.
fn signal(child: &Child, sig: i32) {
    let pid = i32::try_from(child.id()).unwrap();
    // SAFETY: plain kill(2) on our own child.
    assert_eq!(unsafe { libc::kill(pid, sig) }, 0);
}

fn offline(log: &ImuLog) -> (Vec<Estimate>, usize) {
    let cfg = ConfigFile::read(&root().join("configs/gdins.toml"))
        .unwrap()
        .validate()
        .unwrap();
    let aid = heading_aid(&cfg, None).unwrap();
    let mut est = Vec::with_capacity(log.rows.len());
    run_log(log, &cfg, &aid, &BiasInjection::default(), |_, e| {
        est.push(*e)
    });
    let first = est.iter().position(|e| e.phase != Phase::Aligning).unwrap();
    (est, first)
}

#[test]
fn sigkill_then_restart_cleans_up_and_resumes_from_the_periodic_checkpoint() {
    let name = "test_daemon_sigkill";
    cleanup_domain(name);
    let dir = TempDir::new("test-daemon-sigkill");
    let config = write_config(&dir);
    let ckpt = dir.join("checkpoint.bin");
    let log = exp36();
    let (offline, first_aligned) = offline(&log);
    let domain = Domain::new(name).unwrap();

    // First life: fed at 10× real time until it tracks and has saved a periodic checkpoint.
    let first = serve(&config, name, &ckpt, &dir.join("first.log"));
    let attitude = Subscriber::<AttitudeSample>::open(&domain, "test-attitude", WAIT).unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let producer = {
        let (domain, stop, rows) = (domain.clone(), Arc::clone(&stop), log.rows.clone());
        std::thread::spawn(move || {
            let mut p = Producer::new(&domain, "test-sensor", Delivery::Live).unwrap();
            p.wait_for_daemon(WAIT).unwrap();
            let start = Instant::now();
            let t0 = rows[0].t_s;
            for r in &rows {
                if stop.load(Ordering::Relaxed) {
                    break;
                }
                let due = start + Duration::from_secs_f64((r.t_s - t0) / 10.0);
                std::thread::sleep(due.saturating_duration_since(Instant::now()));
                p.send_imu(ImuSample::from(r)).unwrap();
            }
            p.stats()
        })
    };
    let deadline = Instant::now() + WAIT;
    let mut last = AttitudeSample::default();
    while !(last.phase == phase::TRACKING && ckpt.exists()) || last.imu_seq < 4000 {
        assert!(
            Instant::now() < deadline,
            "no tracking and checkpoint in time"
        );
        if let Some(a) = attitude.recv_timeout(Duration::from_millis(100)).unwrap() {
            last = a;
        }
    }
    let mut first = first;
    first.kill().unwrap(); // SIGKILL
    first.wait().unwrap();
    stop.store(true, Ordering::Relaxed);
    let sent = producer.join().unwrap();
    assert!(
        (sent.imu_sent as usize) < log.rows.len(),
        "killed mid-stream"
    );
    let stale = shm_files(name);
    assert!(
        stale.len() > 1,
        "the killed daemon leaves its shared memory behind: {stale:?}"
    );
    let saved = checkpoint::load(&ckpt).expect("a periodic checkpoint");
    let last_t = offline.last().unwrap().t_s;
    assert!(
        saved.t_s > offline[first_aligned].t_s && saved.t_s < last_t,
        "mid-stream state: t = {} s",
        saved.t_s
    );

    // Second life, same domain: the dead node's resources are cleaned, the checkpoint used.
    let second = serve(&config, name, &ckpt, &dir.join("second.log"));
    let bias = Subscriber::<BiasSample>::open(&domain, "test-bias", WAIT).unwrap();
    let diagnostics = Subscriber::<Diagnostics>::open(&domain, "test-diag", WAIT).unwrap();
    let n = first_aligned + 100;
    {
        // The sensor driver restarted too: a new producer, seq and clock from the start.
        let mut p = Producer::new(&domain, "test-sensor-2", Delivery::Live).unwrap();
        p.wait_for_daemon(WAIT).unwrap();
        for (i, r) in log.rows[..n].iter().enumerate() {
            if i % 500 == 0 {
                std::thread::sleep(Duration::from_millis(5)); // stay within the buffers
            }
            p.send_imu(ImuSample::from(r)).unwrap();
        }
        p.finish().unwrap();
        assert_eq!(p.stats().imu_undelivered, 0);
    }
    let first_bias = loop {
        let b = bias
            .recv_timeout(WAIT)
            .unwrap()
            .expect("bias from the new daemon");
        if b.gyro_bias_sd_rad_s[0].is_finite() {
            break b;
        }
    };
    assert_eq!(first_bias.imu_seq, first_aligned as u64);
    // Warm start from the killed daemon's checkpoint, the new rest fused in: as the offline
    // estimator warm-started from the same state over the same rows.
    let warm = {
        let cfg = ConfigFile::read(&config).unwrap().validate().unwrap();
        let aid = heading_aid(&cfg, None).unwrap();
        let mut est = corridor_service::core::Estimator::new(cfg, aid);
        est.set_warm_start(corridor_service::core::WarmStart {
            gyro_bias_rad_s: saved.gyro_bias_rad_s,
            gyro_bias_cov: saved.gyro_bias_cov,
        })
        .unwrap();
        let mut last = None;
        for r in &log.rows[..=first_aligned] {
            last = Some(*est.step(&r.into()).unwrap());
        }
        last.unwrap()
    };
    assert_eq!(
        first_bias.gyro_bias_rad_s, warm.gyro_bias_rad_s,
        "warm start from the checkpoint of the killed daemon"
    );
    assert_ne!(
        first_bias.gyro_bias_rad_s, offline[first_aligned].gyro_bias_rad_s,
        "not a cold start"
    );
    // The consumer that stayed connected through the crash gets the new daemon's attitude.
    let mut after = 0u64;
    while let Some(a) = attitude.recv_timeout(Duration::from_millis(500)).unwrap() {
        if a.imu_seq as usize == n - 1 && a.t_s == log.rows[n - 1].t_s {
            after += 1;
        }
    }
    assert_eq!(after, 1, "the kept consumer receives the restarted stream");
    // The restarted daemon continues the attitude numbering (its accounting file): no restart
    // of `seq` for the consumer, and what it missed around the crash is a counted gap.
    assert_eq!(attitude.publisher_restarts(), 0);
    let d = loop {
        let d = diagnostics
            .recv_timeout(WAIT)
            .unwrap()
            .expect("diagnostics");
        if d.accepted == n as u64 {
            break d;
        }
    };
    assert_eq!((d.seq_gaps, d.dropped_overflow, d.late), (0, 0, 0));
    drop((attitude, bias, diagnostics));

    let (status, out) = terminate(second);
    assert!(status.success(), "{status}");
    let report: serde_json::Value = serde_json::from_str(&out).expect("JSON report");
    assert_eq!(report["warm_started"], true, "{out}");
    assert_eq!(report["accepted"], n as u64, "{out}");
    let log2 = std::fs::read_to_string(dir.join("second.log")).unwrap();
    assert!(log2.contains("warm start from the checkpoint"), "{log2}");
    assert!(log2.contains("health: input"), "{log2}");
    let left = shm_files(name);
    assert!(
        left.iter()
            .all(|f| f.ends_with("global_mgmt") || f.ends_with("daemon.state")),
        "a clean exit removes the domain's shared memory (the accounting file stays for the \
         next daemon): {left:?}"
    );
    cleanup_domain(name);
}

#[test]
fn second_daemon_on_the_same_domain_is_refused() {
    let name = "test_daemon_twice";
    cleanup_domain(name);
    let dir = TempDir::new("test-daemon-twice");
    let config = write_config(&dir);
    let domain = Domain::new(name).unwrap();
    let first = serve(&config, name, &dir.join("a.bin"), &dir.join("first.log"));
    let diag = Subscriber::<Diagnostics>::open(&domain, "test-diag", WAIT).unwrap();

    let out = Command::new(env!("CARGO_BIN_EXE_corridor"))
        .args(["serve", "--domain", name])
        .arg("--config")
        .arg(&config)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&format!(
            "another corridor daemon already serves domain \"{name}\""
        )) && err.contains(&format!(
            "stop it first, or serve another domain (--domain); `corridor status --domain {name}`"
        )),
        "{err}"
    );
    // The first one is undisturbed.
    assert!(diag.recv_timeout(WAIT).unwrap().is_some());
    assert_eq!(diag.publishers(), 1);
    drop(diag);
    let (status, _) = terminate(first);
    assert!(status.success());
    cleanup_domain(name);
}

#[test]
fn sigterm_then_sigcont_stops_the_daemon() {
    // systemd's stop (KillSignal, then SIGCONT) and timeout(1): iceoryx2 keeps only the last
    // signal, and the daemon went on running (1 of 3 tries from a shell, 5 of 6 under
    // `timeout 3`). The race does not show on every try (this test passed on the build without
    // the latch when run once); `shared/tests/termination_latch.rs` shows it every time.
    let name = "test_daemon_term_cont";
    let (dir, _domain, mut child) = serve_fresh(name);
    signal(&child, libc::SIGTERM);
    signal(&child, libc::SIGCONT);
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > WAIT {
            let _ = child.kill();
            panic!(
                "the daemon did not stop on SIGTERM followed by SIGCONT: {}",
                std::fs::read_to_string(dir.join("daemon.log")).unwrap_or_default()
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    assert!(status.success(), "{status:?}");
    let log = std::fs::read_to_string(dir.join("daemon.log")).unwrap();
    assert!(log.contains("termination requested"), "{log}");
    cleanup_domain(name);
}

/// The process state letter of `/proc/PID/stat` (`T`: stopped).
fn proc_state(child: &Child) -> char {
    let stat = std::fs::read_to_string(format!("/proc/{}/stat", child.id())).unwrap();
    // "pid (comm) S ...": the state follows the command's closing parenthesis.
    stat.rsplit_once(") ").unwrap().1.chars().next().unwrap()
}

/// A child killed when dropped (a failed check leaves no daemon running).
struct KillOnDrop(Option<Child>);

impl Drop for KillOnDrop {
    fn drop(&mut self) {
        if let Some(mut c) = self.0.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

#[test]
fn ctrl_z_stops_the_daemon_and_fg_resumes_it() {
    // SIGTSTP: iceoryx2's handler recorded it and the daemon went on running (Ctrl-Z did
    // nothing). The daemon runs in a process group of its own, as a shell's job does: the
    // kernel stops no member of an orphaned group on SIGTSTP (a test run started by setsid
    // is one), and the daemon now takes the default action, as any program.
    let name = "test_daemon_tstp";
    cleanup_domain(name);
    let dir = TempDir::new(&name.replace('_', "-"));
    let config = write_config(&dir);
    let domain = Domain::new(name).unwrap();
    let mut cmd = serve_command(&config, name, &dir.join("c.bin"), &dir.join("daemon.log"));
    std::os::unix::process::CommandExt::process_group(&mut cmd, 0);
    let mut child = KillOnDrop(Some(cmd.spawn().expect("corridor serve starts")));
    let diag = Subscriber::<Diagnostics>::open(&domain, "test-diag-tstp", WAIT).unwrap();
    assert!(diag.recv_timeout(WAIT).unwrap().is_some(), "daemon up");
    let running = child.0.as_ref().unwrap();
    signal(running, libc::SIGTSTP);
    let start = Instant::now();
    while proc_state(running) != 'T' {
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "not stopped by SIGTSTP: state {}",
            proc_state(running)
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    signal(running, libc::SIGCONT);
    // Running again: it publishes new diagnostics (one read may be from before the stop).
    while diag.recv_timeout(Duration::ZERO).unwrap().is_some() {}
    let seqs: Vec<u64> = (0..2)
        .map(|_| diag.recv_timeout(WAIT).unwrap().expect("diagnostics").seq)
        .collect();
    assert!(
        seqs[1] > seqs[0],
        "{seqs:?} {}",
        std::fs::read_to_string(dir.join("daemon.log")).unwrap_or_default()
    );
    drop(diag);
    let (status, out) = terminate(child.0.take().unwrap());
    assert!(status.success(), "{status:?} {out}");
    cleanup_domain(name);
}

#[test]
fn stop_and_continue_leave_the_daemon_running() {
    // Ctrl-Z then `fg` (SIGSTOP, SIGCONT): the interrupted wait of the receive thread is not
    // an error; the daemon goes on receiving and stops cleanly on SIGTERM.
    let name = "test_daemon_stop_cont";
    let (dir, domain, child) = serve_fresh(name);
    for _ in 0..5 {
        signal(&child, libc::SIGSTOP);
        std::thread::sleep(Duration::from_millis(200));
        signal(&child, libc::SIGCONT);
        std::thread::sleep(Duration::from_millis(200));
    }
    let att = Subscriber::<AttitudeSample>::open(&domain, "test-att", WAIT).unwrap_or_else(|e| {
        panic!(
            "{e}; daemon log: {}",
            std::fs::read_to_string(dir.join("daemon.log")).unwrap_or_default()
        )
    });
    let mut p = Producer::open(&domain, "test-producer", Some(Delivery::Live)).unwrap();
    p.wait_for_daemon(WAIT).unwrap();
    let log = exp36();
    for r in &log.rows[..2000] {
        p.send_imu(ImuSample::from(r)).unwrap();
    }
    assert!(
        att.recv_timeout(WAIT).unwrap().is_some(),
        "the daemon estimates after the stops: {}",
        std::fs::read_to_string(dir.join("daemon.log")).unwrap_or_default()
    );
    drop(att);
    let (status, out) = terminate(child);
    assert!(status.success(), "{status:?} {out}");
    drop(p);
    cleanup_domain(name);
}

#[test]
fn a_short_stream_sent_while_the_daemon_is_held_is_not_lost() {
    // A producer that sends a short stream and goes while the daemon has not yet received
    // anything from it (here: the daemon stopped with SIGSTOP; in the field: a busy machine).
    // iceoryx2 0.10 attaches the daemon's side of the connection only when the daemon next
    // receives, and a publisher dropped before that took its queued samples with it: before
    // `close` waited for the daemon's acknowledgement, the daemon received 0 of these 501.
    let name = "test_daemon_held";
    let (_dir, domain, child) = serve_fresh(name);
    signal(&child, libc::SIGSTOP);
    let log = exp36();
    let mut p = Producer::open(&domain, "test-short", None).unwrap();
    p.wait_for_daemon(WAIT).unwrap();
    for r in &log.rows[..500] {
        p.send_imu(ImuSample::from(r)).unwrap();
    }
    p.finish().unwrap();
    // Everything is sent and the daemon has taken nothing; it goes on only while the
    // producer closes.
    let pid = i32::try_from(child.id()).unwrap();
    let resume = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(300));
        // SAFETY: plain kill(2) on our own child.
        assert_eq!(unsafe { libc::kill(pid, libc::SIGCONT) }, 0);
    });
    let stats = p.close().unwrap();
    resume.join().unwrap();
    assert_eq!((stats.imu_sent, stats.imu_undelivered), (501, 0));
    assert_eq!(stats.closes_unconfirmed, 0, "{stats:?}");
    let (status, out) = terminate(child);
    assert!(status.success(), "{status:?}");
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(report["received"], 501, "{out}");
    cleanup_domain(name);
}
