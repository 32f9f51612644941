//! The units checks of the reader: times not in seconds, accelerations in g or out of range,
//! rates in °/s, and the units decision taken on the whole log.

use super::*;

#[test]
fn times_in_another_unit_than_seconds_are_named_in_the_error() {
    for (scale, unit, step) in [
        (1e3, "milliseconds", "5.0000"),
        (1e6, "microseconds", "5000.0000"),
    ] {
        let mut text = String::from(HEADER);
        for i in 0..100 {
            text.push_str(&format!("\n{}", row(i as f64 * 0.005 * scale)));
        }
        let err = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap_err();
        let message = err.to_string();
        assert!(
            message.ends_with(&format!(
                " (the rows' t_s advance by {step} on average: 0.0050 s if they are {unit}; t_s must be in seconds)"
            )),
            "{message}"
        );
    }
    // Milliseconds at about 1 kHz, steps of 1.02 and 0.99 in turn: every other row a jump that
    // the next row follows. Those rows are passed on (the estimator refuses them) and counted
    // here: before, the log was taken with half its rows to be refused downstream.
    let mut text = String::from(HEADER);
    for i in 0..100 {
        text.push_str(&format!(
            "\n{}",
            row(i as f64 * 1.005 + 0.015 * (i % 2) as f64)
        ));
    }
    let message = parse_imu_csv(&text, path(), &ImuCsvOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("51 of 100 data rows rejected")
            && message.ends_with("0.0010 s if they are milliseconds; t_s must be in seconds)"),
        "{message}"
    );
}

#[test]
fn accel_in_g_is_a_units_error() {
    let mut text = String::from(HEADER);
    for i in 0..100 {
        text.push_str(&format!(
            "\n{},0.01,0.02,0.03,0.01,0.02,1.001",
            i as f64 * 0.005
        ));
    }
    let err = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap_err();
    match &err {
        ImuCsvError::Units { column, value, .. } => {
            assert_eq!(*column, "ax_m_s2,ay_m_s2,az_m_s2");
            assert!((value - 1.0012).abs() < 1e-3, "{value}");
        }
        other => panic!("{other:?}"),
    }
    let msg = err.to_string();
    assert!(
        msg.starts_with("data/imu.csv: column ax_m_s2,ay_m_s2,az_m_s2: median |a| (m/s²) = 1.0012"),
        "{msg}"
    );
    assert!(msg.contains("in g") && msg.contains("9.80665"), "{msg}");
    // The check can be turned off.
    let off = ImuCsvOptions {
        check_units: false,
        ..ImuCsvOptions::default()
    };
    assert_eq!(parse_imu_csv(&text, path(), &off).unwrap().rows.len(), 100);
}

#[test]
fn accel_outside_plausible_range_is_a_units_error() {
    for az in [0.0, 3.0, 32.17, 1000.0] {
        let mut text = String::from(HEADER);
        for i in 0..10 {
            text.push_str(&format!("\n{},0.01,0.02,0.03,0,0,{az}", i as f64 * 0.005));
        }
        let err = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap_err();
        assert!(
            matches!(err, ImuCsvError::Units { value, .. } if value == az),
            "{err:?}"
        );
        assert!(err.to_string().contains("gravity"), "{err}");
    }
}

#[test]
fn gyro_in_deg_s_is_a_units_error() {
    let mut text = good_file(100);
    // A turn at 600 °/s written in deg/s.
    text = replace_line(&text, 51, "0.245,0,0,600,0.1,0.2,9.8");
    let err = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap_err();
    match &err {
        ImuCsvError::Units {
            column,
            statistic,
            value,
            ..
        } => {
            assert_eq!(*column, "gx_rad_s,gy_rad_s,gz_rad_s");
            assert_eq!(
                statistic,
                "max |ω| (rad/s, 1 of 100 rows above 40) at line 51"
            );
            assert_eq!(*value, 600.0);
        }
        other => panic!("{other:?}"),
    }
    let msg = err.to_string();
    assert!(
        msg.starts_with(
            "data/imu.csv: column gx_rad_s,gy_rad_s,gz_rad_s: max |ω| (rad/s, 1 of 100 rows above 40) at line 51 = 600.0000"
        ),
        "{msg}"
    );
    assert!(msg.contains("deg/s"), "{msg}");
    // 12 rad/s (a brisk foot swing) passes.
    let text = replace_line(&good_file(100), 51, "0.245,0,0,12,0.1,0.2,9.8");
    assert!(parse_imu_csv(&text, path(), &ImuCsvOptions::default()).is_ok());
    // One corrupt value among 1000 rows is no unit: the file reads (the estimator's
    // plausibility check refuses that sample and counts it).
    let text = replace_line(&good_file(1000), 501, "2.495,0,1e300,0,0.1,0.2,9.8");
    assert_eq!(
        parse_imu_csv(&text, path(), &ImuCsvOptions::default())
            .unwrap()
            .rows
            .len(),
        1000
    );
}

