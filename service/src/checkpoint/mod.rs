//! Estimator checkpoints: the gyro bias, its full covariance and the attitude, saved so that a
//! restarted daemon can warm-start ([`Checkpoint::warm_start`]). The only module that uses
//! bincode.
//!
//! Format versions: 1 (first slice: diagonal covariance, no save time), 2 (full covariance
//! from `Estimator::bias_state`, validated as symmetric positive definite; wall-clock save time),
//! 3 (a checksum: in version 2 one flipped bit turned a bias axis's sign, or scaled it or its
//! variance by a power of two, and the file still decoded to a valid state that was warm-started
//! from).
//!
//! File layout: the 8-byte magic [`MAGIC`], the format version as a little-endian `u32`
//! ([`FORMAT_VERSION`]), then the bincode-2 (`standard` config, serde) encoding of
//! [`Checkpoint`], then the CRC-32 of everything before it as a little-endian `u32`. Trailing
//! bytes, a checksum that does not match, non-finite values or a bad quaternion count as
//! corruption.
//!
//! [`save`] is atomic: it writes `<file>.tmp-<pid>`, fsyncs it, renames it over the target and
//! fsyncs the directory, so a crash leaves either the old or the new checkpoint. [`load`] moves a
//! corrupt or incompatible file aside (`<file>.corrupt-<n>`, first free `n`) so the next start
//! does not trip over it again, and reports it as [`CheckpointError::Corrupt`] or
//! [`CheckpointError::Incompatible`] (see [`CheckpointError::is_cold_start`]).

use crate::core::WarmStart;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};

/// First bytes of every checkpoint file.
pub const MAGIC: [u8; 8] = *b"CORRCKPT";
/// Format version written by [`save`]; [`load`] accepts only this one.
pub const FORMAT_VERSION: u32 = 3;
/// Bytes of the checksum that ends a file (a CRC-32).
const CHECKSUM_BYTES: usize = 4;
/// Largest gyro bias (per axis, rad/s) and bias σ a checkpoint may hold: 1 rad/s (57 °/s) is far
/// beyond any gyro's bias, so a file beyond it holds garbage even when it decodes (a NaN-poisoned
/// or diverged state once saved 1.30 rad/s). The estimator's own bound
/// (`sensor.max_gyro_bias_rad_s`) is checked again at warm start.
pub const MAX_BIAS_RAD_S: f64 = 1.0;
/// Largest payload accepted by the decoder, bytes.
const MAX_PAYLOAD: usize = 1 << 16;
/// Longest checkpoint file: the header, the largest payload and the checksum, bytes.
const MAX_FILE_BYTES: usize = MAGIC.len() + 4 + MAX_PAYLOAD + CHECKSUM_BYTES;

/// What a checkpoint holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    /// Estimation mode name the state belongs to (`Mode::name`), e.g. `rotation_aware`.
    pub mode: String,
    /// Sensor time of the state, s.
    pub t_s: f64,
    /// Wall-clock time of the save, ms since the Unix epoch (to report a checkpoint's age).
    pub saved_unix_ms: u64,
    /// Gyro bias, rad/s, sensor axes.
    pub gyro_bias_rad_s: [f64; 3],
    /// Its covariance, (rad/s)², row-major.
    pub gyro_bias_cov: [[f64; 3]; 3],
    /// Attitude `nav_from_body` as (w, x, y, z), unit norm.
    pub nav_from_body_wxyz: [f64; 4],
}

