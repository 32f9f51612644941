//! Reader for surveyed footprint ground truth (`ground_truth.csv`).
//!
//! The header is exactly [`TRUTH_HEADER`] (`t_s,x_m,y_m,z_m`) or [`TRUTH_HEADER_WITH_STRIDE`]
//! (`t_s,x_m,y_m,z_m,stride,sample_index`). The truth is small and hand-made, so the reader is
//! strict: any bad row is an error that names the file, line, column and value. Like the IMU
//! reader it tolerates a UTF-8 byte-order mark, CRLF line ends, blank lines at the end and
//! spaces around fields.

use crate::imu_csv::{escape_controls, truncate_chars, unquote};
use std::fmt;
use std::path::{Path, PathBuf};

/// The ground-truth header without stride annotation.
pub const TRUTH_HEADER: &str = "t_s,x_m,y_m,z_m";

/// The ground-truth header with the stride number and IMU sample index of each point.
pub const TRUTH_HEADER_WITH_STRIDE: &str = "t_s,x_m,y_m,z_m,stride,sample_index";

/// Column names of the longest accepted header, in order.
const COLUMNS: [&str; 6] = ["t_s", "x_m", "y_m", "z_m", "stride", "sample_index"];

/// Longest text (in characters) quoted from the file in an error.
const MAX_VALUE_CHARS: usize = 64;

/// Longest header text (in characters) quoted in [`TruthCsvError::Header`].
const MAX_HEADER_CHARS: usize = 200;

/// Largest footprint coordinate accepted, m: a building's survey spans far less.
pub const MAX_COORDINATE_M: f64 = 1e6;

/// One surveyed footprint position.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TruthPoint {
    /// Time of the point in seconds, on the IMU log's clock (strictly increasing over the file).
    pub t_s: f64,
    /// Position along the local floor frame's x axis in metres.
    pub x_m: f64,
    /// Position along the local floor frame's y axis in metres.
    pub y_m: f64,
    /// Height in metres (z up).
    pub z_m: f64,
    /// The dataset authors' stride number (0 = initial standing position), when the file has it.
    pub stride: Option<i64>,
    /// 0-based row of the matching sample in `imu.csv` (data rows, header excluded), when the file has it.
    pub sample_index: Option<u64>,
}

/// A ground-truth file that could not be used. Every message names the file, and for row errors
/// the line, column and value.
#[derive(Debug, thiserror::Error)]
pub enum TruthCsvError {
    /// The file could not be read (or is not UTF-8).
    #[error("{path}: cannot read ground truth CSV: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS or decoding error.
        source: std::io::Error,
    },
    /// The header (line 1) is not one of the two accepted headers.
    #[error("{path}:1: header must be \"{expected}\" but found \"{found}\"")]
    Header {
        /// The file.
        path: PathBuf,
        /// The header line as found (at most 200 characters, control characters escaped).
        found: String,
        /// The accepted headers.
        expected: &'static str,
    },
    /// A data row is bad.
    #[error("{path}:{line}{}", row_tail(.column, .value, .reason))]
    Row {
        /// The file.
        path: PathBuf,
        /// 1-based line number (the header is line 1).
        line: u64,
        /// The offending column's name, or `""` when the whole row is at fault.
        column: String,
        /// The offending text (the field, or the row when `column` is empty), at most 64 characters.
        value: String,
        /// What is wrong, e.g. `is not a number`.
        reason: String,
    },
    /// The file has no data rows.
    #[error("{path}: no ground-truth points (the file is empty or holds only a header)")]
    Empty {
        /// The file.
        path: PathBuf,
    },
}

/// The part of [`TruthCsvError::Row`]'s message after the line number.
fn row_tail<'a>(column: &'a str, value: &'a str, reason: &'a str) -> RowTail<'a> {
    RowTail {
        column,
        value,
        reason,
    }
}

/// Formats the part of [`TruthCsvError::Row`] after the line number.
struct RowTail<'a> {
    column: &'a str,
    value: &'a str,
    reason: &'a str,
}

impl fmt::Display for RowTail<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Control characters escaped: a terminal would act on them rather than show them.
        let value = escape_controls(self.value);
        if self.column.is_empty() {
            write!(f, ": row \"{value}\" {}", self.reason)
        } else {
            write!(
                f,
                " column {}: value \"{value}\" {}",
                self.column, self.reason
            )
        }
    }
}