/// `n` rows at 200 Hz, the first `n_ms2` with |a| ≈ 9.8 m/s², the others ≈ 1.0 (in g).
fn units_file(n: usize, n_ms2: usize) -> String {
    let mut s = String::from(HEADER);
    for i in 0..n {
        let az = if i < n_ms2 {
            9.8
        } else {
            1.0 + (i % 7) as f64 * 1e-3
        };
        s.push_str(&format!("\n{},0.01,0.02,0.03,0,0,{az}", i as f64 * 0.005));
    }
    s
}

#[test]
fn the_units_decision_is_the_whole_logs_beyond_the_exact_median_rows() {
    // Longer than the exact-median buffer: the first 24 000 rows in m/s², the 26 000 after
    // them in g. The whole log's median is in g, as the in-memory reader decided.
    let n = 50_000;
    assert!(n > 2 * EXACT_MEDIAN_ROWS);
    let text = units_file(n, 24_000);
    let err = stream(&text).find_map(Result::err).expect("refused");
    match &err {
        ImuCsvError::Units {
            statistic, value, ..
        } => {
            assert_eq!(statistic, "median |a| (m/s², to 0.07 %)");
            let off = ImuCsvOptions {
                check_units: false,
                ..lenient()
            };
            let mut norms: Vec<f64> = parse_imu_csv(&text, path(), &off)
                .unwrap()
                .rows
                .iter()
                .map(|r| norm3(r.accel_m_s2))
                .collect();
            let mid = norms.len() / 2;
            let exact = *norms.select_nth_unstable_by(mid, f64::total_cmp).1;
            assert!((1.0..1.01).contains(&exact), "{exact}");
            assert!((value - exact).abs() < exact * 7e-4, "{value} vs {exact}");
        }
        other => panic!("{other:?}"),
    }
    // More rows in m/s² than in g: accepted.
    let text = units_file(n, n / 2 + 1);
    assert!(stream(&text).all(|r| r.is_ok()));
}

