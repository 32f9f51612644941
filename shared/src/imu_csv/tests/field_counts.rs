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
