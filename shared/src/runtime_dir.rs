//! The runtime directory of a secured domain: where its iceoryx2 files live and how its name
//! prefix is kept from other users (issue 10, finding 5).
//!
//! What iceoryx2 0.10 does, measured (`service/tests/shm_access.rs` checks it): every file it
//! creates is 0600 (0400 for the static ones) for the user who created it, whatever the umask,
//! except the per-prefix `/dev/shm/<prefix>…_node.0_10_0.global_mgmt` segment, which it makes
//! 0666; its directories under `global.root_path` are 0750; shared memory is always in
//! `/dev/shm`, named `<prefix><hash>…`, and `global.root_path` moves only the other files (node
//! and service records, event sockets). So only processes of the daemon's user can connect; no
//! permission setting of iceoryx2 0.10 gives a group access. A world-writable `global_mgmt`
//! with a predictable name let any local user stop every node of the domain from starting.
//!
//! A secured domain therefore lives in a runtime directory owned by the daemon's user that
//! others cannot enter (mode 0700 or 0750):
//! - `<runtime_dir>/<domain>/prefix` holds a random token: the iceoryx2 prefix is
//!   `cr_<token>_`, which other users cannot read, so they cannot name the domain's segments
//!   before they exist; `<runtime_dir>/<domain>/daemon.lock` is locked by the running daemon;
//! - `<runtime_dir>/<token>/` is the iceoryx2 root path (named by the token, not the domain:
//!   iceoryx2's event sockets live there, and a socket path is limited to 107 bytes).
//!
//! At start the daemon takes the lock, and makes a new token (removing its own files of the
//! old one) when there is none, when a `global_mgmt` segment of the token belongs to another
//! user, or when no node can be created with it (a corrupted segment); its first node also
//! cleans up the dead nodes of earlier runs (iceoryx2's cleanup on creation). Every node made
//! in a secured domain sets its `global_mgmt` to 0600 right after creating it.
//!
//! Not protected: the instants between iceoryx2 making a new `global_mgmt` 0666 and corridor
//! setting it to 0600 (a user watching `/dev/shm` could open it then and corrupt it later; the
//! next daemon start then changes the token); the names in `/dev/shm` are visible to everyone.

use std::fs::{File, OpenOptions};
use std::io::Write;
use std::os::unix::fs::{DirBuilderExt, MetadataExt, OpenOptionsExt, PermissionsExt};
use std::path::{Path, PathBuf};

/// The file holding the domain's prefix token.
pub const PREFIX_FILE: &str = "prefix";
/// The file the running daemon keeps locked.
pub const LOCK_FILE: &str = "daemon.lock";
/// Longest path of a unix socket (`sun_path` less its NUL), bytes.
const MAX_SOCKET_PATH: usize = 107;
/// What iceoryx2 adds to the root and the prefix in an event socket's path: `/`, a node or
/// port id of up to 39 digits, `.event`.
const SOCKET_NAME_EXTRA: usize = 1 + 39 + 6;
/// Where iceoryx2 0.10 puts its shared memory (POSIX `shm_open`).
pub const SHM_DIR: &str = "/dev/shm";
/// Suffix of the per-prefix node-counter segment that iceoryx2 makes world-writable.
const GLOBAL_MGMT_SUFFIX: &str = ".global_mgmt";
/// Random bytes of a token (hex-encoded in the prefix).
const TOKEN_BYTES: usize = 8;

/// A problem with a runtime directory; the message names the path and what is wrong.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {problem}")]
pub struct RuntimeDirError {
    /// The path.
    pub path: PathBuf,
    /// What is wrong, with the values found.
    pub problem: String,
}

fn err(path: &Path, problem: impl Into<String>) -> RuntimeDirError {
    RuntimeDirError {
        path: path.to_owned(),
        problem: problem.into(),
    }
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> RuntimeDirError + '_ {
    move |e| err(path, e.to_string())
}

/// The effective uid of this process.
pub fn euid() -> u32 {
    // SAFETY: geteuid cannot fail and touches no memory.
    unsafe { libc::geteuid() }
}

