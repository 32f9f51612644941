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
/// `/dev/zero` aborted the run with "memory allocation failed".
fn read_head(path: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read as _;
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
mod tests {
    use super::*;

    fn sample() -> Checkpoint {
        let s = 0.5f64.sqrt();
        Checkpoint {
            mode: "rotation_aware".into(),
            t_s: 123.456,
            saved_unix_ms: 1_700_000_000_000,
            gyro_bias_rad_s: [1e-3, -2e-3, 5e-3],
            gyro_bias_cov: [[1e-8, 1e-10, 0.0], [1e-10, 2e-8, 0.0], [0.0, 0.0, 3e-8]],
            nav_from_body_wxyz: [s, 0.0, 0.0, s],
        }
    }

    fn tmp_dir(tag: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("corridor-checkpoint-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn the_probe_leaves_nothing_and_never_touches_a_saves_file() {
        let d = tmp_dir("probe");
        let p = d.join("bias.ckpt");
        probe(&p).unwrap();
        assert_eq!(
            std::fs::read_dir(&d).unwrap().count(),
            0,
            "nothing left behind"
        );
        // A save's file of the same pid being written (another container's daemon): kept.
        let saving = tmp_path(&p);
        std::fs::write(&saving, b"half a checkpoint").unwrap();
        probe(&p).unwrap();
        assert_eq!(std::fs::read(&saving).unwrap(), b"half a checkpoint");
        // A directory missing, or the path one: the save's "cannot create".
        let err = probe(&d.join("missing").join("bias.ckpt")).unwrap_err();
        assert!(
            err.to_string().contains("cannot create checkpoint"),
            "{err}"
        );
        let err = probe(&d).unwrap_err();
        assert!(err.to_string().contains("it is a directory"), "{err}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn round_trip_is_exact_and_leaves_no_temp_file() {
        let d = tmp_dir("roundtrip");
        let p = d.join("bias.ckpt");
        save(&p, &sample()).unwrap();
        assert_eq!(load(&p).unwrap(), sample());
        let mut cp2 = sample();
        cp2.t_s = 200.0;
        save(&p, &cp2).unwrap(); // overwrite
        assert_eq!(load(&p).unwrap(), cp2);
        let names: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("bias.ckpt")]);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn missing_file_is_not_found() {
        let d = tmp_dir("missing");
        let e = load(&d.join("nope.ckpt")).unwrap_err();
        assert!(matches!(e, CheckpointError::NotFound { .. }), "{e}");
        assert!(e.is_cold_start());
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn truncated_file_is_corrupt_and_moved_aside() {
        let d = tmp_dir("truncated");
        let p = d.join("bias.ckpt");
        let bytes = encode(&sample());
        for cut in [3, 12, bytes.len() - 1] {
            std::fs::write(&p, &bytes[..cut]).unwrap();
            let e = load(&p).unwrap_err();
            let CheckpointError::Corrupt { moved_to, .. } = &e else {
                panic!("cut at {cut}: {e}");
            };
            // Said in words, not as the decoder's debug form.
            let text = e.to_string();
            assert!(
                !text.contains('{') && !text.contains("Unexpected"),
                "{text}"
            );
            if cut > 12 {
                assert!(text.contains("payload ends before"), "{text}");
            }
            assert!(e.is_cold_start());
            assert!(!p.exists(), "the corrupt file must be moved away");
            assert!(moved_to.as_ref().unwrap().exists());
        }
        assert!(d.join("bias.ckpt.corrupt-1").exists());
        assert!(d.join("bias.ckpt.corrupt-3").exists());
        // Read as someone else's file (`corridor run --checkpoint`): an error, left in place.
        std::fs::write(&p, &bytes[..12]).unwrap();
        let e = read(&p).unwrap_err();
        assert!(
            matches!(&e, CheckpointError::Corrupt { moved_to: None, .. }),
            "{e}"
        );
        assert!(p.exists() && !e.to_string().contains("moved"), "{e}");
        assert!(!d.join("bias.ckpt.corrupt-4").exists());
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn wrong_version_is_incompatible() {
        let d = tmp_dir("version");
        let p = d.join("bias.ckpt");
        let mut bytes = encode(&sample());
        bytes[8..12].copy_from_slice(&7u32.to_le_bytes());
        std::fs::write(&p, &bytes).unwrap();
        let e = load(&p).unwrap_err();
        match &e {
            CheckpointError::Incompatible {
                found,
                expected,
                moved_to,
                ..
            } => {
                assert_eq!((*found, *expected), (7, FORMAT_VERSION));
                assert_eq!(
                    moved_to.as_deref(),
                    Some(d.join("bias.ckpt.corrupt-1").as_path())
                );
            }
            _ => panic!("{e}"),
        }
        assert!(e.to_string().contains("version 7"), "{e}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn garbage_is_corrupt() {
        assert!(matches!(
            decode(b"this is not a checkpoint at all"),
            Err(DecodeError::Corrupt(_))
        ));
        // Right header, garbage payload.
        let mut bytes = MAGIC.to_vec();
        bytes.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        bytes.extend_from_slice(&[0xff; 40]);
        assert!(matches!(decode(&bytes), Err(DecodeError::Corrupt(_))));
        // Trailing bytes.
        let mut bytes = encode(&sample());
        bytes.push(0);
        assert!(matches!(decode(&bytes), Err(DecodeError::Corrupt(r)) if r.contains("trailing")));
        // Valid encoding of an invalid state: a covariance that is not positive definite, or
        // not symmetric.
        let mut bad = sample();
        bad.gyro_bias_cov[2][2] = 0.0;
        assert_eq!(
            decode(&encode(&bad)),
            Err(DecodeError::Invalid(InvalidState::NotPositiveDefinite))
        );
        let mut bad = sample();
        bad.gyro_bias_cov[0][1] = 5e-9;
        assert_eq!(
            decode(&encode(&bad)),
            Err(DecodeError::Invalid(InvalidState::NotSymmetric))
        );
        let mut bad = sample();
        bad.nav_from_body_wxyz = [2.0, 0.0, 0.0, 0.0];
        assert_eq!(
            decode(&encode(&bad)),
            Err(DecodeError::Invalid(InvalidState::QuaternionNotUnit {
                norm: 2.0
            }))
        );
    }

    #[test]
    fn a_file_without_an_end_is_read_no_further_than_a_checkpoint_can_be() {
        // Before: read whole; `--checkpoint /dev/zero` aborted with "memory allocation failed".
        let e = read(Path::new("/dev/zero")).unwrap_err();
        assert!(
            matches!(&e, CheckpointError::Corrupt { moved_to: None, .. }),
            "{e}"
        );
        assert!(e.to_string().contains("longer than any checkpoint"), "{e}");
    }

    #[test]
    fn a_path_to_something_else_than_a_file_is_never_moved_aside() {
        // A FIFO that a writer fills with garbage: corrupt, and left where it is (as a device
        // such as /dev/zero is, which the daemon's move aside would have renamed).
        let d = tmp_dir("fifo");
        let p = d.join("bias.ckpt");
        let made = std::process::Command::new("mkfifo")
            .arg(&p)
            .status()
            .unwrap();
        assert!(made.success());
        let writer = {
            let p = p.clone();
            std::thread::spawn(move || std::fs::write(&p, b"this is not a checkpoint").unwrap())
        };
        let e = load(&p).unwrap_err();
        writer.join().unwrap();
        assert!(
            matches!(&e, CheckpointError::Corrupt { moved_to: None, .. }),
            "{e}"
        );
        assert!(p.exists() && !d.join("bias.ckpt.corrupt-1").exists(), "{e}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn every_flipped_bit_is_refused() {
        // Before (version 2, no checksum): 1 010 of the 1 296 single-bit flips of a checkpoint
        // decoded to a valid state, among them a bias axis with its sign turned (1e-3 to -1e-3
        // rad/s) or its variance scaled by 2^8 (1e-8 to 2.56e-6), and were warm-started from.
        assert_eq!(crc32(b"123456789"), 0xcbf4_3926);
        let bytes = encode(&sample());
        for i in 0..bytes.len() {
            for bit in 0..8 {
                let mut flipped = bytes.clone();
                flipped[i] ^= 1 << bit;
                assert!(
                    decode(&flipped).is_err(),
                    "byte {i} bit {bit}: {:?}",
                    decode(&flipped)
                );
            }
        }
        assert_eq!(decode(&bytes), Ok(sample()));
    }

    #[test]
    fn a_valid_file_with_an_absurd_bias_is_refused_like_a_corrupt_one() {
        // Before: a well-formed file holding 1000 rad/s was accepted as it was.
        let d = tmp_dir("absurd");
        let p = d.join("bias.ckpt");
        let mut bad = sample();
        bad.gyro_bias_rad_s[1] = 1000.0;
        std::fs::write(&p, encode(&bad)).unwrap();
        let e = load(&p).unwrap_err();
        assert!(matches!(e, CheckpointError::Corrupt { .. }), "{e}");
        assert!(e.is_cold_start());
        assert!(e.to_string().contains("1000"), "{e}");
        assert!(!p.exists() && d.join("bias.ckpt.corrupt-1").exists());
        // And it is never written.
        assert!(matches!(
            save(&p, &bad),
            Err(CheckpointError::Invalid { .. })
        ));
        assert!(!p.exists());
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn invalid_state_is_not_saved() {
        let d = tmp_dir("invalid");
        let mut bad = sample();
        bad.gyro_bias_rad_s[0] = f64::NAN;
        let e = save(&d.join("x.ckpt"), &bad).unwrap_err();
        assert!(matches!(e, CheckpointError::Invalid { .. }));
        assert!(!d.join("x.ckpt").exists());
        std::fs::remove_dir_all(&d).unwrap();
    }
}
