//! The checkpoint file: its encoding, every corruption refused, the atomic save and the move aside.

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
    let d = std::env::temp_dir().join(format!("corridor-checkpoint-{tag}-{}", std::process::id()));
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

/// A FIFO at `bias.ckpt` in a fresh directory named after `name`: the directory and its path.
fn fifo(name: &str) -> (PathBuf, PathBuf) {
    let d = tmp_dir(name);
    let p = d.join("bias.ckpt");
    let made = std::process::Command::new("mkfifo")
        .arg(&p)
        .status()
        .unwrap();
    assert!(made.success());
    (d, p)
}

#[test]
fn a_path_to_something_else_than_a_file_is_never_moved_aside() {
    // A FIFO: a cold start, and left where it is (as a device such as /dev/zero is, which the
    // daemon's move aside would have renamed). Not opened: with no writer, the open waited for
    // ever, and the daemon never started (a review; a writer was needed here).
    let (d, p) = fifo("fifo");
    let (tx, rx) = std::sync::mpsc::channel();
    let q = p.clone();
    std::thread::spawn(move || tx.send(load(&q)).unwrap());
    let Ok(loaded) = rx.recv_timeout(std::time::Duration::from_secs(10)) else {
        // Release the blocked reader before failing.
        let _ = std::fs::OpenOptions::new().write(true).open(&p);
        panic!("loading a FIFO waits for a writer");
    };
    let e = loaded.unwrap_err();
    assert!(
        matches!(&e, CheckpointError::Io { .. }) && e.is_cold_start(),
        "{e}"
    );
    assert!(e.to_string().contains("FIFO"), "{e}");
    assert!(p.exists() && !d.join("bias.ckpt.corrupt-1").exists(), "{e}");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn a_save_never_replaces_something_else_than_a_file() {
    // A FIFO (as a device such as /dev/zero) at the path is not moved aside at start; the
    // first save renamed its file over it (a review). Refused, said at start by the probe.
    use std::os::unix::fs::FileTypeExt as _;
    let (d, p) = fifo("fifo-save");
    let probed = probe(&p).unwrap_err().to_string();
    let saved = save(&p, &sample()).unwrap_err().to_string();
    assert!(saved.contains("not a file"), "{saved}");
    assert_eq!(probed, saved, "said once by the daemon");
    let kind = std::fs::symlink_metadata(&p).unwrap().file_type();
    assert!(kind.is_fifo(), "the FIFO was replaced");
    assert_eq!(
        std::fs::read_dir(&d).unwrap().count(),
        1,
        "nothing left beside it"
    );
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