/// A checkpoint that could not be saved or loaded.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// There is no checkpoint file (a normal cold start).
    #[error("{path}: no checkpoint")]
    NotFound {
        /// The file.
        path: PathBuf,
    },
    /// Reading or writing failed.
    #[error("{path}: cannot {operation} checkpoint: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What was attempted.
        operation: &'static str,
        /// The OS error.
        source: std::io::Error,
    },
    /// The file is not a valid checkpoint; it was moved to `moved_to`.
    #[error("{path}: corrupt checkpoint ({reason}){}", moved_note(moved_to))]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
        /// Where it was moved (`None`: left where it is, by [`read`] or when the rename failed).
        moved_to: Option<PathBuf>,
    },
    /// The file has another format version; it was moved to `moved_to`.
    #[error(
        "{path}: checkpoint format version {found}, this build reads {expected}{}",
        moved_note(moved_to)
    )]
    Incompatible {
        /// The file.
        path: PathBuf,
        /// Version in the file.
        found: u32,
        /// Version this build reads.
        expected: u32,
        /// Where it was moved (`None` if the rename failed too).
        moved_to: Option<PathBuf>,
    },
    /// The state to save is not valid (non-finite value, quaternion not unit).
    #[error("refusing to save checkpoint to {path}: {reason}")]
    Invalid {
        /// The target file.
        path: PathBuf,
        /// What is wrong.
        reason: InvalidState,
    },
}

impl CheckpointError {
    /// True when the daemon should warn and start cold: the file was missing, corrupt or of
    /// another version (IO errors other than "not found" are true too: a checkpoint is never
    /// required).
    pub fn is_cold_start(&self) -> bool {
        !matches!(self, CheckpointError::Invalid { .. })
    }
}

fn moved_note(p: &Option<PathBuf>) -> String {
    p.as_ref()
        .map_or_else(String::new, |p| format!("; moved to {}", p.display()))
}

/// Why a checkpoint's state is not one to warm-start from ([`Checkpoint::validate`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InvalidState {
    /// A time, bias, covariance or quaternion value is NaN or infinite.
    #[error("a value is not finite")]
    NotFinite,
    /// A bias component beyond [`MAX_BIAS_RAD_S`].
    #[error("gyro bias {bias_rad_s} rad/s is beyond the physical bound {MAX_BIAS_RAD_S} rad/s")]
    BiasBeyondBound {
        /// The component, rad/s.
        bias_rad_s: f64,
    },
    /// A bias variance beyond [`MAX_BIAS_RAD_S`]².
    #[error("bias variance {cov:?} is beyond the physical bound {MAX_BIAS_RAD_S}² (rad/s)²")]
    VarianceBeyondBound {
        /// The covariance, (rad/s)².
        cov: [[f64; 3]; 3],
    },
    /// The covariance differs from its transpose by more than 1e-12 of its largest entry.
    #[error("bias covariance is not symmetric")]
    NotSymmetric,
    /// The covariance has no Cholesky factor.
    #[error("bias covariance is not positive definite")]
    NotPositiveDefinite,
    /// The quaternion's norm is off 1 by more than 1e-6.
    #[error("attitude quaternion has norm {norm}")]
    QuaternionNotUnit {
        /// Its norm.
        norm: f64,
    },
}

impl Checkpoint {
    /// Checks that every value is finite, the bias and its σ within [`MAX_BIAS_RAD_S`], the
    /// covariance symmetric positive definite (what `Estimator::set_warm_start` accepts) and the
    /// quaternion of unit norm (within 1e-6).
    pub fn validate(&self) -> Result<(), InvalidState> {
        let finite = self.t_s.is_finite()
            && self.gyro_bias_rad_s.iter().all(|v| v.is_finite())
            && self.gyro_bias_cov.iter().flatten().all(|v| v.is_finite())
            && self.nav_from_body_wxyz.iter().all(|v| v.is_finite());
        if !finite {
            return Err(InvalidState::NotFinite);
        }
        if let Some(&bias_rad_s) = self
            .gyro_bias_rad_s
            .iter()
            .find(|b| b.abs() > MAX_BIAS_RAD_S)
        {
            return Err(InvalidState::BiasBeyondBound { bias_rad_s });
        }
        if (0..3).any(|i| self.gyro_bias_cov[i][i] > MAX_BIAS_RAD_S * MAX_BIAS_RAD_S) {
            return Err(InvalidState::VarianceBeyondBound {
                cov: self.gyro_bias_cov,
            });
        }
        let p = nalgebra::Matrix3::from_fn(|i, j| self.gyro_bias_cov[i][j]);
        let scale = p.abs().max().max(1e-300);
        if (p - p.transpose()).abs().max() > 1e-12 * scale {
            return Err(InvalidState::NotSymmetric);
        }
        if p.cholesky().is_none() {
            return Err(InvalidState::NotPositiveDefinite);
        }
        let norm = self
            .nav_from_body_wxyz
            .iter()
            .map(|v| v * v)
            .sum::<f64>()
            .sqrt();
        if (norm - 1.0).abs() > 1e-6 {
            return Err(InvalidState::QuaternionNotUnit { norm });
        }
        Ok(())
    }
}

