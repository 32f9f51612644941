//! CLI habits of the client tools (issue 12): the producer takes the daemon's delivery policy
//! (`--delivery` is an assertion), errors are printed once without a backtrace, every tool's
//! `--help` has examples.

use corridor_shared::services::{Access, Delivery, Domain};
use corridor_shared::wire::{ImuSample, NavSample};
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use std::os::unix::process::{CommandExt as _, ExitStatusExt as _};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The first `rows` rows of the exp36 log, in a fresh file.
fn short_log(tag: &str, rows: usize) -> PathBuf {
    let src = root().join("tests/data/gdins_exp36_corridor_out_and_back/imu.csv");
    let text = std::fs::read_to_string(src).unwrap();
    let head: Vec<&str> = text.lines().take(rows + 1).collect();
    let path = std::env::temp_dir().join(format!("corridor-eco-{tag}-{}.csv", std::process::id()));
    std::fs::write(&path, head.join("\n") + "\n").unwrap();
    path
}

fn tool(exe: &str, args: &[&str]) -> Output {
    Command::new(exe)
        .args(args)
        .env("RUST_BACKTRACE", "1")
        .output()
        .expect("tool runs")
}

/// Stands in for a daemon that chose `lossless`: creates the IMU service with that policy and
/// reads it while `corridor-replay` (given `extra` flags) runs. Returns the replay's output and
/// the samples received.
fn replay_into_lossless_daemon(domain_name: &str, extra: &[&str]) -> (Output, usize) {
    replay_into_stand_in(domain_name, extra, "max", usize::MAX)
}

/// [`replay_into_lossless_daemon`] at `--speed speed`, with a stand-in that stops reading (its
/// subscriber goes away, as a daemon that stopped) after `read_at_most` samples.
fn replay_into_stand_in(
    domain_name: &str,
    extra: &[&str],
    speed: &str,
    read_at_most: usize,
) -> (Output, usize) {
    // One stand-in daemon per process at a time (two in one process can lose a wake-up in
    // iceoryx2 0.10: docs/known-issues.md, "Attitudes that stopped for 60 s").
    static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one = ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let domain = Domain::new(domain_name).unwrap();
    let node = domain
        .node("eco-fake-daemon", SignalHandlingMode::Disabled)
        .unwrap();
    let service = domain
        .open::<ImuSample>(&node, Access::Owner(Delivery::Lossless))
        .unwrap();
    let _event = domain
        .open_event(&node, corridor_shared::services::IMU_SERVICE, true)
        .unwrap();
    let mut sub = Some(
        service
            .subscriber_builder()
            .buffer_size(IMU_BUFFER)
            .create()
            .unwrap(),
    );
    // Acknowledges each producer at its first sample, as the daemon does.
    let ack = domain
        .open_event(&node, corridor_shared::services::IMU_ACK_SERVICE, true)
        .unwrap()
        .notifier_builder()
        .create()
        .unwrap();
    let mut acknowledged = std::collections::HashSet::new();
    let mut take = |s: iceoryx2::sample::Sample<ipc::Service, ImuSample, ()>| {
        let id = s.header().publisher_id().value();
        if acknowledged.insert(id) {
            ack.notify_with_custom_event_id(EventId::new(corridor_shared::services::ack_event_id(
                id,
            )))
            .unwrap();
        }
    };
    let log = short_log(domain_name, 200);
    let mut child = Command::new(env!("CARGO_BIN_EXE_corridor-replay"))
        .args(["--imu", log.to_str().unwrap(), "--domain", domain_name])
        .args(["--speed", speed, "--wait-s", "30"])
        .args(extra)
        .env("RUST_BACKTRACE", "1")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut received = 0;
    let start = Instant::now();
    let mut read = |sub: &mut Option<_>, received: &mut usize| {
        while let Some(s) = sub
            .as_ref()
            .and_then(|r: &Subscriber<ipc::Service, ImuSample, ()>| r.receive().unwrap())
        {
            take(s);
            *received += 1;
            if *received >= read_at_most {
                *sub = None;
            }
        }
    };
    loop {
        read(&mut sub, &mut received);
        if child.try_wait().unwrap().is_some() {
            read(&mut sub, &mut received);
            break;
        }
        assert!(start.elapsed() < Duration::from_secs(120), "replay hangs");
        std::thread::sleep(Duration::from_millis(1));
    }
    let out = child.wait_with_output().unwrap();
    let _ = std::fs::remove_file(log);
    (out, received)
}