/// Checks that `dir` is a directory owned by this process's user that no one else may write
/// to, creating it (mode `mode`) when it is missing.
fn own_dir(dir: &Path, mode: u32) -> Result<(), RuntimeDirError> {
    if !dir.exists() {
        std::fs::DirBuilder::new()
            .mode(mode)
            .create(dir)
            .map_err(io(dir))?;
    }
    let m = std::fs::symlink_metadata(dir).map_err(io(dir))?;
    if !m.is_dir() {
        return Err(err(dir, "is not a directory"));
    }
    if m.uid() != euid() {
        return Err(err(
            dir,
            format!(
                "is owned by uid {}, not by this process's uid {}",
                m.uid(),
                euid()
            ),
        ));
    }
    if m.mode() & 0o027 != 0 {
        return Err(err(
            dir,
            format!(
                "has mode {:04o}: its group may write to it or others may enter it (0700 or 0750 wanted)",
                m.mode() & 0o7777
            ),
        ));
    }
    Ok(())
}

/// The iceoryx2 root path of `token` under `runtime_dir`.
pub fn iox2_root(runtime_dir: &Path, token: &str) -> PathBuf {
    runtime_dir.join(token)
}

/// Refuses a runtime directory whose event-socket paths would exceed the unix limit.
pub fn check_socket_paths(runtime_dir: &Path, token: &str) -> Result<(), RuntimeDirError> {
    let root = iox2_root(runtime_dir, token);
    let longest = root.as_os_str().len() + prefix(token).len() + SOCKET_NAME_EXTRA;
    if longest > MAX_SOCKET_PATH {
        return Err(err(
            runtime_dir,
            format!(
                "too long: iceoryx2's socket paths under it reach {longest} bytes, above the limit of {MAX_SOCKET_PATH} \
                 (use a runtime directory of at most {} bytes)",
                runtime_dir.as_os_str().len() + MAX_SOCKET_PATH - longest
            ),
        ));
    }
    Ok(())
}

/// The directory of `domain` under `runtime_dir`.
pub fn domain_dir(runtime_dir: &Path, domain: &str) -> PathBuf {
    runtime_dir.join(domain)
}

/// The iceoryx2 prefix of a secured domain with `token`.
pub fn prefix(token: &str) -> String {
    format!("cr_{token}_")
}

/// Reads the token of `domain` (for a client, or a daemon restarting).
pub fn read_token(runtime_dir: &Path, domain: &str) -> Result<String, RuntimeDirError> {
    let path = domain_dir(runtime_dir, domain).join(PREFIX_FILE);
    let text = std::fs::read_to_string(&path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => err(
            &path,
            format!("no daemon has served domain {domain:?} here (`corridor serve` with daemon.runtime_dir)"),
        ),
        std::io::ErrorKind::PermissionDenied => err(
            &path,
            format!(
                "permission denied: only the daemon's user may use domain {domain:?} (this process runs as uid {})",
                euid()
            ),
        ),
        _ => err(&path, e.to_string()),
    })?;
    let token = text.trim();
    if token.len() != 2 * TOKEN_BYTES || !token.bytes().all(|b| b.is_ascii_hexdigit()) {
        return Err(err(&path, format!("holds {token:?}, not a token")));
    }
    Ok(token.to_owned())
}

/// A new random token.
fn new_token() -> Result<String, RuntimeDirError> {
    use std::io::Read;
    let src = Path::new("/dev/urandom");
    let mut b = [0u8; TOKEN_BYTES];
    File::open(src)
        .and_then(|mut f| f.read_exact(&mut b))
        .map_err(io(src))?;
    Ok(b.iter().map(|x| format!("{x:02x}")).collect())
}

/// The `/dev/shm` entries whose name starts with `prefix`.
fn shm_files(prefix: &str) -> Vec<(PathBuf, std::fs::Metadata)> {
    std::fs::read_dir(SHM_DIR)
        .into_iter()
        .flatten()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with(prefix))
        .filter_map(|e| Some((e.path(), std::fs::symlink_metadata(e.path()).ok()?)))
        .collect()
}

