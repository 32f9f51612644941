//! The time rule of the reader (`sensor::TimeGuard`), row by row: going back, duplicates, an
//! absurd time mid-file, on the last row and on the first.

use super::*;

/// [`good_file`] with gaps: each `(line, gap_s)` makes that line and every later one `gap_s`
/// later.
fn with_gaps(n: usize, gaps: &[(u64, f64)]) -> String {
    let mut s = String::from(HEADER);
    s.push('\n');
    for i in 0..n {
        let line = i as u64 + 2;
        let shift_s: f64 = gaps.iter().filter(|g| line >= g.0).map(|g| g.1).sum();
        s.push_str(&row(i as f64 * 0.005 + shift_s));
        s.push('\n');
    }
    s
}

#[test]
fn time_going_backwards_is_rejected() {
    // Line 6 holds t = 0.02; put an earlier time there.
    let text = replace_line(&good_file(200), 6, "0.001,0.01,0.02,0.03,0.1,0.2,9.8");
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!(log.rows.len(), 199);
    let r = &log.rejected[0];
    assert_eq!(
        (r.line, r.column.as_str(), r.value.as_str()),
        (6, "t_s", "0.001")
    );
    assert_eq!(r.reason, RejectReason::TimeNotIncreasing);
    assert_eq!(log.rejected_counts()["time_not_increasing"], 1);
    assert_eq!(
        r.to_string(),
        "line 6 column t_s: value \"0.001\" is not after the previous accepted t_s"
    );
    // The next row is compared with the last accepted time, not with the rejected one.
    assert_eq!(log.rows[4].line, 7);
}

#[test]
fn an_absurd_time_is_rejected_and_the_rows_after_it_are_kept() {
    // Before: t = 1e30 on line 6 became the time base and every later row was rejected as
    // "not after the previous accepted t_s", the error naming line 7.
    let text = replace_line(&good_file(200), 6, "1e30,0.01,0.02,0.03,0.1,0.2,9.8");
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!(log.rows.len(), 199);
    assert_eq!(log.rejected.len(), 1);
    let r = &log.rejected[0];
    assert_eq!((r.line, r.reason), (6, RejectReason::TimeJump));
    assert_eq!(log.rejected_counts()["time_jump"], 1);
    // On the last row too.
    let n = good_file(200).trim_end().lines().count();
    let text = replace_line(&good_file(200), n, "1e30,0.01,0.02,0.03,0.1,0.2,9.8");
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!((log.rows.len(), log.rejected[0].line), (199, n as u64));
    assert!(log.rows.iter().all(|r| r.t_s < 2.0));
}