impl Checkpoint {
    /// The estimator's warm-start state (bias and covariance, sensor axes).
    pub fn warm_start(&self) -> WarmStart {
        WarmStart {
            gyro_bias_rad_s: self.gyro_bias_rad_s,
            gyro_bias_cov: self.gyro_bias_cov,
        }
    }

    /// Age of the checkpoint against the wall clock (`None` if the clock is behind it).
    pub fn age(&self) -> Option<std::time::Duration> {
        let now = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .ok()?
            .as_millis();
        let now = u64::try_from(now).ok()?;
        now.checked_sub(self.saved_unix_ms)
            .map(std::time::Duration::from_millis)
    }
}

/// Now, ms since the Unix epoch (0 if the clock is before 1970).
pub fn unix_now_ms() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| u64::try_from(d.as_millis()).unwrap_or(u64::MAX))
}

fn config() -> impl bincode::config::Config {
    bincode::config::standard().with_limit::<MAX_PAYLOAD>()
}

/// Encodes a checkpoint into the file layout (magic, version, payload, checksum).
pub fn encode(cp: &Checkpoint) -> Vec<u8> {
    let mut out = Vec::with_capacity(128);
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    let payload = bincode::serde::encode_to_vec(cp, config()).expect("a checkpoint always encodes");
    out.extend_from_slice(&payload);
    out.extend_from_slice(&crc32(&out).to_le_bytes());
    out
}

/// The CRC-32 of `bytes` (IEEE 802.3, as zlib's `crc32`); bitwise: a checkpoint is 170 bytes.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = (crc >> 1) ^ (0xEDB8_8320 & (crc & 1).wrapping_neg());
        }
    }
    !crc
}

/// Why bytes are not a checkpoint.
#[derive(Debug, Clone, PartialEq)]
pub enum DecodeError {
    /// Not a checkpoint or damaged, in words.
    Corrupt(String),
    /// A well-formed checkpoint whose state is not valid.
    Invalid(InvalidState),
    /// Another format version.
    Version(u32),
}

/// Decodes the file layout.
pub fn decode(bytes: &[u8]) -> Result<Checkpoint, DecodeError> {
    let header = MAGIC.len() + 4;
    if bytes.len() > MAX_FILE_BYTES {
        return Err(DecodeError::Corrupt(format!(
            "longer than any checkpoint ({MAX_FILE_BYTES} bytes)"
        )));
    }
    if bytes.len() < header {
        return Err(DecodeError::Corrupt(format!(
            "{} bytes, shorter than the {header}-byte header",
            bytes.len()
        )));
    }
    if bytes[..MAGIC.len()] != MAGIC {
        return Err(DecodeError::Corrupt("bad magic".into()));
    }
    let version = u32::from_le_bytes(bytes[MAGIC.len()..header].try_into().expect("4 bytes"));
    if version != FORMAT_VERSION {
        return Err(DecodeError::Version(version));
    }
    let payload = &bytes[header..];
    let (cp, used): (Checkpoint, usize) = bincode::serde::decode_from_slice(payload, config())
        .map_err(|e| DecodeError::Corrupt(payload_problem(&e, payload.len())))?;
    let checksum = &payload[used..];
    if checksum.len() < CHECKSUM_BYTES {
        return Err(DecodeError::Corrupt(format!(
            "its {}-byte payload ends before the checkpoint does (truncated: {} of the \
             {CHECKSUM_BYTES} checksum bytes)",
            payload.len(),
            checksum.len()
        )));
    }
    if checksum.len() > CHECKSUM_BYTES {
        return Err(DecodeError::Corrupt(format!(
            "{} trailing bytes after the checksum",
            checksum.len() - CHECKSUM_BYTES
        )));
    }
    let stored = u32::from_le_bytes(checksum.try_into().expect("4 bytes"));
    let computed = crc32(&bytes[..bytes.len() - CHECKSUM_BYTES]);
    if stored != computed {
        return Err(DecodeError::Corrupt(format!(
            "checksum {stored:08x}, its content's is {computed:08x}: bytes changed on disk"
        )));
    }
    cp.validate().map_err(DecodeError::Invalid)?;
    Ok(cp)
}

