use super::*;

const HEADER: &str = "t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2";

/// The time rule of the reader (`sensor::TimeGuard`), row by row.
mod time;

/// The units checks: times not in seconds, accelerations in g, rates in °/s, and the whole
/// log's decision.
mod units;

/// Files that are not CSV text: compressed, or a header that is not UTF-8.
mod not_text;
// The reader's bounds on lines and files, and escaped invisible characters.
mod limits;

/// Rows whose field count differs from the header's, as the message says them.
mod field_counts;

fn path() -> &'static Path {
    Path::new("data/imu.csv")
}

/// A plausible data row at time `t_s` (gyro small, |a| ≈ 9.81 m/s²).
fn row(t_s: f64) -> String {
    format!("{t_s},0.01,-0.02,0.03,0.1,0.2,9.8")
}

/// A header plus `n` good rows at 200 Hz, LF line ends.
fn good_file(n: usize) -> String {
    let mut s = String::from(HEADER);
    s.push('\n');
    for i in 0..n {
        s.push_str(&row(i as f64 * 0.005));
        s.push('\n');
    }
    s
}

/// Replaces data line `line` (1-based file line; data starts at line 2) of `text`.
fn replace_line(text: &str, line: usize, new: &str) -> String {
    let mut lines: Vec<&str> = text.split('\n').collect();
    lines[line - 1] = new;
    lines.join("\n")
}

fn lenient() -> ImuCsvOptions {
    ImuCsvOptions {
        max_rejected_fraction: 0.5,
        ..ImuCsvOptions::default()
    }
}

#[test]
fn real_files_parse_with_expected_counts_and_no_rejections() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data");
    // (set, imu data rows, has magnetometer, ground-truth points)
    let sets = [
        ("gdins_exp29_corridor_circuit", 21001, true, 9),
        ("gdins_exp25_multi_corridor", 20800, true, 12),
        ("gdins_exp36_corridor_out_and_back", 14000, true, 59),
        ("xio_ngimu_long_walk", 27880, false, 2),
    ];
    for (set, n_rows, has_mag, n_truth) in sets {
        let file = root.join(set).join("imu.csv");
        let log = read_imu_csv(&file, &ImuCsvOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(log.rows.len(), n_rows, "{set}");
        assert!(log.rejected.is_empty(), "{set}: {:?}", log.rejected.first());
        assert_eq!(log.rejected_counts().values().sum::<u64>(), 0);
        assert!(!log.has_temperature, "{set}");
        assert_eq!(log.rows[0].t_s, 0.0, "{set}");
        assert_eq!(log.rows[0].line, 2, "{set}");
        assert_eq!(log.rows.last().unwrap().line, n_rows as u64 + 1, "{set}");
        let mag = ["mx_gauss", "my_gauss", "mz_gauss"]
            .map(String::from)
            .to_vec();
        assert_eq!(
            log.extra_columns,
            if has_mag { mag } else { vec![] },
            "{set}"
        );
        assert!(log.rows.windows(2).all(|w| w[1].t_s > w[0].t_s), "{set}");

        let truth = crate::truth_csv::read_truth_csv(&root.join(set).join("ground_truth.csv"))
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(truth.len(), n_truth, "{set}");
        assert_eq!(truth[0].stride.is_some(), has_mag, "{set}");
    }
    // The exp29 README: duration 105.00 s at 200 Hz, first gyro sample as in the file.
    let log = read_imu_csv(
        &root.join("gdins_exp29_corridor_circuit/imu.csv"),
        &ImuCsvOptions::default(),
    )
    .unwrap();
    assert!((log.rows.last().unwrap().t_s - 104.9963608).abs() < 1e-9);
    assert_eq!(
        log.rows[0].gyro_rad_s,
        [-0.022266533, 0.005827301, 0.012808873]
    );
}