/// Sets this user's `global_mgmt` segments of `prefix` to 0600 (iceoryx2 makes them 0666).
pub fn restrict_global_mgmt(prefix: &str) -> Result<(), RuntimeDirError> {
    for (path, m) in shm_files(prefix) {
        let name = path.to_string_lossy();
        if name.ends_with(GLOBAL_MGMT_SUFFIX) && m.uid() == euid() && m.mode() & 0o077 != 0 {
            std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o600))
                .map_err(io(&path))?;
        }
    }
    Ok(())
}

/// Whether a `global_mgmt` segment of `prefix` belongs to another user (planted).
fn foreign_global_mgmt(prefix: &str) -> Option<PathBuf> {
    shm_files(prefix).into_iter().find_map(|(path, m)| {
        (path.to_string_lossy().ends_with(GLOBAL_MGMT_SUFFIX) && m.uid() != euid()).then_some(path)
    })
}

/// The daemon's hold on a secured domain: the lock, the token, the iceoryx2 root.
#[derive(Debug)]
pub struct DaemonHold {
    /// Locked while the daemon runs.
    _lock: File,
    /// The domain's directory.
    pub dir: PathBuf,
    /// The runtime directory.
    pub runtime_dir: PathBuf,
    /// The current token.
    pub token: String,
}

/// What [`hold`] found when it could not take the domain.
#[derive(Debug, thiserror::Error)]
pub enum HoldError {
    /// The directory is unusable.
    #[error(transparent)]
    Dir(#[from] RuntimeDirError),
    /// Another daemon holds the lock.
    #[error("{lock}: locked by another daemon")]
    Locked {
        /// The lock file.
        lock: PathBuf,
    },
}

/// Takes `domain` under `runtime_dir` for a daemon: checks or creates the directories, locks,
/// reads the token or makes one (also when a `global_mgmt` of the token belongs to another
/// user).
pub fn hold(runtime_dir: &Path, domain: &str) -> Result<DaemonHold, HoldError> {
    // Every token has the same length, so a directory too long for iceoryx2's socket paths is
    // refused before anything is made in it (it used to be refused after the domain directory,
    // its lock and a token were made, and those were left behind).
    check_socket_paths(runtime_dir, &"0".repeat(2 * TOKEN_BYTES))?;
    own_dir(runtime_dir, 0o700)?;
    let dir = domain_dir(runtime_dir, domain);
    own_dir(&dir, 0o700)?;
    let lock_path = dir.join(LOCK_FILE);
    let lock = OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .mode(0o600)
        .open(&lock_path)
        .map_err(io(&lock_path))?;
    if lock.try_lock().is_err() {
        return Err(HoldError::Locked { lock: lock_path });
    }
    let mut hold = DaemonHold {
        _lock: lock,
        dir,
        runtime_dir: runtime_dir.to_owned(),
        token: String::new(),
    };
    match read_token(runtime_dir, domain) {
        Ok(t) if foreign_global_mgmt(&prefix(&t)).is_none() => hold.token = t,
        Ok(t) => {
            tracing::warn!(
                "domain {domain:?}: a shared-memory segment of its prefix belongs to another user; new prefix"
            );
            hold.rotate(domain, Some(&t))?;
        }
        Err(_) => hold.rotate(domain, None)?,
    }
    own_dir(&hold.iox2_root(), 0o700)?;
    Ok(hold)
}

impl DaemonHold {
    /// The iceoryx2 root path of the current token.
    pub fn iox2_root(&self) -> PathBuf {
        iox2_root(&self.runtime_dir, &self.token)
    }