#[test]
fn an_absurd_first_time_is_rejected_once_the_rows_after_it_agree() {
    // Before: t = 1e9 on the first row became the time base and every later row was rejected
    // as "not after the previous accepted t_s" (the whole log refused).
    let text = replace_line(&good_file(200), 2, "1e9,0.01,0.02,0.03,0.1,0.2,9.8");
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    // The row that exposed it (line 3) goes too: it was refused before the next one agreed.
    assert_eq!(log.rows.len(), 198);
    assert_eq!(log.rows[0].line, 4);
    assert!(log.rows.windows(2).all(|w| w[1].t_s > w[0].t_s));
    let reasons: Vec<_> = log.rejected.iter().map(|r| (r.line, r.reason)).collect();
    assert_eq!(
        reasons,
        [
            (3, RejectReason::TimeNotIncreasing),
            (2, RejectReason::TimeOutlier)
        ]
    );
    assert_eq!(log.rejected[1].value, "1000000000");
    assert_eq!(log.rejected_counts()["time_outlier"], 1);
    // A good first row is held only until the second follows it, and a one-row log keeps its
    // row.
    let log = parse_imu_csv(&good_file(200), path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!(
        (log.rows.len(), log.rows[0].line, log.rows[1].line),
        (200, 2, 3)
    );
    let log = parse_imu_csv(&good_file(1), path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!(log.rows.len(), 1);
}

#[test]
fn a_rejected_time_held_as_a_number_is_quoted_short() {
    // Before: a first t_s of -1e308, rejected as the outlier once the rows after it agreed,
    // was quoted with its 309 digits (every other quoted value is cut at 64 characters).
    for (first, shown) in [
        ("-1e308", "-1e308"),
        ("5e300", "5e300"),
        ("-123456789012345678901234567890", "-1.2345678901234568e29"),
    ] {
        let text = replace_line(
            &good_file(200),
            2,
            &format!("{first},0.01,0.02,0.03,0.1,0.2,9.8"),
        );
        let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
        let r = log
            .rejected
            .iter()
            .find(|r| r.line == 2)
            .expect("line 2 rejected");
        assert_eq!(r.value, shown, "{first}");
        let message = r.located(path()).to_string();
        assert!(message.len() < 200, "{message}");
    }
}

#[test]
fn a_stamp_glitched_forward_by_less_than_a_jump_is_rejected_and_the_rows_after_it_kept() {
    // Line 100 holds t = 0.49; put it 0.9 s ahead (a gap, not a jump: max_dt_s is 1 s).
    // Before: it was accepted as a gap and the next 180 rows, up to t = 1.39, were rejected as
    // "not after the previous accepted t_s".
    let text = replace_line(&good_file(400), 100, &row(1.39));
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!(log.rows.len(), 399);
    let r = &log.rejected[0];
    assert_eq!((r.line, r.reason), (100, RejectReason::TimeGlitch));
    assert_eq!(log.rejected_counts()["time_glitch"], 1);
    assert_eq!(
        r.to_string(),
        "line 100 column t_s: value \"1.39\" came after a gap or a jump, and a later row goes \
         back and follows the row before it (a glitched stamp)"
    );
    assert_eq!((log.rows[97].line, log.rows[98].line), (99, 101));
    // A real gap at the same place (every row from line 100 on 0.9 s later): the row after it
    // is held until the next one follows it, then both are kept, in order.
    assert_every_row_kept_in_order(&[(100, 0.9)]);
}

#[test]
fn gaps_in_a_row_keep_every_row_and_a_glitch_next_to_a_gap_is_still_caught() {
    // Two gaps in a row (lines 100 and 101 each 0.3 s later than the row before): the held
    // row goes out when the next gap's row is held, none is lost and the order stays.
    assert_every_row_kept_in_order(&[(100, 0.3), (101, 0.3)]);
    // A glitched stamp on the row right after a gap's far side (one gap of 0.3 s at line 100,
    // line 101 0.7 s ahead), and one on the second row: before, the rows after either were
    // refused as not increasing until the stamp's time.
    let gapped = with_gaps(400, &[(100, 0.3)]);
    let text = replace_line(&gapped, 101, &row(1.5));
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!((log.rows.len(), log.rejected.len()), (399, 1));
    assert_eq!(
        (log.rejected[0].line, log.rejected[0].reason),
        (101, RejectReason::TimeGlitch)
    );
    let text = replace_line(&good_file(400), 3, &row(0.9));
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!((log.rows.len(), log.rejected.len()), (399, 1));
    assert_eq!(
        (log.rejected[0].line, log.rejected[0].reason),
        (3, RejectReason::TimeGlitch)
    );
}

#[test]
fn the_row_after_a_real_long_gap_goes_out_once_the_next_row_follows_it() {
    // Every row from line 100 on 10 s later (beyond max_dt_s, 1 s). Before, line 100 was
    // rejected as a time jump and the estimator behind the reader refused line 101 too (the
    // jump again, from its own last time): two rows for one gap, and the gap reported one row
    // late. Now the reader passes line 100 on, and the stream is the one a live sensor gives.
    assert_every_row_kept_in_order(&[(100, 10.0)]);
    // Two jumps in a row, the second confirmed: the first is rejected, the second goes out.
    let text = replace_line(&with_gaps(400, &[(101, 20.0)]), 100, &row(10.0));
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    let rejected: Vec<_> = log.rejected.iter().map(|r| (r.line, r.reason)).collect();
    assert_eq!(rejected, [(100, RejectReason::TimeJump)]);
    assert_eq!((log.rows.len(), log.rows[98].line), (399, 101));
    // A jump that the next row does not follow, on the last row too, is rejected as before.
    let n = good_file(200).trim_end().lines().count();
    let text = replace_line(&good_file(200), n, &row(50.0));
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!((log.rows.len(), log.rejected[0].line), (199, n as u64));
}

/// Lines 100.. of a 5,000-row log, `n_glitched` of them, stamped `ahead_s` ahead (and 5 ms
/// apart, as they came): each is rejected as glitched, every other row kept in order.
fn assert_glitched_rows_rejected(ahead_s: f64, n_glitched: u64) {
    let mut text = good_file(5000);
    for line in 100..100 + n_glitched {
        text = replace_line(&text, line as usize, &row(ahead_s + line as f64 * 0.005));
    }
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    let rejected: Vec<_> = log.rejected.iter().map(|r| (r.line, r.reason)).collect();
    let expected: Vec<_> = (100..100 + n_glitched)
        .map(|line| (line, RejectReason::TimeGlitch))
        .collect();
    assert_eq!(
        rejected, expected,
        "{n_glitched} glitched {ahead_s} s ahead"
    );
    assert_eq!(log.rows.len() as u64, 5000 - n_glitched);
    assert!(log.rows.windows(2).all(|w| w[1].t_s > w[0].t_s));
    assert_eq!(log.rows[98].line, 100 + n_glitched);
}

#[test]
fn stamps_glitched_far_ahead_two_or_more_in_a_row_are_rejected_and_the_rows_after_them_kept() {
    // Lines 100 and 101 (t = 0.49, 0.495) put 975 s ahead, as a review did to exp36: the
    // second followed the first, so both were taken for a real gap's far side and every later
    // row was rejected as not increasing (the log refused at the 1 % rule).
    for n_glitched in [2, 3, 40] {
        assert_glitched_rows_rejected(975.0, n_glitched);
    }
    // A second jump within the run (lines 102 and 103 a further 975 s ahead): one run, all
    // four rejected (a review: the second opened a run of its own, and every later row was
    // rejected as not increasing).
    let mut text = good_file(5000);
    for (line, ahead) in [(100, 975.0), (101, 975.0), (102, 1950.0), (103, 1950.0)] {
        text = replace_line(&text, line, &row(ahead + line as f64 * 0.005));
    }
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    let rejected: Vec<_> = log.rejected.iter().map(|r| (r.line, r.reason)).collect();
    assert_eq!(
        rejected,
        (100..104)
            .map(|line| (line, RejectReason::TimeGlitch))
            .collect::<Vec<_>>()
    );
    assert_eq!(log.rows.len(), 4996);
    // The jumped row is named with its value as written.
    let text = replace_line(&good_file(400), 100, "9.75e2,0.01,0.02,0.03,0.1,0.2,9.8");
    let text = replace_line(&text, 101, &row(975.005));
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!(log.rejected[0].value, "9.75e2");
    // A real gap of 10 s: the rows after it are held for the run's 1 s, then go out, in order
    // and all of them, also when the log ends within that second.
    for n in [400, 150] {
        let log = parse_imu_csv(
            &with_gaps(n, &[(100, 10.0)]),
            path(),
            &ImuCsvOptions::default(),
        )
        .unwrap();
        assert_eq!((log.rows.len(), log.rejected.len()), (n, 0));
        assert!(log.rows.windows(2).all(|w| w[1].line == w[0].line + 1));
    }
    // A row that goes back to the time before the jump after that second is refused, as
    // before (line 350 is 1.25 s after line 100).
    let text = replace_line(&with_gaps(400, &[(100, 10.0)]), 350, &row(0.5));
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    let rejected: Vec<_> = log.rejected.iter().map(|r| (r.line, r.reason)).collect();
    assert_eq!(rejected, [(350, RejectReason::TimeNotIncreasing)]);
}

#[test]
fn a_clock_set_back_runs_on_from_the_step_and_its_first_row_goes_out() {
    // Every row from line 100 on 0.3 s earlier (a host clock set back). Before, the 60 rows up
    // to the old time were rejected as not increasing: 15 % of this log, so it was refused
    // whole. Now line 100 is held until line 101 follows it, and both go out (the estimator
    // behind the reader refuses line 100 and judges the step from the rates).
    assert_every_row_kept_in_order(&[(100, -0.3)]);
    // A step back beyond max_dt_s (1 s) is not one: the rows are refused until the time passes
    // the last accepted one, as before.
    let opts = ImuCsvOptions {
        max_rejected_fraction: 0.5,
        ..ImuCsvOptions::default()
    };
    // A stray earlier row between a real gap's far side and the row that confirms it: only the
    // stray row is rejected.
    let text = replace_line(&with_gaps(400, &[(100, 10.0)]), 101, &row(0.3));
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    let rejected: Vec<_> = log.rejected.iter().map(|r| (r.line, r.reason)).collect();
    assert_eq!(rejected, [(101, RejectReason::TimeNotIncreasing)]);
    assert_eq!((log.rows.len(), log.rows[98].line), (399, 100));
    // A jump held, then a step back confirmed: the jump is rejected, the row that went back
    // goes out (a review found the jump passed on in its place).
    let mut text = with_gaps(400, &[(101, -0.3)]);
    text = replace_line(&text, 100, &row(1e30));
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    let rejected: Vec<_> = log.rejected.iter().map(|r| (r.line, r.reason)).collect();
    assert_eq!(rejected, [(100, RejectReason::TimeJump)]);
    assert_eq!((log.rows.len(), log.rows[98].line), (399, 101));
    let log = parse_imu_csv(&with_gaps(1000, &[(100, -1.5)]), path(), &opts).unwrap();
    let before_s = log.rows[97].t_s;
    assert_eq!(log.rows[97].line, 99);
    let behind = log.rows[98..].iter().all(|r| r.t_s > before_s);
    assert!(behind && log.rows[98].line > 390, "{:?}", log.rows[98]);
    assert_eq!(
        log.rejected_counts()["time_not_increasing"] as usize,
        1000 - log.rows.len()
    );
}

#[test]
fn duplicate_timestamp_is_rejected() {
    let text = replace_line(&good_file(200), 4, &row(0.005));
    let log = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!(log.rows.len(), 199);
    assert_eq!(log.rejected.len(), 1);
    assert_eq!(log.rejected[0].line, 4);
    assert_eq!(log.rejected[0].reason, RejectReason::TimeNotIncreasing);
    assert_eq!(log.rejected[0].value, "0.005");
}

#[test]
fn stamps_glitched_a_gaps_length_ahead_two_or_more_in_a_row_are_rejected_and_the_rows_after_them_kept()
 {
    // Lines 100.. put 0.9 s ahead (a gap's length, within `sensor.max_dt_s`): before session
    // 37 they were a gap's far side and every row of the next 0.9 s was rejected as not
    // increasing (180 rows).
    for n_glitched in [2, 3, 40] {
        assert_glitched_rows_rejected(0.9, n_glitched);
    }
    // A real gap of 0.5 s: the rows after it are held for the run's 1 s, then go out, in order
    // and all of them.
    assert_every_row_kept_in_order(&[(100, 0.5)]);
    // Rows 100..160 lost and one of them (t of line 130) written after line 180: refused as
    // not increasing, every other row kept (a review: it was taken for the clock's return, the
    // 20 rows since the gap rejected as glitched, and a log with 8 such places refused whole).
    let mut lines: Vec<String> = good_file(5000).lines().map(String::from).collect();
    let late = lines[129].clone();
    lines.insert(181, late);
    lines.drain(99..159);
    let log = parse_imu_csv(
        &(lines.join("\n") + "\n"),
        path(),
        &ImuCsvOptions::default(),
    )
    .unwrap();
    let rejected: Vec<_> = log.rejected.iter().map(|r| r.reason).collect();
    assert_eq!(rejected, [RejectReason::TimeNotIncreasing]);
    assert_eq!(log.rows.len(), 5000 - 60);
}

/// 400 rows with the given gaps (from a line on, every row that much later): every row read,
/// none rejected, in file order.
fn assert_every_row_kept_in_order(gaps: &[(u64, f64)]) {
    let log = parse_imu_csv(&with_gaps(400, gaps), path(), &ImuCsvOptions::default()).unwrap();
    assert_eq!((log.rows.len(), log.rejected.len()), (400, 0), "{gaps:?}");
    assert!(
        log.rows.windows(2).all(|w| w[1].line == w[0].line + 1),
        "{gaps:?}"
    );
}