/// What is wrong with a payload bincode cannot decode, in words: its errors print as their
/// debug form (`UnexpectedEnd { additional: 2 }`), which told a user nothing (a review).
fn payload_problem(e: &bincode::error::DecodeError, len: usize) -> String {
    use bincode::error::DecodeError as E;
    match e {
        E::UnexpectedEnd { .. } => format!(
            "its {len}-byte payload ends before the checkpoint does (truncated, or a length in it \
             corrupt)"
        ),
        E::Utf8 { .. } => "a text field that is not UTF-8".to_owned(),
        E::UnexpectedVariant { found, .. } => format!("an unknown variant number {found}"),
        E::LimitExceeded => "a length beyond the format's limit".to_owned(),
        _ => "its payload is not a checkpoint's".to_owned(),
    }
}

/// The file a save writes before renaming it onto `path`.
fn tmp_path(path: &Path) -> PathBuf {
    let mut tmp_name = path.as_os_str().to_owned();
    tmp_name.push(format!(".tmp-{}", std::process::id()));
    PathBuf::from(tmp_name)
}

/// Whether [`save`] can write at `path`: creates a file beside it, and removes it. The daemon
/// asks at start, so that a directory that is not there or not writable is said then, not
/// after its first stream (a review: `corridor serve --config configs/service.toml` said
/// nothing of `/var/lib/corridor` until a stream had ended); for those the error is the one a
/// save gives. A `path` that is a directory is refused too. The probe's file has a name of its
/// own and is created only if it is not there, so that a save's file (another daemon of the
/// same pid, in another container sharing the volume) is never truncated or removed (a
/// review); one left by a daemon that died probing is no failure, and is left alone.
pub fn probe(path: &Path) -> Result<(), CheckpointError> {
    let io = |source| CheckpointError::Io {
        path: path.to_owned(),
        operation: "create",
        source,
    };
    if path.is_dir() {
        return Err(io(std::io::Error::other("it is a directory")));
    }
    refuse_non_file(path)?;
    let mut name = path.as_os_str().to_owned();
    name.push(format!(".probe-{}", std::process::id()));
    let probe = PathBuf::from(name);
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(()),
        Err(e) => Err(io(e)),
    }
}

/// A save renames its file onto `path`: refused when something other than a file (or a link)
/// is there, a device or a FIFO, which holds no checkpoint and is not the daemon's to replace
/// (`checkpoint_path = "/dev/zero"`: not moved aside at start, but the first save renamed its
/// file over `/dev/zero`, a review). The same error from [`probe`] and [`save`], so that the
/// daemon says it once.
fn refuse_non_file(path: &Path) -> Result<(), CheckpointError> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if !(m.is_file() || m.is_symlink() || m.is_dir()) => Err(CheckpointError::Io {
            path: path.to_owned(),
            operation: "write",
            source: std::io::Error::other(
                "it is not a file (a device, a FIFO or a socket): a save would replace it",
            ),
        }),
        _ => Ok(()),
    }
}