#[test]
fn a_log_in_g_is_told_from_the_rows_read_so_far_on_request() {
    // Rows in g first, then rows in m/s²: over the first 30 rows the log looks like g, and the
    // error names the rows it covers; over all of them the units are m/s².
    let text = units_file(100, 0)
        .lines()
        .enumerate()
        .map(|(i, l)| match i {
            0..=30 => l.to_string(),
            _ => l.replace(",0,0,1.00", ",0,0,9.80"),
        })
        .collect::<Vec<_>>()
        .join("\n");
    let mut reader = ImuCsvReader::new(text.as_bytes(), path(), &lenient()).unwrap();
    assert!(reader.check_units_so_far().is_ok(), "no row read yet");
    for _ in 0..30 {
        reader.next().unwrap().unwrap();
    }
    match reader.check_units_so_far().unwrap_err() {
        ImuCsvError::Units {
            statistic, value, ..
        } => {
            assert_eq!(statistic, "median |a| (m/s²) over the first 30 rows");
            assert!((1.0..1.01).contains(&value), "{value}");
        }
        other => panic!("{other:?}"),
    }
    // The request changes nothing of the end's check over every row: m/s².
    assert!(reader.all(|r| r.is_ok()));
    // Not checked at all when the check is off.
    let off = ImuCsvOptions {
        check_units: false,
        ..lenient()
    };
    let mut reader = ImuCsvReader::new(text.as_bytes(), path(), &off).unwrap();
    reader.next().unwrap().unwrap();
    assert!(reader.check_units_so_far().is_ok());
    // Only the verdict "in g": first rows that read nothing (an accelerometer that starts
    // late) are no units error so far, and the log is judged at its end, on every row.
    let text = units_file(100, 100)
        .lines()
        .enumerate()
        .map(|(i, l)| match i {
            1..=30 => l.replace(",0,0,9.8", ",0,0,0.0"),
            _ => l.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n");
    let mut reader = ImuCsvReader::new(text.as_bytes(), path(), &lenient()).unwrap();
    for _ in 0..30 {
        reader.next().unwrap().unwrap();
    }
    assert!(reader.check_units_so_far().is_ok());
    assert!(reader.all(|r| r.is_ok()));
}

#[test]
fn a_gyro_in_deg_s_is_told_from_the_rows_read_so_far_but_a_burst_of_bad_rates_is_not() {
    // 1000 rows in m/s², the gyro's z axis reading 57.3 (1 rad/s in deg/s) on rows `bad`.
    let with_z = |bad: &dyn Fn(usize) -> bool| {
        units_file(1000, 1000)
            .lines()
            .enumerate()
            .map(|(i, l)| match i {
                i if bad(i) => l.replace("0.01,0.02,0.03", "0.01,0.02,57.3"),
                _ => l.to_string(),
            })
            .collect::<Vec<_>>()
            .join("\n")
    };
    // In deg/s from row 451 on: at 500 rows read, 50 above the plausible rate (a tenth).
    let text = with_z(&|i| i > 450);
    let mut reader = ImuCsvReader::new(text.as_bytes(), path(), &lenient()).unwrap();
    for _ in 0..499 {
        reader.next().unwrap().unwrap();
    }
    assert!(reader.check_units_so_far().is_ok(), "49 of 499: not yet");
    reader.next().unwrap().unwrap();
    match reader.check_units_so_far().unwrap_err() {
        ImuCsvError::Units {
            column,
            statistic,
            hint,
            ..
        } => {
            assert_eq!(column, "gx_rad_s,gy_rad_s,gz_rad_s");
            assert!(statistic.contains("50 of 500 rows above"), "{statistic}");
            assert!(hint.contains("deg/s"), "{hint}");
        }
        other => panic!("{other:?}"),
    }
    // Too few rows read: 100 of 100 above it are no verdict yet (the end judges them).
    let all_bad = with_z(&|_| true);
    let mut reader = ImuCsvReader::new(all_bad.as_bytes(), path(), &lenient()).unwrap();
    for _ in 0..100 {
        reader.next().unwrap().unwrap();
    }
    assert!(reader.check_units_so_far().is_ok());
    // A burst of 35 bad rows among 1000 (0.2 s of a 200 Hz walk): refused one by one, not
    // units (the end's 1 % alone took 25 among 2,002 for units: a review).
    let text = with_z(&|i| (300..335).contains(&i));
    let mut reader = ImuCsvReader::new(text.as_bytes(), path(), &lenient()).unwrap();
    for _ in 0..1000 {
        reader.next().unwrap().unwrap();
    }
    assert!(reader.check_units_so_far().is_ok());
}

#[test]
fn an_accelerometer_off_scale_is_told_from_200_rows_read_so_far_not_from_a_few() {
    // 0.4 × m/s² (3.9 at rest): a few rows could be a foot struck hard, 200 are a stretch.
    let text = units_file(400, 400).replace(",0,0,9.8", ",0,0,3.92");
    let mut reader = ImuCsvReader::new(text.as_bytes(), path(), &lenient()).unwrap();
    for _ in 0..199 {
        reader.next().unwrap().unwrap();
    }
    assert!(reader.check_units_so_far().is_ok());
    reader.next().unwrap().unwrap();
    match reader.check_units_so_far().unwrap_err() {
        ImuCsvError::Units { statistic, .. } => {
            assert_eq!(statistic, "median |a| (m/s²) over the first 200 rows");
        }
        other => panic!("{other:?}"),
    }
}