#[test]
fn parses_values_and_extra_columns() {
    let text = format!(
        "{HEADER},mx_gauss,temp_c\n0.0,0.1,0.2,0.3,1.0,2.0,9.0,0.4,25.5\n0.005,-0.1,-0.2,-0.3,-1.0,-2.0,-9.0,0.4,25.75\n"
    );
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!(log.path, Path::new("data/imu.csv"));
    assert_eq!(log.rows.len(), 2);
    assert!(log.has_temperature);
    assert_eq!(
        log.extra_columns,
        vec!["mx_gauss".to_string(), "temp_c".to_string()]
    );
    assert_eq!(
        log.rows[1],
        ImuRow {
            t_s: 0.005,
            gyro_rad_s: [-0.1, -0.2, -0.3],
            accel_m_s2: [-1.0, -2.0, -9.0],
            temp_c: Some(25.75),
            line: 3,
        }
    );
    assert_eq!(log.rows[0].temp_c, Some(25.5));
}

/// A temperature logged at a lower rate than the rest (empty fields), or a bad one, leaves
/// that row's temperature unknown, counted, and costs the row nothing: the estimator never
/// uses it (such a file lost every row to the 1 % rule, a review of session 38).
#[test]
fn an_empty_or_bad_temperature_is_unknown_and_counted_not_a_rejected_row() {
    let mut text = format!("{HEADER},temp_c\n");
    let temps = ["25.5", "", "nan", "warm", "inf", "26.0", " "];
    for (k, t) in temps.iter().enumerate() {
        text.push_str(&format!(
            "{},0.1,0.2,0.3,1.0,2.0,9.0,{t}\n",
            k as f64 * 0.005
        ));
    }
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!(log.rows.len(), temps.len());
    assert!(log.rejected.is_empty());
    let got: Vec<Option<f64>> = log.rows.iter().map(|r| r.temp_c).collect();
    assert_eq!(got, [Some(25.5), None, None, None, None, Some(26.0), None]);
    assert_eq!(log.temperature_missing, 5);
    // The measured columns are still checked as before.
    let bad = format!("{HEADER},temp_c\n0.0,0.1,x,0.3,1.0,2.0,9.0,25.0\n");
    let err = parse_imu_csv(&bad, path(), &ImuCsvOptions::default()).unwrap_err();
    assert!(err.to_string().contains("gy_rad_s"), "{err}");
}

#[test]
fn no_temperature_column_gives_none() {
    let log = parse_imu_csv(&good_file(3), path(), &ImuCsvOptions::default()).unwrap();
    assert!(!log.has_temperature);
    assert!(log.extra_columns.is_empty());
    assert!(log.rows.iter().all(|r| r.temp_c.is_none()));
}

#[test]
fn bom_crlf_whitespace_and_trailing_blank_lines_are_accepted() {
    let text = format!(
        "\u{feff}{HEADER}\r\n 0.0 , 0.01,0.02,0.03,\t0.1,0.2,9.8 \r\n0.005,0.01,0.02,0.03,0.1,0.2,9.8\r\n\r\n\r\n  \n"
    );
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!(log.rows.len(), 2);
    assert!(log.rejected.is_empty());
    assert_eq!(log.rows[0].t_s, 0.0);
    assert_eq!(log.rows[0].accel_m_s2, [0.1, 0.2, 9.8]);
    assert_eq!(log.rows[1].line, 3);
    // Header fields with spaces around them are accepted too.
    let spaced = format!(
        " t_s , gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2 \n{}\n",
        row(0.0)
    );
    assert_eq!(
        parse_imu_csv(&spaced, path(), &ImuCsvOptions::default())
            .unwrap()
            .rows
            .len(),
        1
    );
}