/// Reads and parses the ground-truth file at `path`; see [`parse_truth_csv`].
pub fn read_truth_csv(path: &Path) -> Result<Vec<TruthPoint>, TruthCsvError> {
    let text = crate::text_file::read_text(path).map_err(|source| TruthCsvError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_truth_csv(&text, path)
}

/// Parses ground-truth CSV `text` (the content of the file `path`, which is only used in messages).
///
/// Names and values may be quoted (`"t_s"`, `"1.5"`: spreadsheets and `csv.QUOTE_ALL` write
/// them so), as in the IMU reader. Strict: a wrong field count, a field that is not a number (or not an integer for `stride`,
/// not a non-negative integer for `sample_index`), a non-finite value, a blank line between rows
/// or a `t_s` that is not greater than the previous row's is an error.
pub fn parse_truth_csv(text: &str, path: &Path) -> Result<Vec<TruthPoint>, TruthCsvError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let empty = || TruthCsvError::Empty {
        path: path.to_path_buf(),
    };
    if text.trim().is_empty() {
        return Err(empty());
    }
    let mut lines = text.split('\n');
    let header = strip_cr(lines.next().unwrap_or(""));
    let names: Vec<&str> = header.split(',').map(unquote).collect();
    let n_fields = match names.len() {
        4 | 6 if names[..] == COLUMNS[..names.len()] => names.len(),
        _ => {
            return Err(TruthCsvError::Header {
                path: path.to_path_buf(),
                found: escape_controls(&truncate_chars(header, MAX_HEADER_CHARS)).into_owned(),
                expected: "t_s,x_m,y_m,z_m\" or \"t_s,x_m,y_m,z_m,stride,sample_index",
            });
        }
    };

    let row_error = |line: u64, column: &str, value: &str, reason: String| TruthCsvError::Row {
        path: path.to_path_buf(),
        line,
        column: column.to_string(),
        value: truncate_chars(value, MAX_VALUE_CHARS),
        reason,
    };
    let mut points = Vec::new();
    let mut first_blank: Option<u64> = None;
    let mut line_no: u64 = 1;
    for raw in lines {
        line_no += 1;
        let line = strip_cr(raw);
        if line.trim_ascii().is_empty() {
            first_blank.get_or_insert(line_no);
            continue;
        }
        if let Some(blank) = first_blank {
            return Err(row_error(
                blank,
                "",
                "",
                "is blank (blank lines are allowed only at the end)".into(),
            ));
        }
        let fields: Vec<&str> = line.split(',').map(unquote).collect();
        if fields.len() != n_fields {
            return Err(row_error(
                line_no,
                "",
                line,
                format!(
                    "has {} fields but the header has {n_fields}{}",
                    fields.len(),
                    // (as the IMU reader says it: a trailing comma is the usual cause)
                    if fields.len() == n_fields + 1 && fields[n_fields].is_empty() {
                        ": the row ends with a comma"
                    } else {
                        ""
                    }
                ),
            ));
        }
        let mut xyzt = [0.0f64; 4];
        for (i, v) in xyzt.iter_mut().enumerate() {
            *v = match fields[i].parse::<f64>() {
                // Positions within 1000 km of the survey's origin (a footprint at 1e300 m made
                // the evaluation's RMS null, with exit 0).
                Ok(x) if i > 0 && x.is_finite() && x.abs() > MAX_COORDINATE_M => {
                    return Err(row_error(
                        line_no,
                        COLUMNS[i],
                        fields[i],
                        format!("is beyond ±{MAX_COORDINATE_M:e} m of the survey's origin"),
                    ));
                }
                Ok(x) if x.is_finite() => x,
                Ok(_) => {
                    return Err(row_error(
                        line_no,
                        COLUMNS[i],
                        fields[i],
                        "is not finite".into(),
                    ));
                }
                Err(_) => {
                    return Err(row_error(
                        line_no,
                        COLUMNS[i],
                        fields[i],
                        "is not a number".into(),
                    ));
                }
            };
        }
        let (stride, sample_index) = if n_fields == 6 {
            let stride = fields[4].parse::<i64>().map_err(|_| {
                row_error(line_no, COLUMNS[4], fields[4], "is not an integer".into())
            })?;
            let sample_index = fields[5].parse::<u64>().map_err(|_| {
                row_error(
                    line_no,
                    COLUMNS[5],
                    fields[5],
                    "is not a non-negative integer".into(),
                )
            })?;
            (Some(stride), Some(sample_index))
        } else {
            (None, None)
        };
        let [t_s, x_m, y_m, z_m] = xyzt;
        if let Some(prev) = points.last().map(|p: &TruthPoint| p.t_s)
            && t_s <= prev
        {
            return Err(row_error(
                line_no,
                COLUMNS[0],
                fields[0],
                format!("is not after the previous row's t_s ({prev})"),
            ));
        }
        points.push(TruthPoint {
            t_s,
            x_m,
            y_m,
            z_m,
            stride,
            sample_index,
        });
    }
    if points.is_empty() {
        return Err(empty());
    }
    Ok(points)
}