    /// A new token: removes this user's files of the old one (shared memory and the iceoryx2
    /// root; no daemon runs, we hold the lock) and writes the new one.
    pub fn rotate(&mut self, domain: &str, old: Option<&str>) -> Result<(), RuntimeDirError> {
        if let Some(old) = old {
            for (path, m) in shm_files(&prefix(old)) {
                if m.uid() == euid() {
                    let _ = std::fs::remove_file(&path);
                }
            }
            let root = iox2_root(&self.runtime_dir, old);
            if root.exists() {
                std::fs::remove_dir_all(&root).map_err(io(&root))?;
            }
        }
        tracing::info!("domain {domain:?}: new iceoryx2 prefix");
        let token = new_token()?;
        let path = self.dir.join(PREFIX_FILE);
        let tmp = self.dir.join(format!("{PREFIX_FILE}.new"));
        let mut f = OpenOptions::new()
            .create(true)
            .truncate(true)
            .write(true)
            .mode(0o600)
            .open(&tmp)
            .map_err(io(&tmp))?;
        writeln!(f, "{token}").map_err(io(&tmp))?;
        f.sync_all().map_err(io(&tmp))?;
        std::fs::rename(&tmp, &path).map_err(io(&path))?;
        self.token = token;
        own_dir(&self.iox2_root(), 0o700)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A short fresh directory under /tmp, removed when dropped.
    struct Tmp(PathBuf);
    impl Tmp {
        fn new(tag: &str) -> Self {
            let p = PathBuf::from(format!("/tmp/crd{}{tag}", std::process::id()));
            let _ = std::fs::remove_dir_all(&p);
            Tmp(p)
        }
    }
    impl Drop for Tmp {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    fn mode(p: &Path) -> u32 {
        std::fs::metadata(p).unwrap().mode() & 0o7777
    }

    #[test]
    fn a_hold_makes_private_directories_a_token_and_a_lock() {
        let t = Tmp::new("a");
        let h = hold(&t.0, "lab").unwrap();
        assert_eq!(h.token.len(), 2 * TOKEN_BYTES);
        assert!(h.token.bytes().all(|b| b.is_ascii_hexdigit()));
        for dir in [t.0.clone(), t.0.join("lab"), h.iox2_root()] {
            assert_eq!(mode(&dir), 0o700, "{}", dir.display());
        }
        assert_eq!(mode(&t.0.join("lab").join(PREFIX_FILE)), 0o600);
        assert_eq!(read_token(&t.0, "lab").unwrap(), h.token);
        // A second daemon is refused while the first holds the lock.
        assert!(matches!(hold(&t.0, "lab"), Err(HoldError::Locked { .. })));
        // A restart keeps the token.
        let token = h.token.clone();
        drop(h);
        assert_eq!(hold(&t.0, "lab").unwrap().token, token);
    }

    #[test]
    fn a_runtime_directory_too_long_for_the_sockets_is_refused_before_anything_is_made() {
        let t = Tmp::new("long");
        std::fs::create_dir(&t.0).unwrap();
        std::fs::set_permissions(&t.0, std::fs::Permissions::from_mode(0o700)).unwrap();
        let long = t.0.join("x".repeat(80));
        std::fs::create_dir(&long).unwrap();
        std::fs::set_permissions(&long, std::fs::Permissions::from_mode(0o700)).unwrap();
        let e = hold(&long, "lab").unwrap_err().to_string();
        assert!(e.contains("too long") && e.contains("at most"), "{e}");
        let left: Vec<_> = std::fs::read_dir(&long).unwrap().collect();
        assert!(left.is_empty(), "made in a refused directory: {left:?}");
    }

    #[test]
    fn unusable_runtime_directories_are_refused_naming_path_and_problem() {
        let t = Tmp::new("b");
        std::fs::create_dir(&t.0).unwrap();
        std::fs::set_permissions(&t.0, std::fs::Permissions::from_mode(0o755)).unwrap();
        let e = hold(&t.0, "lab").unwrap_err().to_string();
        assert!(
            e.contains(&t.0.display().to_string()) && e.contains("0755"),
            "{e}"
        );
        let long = t.0.join("x".repeat(60));
        assert!(
            check_socket_paths(&long, "0123456789abcdef")
                .unwrap_err()
                .to_string()
                .contains("too long")
        );
        assert!(check_socket_paths(Path::new("/run/corridor"), "0123456789abcdef").is_ok());
        let e = read_token(&t.0, "nowhere").unwrap_err().to_string();
        assert!(e.contains("no daemon has served domain \"nowhere\""), "{e}");
    }
}
