//! A row whose field count differs from the header's: what its rejection says.

use super::*;

#[test]
fn a_row_with_a_trailing_comma_the_header_lacks_is_said_so() {
    // It said "(8 fields, the header has 7)" of a row of seven numbers and a comma, and a long
    // row's comma fell after the value's cut (a review).
    let long = "0.01,0.0100000000000001,0.0200000000000001,0.0300000000000001,0.1,0.2,9.8,";
    let text = replace_line(&good_file(200), 3, "0.005,0.01,0.02,0.03,0.1,0.2,9.8,");
    let text = replace_line(&text, 4, long);
    let log = parse_imu_csv(&text, path(), &lenient()).unwrap();
    assert_eq!(log.rejected.len(), 2);
    assert_eq!(
        log.rejected[0].to_string(),
        "line 3: row \"0.005,0.01,0.02,0.03,0.1,0.2,9.8,\" is malformed (8 fields, the header \
         has 7: the row ends with a comma, an empty field 8 the header does not have)"
    );
    assert!(!log.rejected[1].value.ends_with(','), "{}", log.rejected[1]);
    assert!(
        log.rejected[1]
            .to_string()
            .ends_with("(8 fields, the header has 7: the row ends with a comma, an empty field 8 the header does not have)"),
        "{}",
        log.rejected[1]
    );
    // A row short of a field and ending with a comma: its count, and its comma.
    let text = replace_line(&good_file(200), 3, "0.005,0.01,0.02,0.03,0.1,");
    let log = parse_imu_csv(&text, path(), &lenient()).unwrap();
    assert!(
        log.rejected[0]
            .to_string()
            .ends_with("(6 fields, the header has 7: the row ends with a comma, an empty field 6)"),
        "{}",
        log.rejected[0]
    );
    // A row without the comma is said as before.
    let text = replace_line(&good_file(200), 3, "0.005,0.01,0.02,0.03,0.1,0.2,9.8,7");
    let log = parse_imu_csv(&text, path(), &lenient()).unwrap();
    assert!(
        log.rejected[0]
            .to_string()
            .ends_with("(8 fields, the header has 7)"),
        "{}",
        log.rejected[0]
    );
}

#[test]
fn a_semicolon_or_tab_separated_file_is_said_to_be_one() {
    // A semicolon-separated export gave "(1 fields, the header has 7)" with no word of its
    // separator (a review).
    let semi = good_file(200).replace(',', ";");
    let rows = format!("{HEADER}\n{}", semi.split_once('\n').unwrap().1);
    let e = parse_imu_csv(&rows, path(), &ImuCsvOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.ends_with(
            "data/imu.csv:2: row \"0;0.01;-0.02;0.03;0.1;0.2;9.8\" is malformed (1 field, the header \
             has 7: the row has semicolons and no comma: the file looks semicolon-separated, \
             and corridor reads comma-separated CSV)"
        ),
        "{e}"
    );
    let tabs = good_file(200).replace(',', "\t");
    let rows = format!("{HEADER}\n{}", tabs.split_once('\n').unwrap().1);
    let e = parse_imu_csv(&rows, path(), &ImuCsvOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.ends_with("(1 field, the header has 7: the row has tabs and no comma: the file looks tab-separated, and corridor reads comma-separated CSV)"),
        "{e}"
    );
    // The whole file: its header says it.
    let e = parse_imu_csv(&semi, path(), &ImuCsvOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with(
            "data/imu.csv:1: header does not start with the required columns (the header has \
             semicolons and no comma: the file looks semicolon-separated, and corridor reads \
             comma-separated CSV): it must start with"
        ),
        "{e}"
    );
    let e = parse_imu_csv(&tabs, path(), &ImuCsvOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("(the header has tabs and no comma: the file looks tab-separated"),
        "{e}"
    );
    // One field of a number without a separator: its count alone, in the singular.
    let text = replace_line(&good_file(200), 3, "0.005");
    let log = parse_imu_csv(&text, path(), &lenient()).unwrap();
    assert_eq!(
        log.rejected[0].to_string(),
        "line 3: row \"0.005\" is malformed (1 field, the header has 7)"
    );
    // A header with commas whose names are wrong: no word of separators.
    let text = good_file(200).replacen("gx_rad_s", "gx;rad_s", 1);
    let e = parse_imu_csv(&text, path(), &ImuCsvOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("required columns: it must"), "{e}");
}