/// Removes one trailing `\r` (CRLF line ends).
fn strip_cr(line: &str) -> &str {
    line.strip_suffix('\r').unwrap_or(line)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path() -> &'static Path {
        Path::new("data/ground_truth.csv")
    }

    #[test]
    fn short_header_variant() {
        let pts = parse_truth_csv(
            "t_s,x_m,y_m,z_m\n0.0,0.0,0.0,0.0\n70.73208332,1.5,-2.25,0.0\n",
            path(),
        )
        .unwrap();
        assert_eq!(
            pts,
            vec![
                TruthPoint {
                    t_s: 0.0,
                    x_m: 0.0,
                    y_m: 0.0,
                    z_m: 0.0,
                    stride: None,
                    sample_index: None
                },
                TruthPoint {
                    t_s: 70.73208332,
                    x_m: 1.5,
                    y_m: -2.25,
                    z_m: 0.0,
                    stride: None,
                    sample_index: None
                },
            ]
        );
    }

    #[test]
    fn stride_header_variant_with_bom_crlf_and_spaces() {
        let text = "\u{feff}t_s, x_m ,y_m,z_m,stride,sample_index\r\n2.359881878,0.0,0.0,0.0,0,472\r\n 8.989739418 ,0.0,9.0,0.0, 6 ,1798\r\n\r\n";
        let pts = parse_truth_csv(text, path()).unwrap();
        assert_eq!(pts.len(), 2);
        assert_eq!(
            pts[1],
            TruthPoint {
                t_s: 8.989739418,
                x_m: 0.0,
                y_m: 9.0,
                z_m: 0.0,
                stride: Some(6),
                sample_index: Some(1798),
            }
        );
        assert_eq!((pts[0].stride, pts[0].sample_index), (Some(0), Some(472)));
    }

    #[test]
    fn quoted_names_and_values_read_as_unquoted() {
        // As spreadsheets and Python's csv.QUOTE_ALL write them (the header was refused).
        let quoted = "\"t_s\",\"x_m\",\"y_m\",\"z_m\",\"stride\",\"sample_index\"\n\
                      \"2.5\",\"1.0\",\"-2.0\",\"0.0\",\"3\",\"472\"\n";
        let plain = "t_s,x_m,y_m,z_m,stride,sample_index\n2.5,1.0,-2.0,0.0,3,472\n";
        assert_eq!(
            parse_truth_csv(quoted, path()).unwrap(),
            parse_truth_csv(plain, path()).unwrap()
        );
        // A quote left open is still a bad value, named as the file has it.
        let err = parse_truth_csv("t_s,x_m,y_m,z_m\n\"2.5,1,2,3\n", path()).unwrap_err();
        assert!(
            err.to_string().contains("value \"\"2.5\" is not a number"),
            "{err}"
        );
    }

    #[test]
    fn wrong_header_is_an_error() {
        for header in [
            "t,x,y,z",
            "t_s,x_m,y_m",
            "t_s,x_m,y_m,z_m,stride",
            "x_m,t_s,y_m,z_m",
        ] {
            let err = parse_truth_csv(&format!("{header}\n0,0,0,0\n"), path()).unwrap_err();
            assert!(matches!(err, TruthCsvError::Header { .. }), "{err:?}");
            let msg = err.to_string();
            assert_eq!(
                msg,
                format!(
                    "data/ground_truth.csv:1: header must be \"t_s,x_m,y_m,z_m\" or \
                     \"t_s,x_m,y_m,z_m,stride,sample_index\" but found \"{header}\""
                )
            );
        }
        // Control characters are shown escaped, in the header as in a row.
        let err = parse_truth_csv("t_s,x_m,\x1b[2J\ty_m\n", path()).unwrap_err();
        assert!(
            err.to_string()
                .ends_with("found \"t_s,x_m,\\x1b[2J\\ty_m\""),
            "{err}"
        );
        let err = parse_truth_csv("t_s,x_m,y_m,z_m\n0,0,\x07,0\n", path()).unwrap_err();
        assert!(err.to_string().contains("value \"\\x07\""), "{err}");
    }

    fn row_err(text: &str) -> (u64, String, String, String) {
        match parse_truth_csv(text, path()).unwrap_err() {
            TruthCsvError::Row {
                line,
                column,
                value,
                reason,
                ..
            } => (line, column, value, reason),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn bad_number_names_line_column_and_value() {
        let text = "t_s,x_m,y_m,z_m\n0.0,0.0,0.0,0.0\n1.0,1.0,abc,0.0\n";
        let err = parse_truth_csv(text, path()).unwrap_err();
        assert_eq!(
            err.to_string(),
            "data/ground_truth.csv:3 column y_m: value \"abc\" is not a number"
        );
        let (line, column, value, _) = row_err(text);
        assert_eq!((line, column.as_str(), value.as_str()), (3, "y_m", "abc"));
    }

    #[test]
    fn other_bad_rows_are_errors() {
        let h6 = "t_s,x_m,y_m,z_m,stride,sample_index\n";
        let cases = [
            (
                format!("{h6}0,0,0,0,0,1\n1,0,0\n"),
                (3, "", "1,0,0", "has 3 fields but the header has 6"),
            ),
            (
                format!("{h6}0,0,0,0,0,1,\n"),
                (
                    2,
                    "",
                    "0,0,0,0,0,1,",
                    "has 7 fields but the header has 6: the row ends with a comma",
                ),
            ),
            (
                format!("{h6}0,0,0,inf,0,1\n"),
                (2, "z_m", "inf", "is not finite"),
            ),
            (
                format!("{h6}0,1e300,0,0,0,1\n"),
                (2, "x_m", "1e300", "is beyond ±1e6 m of the survey's origin"),
            ),
            (
                format!("{h6}0,0,0,0,1.5,1\n"),
                (2, "stride", "1.5", "is not an integer"),
            ),
            (
                format!("{h6}0,0,0,0,1,-3\n"),
                (2, "sample_index", "-3", "is not a non-negative integer"),
            ),
            (
                format!("{h6}1,0,0,0,0,1\n1,0,0,0,1,2\n"),
                (3, "t_s", "1", "is not after the previous row's t_s (1)"),
            ),
            (
                format!("{h6}1,0,0,0,0,1\n0.5,0,0,0,1,2\n"),
                (3, "t_s", "0.5", "is not after the previous row's t_s (1)"),
            ),
            (
                format!("{h6}0,0,0,0,0,1\n\n2,0,0,0,1,2\n"),
                (
                    3,
                    "",
                    "",
                    "is blank (blank lines are allowed only at the end)",
                ),
            ),
        ];
        for (text, (line, column, value, reason)) in cases {
            let got = row_err(&text);
            assert_eq!(
                (got.0, got.1.as_str(), got.2.as_str(), got.3.as_str()),
                (line, column, value, reason),
                "{text:?}"
            );
        }
        let err = parse_truth_csv(&format!("{h6}0,0,0,0,0,1\n1,0,0\n"), path()).unwrap_err();
        assert_eq!(
            err.to_string(),
            "data/ground_truth.csv:3: row \"1,0,0\" has 3 fields but the header has 6"
        );
    }

    #[test]
    fn empty_and_io_errors_name_the_file() {
        for text in ["", "\u{feff}\r\n", "t_s,x_m,y_m,z_m\n\n"] {
            let err = parse_truth_csv(text, path()).unwrap_err();
            assert!(matches!(err, TruthCsvError::Empty { .. }), "{err:?}");
            assert!(
                err.to_string()
                    .starts_with("data/ground_truth.csv: no ground-truth points")
            );
        }
        let err = read_truth_csv(Path::new("/nonexistent/corridor/ground_truth.csv")).unwrap_err();
        assert!(matches!(err, TruthCsvError::Io { .. }));
        assert!(
            err.to_string()
                .starts_with("/nonexistent/corridor/ground_truth.csv: cannot read")
        );
    }
}