#[test]
fn quoted_names_and_numbers_are_read_as_unquoted() {
    let plain = good_file(3);
    let quote_all = |line: &str| -> String {
        line.split(',')
            .map(|f| format!("\"{f}\""))
            .collect::<Vec<_>>()
            .join(",")
    };
    let quoted: String = plain.lines().map(|l| quote_all(l) + "\n").collect();
    // Names quoted, numbers not (Python's csv.QUOTE_NONNUMERIC).
    let names_only: String = plain
        .lines()
        .enumerate()
        .map(|(i, l)| if i == 0 { quote_all(l) } else { l.to_string() } + "\n")
        .collect();
    let want = parse_imu_csv(&plain, path(), &ImuCsvOptions::default()).unwrap();
    for text in [quoted, names_only] {
        let got = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
        assert_eq!(got.rows, want.rows, "{text}");
    }
    // An unmatched quote is still malformed, named with its text.
    let text = replace_line(&plain, 3, "\"0.005,0.01,-0.02,0.03,0.1,0.2,9.8");
    let log = parse_imu_csv(&text, path(), &lenient()).unwrap();
    assert_eq!(log.rejected[0].value, "\"0.005");
}

#[test]
fn wrong_header_is_an_error_naming_file_line_and_text() {
    let text = format!("time,gx,gy,gz,ax,ay,az\n{}\n", row(0.0));
    let err = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap_err();
    assert!(matches!(err, ImuCsvError::Header { .. }), "{err:?}");
    let msg = err.to_string();
    assert_eq!(
        msg,
        "data/imu.csv:1: header does not start with the required columns: it must start with \
         \"t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2\", found \"time,gx,gy,gz,ax,ay,az\""
    );
    // Blank lines before the header are skipped (the header was checked as the blank line).
    let text = format!("\n  \n{IMU_HEADER}\n{}\n", row(0.0));
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!(log.rows.len(), 1);
    let err = parse_imu_csv("\n\ntime,gx\n", path(), &ImuCsvOptions::default()).unwrap_err();
    assert!(
        err.to_string().starts_with("data/imu.csv:3: header"),
        "{err}"
    );
    // A repeated column says so.
    let err = parse_imu_csv(
        &format!("{IMU_HEADER},mx_gauss,mx_gauss\n"),
        path(),
        &ImuCsvOptions::default(),
    )
    .unwrap_err();
    assert!(err.to_string().contains("repeats a column name"), "{err}");
    // A data row instead of a header.
    let err = parse_imu_csv(
        &format!("{}\n", row(0.0)),
        path(),
        &ImuCsvOptions::default(),
    )
    .unwrap_err();
    assert!(err.to_string().contains("found \"0,0.01,"), "{err}");
}

#[test]
fn missing_or_reordered_or_repeated_column_is_a_header_error() {
    for header in [
        "t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2",
        "t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,az_m_s2,ay_m_s2",
        "t_s,gy_rad_s,gx_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2",
        "t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2,temp_c,temp_c",
        // An empty name before the last, or two trailing commas.
        "t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2,,temp_c",
        "t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2,,",
    ] {
        let text = format!("{header}\n0,0,0,0,0,0,9.8\n");
        let err = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap_err();
        match &err {
            ImuCsvError::Header { found, .. } => assert_eq!(found, header),
            other => panic!("{header}: {other:?}"),
        }
        assert!(
            err.to_string().starts_with("data/imu.csv:1: header"),
            "{err}"
        );
    }
}

#[test]
fn a_trailing_comma_on_every_line_is_an_unnamed_column_ignored() {
    // As spreadsheet exports write it: the header "has an empty column name" refused the file,
    // although extra columns are ignored.
    let text: String = good_file(200).lines().map(|l| format!("{l},\n")).collect();
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!(log.rows.len(), 200);
    assert!(log.rejected.is_empty(), "{:?}", log.rejected);
    assert_eq!(log.rows[1].t_s, 0.005);
    assert_eq!(log.rows[1].accel_m_s2, [0.1, 0.2, 9.8]);
    // The header's comma alone (rows without the empty field), with a temperature column.
    let header = format!("{HEADER},temp_c,");
    let text = format!("{header}\n{},21.5\n{},21.5,\n", row(0.0), row(0.005));
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!(log.rows.len(), 2);
    assert_eq!(log.rows[1].temp_c, Some(21.5));
}

