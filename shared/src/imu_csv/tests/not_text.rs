//! Files that are not CSV text: a compressed file is named with the tool that decompresses it,
//! a header that is not UTF-8 is not taken for a file whose lines end in CR alone, and no raw
//! byte of such a file reaches the message (a terminal would act on it).

use super::*;

/// The first bytes of a compressed copy of a log, by its suffix, with what the reader must name
/// it and the tool it must name. The gzip bytes hold a CR (in the time stamp), a NUL, an escape
/// sequence and a bell, as `gzip -c imu.csv` may write them (a review saw the header refused as
/// a CR-only file, the bytes printed raw).
fn compressed_heads() -> [(&'static str, &'static str, &'static str, Vec<u8>); 5] {
    let gzip = [
        &[0x1f, 0x8b, 0x08, 0x08, 0xd2, 0x0d, 0x5e, 0x66, 0x00, 0x03][..],
        b"imu.csv\0\x8d\x92\xc9\x8e\x1b[2J\x9b\xff\x07\n\xe3rest\n",
    ]
    .concat();
    [
        ("gz", "gzip-compressed", "gunzip -c", gzip),
        (
            "xz",
            "xz-compressed",
            "unxz -c",
            b"\xfd7zXZ\0\0\x04\xe6\xd6\xb4F\x02\0!\x01\r\n".to_vec(),
        ),
        (
            "zst",
            "zstd-compressed",
            "zstd -dc",
            b"(\xb5/\xfd$\x9b\r\x1b".to_vec(),
        ),
        (
            "zip",
            "a zip archive",
            "unzip -p",
            b"PK\x03\x04\x14\0\0\0\x08\0imu.csv\r".to_vec(),
        ),
        (
            "bz2",
            "bzip2-compressed",
            "bunzip2 -c",
            b"BZh91AY&SY\x9a\r\x1b\xc2".to_vec(),
        ),
    ]
}

#[test]
fn a_compressed_file_is_named_with_its_tool_and_no_raw_byte_is_printed() {
    for (ext, kind, tool, bytes) in compressed_heads() {
        let file = PathBuf::from(format!("data/imu.csv.{ext}"));
        let err = ImuCsvReader::new(bytes.as_slice(), &file, &lenient()).unwrap_err();
        assert!(
            matches!(err, ImuCsvError::Header { line: 1, .. }),
            "{err:?}"
        );
        let msg = err.to_string();
        assert!(
            msg.starts_with(&format!(
                "data/imu.csv.{ext}:1: header is not text: the file is {kind} (decompress it \
                 first: {tool} data/imu.csv.{ext} > data/imu.csv): it must start with"
            )),
            "{msg}"
        );
        assert!(!msg.contains("CR alone") && !msg.contains("UTF-8"), "{msg}");
        assert!(!msg.chars().any(char::is_control), "{msg:?}");
    }
    let (.., gzip) = &compressed_heads()[0];
    let err = ImuCsvReader::new(gzip.as_slice(), Path::new("imu.gz"), &lenient()).unwrap_err();
    assert_eq!(
        err.to_string(),
        "imu.gz:1: header is not text: the file is gzip-compressed (decompress it first: \
         gunzip -c imu.gz > imu.csv): it must start with \
         \"t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2\", found \"\\x1f\\x8b\\x08\\x08\\xd2\\x0d^f\""
    );
    // Never onto the file itself; a name the shell would split is quoted.
    for (name, command) in [
        ("imu.csv", "gunzip -c imu.csv > imu-decompressed.csv"),
        ("my log.gz", "gunzip -c 'my log.gz' > 'my log.csv'"),
    ] {
        let err = ImuCsvReader::new(gzip.as_slice(), Path::new(name), &lenient()).unwrap_err();
        assert!(
            err.to_string().contains(&format!("first: {command})")),
            "{err}"
        );
    }
    // A text that only starts with "BZh" is no bzip2 file.
    let err = parse_imu_csv("BZh,x\n", path(), &lenient()).unwrap_err();
    assert!(err.to_string().contains("required columns"), "{err}");
}

#[test]
fn a_header_with_a_nul_or_a_byte_that_is_not_utf8_is_not_called_a_cr_file() {
    for (bad, shown) in [
        (&b"\0"[..], ""),
        (b"\xff", "\\xff"),
        (b"\x1b\xc3", "\\x1b\\xc3"),
    ] {
        let bytes = [
            &b"t_s,gx_rad_s"[..],
            bad,
            b",gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2\r0,0.01,0.02,0.03,0.1,0.2,9.8\r",
        ]
        .concat();
        let err = ImuCsvReader::new(bytes.as_slice(), path(), &lenient()).unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.starts_with("data/imu.csv:1: header is not UTF-8 text") && !msg.contains("CR"),
            "{msg}"
        );
        assert!(!msg.chars().any(char::is_control), "{msg:?}");
        assert!(
            msg.ends_with(&format!(
                "found \"t_s,gx_rad_s{shown},gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2\""
            )),
            "{msg}"
        );
    }
    // A file whose lines end in CR alone stays one, when its bad byte is in a row after the
    // header (read alone, that row would be rejected, the others kept).
    let mut bytes = good_file(3).replace('\n', "\r").into_bytes();
    bytes.extend_from_slice(b"0.015,0.01,\xff,0.03,0.1,0.2,9.8\r");
    let err = ImuCsvReader::new(bytes.as_slice(), path(), &lenient()).unwrap_err();
    assert!(err.to_string().contains("end in CR alone"), "{err}");
}
