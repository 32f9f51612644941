//! Shared-memory access of a secured domain against a second user (issue 10, finding 5: any
//! local user could lock the daemon and every client out by writing 16 bytes to a
//! world-writable segment with a predictable name).
//!
//! A `corridor serve --runtime-dir` process (domain `stream_shm`), and the user `nobody`
//! (`setpriv --reuid=65534`) trying to read it, to inject into it and to lock it out. Needs root
//! (to switch users); without it the test says so and passes without checking anything.
//! Before the fix the segments lived under a predictable prefix and `global_mgmt` was 0666:
//! `nobody` could open it for writing, and a restarted daemon failed with
//! `UnableToGenerateUniqueNodeId` after 16 random bytes were written to it.

use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

const DOMAIN: &str = "stream_shm";
const WAIT: Duration = Duration::from_secs(60);
const NOBODY: &str = "65534";
/// The hash iceoryx2 0.10 puts in every `global_mgmt` segment's name after the prefix.
const GLOBAL_MGMT_HASH: &str = "9204dd183d1c4d8e1ff592a30766ffa6765aa8b5";

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Why this test cannot run here, if it cannot.
fn cannot_run() -> Option<String> {
    // SAFETY: geteuid cannot fail.
    if unsafe { libc::geteuid() } != 0 {
        return Some("not root: cannot run a process as a second user".into());
    }
    if Command::new("setpriv").arg("--version").output().is_err() {
        return Some("setpriv (util-linux) is not installed".into());
    }
    None
}

/// A short temporary directory (iceoryx2's socket paths under it must stay below 107 bytes),
/// removed when dropped.
struct ShortDir(PathBuf);

impl Drop for ShortDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

struct Setup {
    _dir: ShortDir,
    /// The binary, copied where `nobody` may run it.
    bin: PathBuf,
    runtime: PathBuf,
}

impl Setup {
    fn new() -> Self {
        let dir = ShortDir(PathBuf::from(format!("/tmp/cs{}", std::process::id())));
        let _ = std::fs::remove_dir_all(&dir.0);
        std::fs::create_dir(&dir.0).unwrap();
        let bin = dir.0.join("corridor");
        std::fs::copy(env!("CARGO_BIN_EXE_corridor"), &bin).unwrap();
        let runtime = dir.0.join("run");
        Self {
            _dir: dir,
            bin,
            runtime,
        }
    }

    fn serve(&self) -> Daemon {
        let child = Command::new(&self.bin)
            .args(["serve", "--domain", DOMAIN, "--runtime-dir"])
            .arg(&self.runtime)
            .arg("--config")
            .arg(root().join("configs/gdins.toml"))
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let d = Daemon(child);
        let start = Instant::now();
        while !self.status(None).status.success() {
            assert!(start.elapsed() < WAIT, "the daemon did not come up");
            std::thread::sleep(Duration::from_millis(100));
        }
        d
    }

    /// `corridor status` with the runtime directory, as root or as `user`.
    fn status(&self, user: Option<&str>) -> Output {
        let mut c = as_user(user, &self.bin);
        c.args(["status", "--domain", DOMAIN, "--timeout-s", "2"])
            .env("CORRIDOR_RUNTIME_DIR", &self.runtime);
        c.output().unwrap()
    }

    fn token(&self) -> String {
        std::fs::read_to_string(self.runtime.join(DOMAIN).join("prefix"))
            .unwrap()
            .trim()
            .to_owned()
    }
}

/// `program` run as root, or as `uid` (and its group) with no supplementary groups.
fn as_user(uid: Option<&str>, program: &Path) -> Command {
    match uid {
        None => Command::new(program),
        Some(uid) => {
            let mut c = Command::new("setpriv");
            c.arg(format!("--reuid={uid}"))
                .arg(format!("--regid={uid}"))
                .arg("--clear-groups")
                .arg(program);
            c
        }
    }
}

struct Daemon(Child);