const IMU_BUFFER: usize = {
    use corridor_shared::services::Topic;
    ImuSample::QOS.buffer_size
};

#[test]
fn replay_takes_the_daemons_delivery_policy() {
    let (out, received) = replay_into_lossless_daemon("eco_delivery_adopt", &[]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("delivery lossless"), "{stdout}");
    assert_eq!(
        received,
        200 + 1,
        "every sample and the end-of-stream marker"
    );
    // The stand-in acknowledged the producer: the replay did not wait or warn.
    assert!(
        stdout.contains("daemon acknowledged this producer: yes"),
        "{stdout}"
    );
}

#[test]
fn replay_delivery_flag_is_an_assertion() {
    let (out, received) =
        replay_into_lossless_daemon("eco_delivery_assert", &["--delivery", "live"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("uses lossless delivery") && err.contains("live was asked for"),
        "{err}"
    );
    assert_eq!(received, 0);
}

#[test]
fn a_replay_whose_daemon_went_away_fails_and_counts_what_nobody_received() {
    // The stand-in stops reading after 50 of the 200 samples (1 s of log, sent in real time):
    // the rest reached no subscriber, and a script must not take the replay for a success.
    let (out, received) = replay_into_stand_in("eco_daemon_gone", &[], "realtime", 50);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(received, 50);
    assert!(!out.status.success(), "{stdout}{stderr}");
    let undelivered: usize = stdout
        .lines()
        .find_map(|l| l.strip_prefix("samples nobody received: "))
        .and_then(|l| l.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{stdout}"));
    // Some of the 150 and the end-of-stream marker were taken into the stand-in's buffer
    // before it went away.
    assert!(undelivered > 0 && undelivered <= 151, "{stdout}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with("error: ") && stderr.contains("reached no subscriber"),
        "{stderr}"
    );
}

#[test]
fn replay_flags_that_would_do_nothing_are_usage_errors() {
    for (args, flag) in [
        (&["--loop", "0"][..], "--loop"),
        (&["--inject-after-s", "3"][..], "--inject-gyro-bias"),
    ] {
        let o = tool(
            env!("CARGO_BIN_EXE_corridor-replay"),
            &[&["--imu", "imu.csv"][..], args].concat(),
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(flag), "{args:?}: {err}");
    }
}

#[test]
fn replay_error_is_printed_once_without_a_backtrace() {
    let o = tool(
        env!("CARGO_BIN_EXE_corridor-replay"),
        &["--imu", "/nonexistent/imu.csv"],
    );
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("error: "), "{err}");
    assert_eq!(err.matches("No such file or directory").count(), 1, "{err}");
    assert!(!err.contains("backtrace"), "{err}");
}

#[test]
fn every_tool_help_has_examples() {
    for (exe, name) in [
        (env!("CARGO_BIN_EXE_corridor-replay"), "corridor-replay"),
        (env!("CARGO_BIN_EXE_corridor-log"), "corridor-log"),
        (env!("CARGO_BIN_EXE_corridor-pdr"), "corridor-pdr"),
    ] {
        let o = tool(exe, &["--help"]);
        assert!(o.status.success(), "{name}");
        let help = String::from_utf8_lossy(&o.stdout);
        let examples = help
            .split_once("Examples:")
            .unwrap_or_else(|| panic!("{name}: no examples in\n{help}"))
            .1;
        assert!(
            examples.contains(&format!("{name} --")),
            "{name}: {examples}"
        );
    }
}

#[test]
fn a_reader_tool_without_a_daemon_says_so_as_status_does_and_a_bad_out_at_once() {
    // They gave iceoryx2's service text ("service … no publisher after 1s"); corridor-log
    // said its `--out` was a file only after waiting `--wait-s` for a daemon (a review).
    let dir = std::env::temp_dir().join(format!("corridor-client-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let a_file = dir.join("a-file");
    std::fs::write(&a_file, "").unwrap();
    let o = tool(
        env!("CARGO_BIN_EXE_corridor-log"),
        &[
            "--domain",
            "eco_cli_nobody",
            "--wait-s",
            "1",
            "--out",
            a_file.to_str().unwrap(),
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("exists and is not a directory"), "{err}");
    let o = tool(
        env!("CARGO_BIN_EXE_corridor-pdr"),
        &["--domain", "eco_cli_nobody", "--wait-s", "0.3"],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.starts_with("error: no corridor daemon answers on domain \"eco_cli_nobody\"")
            && err.contains("has no publisher"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The three stream tools with the arguments each needs besides its domain: the replay reads
/// `imu`, the logger writes into `out`.
fn stream_tools<'a>(imu: &'a Path, out: &'a Path) -> [(&'static str, Vec<&'a str>); 3] {
    [
        (
            env!("CARGO_BIN_EXE_corridor-replay"),
            vec!["--imu", imu.to_str().unwrap()],
        ),
        (
            env!("CARGO_BIN_EXE_corridor-log"),
            vec!["--out", out.to_str().unwrap()],
        ),
        (env!("CARGO_BIN_EXE_corridor-pdr"), vec![]),
    ]
}

#[test]
fn no_daemon_is_exit_code_3_in_every_tool_a_usage_error_2_and_help_says_so() {
    // As `corridor status`: they exited 1 for no daemon, as for any error, and status 2, as
    // for a usage error.
    let imu = short_log("nodaemon", 10);
    let out = std::env::temp_dir().join(format!("corridor-nodaemon-{}", std::process::id()));
    for (exe, args) in stream_tools(&imu, &out) {
        let o = tool(
            exe,
            &[
                &["--domain", "eco_cli_nobody", "--wait-s", "0.3"][..],
                &args,
            ]
            .concat(),
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(3), "{exe}: {err}");
        assert!(err.contains("no corridor daemon answers"), "{exe}: {err}");
        assert_eq!(
            tool(exe, &["--no-such-flag"]).status.code(),
            Some(2),
            "{exe}"
        );
        let help = String::from_utf8_lossy(&tool(exe, &["--help"]).stdout).into_owned();
        assert!(
            help.contains("Exit code: 0 success, 1 error, 2 usage error, 3 no daemon"),
            "{exe}: {help}"
        );
    }
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_file(&imu);
}

type Ipc = iceoryx2::service::ipc::Service;
type NavService =
    iceoryx2::service::port_factory::publish_subscribe::PortFactory<Ipc, NavSample, ()>;
type NavEvent = iceoryx2::service::port_factory::event::PortFactory<Ipc>;
type NavPublisher = iceoryx2::port::publisher::Publisher<Ipc, NavSample, ()>;

/// A stand-in daemon's nav service on domain `name` (its node, service, event and publisher)
/// and `corridor-pdr --wait-s 2` attached to it.
fn fake_daemon_and_pdr(
    name: &str,
) -> (
    iceoryx2::node::Node<Ipc>,
    NavService,
    NavEvent,
    NavPublisher,
    std::process::Child,
) {
    let domain = Domain::new(name).unwrap();
    let node = domain
        .node(&format!("{name}-fake-daemon"), SignalHandlingMode::Disabled)
        .unwrap();
    let service = domain
        .open::<NavSample>(&node, Access::Owner(Delivery::Live))
        .unwrap();
    let event = domain
        .open_event(&node, corridor_shared::services::NAV_SERVICE, true)
        .unwrap();
    let publisher = service.publisher_builder().create().unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_corridor-pdr"))
        .args(["--domain", name, "--wait-s", "2"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while service.dynamic_config().number_of_subscribers() == 0 {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "pdr never attached"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    (node, service, event, publisher, child)
}

/// The stance-th stride as the daemon would publish it, 1 m apart.
fn nav(stance: u64) -> NavSample {
    NavSample {
        seq: stance - 1,
        stance,
        p_m: [stance as f64, 0.0, 0.0],
        imu_seq: stance * 100,
        t_s: stance as f64,
        ..NavSample::default()
    }
}

/// Waits for `child` (a corridor-pdr) to exit, killing it and failing after 30 s; how long it
/// took.
fn wait_for_exit(child: &mut std::process::Child, after: &str) -> Duration {
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(30) {
            let _ = child.kill();
            panic!("corridor-pdr still runs 30 s {after}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    start.elapsed()
}

#[test]
fn pdr_stops_and_says_so_when_the_daemon_stops_within_a_stream() {
    // It waited for ever, saying nothing, after a daemon's clean stop (a review). Now it waits
    // --wait-s for the daemon to come back, then fails.
    let (node, service, event, publisher, mut child) =
        fake_daemon_and_pdr("eco_cli_pdr_daemon_stops");
    for stance in 1..=2 {
        publisher.send_copy(nav(stance)).unwrap();
    }
    std::thread::sleep(Duration::from_millis(500));
    // A daemon back within --wait-s is followed.
    drop(publisher);
    std::thread::sleep(Duration::from_millis(700));
    let publisher = service.publisher_builder().create().unwrap();
    publisher.send_copy(nav(3)).unwrap();
    std::thread::sleep(Duration::from_millis(500));
    drop((publisher, event, service, node));
    let waited = wait_for_exit(&mut child, "after the daemon stopped");
    // Not before --wait-s: a daemon may come back within it.
    assert!(waited >= Duration::from_secs(2), "{waited:?}");
    let o = child.wait_with_output().unwrap();
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert_eq!(o.status.code(), Some(1), "{out}{err}");
    assert!(out.contains("daemon stopped: 3 strides received"), "{out}");
    assert!(
        err.contains("stopped within the stream and did not come back within --wait-s (2 s)"),
        "{err}"
    );
}

#[test]
fn pdr_stopped_by_sigterm_says_interrupted_and_what_it_got() {
    // It said "stopped: …", where the README says every tool stopped so says "interrupted".
    let (node, service, event, publisher, mut child) =
        fake_daemon_and_pdr("eco_cli_pdr_interrupted");
    for stance in 1..=2 {
        publisher.send_copy(nav(stance)).unwrap();
    }
    std::thread::sleep(Duration::from_millis(500));
    // SAFETY: plain kill(2) on our own child.
    unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGTERM) };
    wait_for_exit(&mut child, "after SIGTERM");
    drop((publisher, event, service, node));
    let o = child.wait_with_output().unwrap();
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    // It ends as SIGTERM would (it exited with 0: a review), having said what it got.
    assert_eq!(o.status.signal(), Some(libc::SIGTERM), "{out}{err}");
    assert!(out.contains("interrupted: 2 strides received"), "{out}");
    assert!(err.is_empty(), "{err}");
}

/// Whether process `pid` catches SIGINT (`SigCgt` of /proc/PID/status): its signal latch is in
/// place.
fn catches_sigint(pid: u32) -> bool {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("SigCgt:"))
        .and_then(|mask| u64::from_str_radix(mask.trim(), 16).ok())
        .is_some_and(|mask| mask & (1 << (libc::SIGINT - 1)) != 0)
}

#[test]
fn ctrl_c_while_a_tool_waits_for_a_daemon_ends_it_as_ctrl_c_quietly() {
    // It said "error: interrupted by a termination request (SIGINT/SIGTERM)" and exited with 1,
    // where once the daemon had answered it exited with 0 (a review): every tool now ends as
    // Ctrl-C does (a shell's $? 130), saying "interrupted".
    let imu = short_log("sigint", 10);
    let out = std::env::temp_dir().join(format!("corridor-sigint-{}", std::process::id()));
    for (exe, args) in stream_tools(&imu, &out) {
        let mut cmd = Command::new(exe);
        cmd.args(["--domain", "eco_cli_sigint_nobody", "--wait-s", "60"])
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        // As a terminal starts it: SIGINT at its default. Run from a script's background job
        // (`cmd &`), the test inherits SIGINT ignored, and the tools keep ignoring what their
        // starter ignored (signals.rs), so no latch ever came (the fresh-clone CI run, started
        // with `setsid ... &`).
        // SAFETY: signal(2) only, between fork and exec.
        unsafe {
            cmd.pre_exec(|| {
                libc::signal(libc::SIGINT, libc::SIG_DFL);
                Ok(())
            });
        }
        let mut child = cmd.spawn().unwrap();
        let start = Instant::now();
        while !catches_sigint(child.id()) {
            assert!(start.elapsed() < Duration::from_secs(30), "{exe}: no latch");
            std::thread::sleep(Duration::from_millis(20));
        }
        // SAFETY: plain kill(2) on our own child.
        unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) };
        wait_for_exit(&mut child, "after SIGINT");
        let o = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.signal(), Some(libc::SIGINT), "{exe}: {err}");
        assert_eq!(err.trim_end(), "interrupted", "{exe}");
    }
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_file(&imu);
}

#[test]
fn pdr_with_a_daemon_gone_before_any_stream_is_no_daemon_not_a_cut_stream() {
    // It said "daemon stopped: 0 strides received" and "stopped within the stream", exit 1,
    // where no stream had begun (a review): now exit 3, no daemon, as at its start.
    let (node, service, event, publisher, mut child) =
        fake_daemon_and_pdr("eco_cli_pdr_daemon_gone_idle");
    drop((publisher, event, service, node));
    wait_for_exit(&mut child, "after the daemon left");
    let o = child.wait_with_output().unwrap();
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert_eq!(o.status.code(), Some(3), "{out}{err}");
    assert!(err.contains("no corridor daemon answers"), "{err}");
    assert!(!out.contains("strides received"), "{out}");
}
