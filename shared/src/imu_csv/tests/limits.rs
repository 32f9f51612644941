//! Lines and files beyond any plausible size, and characters a message must not show as they
//! are: the reader's bounds (a fuzzing review, session 45).

use super::*;
use crate::imu_csv::lines::MAX_LINE_BYTES;

#[test]
fn a_line_without_an_end_is_read_in_memory_independent_of_its_length() {
    // Before: a line was read whole into memory; 300 MB of binary without a line end took
    // 1.3 GB and 13 s to be called "not UTF-8", and `--imu /dev/zero` aborted with "memory
    // allocation failed".
    use std::io::Read as _;
    let mut zeros = std::io::BufReader::new(std::io::repeat(0).take(64 << 20));
    let err = ImuCsvReader::new(&mut zeros, path(), &ImuCsvOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("data/imu.csv:1: header is longer than 65536 bytes without a line end"),
        "{err}"
    );
    assert!(
        zeros.get_ref().limit() > 60 << 20,
        "read {} bytes of a header",
        (64 << 20) - zeros.get_ref().limit()
    );
    // A data row past the limit is rejected, never parsed (a number cut short would read as
    // another), and the rows after it keep their lines.
    let digits = format!("0.01{}", "0".repeat(100_000));
    let fields = vec!["1"; 100_000].join(",");
    let mut text = good_file(400);
    for (line, row) in [
        (100, format!("0.49,{digits},0.02,0.03,0.1,0.2,9.8")),
        (200, format!("0.99,{fields}")),
    ] {
        text = replace_line(&text, line, &row);
    }
    let log = parse_imu_csv(&text, path(), &lenient()).unwrap();
    assert_eq!(log.rows.len(), 398);
    assert_eq!(log.rows.last().unwrap().line, 401);
    let r = &log.rejected;
    assert_eq!(r.len(), 2, "{r:?}");
    assert_eq!(
        (r[0].line, r[0].column.as_str(), r[0].reason),
        (100, "gx_rad_s", RejectReason::Malformed)
    );
    assert_eq!(r[0].value, digits[..64]);
    assert_eq!(
        (r[1].line, r[1].column.as_str(), r[1].field_counts),
        (200, "", Some((100_001, 7)))
    );
    let message = r[1].to_string();
    assert!(
        message.contains("(100001 fields, the header has 7)") && message.len() < 200,
        "{message}"
    );
}

#[test]
fn an_invisible_character_in_a_value_is_shown_escaped() {
    // Before: a BOM inside a field was quoted as it is, invisible: the message read
    // `value "-0.02" is malformed (not a number)`. A direction override reordered the rest.
    for (field, shown) in [
        ("\u{feff}-0.02", "value \"\\u{feff}-0.02\""),
        ("-0.0\u{200b}2", "value \"-0.0\\u{200b}2\""),
        ("\u{202e}-0.02", "value \"\\u{202e}-0.02\""),
        ("-0.02\u{a0}1", "value \"-0.02\\u{a0}1\""),
    ] {
        let text = replace_line(
            &good_file(200),
            3,
            &format!("0.005,0.01,{field},0.03,0.1,0.2,9.8"),
        );
        let log = parse_imu_csv(&text, path(), &lenient()).unwrap();
        let message = log.rejected[0].located(path()).to_string();
        assert_eq!(
            message,
            format!("data/imu.csv:3 column gy_rad_s: {shown} is malformed (not a number)")
        );
    }
    // Visible text beyond ASCII stays as it is.
    assert_eq!(escape_controls("µ-0.02°"), "µ-0.02°");
}

#[test]
fn a_length_that_promises_more_rows_than_memory_holds_is_no_failure() {
    // The rows are reserved from the file's length and the first row's: a sparse 200 GB file
    // with three short rows asked for 1.2 TB, and the reservation aborted the run.
    let text = good_file(10);
    let mut reader = ImuCsvReader::new(text.as_bytes(), path(), &lenient()).unwrap();
    reader.len_bytes = Some(u64::MAX / 2);
    let log = collect(reader).unwrap();
    assert_eq!(log.rows.len(), 10);
}

#[test]
fn a_row_of_exactly_the_bound_is_kept_with_lf_or_crlf_line_ends() {
    // A row of 65536 bytes before its line end is within the bound: kept with LF, and with
    // CRLF too (its CR was read as the byte beyond the bound: the row was cut, and its last
    // field, a good "9.8\r", named as malformed).
    let head = "0.49,0.01";
    let tail = ",-0.02,0.03,0.1,0.2,9.8";
    let pad = "0".repeat(MAX_LINE_BYTES - head.len() - tail.len());
    let long = format!("{head}{pad}{tail}");
    assert_eq!(long.len(), MAX_LINE_BYTES);
    for crlf in [false, true] {
        let mut text = replace_line(&good_file(400), 100, &long);
        if crlf {
            text = text.replace('\n', "\r\n");
        }
        let log = parse_imu_csv(&text, path(), &lenient()).unwrap();
        assert!(log.rejected.is_empty(), "crlf {crlf}: {:?}", log.rejected);
        assert_eq!(log.rows.len(), 400, "crlf {crlf}");
        assert_eq!(log.rows[98].line, 100);
        assert_eq!(log.rows[98].gyro_rad_s[0], 0.01);
    }
    // One byte more is cut, with either line end.
    let longer = format!("{head}0{pad}{tail}");
    for crlf in [false, true] {
        let mut text = replace_line(&good_file(400), 100, &longer);
        if crlf {
            text = text.replace('\n', "\r\n");
        }
        let log = parse_imu_csv(&text, path(), &lenient()).unwrap();
        assert_eq!(log.rejected.len(), 1, "crlf {crlf}");
        assert_eq!(log.rejected[0].line, 100);
    }
}