/// Saves atomically (temp file, fsync, rename, fsync of the directory).
pub fn save(path: &Path, cp: &Checkpoint) -> Result<(), CheckpointError> {
    cp.validate().map_err(|reason| CheckpointError::Invalid {
        path: path.to_owned(),
        reason,
    })?;
    let io = |operation, source| CheckpointError::Io {
        path: path.to_owned(),
        operation,
        source,
    };
    refuse_non_file(path)?;
    let tmp = tmp_path(path);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp).map_err(|e| io("create", e))?;
        f.write_all(&encode(cp)).map_err(|e| io("write", e))?;
        f.sync_all().map_err(|e| io("fsync", e))?;
        drop(f);
        std::fs::rename(&tmp, path).map_err(|e| io("rename", e))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
        return result;
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    // Makes the rename durable; not every filesystem allows opening a directory.
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// Loads a checkpoint. A corrupt or incompatible file is moved aside to `<path>.corrupt-<n>`
/// (the daemon owns its checkpoint file and would otherwise fail on it at every start).
pub fn load(path: &Path) -> Result<Checkpoint, CheckpointError> {
    load_with(path, true)
}

/// Reads a checkpoint the caller does not own (`corridor run --checkpoint`): a corrupt or
/// incompatible file is an error and is left where it is (it used to be renamed: the user's
/// input file moved to `.corrupt-1`).
pub fn read(path: &Path) -> Result<Checkpoint, CheckpointError> {
    load_with(path, false)
}

fn load_with(path: &Path, move_bad: bool) -> Result<Checkpoint, CheckpointError> {
    let aside = |path: &Path| if move_bad { move_aside(path) } else { None };
    let bytes = match read_head(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(CheckpointError::NotFound {
                path: path.to_owned(),
            });
        }
        Err(source) => {
            return Err(CheckpointError::Io {
                path: path.to_owned(),
                operation: "read",
                source,
            });
        }
    };
    match decode(&bytes) {
        Ok(cp) => Ok(cp),
        Err(DecodeError::Corrupt(reason)) => Err(CheckpointError::Corrupt {
            path: path.to_owned(),
            reason,
            moved_to: aside(path),
        }),
        Err(DecodeError::Invalid(invalid)) => Err(CheckpointError::Corrupt {
            path: path.to_owned(),
            reason: invalid.to_string(),
            moved_to: aside(path),
        }),
        Err(DecodeError::Version(found)) => Err(CheckpointError::Incompatible {
            path: path.to_owned(),
            found,
            expected: FORMAT_VERSION,
            moved_to: aside(path),
        }),
    }
}

/// The file at `path`, up to one byte more than the longest checkpoint ([`MAX_FILE_BYTES`]):
/// a path to something else (`/dev/zero`, a large file) was read whole into memory, and
/// `/dev/zero` aborted the run with "memory allocation failed". A FIFO or a socket is not
/// opened: opening a FIFO waits for a writer, and the estimator thread of a daemon whose
/// `checkpoint_path` was one waited there at start, taking no sample (`corridor run
/// --checkpoint FIFO` too: a review).
fn read_head(path: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read as _;
    use std::os::unix::fs::FileTypeExt as _;
    let kind = std::fs::metadata(path)?.file_type();
    if kind.is_fifo() || kind.is_socket() {
        return Err(std::io::Error::other(
            "it is a FIFO or a socket, not a file (not opened: a FIFO waits for a writer)",
        ));
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(MAX_FILE_BYTES as u64 + 1)
        .read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// Renames `path` to the first free `<path>.corrupt-<n>` (n = 1, 2, …); not a path to anything
/// but a file (or a link): a device or a FIFO holds no checkpoint to keep, and is not the
/// daemon's to move (`checkpoint_path = "/dev/zero"` would have renamed `/dev/zero`).
fn move_aside(path: &Path) -> Option<PathBuf> {
    let kind = std::fs::symlink_metadata(path).ok()?.file_type();
    if !(kind.is_file() || kind.is_symlink()) {
        return None;
    }
    (1..10_000).find_map(|n| {
        let mut name = path.as_os_str().to_owned();
        name.push(format!(".corrupt-{n}"));
        let target = PathBuf::from(name);
        if target.exists() {
            return None;
        }
        std::fs::rename(path, &target).ok().map(|()| target)
    })
}

#[cfg(test)]
mod tests;