impl Daemon {
    fn stop(mut self, signal: i32) {
        let pid = i32::try_from(self.0.id()).unwrap();
        // SAFETY: plain kill(2) on our own child.
        unsafe { libc::kill(pid, signal) };
        let start = Instant::now();
        while self.0.try_wait().unwrap().is_none() {
            assert!(start.elapsed() < WAIT, "the daemon did not stop");
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

impl Drop for Daemon {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// The files in /dev/shm of the secured prefix with `token`, with their owner.
fn shm_files(token: &str) -> Vec<(PathBuf, u32)> {
    std::fs::read_dir("/dev/shm")
        .unwrap()
        .flatten()
        .filter(|e| {
            e.file_name()
                .to_string_lossy()
                .starts_with(&format!("cr_{token}_"))
        })
        .filter_map(|e| Some((e.path(), e.metadata().ok()?.uid())))
        .collect()
}

/// A shell script run as `nobody`; its output.
fn nobody_sh(script: &str, args: &[&Path]) -> Output {
    let mut c = as_user(Some(NOBODY), Path::new("/bin/sh"));
    c.arg("-c").arg(script).arg("sh").args(args);
    c.output().unwrap()
}

#[test]
fn another_user_can_neither_read_nor_inject_nor_lock_out() {
    if let Some(why) = cannot_run() {
        eprintln!("SKIPPED another_user_can_neither_read_nor_inject_nor_lock_out: {why}");
        return;
    }
    // What the open domain gives (and the secured one fixes): iceoryx2 makes `global_mgmt`
    // world-writable under a predictable name.
    let open = corridor_shared::services::Domain::unsecured("stream_shm_open").unwrap();
    let node = open
        .node("probe", iceoryx2::prelude::SignalHandlingMode::Disabled)
        .unwrap();
    let mgmt_open = PathBuf::from(format!(
        "/dev/shm/corridor_stream_shm_open_{GLOBAL_MGMT_HASH}_node.0_10_0.global_mgmt"
    ));
    assert_eq!(std::fs::metadata(&mgmt_open).unwrap().mode() & 0o777, 0o666);
    let o = nobody_sh(r#"(exec 3<>"$1")"#, &[&mgmt_open]);
    assert!(
        o.status.success(),
        "nobody could not open the open domain's global_mgmt"
    );
    drop(node);
    let _ = std::fs::remove_file(&mgmt_open);

    let s = Setup::new();
    let daemon = s.serve();
    let token = s.token();
    let files = shm_files(&token);
    assert!(files.len() > 3, "{files:?}");
    assert!(files.iter().all(|(_, uid)| *uid == 0));
    let owned: Vec<&Path> = files.iter().map(|(p, _)| p.as_path()).collect();

    // Read or open for writing any of the daemon's segments: refused, each one.
    let o = nobody_sh(
        r#"n=0; for f in "$@"; do
             if (exec 3<"$f") 2>/dev/null; then echo "read $f"; n=$((n+1)); fi
             if (exec 3<>"$f") 2>/dev/null; then echo "write $f"; n=$((n+1)); fi
           done; exit $n"#,
        &owned,
    );
    assert!(
        o.status.success(),
        "nobody opened: {}",
        String::from_utf8_lossy(&o.stdout)
    );
    // The runtime directory and the prefix: unreadable.
    let o = nobody_sh(r#"ls "$1" || cat "$1/stream_shm/prefix""#, &[&s.runtime]);
    assert!(!o.status.success());
    // Joining as a client: refused, with the reason.
    let o = s.status(Some(NOBODY));
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("permission denied"), "{err}");
    // Planting the segment names it could guess (the open domain's), then serving itself.
    let planted = format!("/dev/shm/corridor_{DOMAIN}_{GLOBAL_MGMT_HASH}_node.0_10_0.global_mgmt");
    let o = nobody_sh(r#"head -c 16 /dev/urandom > "$1""#, &[Path::new(&planted)]);
    assert!(o.status.success());
    let o = as_user(Some(NOBODY), &s.bin)
        .args(["serve", "--domain", DOMAIN, "--runtime-dir"])
        .arg(&s.runtime)
        .output()
        .unwrap();
    assert!(!o.status.success());

    // The daemon still serves, and a restart still starts with the same prefix.
    assert!(s.status(None).status.success());
    daemon.stop(libc::SIGTERM);
    let daemon = s.serve();
    assert_eq!(s.token(), token);
    assert!(s.status(None).status.success());

    // Stale files of a killed daemon are removed by the next start.
    let before_kill: Vec<PathBuf> = shm_files(&token)
        .into_iter()
        .map(|(p, _)| p)
        .filter(|p| !p.to_string_lossy().ends_with(".global_mgmt"))
        .collect();
    daemon.stop(libc::SIGKILL);
    assert!(before_kill.iter().all(|p| p.exists()));
    let daemon = s.serve();
    let stale: Vec<&PathBuf> = before_kill.iter().filter(|p| p.exists()).collect();
    assert!(stale.is_empty(), "left after restart: {stale:?}");

    // A user who learnt the prefix plants its segment before a start: a new prefix is taken.
    daemon.stop(libc::SIGTERM);
    let mgmt = shm_files(&token)
        .into_iter()
        .map(|(p, _)| p)
        .find(|p| p.to_string_lossy().ends_with(".global_mgmt"))
        .expect("the domain's global_mgmt");
    std::fs::remove_file(&mgmt).unwrap();
    let o = nobody_sh(r#"head -c 16 /dev/urandom > "$1""#, &[&mgmt]);
    assert!(o.status.success());
    let daemon = s.serve();
    let new_token = s.token();
    assert_ne!(new_token, token);
    assert!(s.status(None).status.success());
    assert!(!s.runtime.join(&token).exists());
    daemon.stop(libc::SIGTERM);

    // A non-root daemon user could not remove nobody's files from the sticky /dev/shm; root
    // cleans up after the test.
    let _ = std::fs::remove_file(&planted);
    for (path, _) in shm_files(&token).into_iter().chain(shm_files(&new_token)) {
        let _ = std::fs::remove_file(path);
    }
}