#[test]
fn nan_row_is_rejected_and_counted_with_line_and_column() {
    let text = replace_line(&good_file(200), 5, "0.015,0.01,nan,0.03,0.1,0.2,9.8");
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!(log.rows.len(), 199);
    assert_eq!(
        log.rejected,
        vec![RejectedRow {
            line: 5,
            column: "gy_rad_s".into(),
            value: "nan".into(),
            reason: RejectReason::NonFinite,
            field_counts: None,
            ends_with_comma: false,
        }]
    );
    let counts = log.rejected_counts();
    assert_eq!(counts["non_finite"], 1);
    assert_eq!(counts["malformed"], 0);
    assert_eq!(counts["time_not_increasing"], 0);
    assert_eq!(
        log.rejected[0].to_string(),
        "line 5 column gy_rad_s: value \"nan\" is not finite"
    );
    assert_eq!(
        log.rejected[0].located(path()).to_string(),
        "data/imu.csv:5 column gy_rad_s: value \"nan\" is not finite"
    );
    // Rows around the rejected one are kept and keep their own line numbers.
    assert_eq!(log.rows[2].line, 4);
    assert_eq!(log.rows[3].line, 6);
}

#[test]
fn infinite_and_overflowing_values_are_non_finite() {
    let text = replace_line(&good_file(200), 10, "0.04,0.01,0.02,0.03,inf,0.2,9.8");
    let text = replace_line(&text, 20, "0.09,0.01,0.02,0.03,0.1,0.2,1e999");
    let log = parse_imu_csv(&text, path(), &lenient()).unwrap();
    assert_eq!(log.rejected.len(), 2);
    assert_eq!(
        (log.rejected[0].line, log.rejected[0].column.as_str()),
        (10, "ax_m_s2")
    );
    assert_eq!(
        (log.rejected[1].line, log.rejected[1].column.as_str()),
        (20, "az_m_s2")
    );
    assert!(
        log.rejected
            .iter()
            .all(|r| r.reason == RejectReason::NonFinite)
    );
    assert_eq!(log.rejected_counts()["non_finite"], 2);
}

#[test]
fn malformed_number_is_rejected_with_column_and_value() {
    let text = replace_line(&good_file(200), 8, "0.03,0.01,0.02,0.03,0.1,0..2,9.8");
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    let r = &log.rejected[0];
    assert_eq!(
        (r.line, r.column.as_str(), r.value.as_str()),
        (8, "ay_m_s2", "0..2")
    );
    assert_eq!(r.reason, RejectReason::Malformed);
    assert_eq!(
        r.located(path()).to_string(),
        "data/imu.csv:8 column ay_m_s2: value \"0..2\" is malformed (not a number)"
    );
    // An empty field is not a number either.
    let text = replace_line(&good_file(200), 8, "0.03,,0.02,0.03,0.1,0.2,9.8");
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!(log.rejected[0].column, "gx_rad_s");
    assert_eq!(log.rejected[0].value, "");
}

#[test]
fn wrong_field_count_is_a_whole_row_rejection() {
    let text = replace_line(&good_file(200), 3, "0.005,0.01,0.02,0.03,0.1,0.2");
    let text = replace_line(&text, 4, "0.01,0.01,0.02,0.03,0.1,0.2,9.8,7");
    let log = parse_imu_csv(&text, path(), &lenient()).unwrap();
    assert_eq!(log.rows.len(), 198);
    assert_eq!(log.rejected.len(), 2);
    for (r, (line, value)) in log.rejected.iter().zip([
        (3, "0.005,0.01,0.02,0.03,0.1,0.2"),
        (4, "0.01,0.01,0.02,0.03,0.1,0.2,9.8,7"),
    ]) {
        assert_eq!(
            (r.line, r.column.as_str(), r.value.as_str()),
            (line, "", value)
        );
        assert_eq!(r.reason, RejectReason::Malformed);
    }
    assert_eq!(
        log.rejected[0].to_string(),
        "line 3: row \"0.005,0.01,0.02,0.03,0.1,0.2\" is malformed (6 fields, the header has 7)"
    );
    // A wrong field count outranks a bad field in the same row.
    let text = replace_line(&good_file(200), 3, "0.005,abc,0.02");
    let log = parse_imu_csv(&text, path(), &lenient()).unwrap();
    assert_eq!(log.rejected[0].column, "");
}

#[test]
fn blank_line_in_the_middle_is_rejected_not_skipped() {
    let text = replace_line(&good_file(200), 10, "");
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!(log.rows.len(), 199);
    assert_eq!(log.rejected.len(), 1);
    assert_eq!(
        (log.rejected[0].line, log.rejected[0].reason),
        (10, RejectReason::Malformed)
    );
}

#[test]
fn find_comma_or_newline_matches_a_byte_loop() {
    let text =
        "0.004998144,0.004951937,-0.0011,,x\n\n1,22,333,4444,55555,666666,7777777,88888888,\näö,ü";
    let bytes = text.as_bytes();
    for from in 0..=bytes.len() {
        let expected = (from..bytes.len())
            .find(|&i| bytes[i] == b',' || bytes[i] == b'\n')
            .unwrap_or(bytes.len());
        assert_eq!(find_comma_or_newline(bytes, from), expected, "from {from}");
    }
    assert_eq!(find_comma_or_newline(b"12345678901234567890", 3), 20);
}

#[test]
fn long_values_are_truncated_to_64_characters() {
    let long = "9".repeat(40) + &"x".repeat(60);
    let text = replace_line(
        &good_file(200),
        3,
        &format!("0.005,{long},0.02,0.03,0.1,0.2,9.8"),
    );
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!(log.rejected[0].value.chars().count(), 64);
    assert!(long.starts_with(&log.rejected[0].value));
    assert_eq!(truncate_chars("äöü", 2), "äö");
}

#[test]
fn too_many_rejected_is_an_error_naming_the_first() {
    // 2 bad rows of 100 is 2 % > 1 %.
    let text = replace_line(&good_file(100), 7, "0.025,0.01,0.02,0.03,0.1,NaN,9.8");
    let text = replace_line(&text, 9, "0.035,0.01,0.02,0.03");
    let err = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap_err();
    match &err {
        ImuCsvError::TooManyRejected {
            rejected,
            total,
            first,
            ..
        } => {
            assert_eq!((*rejected, *total), (2, 100));
            assert_eq!((first.line, first.column.as_str()), (7, "ay_m_s2"));
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(
        err.to_string(),
        "data/imu.csv: 2 of 100 data rows rejected, more than the allowed fraction 0.01; \
         first: data/imu.csv:7 column ay_m_s2: value \"NaN\" is not finite"
    );
    // 1 of 100 is exactly 1 %: allowed.
    let text = replace_line(&good_file(100), 7, "0.025,0.01,0.02,0.03,0.1,NaN,9.8");
    assert_eq!(
        parse_imu_csv(&text, path(), &ImuCsvOptions::default())
            .unwrap()
            .rows
            .len(),
        99
    );
    // Fraction 0 refuses any rejection.
    let strict = ImuCsvOptions {
        max_rejected_fraction: 0.0,
        ..ImuCsvOptions::default()
    };
    assert!(matches!(
        parse_imu_csv(&text, path(), &strict),
        Err(ImuCsvError::TooManyRejected { rejected: 1, .. })
    ));
}

#[test]
fn empty_inputs_are_empty_errors() {
    for text in [
        "",
        "\u{feff}",
        "\n\n",
        " \r\n",
        HEADER,
        &format!("{HEADER}\r\n\r\n"),
    ] {
        let err = parse_imu_csv(text, path(), &ImuCsvOptions::default()).unwrap_err();
        assert!(
            matches!(err, ImuCsvError::Empty { .. }),
            "{text:?}: {err:?}"
        );
        assert!(
            err.to_string().starts_with("data/imu.csv: no IMU samples"),
            "{err}"
        );
    }
    // Every row rejected but the fraction allowed: still no samples.
    let all_bad = format!("{HEADER}\n0,1,2\n");
    let anything = ImuCsvOptions {
        max_rejected_fraction: 1.0,
        ..ImuCsvOptions::default()
    };
    assert!(matches!(
        parse_imu_csv(&all_bad, path(), &anything),
        Err(ImuCsvError::Empty { .. })
    ));
}

#[test]
fn io_errors_name_the_file() {
    let missing = Path::new("/nonexistent/corridor/imu.csv");
    let err = read_imu_csv(missing, &ImuCsvOptions::default()).unwrap_err();
    assert!(matches!(err, ImuCsvError::Io { .. }));
    assert!(
        err.to_string()
            .starts_with("/nonexistent/corridor/imu.csv: cannot read IMU CSV"),
        "{err}"
    );
}

#[test]
fn lines_that_end_in_cr_alone_and_utf16_are_named_as_such() {
    // Also past the 64 KiB line bound, where a file read as one line is cut: it was called
    // "longer than 65536 bytes without a line end (a binary file?)", a real log of 1,700 rows
    // (a review).
    for rows in [3, 3000] {
        let text = good_file(rows).replace('\n', "\r");
        let err = ImuCsvReader::new(text.as_bytes(), path(), &lenient())
            .unwrap_err()
            .to_string();
        // The header shown stops at its CR: a terminal would return to the line's start there.
        assert!(
            err.contains("end in CR alone") && !err.contains('\r'),
            "{rows}: {err}"
        );
    }
    assert!(good_file(3000).len() > super::lines::MAX_LINE_BYTES);
    let utf16: Vec<u8> = [0xff, 0xfe]
        .into_iter()
        .chain(good_file(3).encode_utf16().flat_map(u16::to_le_bytes))
        .collect();
    let err = ImuCsvReader::new(utf16.as_slice(), path(), &lenient())
        .unwrap_err()
        .to_string();
    assert!(err.contains("UTF-16") && !err.contains('\0'), "{err}");
}

#[test]
fn a_byte_that_is_not_utf8_costs_its_row_at_most() {
    // In a number: that row is rejected as malformed, named by line and column, and counted;
    // the rows around it are read (a stray byte used to stop the whole run).
    let mut bytes = good_file(3).into_bytes();
    bytes.extend_from_slice(b"0.02,0.01,0.02,\xff,0.1,0.2,9.8\n");
    bytes.extend_from_slice(row(0.025).as_bytes());
    bytes.push(b'\n');
    let log = read_bytes(&bytes, &lenient());
    assert_eq!(log.rows.len(), 4);
    assert_eq!(log.rejected_counts()["malformed"], 1);
    let r = &log.rejected[0];
    assert_eq!((r.line, r.column.as_str()), (5, "gz_rad_s"), "{r}");
    assert!(r.to_string().contains('\u{fffd}'), "{r}");
    // In a column the reader does not use: nothing is lost.
    let mut bytes = format!("{HEADER},note\n").into_bytes();
    for i in 0..4 {
        bytes.extend_from_slice(row(f64::from(i) * 0.005).as_bytes());
        bytes.extend_from_slice(if i == 2 { b",caf\xe9\n" } else { b",ok\n" });
    }
    let log = read_bytes(&bytes, &ImuCsvOptions::default());
    assert_eq!((log.rows.len(), log.rejected.len()), (4, 0));
}

/// The log that `bytes` holds, read from a file.
fn read_bytes(bytes: &[u8], opts: &ImuCsvOptions) -> ImuLog {
    let dir = std::env::temp_dir().join(format!(
        "corridor-imu-csv-{}-{}",
        std::process::id(),
        bytes.len()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("bytes.csv");
    std::fs::write(&file, bytes).unwrap();
    let log = read_imu_csv(&file, opts);
    std::fs::remove_dir_all(&dir).unwrap();
    log.unwrap()
}

/// A streaming reader over `text`, with the default options.
fn stream(text: &str) -> ImuCsvReader<&[u8]> {
    ImuCsvReader::new(text.as_bytes(), path(), &lenient()).unwrap()
}

#[test]
fn the_reader_counts_every_rejection_but_keeps_only_the_first() {
    // 30 NaN rows among 3000: all counted, 20 kept, the rows the same as collected.
    let mut text = good_file(3000);
    for k in 0..30 {
        let line = 10 + 50 * k;
        text = replace_line(&text, line, "0.5,0.01,nan,0.03,0.1,0.2,9.8");
    }
    let mut reader = stream(&text);
    let rows: Vec<ImuRow> = reader.by_ref().map(Result::unwrap).collect();
    let log = parse_imu_csv(&text, path(), &lenient()).unwrap();
    assert_eq!(rows, log.rows);
    assert_eq!(reader.rows_accepted(), 2970);
    assert_eq!(reader.rows_rejected(), 30);
    assert_eq!(reader.rejected_counts(), log.rejected_counts());
    assert_eq!(reader.rejected_rows(), &log.rejected[..REJECTED_ROWS_KEPT]);
    assert_eq!(log.rejected.len(), 30);
}

#[test]
fn the_whole_log_checks_come_after_the_rows_as_the_last_item() {
    // 2 of 100 rejected at the end: the rows come first, then the error, then nothing.
    let text = replace_line(&good_file(100), 99, "x");
    let text = replace_line(&text, 100, "y");
    let mut reader = ImuCsvReader::new(text.as_bytes(), path(), &ImuCsvOptions::default()).unwrap();
    let items: Vec<_> = reader.by_ref().collect();
    assert_eq!(items.len(), 99);
    assert!(items[..98].iter().all(Result::is_ok));
    assert!(matches!(
        items[98],
        Err(ImuCsvError::TooManyRejected { rejected: 2, .. })
    ));
    assert!(reader.next().is_none());
}

#[test]
fn a_wrong_field_count_names_both_counts_and_counts_as_malformed() {
    let header = format!("{HEADER},mx_gauss,my_gauss,mz_gauss");
    let mut text = header + "\n";
    for i in 0..200 {
        text.push_str(&format!("{},0.04,0.40,-0.1", row(f64::from(i) * 0.005)));
        text.push_str(if i == 1 {
            ",0.5,3.8948949810274\n"
        } else {
            "\n"
        });
    }
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    let r = &log.rejected[0];
    assert_eq!((r.line, r.column.as_str()), (3, ""));
    assert_eq!(r.value.chars().count(), MAX_VALUE_CHARS);
    assert!(
        r.located(path())
            .to_string()
            .ends_with("-0.1,0.5,3.894894981\" is malformed (12 fields, the header has 10)"),
        "{r}"
    );
    // The counts by reason keep their keys.
    assert_eq!(log.rejected_counts()["malformed"], 1);
    // A control character in a rejected field is shown escaped.
    let text = replace_line(&good_file(200), 3, "0.005,\x1b[2J,0.02,0.03,0.1,0.2,9.8");
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!(log.rejected[0].value, "\x1b[2J");
    assert_eq!(
        log.rejected[0].to_string(),
        "line 3 column gx_rad_s: value \"\\x1b[2J\" is malformed (not a number)"
    );
}
