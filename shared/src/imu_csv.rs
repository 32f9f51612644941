//! Reader for IMU logs in the corridor CSV format.
//!
//! The header's first seven columns must be exactly [`IMU_HEADER`]
//! (`t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2`). More columns may follow, for example
//! `mx_gauss,my_gauss,mz_gauss` or `temp_c`; a `temp_c` column is read into [`ImuRow::temp_c`], the
//! others are kept only by name in [`ImuLog::extra_columns`] and their values are not parsed.
//!
//! The reader tolerates a UTF-8 byte-order mark, CRLF line ends, blank lines at the end of the file
//! and spaces or tabs around fields. It is a hand-rolled single pass over the bytes of each line
//! (fields split at `,` eight bytes at a time, numbers read with [`str::parse::<f64>`]); on the
//! 21 001-row exp29 log it parses about 2.5 million rows per second on one core
//! (`cargo bench -p corridor-shared --bench csv_parse`).
//!
//! Bad rows are never dropped silently. A row with the wrong number of fields, a field that is not a
//! number, a non-finite value or a timestamp that does not increase is moved to
//! [`ImuLog::rejected`] with its line, column, text and [`RejectReason`]. If more than
//! [`ImuCsvOptions::max_rejected_fraction`] of the data rows are rejected, the whole file is
//! refused with [`ImuCsvError::TooManyRejected`]. Finally a units check on the accepted rows
//! refuses accelerometers logged in g and gyroscopes logged in deg/s ([`ImuCsvError::Units`]).

use crate::sensor::{TimeGuard, TimeVerdict};
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

/// The seven columns every IMU CSV header must start with, in this order.
pub const IMU_HEADER: &str = "t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2";

/// The names of the seven required columns, in file order.
const REQUIRED_COLUMNS: [&str; 7] = [
    "t_s", "gx_rad_s", "gy_rad_s", "gz_rad_s", "ax_m_s2", "ay_m_s2", "az_m_s2",
];

/// Name of the optional temperature column (degrees Celsius).
pub const TEMPERATURE_COLUMN: &str = "temp_c";

/// Longest text (in characters) kept in [`RejectedRow::value`] and in error messages.
const MAX_VALUE_CHARS: usize = 64;

/// Longest header text (in characters) quoted in [`ImuCsvError::Header`].
const MAX_HEADER_CHARS: usize = 200;

/// Median |a| range (m/s²) that means the accelerometer was logged in g.
const ACCEL_LOOKS_LIKE_G_M_S2: (f64, f64) = (0.5, 2.0);

/// Plausible median |a| range (m/s²) for specific force of a walking foot (gravity included).
const ACCEL_PLAUSIBLE_MEDIAN_M_S2: (f64, f64) = (5.0, 20.0);

/// Largest plausible |ω| (rad/s) of a foot-mounted MEMS gyro (≈ 2300 °/s; real peaks are ≈ 12 rad/s).
const GYRO_MAX_PLAUSIBLE_RAD_S: f64 = 40.0;

/// Standard gravity (m/s² per g), used in the unit hints.
const STANDARD_GRAVITY_M_S2: f64 = 9.80665;

/// One accepted IMU sample.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ImuRow {
    /// Sample time in seconds (strictly increasing over the accepted rows).
    pub t_s: f64,
    /// Angular rate about the body x, y, z axes in rad/s.
    pub gyro_rad_s: [f64; 3],
    /// Specific force along the body x, y, z axes in m/s² (points up at rest).
    pub accel_m_s2: [f64; 3],
    /// Sensor temperature in °C; `Some` exactly when the file has a `temp_c` column.
    pub temp_c: Option<f64>,
    /// 1-based line number of this row in the file (the header is line 1).
    pub line: u64,
}

/// Why a data row was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RejectReason {
    /// The row does not have as many fields as the header, or a field is not a number.
    Malformed,
    /// A field parsed to NaN or ±infinity.
    NonFinite,
    /// `t_s` is not greater than the previous accepted row's `t_s` (duplicates included).
    TimeNotIncreasing,
    /// `t_s` jumps forward by more than [`ImuCsvOptions::max_dt_s`] and the next row does not
    /// follow it (an outlier such as `1e30`; the first row after a real gap also lands here).
    TimeJump,
}

impl RejectReason {
    /// All reasons, in the order used by [`ImuLog::rejected_counts`].
    pub const ALL: [RejectReason; 4] = [
        RejectReason::Malformed,
        RejectReason::NonFinite,
        RejectReason::TimeNotIncreasing,
        RejectReason::TimeJump,
    ];

    /// Stable snake_case name of the reason (`malformed`, `non_finite`, `time_not_increasing`,
    /// `time_jump`).
    pub fn name(self) -> &'static str {
        match self {
            RejectReason::Malformed => "malformed",
            RejectReason::NonFinite => "non_finite",
            RejectReason::TimeNotIncreasing => "time_not_increasing",
            RejectReason::TimeJump => "time_jump",
        }
    }
}

impl fmt::Display for RejectReason {
    /// A predicate phrase that completes "value "…" …", e.g. `is not finite`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RejectReason::Malformed => "is malformed",
            RejectReason::NonFinite => "is not finite",
            RejectReason::TimeNotIncreasing => "is not after the previous accepted t_s",
            RejectReason::TimeJump => {
                "jumps beyond the largest time step after the previous accepted t_s"
            }
        })
    }
}

/// A data row that was not accepted, with where and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RejectedRow {
    /// 1-based line number in the file (the header is line 1).
    pub line: u64,
    /// Name of the offending column, or `""` when the whole row is at fault (wrong field count).
    pub column: String,
    /// The offending text (the field, or the whole row when `column` is empty), at most 64 characters.
    pub value: String,
    /// Why the row was rejected.
    pub reason: RejectReason,
}

impl RejectedRow {
    /// Displays the rejection prefixed with the file, as `data/imu.csv:1523 column gy_rad_s: value "nan" is not finite`.
    pub fn located<'a>(&'a self, path: &'a Path) -> impl fmt::Display + 'a {
        Located { row: self, path }
    }

    /// Writes everything after the line number: ` column c: value "v" reason` or `: row "v" reason`.
    fn fmt_tail(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.column.is_empty() {
            write!(f, ": row \"{}\" {}", self.value, self.reason)?;
            if self.reason == RejectReason::Malformed {
                f.write_str(" (its field count differs from the header's)")?;
            }
        } else {
            write!(
                f,
                " column {}: value \"{}\" {}",
                self.column, self.value, self.reason
            )?;
            if self.reason == RejectReason::Malformed {
                f.write_str(" (not a number)")?;
            }
        }
        Ok(())
    }
}

impl fmt::Display for RejectedRow {
    /// `line 1523 column gy_rad_s: value "nan" is not finite`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}", self.line)?;
        self.fmt_tail(f)
    }
}

/// [`RejectedRow`] displayed with its file name; see [`RejectedRow::located`].
struct Located<'a> {
    row: &'a RejectedRow,
    path: &'a Path,
}

impl fmt::Display for Located<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.path.display(), self.row.line)?;
        self.row.fmt_tail(f)
    }
}

/// A parsed IMU log: the accepted samples and every rejected row.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImuLog {
    /// The file the log was read from (or the name given to [`parse_imu_csv`]).
    pub path: PathBuf,
    /// Accepted samples in file order; `t_s` is strictly increasing.
    pub rows: Vec<ImuRow>,
    /// Rejected data rows in file order, each with its reason.
    pub rejected: Vec<RejectedRow>,
    /// Whether the file has a `temp_c` column (then every row has `temp_c: Some(_)`).
    pub has_temperature: bool,
    /// Names of the header columns after the seven required ones, in order (including `temp_c`).
    pub extra_columns: Vec<String>,
}

impl ImuLog {
    /// Number of rejected rows per reason name ([`RejectReason::name`]); every reason is present,
    /// with 0 when it never occurred.
    pub fn rejected_counts(&self) -> BTreeMap<&'static str, u64> {
        let mut counts: BTreeMap<&'static str, u64> =
            RejectReason::ALL.iter().map(|r| (r.name(), 0)).collect();
        for r in &self.rejected {
            *counts.entry(r.reason.name()).or_insert(0) += 1;
        }
        counts
    }
}

/// Options for [`read_imu_csv`] and [`parse_imu_csv`].
#[derive(Debug, Clone, PartialEq)]
pub struct ImuCsvOptions {
    /// Largest allowed fraction of rejected data rows (rejected / all data rows); above it the
    /// file is refused with [`ImuCsvError::TooManyRejected`]. Default 0.01. A NaN is treated as 0.
    pub max_rejected_fraction: f64,
    /// Whether to run the units check (accelerometer in m/s², gyroscope in rad/s). Default `true`.
    pub check_units: bool,
    /// A row must follow the previous accepted one by more than this, s. Default 0.
    pub min_dt_s: f64,
    /// A row more than this after the previous accepted one is a time jump, accepted only when
    /// the next row confirms it ([`crate::sensor::TimeGuard`]), s. Default
    /// [`crate::sensor::DEFAULT_MAX_DT_S`].
    pub max_dt_s: f64,
}

impl Default for ImuCsvOptions {
    fn default() -> Self {
        Self {
            max_rejected_fraction: 0.01,
            check_units: true,
            min_dt_s: 0.0,
            max_dt_s: crate::sensor::DEFAULT_MAX_DT_S,
        }
    }
}

/// An IMU CSV file that could not be used. Every message names the file, and where relevant the
/// line, column and value.
#[derive(Debug, thiserror::Error)]
pub enum ImuCsvError {
    /// The file could not be read (or is not UTF-8; the message then names the line).
    #[error("{path}: cannot read IMU CSV: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS or decoding error.
        source: std::io::Error,
    },
    /// The header (line 1) is missing or does not start with the required columns, or it has an
    /// empty or repeated column name.
    #[error("{path}:1: header must start with \"{expected}\" but found \"{found}\"")]
    Header {
        /// The file.
        path: PathBuf,
        /// The header line as found (at most 200 characters).
        found: String,
        /// What the header must look like.
        expected: &'static str,
    },
    /// The accepted rows do not look like m/s² (accelerometer) or rad/s (gyroscope).
    #[error("{path}: column {column}: {statistic} = {value:.4}; {hint}")]
    Units {
        /// The file.
        path: PathBuf,
        /// The column or columns checked, e.g. `ax_m_s2,ay_m_s2,az_m_s2`.
        column: &'static str,
        /// The statistic, e.g. `median |a| (m/s²)` or `max |ω| (rad/s) at line 812`.
        statistic: String,
        /// The statistic's value.
        value: f64,
        /// What is probably wrong and how to fix it.
        hint: String,
    },
    /// More than the allowed fraction of data rows was rejected.
    #[error(
        "{path}: {rejected} of {total} data rows rejected, more than the allowed fraction {max_rejected_fraction}; first: {}",
        .first.located(.path)
    )]
    TooManyRejected {
        /// The file.
        path: PathBuf,
        /// Number of rejected data rows.
        rejected: u64,
        /// Number of data rows (accepted + rejected).
        total: u64,
        /// The allowed fraction ([`ImuCsvOptions::max_rejected_fraction`]).
        max_rejected_fraction: f64,
        /// The first rejected row.
        first: RejectedRow,
    },
    /// The file has no data rows (it is empty or holds only a header) or no row was accepted.
    #[error(
        "{path}: no IMU samples (the file is empty, holds only a header, or every row was rejected)"
    )]
    Empty {
        /// The file.
        path: PathBuf,
    },
}

/// Reads and parses the IMU CSV file at `path`; see [`parse_imu_csv`].
pub fn read_imu_csv(path: &Path, opts: &ImuCsvOptions) -> Result<ImuLog, ImuCsvError> {
    let bytes = std::fs::read(path).map_err(|source| ImuCsvError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = valid.iter().filter(|&&b| b == b'\n').count() + 1;
        ImuCsvError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!("line {line}: not valid UTF-8"),
            ),
        }
    })?;
    parse_imu_csv(&text, path, opts)
}

/// Parses IMU CSV `text` (the content of the file `path`, which is only used in messages).
///
/// Steps: header check, row parsing with rejection, rejected-fraction check, units check.
/// Returns [`ImuCsvError::Empty`] when there is no data row or no accepted row.
pub fn parse_imu_csv(text: &str, path: &Path, opts: &ImuCsvOptions) -> Result<ImuLog, ImuCsvError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    if text.trim().is_empty() {
        return Err(ImuCsvError::Empty {
            path: path.to_path_buf(),
        });
    }
    let bytes = text.as_bytes();
    let header_end = bytes
        .iter()
        .position(|&b| b == b'\n')
        .unwrap_or(bytes.len());
    let header = strip_cr(&text[..header_end]);
    let names: Vec<&str> = header.split(',').map(str::trim_ascii).collect();
    let header_ok = names.len() >= REQUIRED_COLUMNS.len()
        && names.iter().zip(REQUIRED_COLUMNS).all(|(a, b)| *a == b)
        && names.iter().all(|n| !n.is_empty())
        && names
            .iter()
            .enumerate()
            .all(|(i, n)| !names[..i].contains(n));
    if !header_ok {
        return Err(ImuCsvError::Header {
            path: path.to_path_buf(),
            found: truncate_chars(header, MAX_HEADER_CHARS),
            expected: IMU_HEADER,
        });
    }
    let n_fields = names.len();
    let temp_index = names.iter().position(|n| *n == TEMPERATURE_COLUMN);

    let mut rows: Vec<ImuRow> = Vec::new();
    let mut rejected: Vec<RejectedRow> = Vec::new();
    let mut blank_lines: Vec<u64> = Vec::new();
    let mut total: u64 = 0;
    let mut time = TimeGuard::new(opts.min_dt_s, opts.max_dt_s);
    let mut line_no: u64 = 1;
    let mut pos = header_end + 1; // start of the current line

    while pos < bytes.len() {
        line_no += 1;
        let first_non_space = bytes[pos..]
            .iter()
            .position(|&b| b == b'\n' || !b.is_ascii_whitespace())
            .map_or(bytes.len(), |i| pos + i);
        if first_non_space == bytes.len() || bytes[first_non_space] == b'\n' {
            // Blank lines are fine at the end of the file; in the middle they are malformed rows.
            blank_lines.push(line_no);
            pos = first_non_space + 1;
            continue;
        }
        for blank in blank_lines.drain(..) {
            total += 1;
            rejected.push(RejectedRow {
                line: blank,
                column: String::new(),
                value: String::new(),
                reason: RejectReason::Malformed,
            });
        }
        total += 1;
        let (line_end, result) = parse_row(text, pos, line_no, n_fields, temp_index);
        let line = strip_cr(&text[pos..line_end]);
        if rows.capacity() == 0 {
            // Size the buffer from the first row's length (rows of one file are about equally long).
            rows.reserve((bytes.len() - pos) / (line_end - pos + 1) * 9 / 8 + 16);
        }
        pos = line_end + 1;
        match result {
            Ok(row) => match time.check(row.t_s) {
                TimeVerdict::Accept => {
                    time.accept(row.t_s);
                    rows.push(row);
                }
                verdict => rejected.push(RejectedRow {
                    line: line_no,
                    column: REQUIRED_COLUMNS[0].to_string(),
                    value: truncate_chars(
                        line.split(',').next().unwrap_or("").trim_ascii(),
                        MAX_VALUE_CHARS,
                    ),
                    reason: if verdict == TimeVerdict::Jump {
                        RejectReason::TimeJump
                    } else {
                        RejectReason::TimeNotIncreasing
                    },
                }),
            },
            Err(RowProblem::FieldCount) => rejected.push(RejectedRow {
                line: line_no,
                column: String::new(),
                value: truncate_chars(line, MAX_VALUE_CHARS),
                reason: RejectReason::Malformed,
            }),
            Err(RowProblem::Field {
                index,
                text,
                reason,
            }) => rejected.push(RejectedRow {
                line: line_no,
                column: names[index].to_string(),
                value: truncate_chars(text, MAX_VALUE_CHARS),
                reason,
            }),
        }
    }

    if total == 0 {
        return Err(ImuCsvError::Empty {
            path: path.to_path_buf(),
        });
    }
    let max_fraction = if opts.max_rejected_fraction.is_nan() {
        0.0
    } else {
        opts.max_rejected_fraction
    };
    let n_rejected = rejected.len() as u64;
    if n_rejected as f64 > max_fraction * total as f64 {
        return Err(ImuCsvError::TooManyRejected {
            path: path.to_path_buf(),
            rejected: n_rejected,
            total,
            max_rejected_fraction: opts.max_rejected_fraction,
            first: rejected[0].clone(),
        });
    }
    if rows.is_empty() {
        return Err(ImuCsvError::Empty {
            path: path.to_path_buf(),
        });
    }
    if opts.check_units {
        check_units(&rows, path)?;
    }
    Ok(ImuLog {
        path: path.to_path_buf(),
        rows,
        rejected,
        has_temperature: temp_index.is_some(),
        extra_columns: names[REQUIRED_COLUMNS.len()..]
            .iter()
            .map(|s| s.to_string())
            .collect(),
    })
}

/// What is wrong with one data row.
enum RowProblem<'a> {
    /// The field count differs from the header's.
    FieldCount,
    /// The first bad field: its index, its (trimmed) text and why.
    Field {
        index: usize,
        text: &'a str,
        reason: RejectReason,
    },
}

/// Parses the non-blank data line that starts at byte `start` of `text`, in one pass over its
/// bytes. Returns the index of the line's end (its `\n`, or the end of the text) and the row;
/// time ordering is checked by the caller.
#[inline]
fn parse_row(
    text: &str,
    start: usize,
    line_no: u64,
    n_fields: usize,
    temp_index: Option<usize>,
) -> (usize, Result<ImuRow, RowProblem<'_>>) {
    let bytes = text.as_bytes();
    let mut values = [0.0f64; 7];
    let mut temp_c: Option<f64> = None;
    let mut problem: Option<RowProblem<'_>> = None;
    let mut index = 0usize;
    let mut field_start = start;
    let line_end = loop {
        let field_end = find_comma_or_newline(bytes, field_start);
        // Keep counting fields after a problem: a wrong count outranks a bad field.
        if problem.is_none() && (index < values.len() || Some(index) == temp_index) {
            // `,` and `\n` are ASCII, so both ends are char boundaries.
            let field = text[field_start..field_end].trim_ascii();
            match field.parse::<f64>() {
                Ok(v) if v.is_finite() => {
                    if index < values.len() {
                        values[index] = v;
                    } else {
                        temp_c = Some(v);
                    }
                }
                Ok(_) => {
                    problem = Some(RowProblem::Field {
                        index,
                        text: field,
                        reason: RejectReason::NonFinite,
                    })
                }
                Err(_) => {
                    problem = Some(RowProblem::Field {
                        index,
                        text: field,
                        reason: RejectReason::Malformed,
                    })
                }
            }
        }
        index += 1;
        if field_end == bytes.len() || bytes[field_end] == b'\n' {
            break field_end;
        }
        field_start = field_end + 1;
    };
    let row = if index != n_fields {
        Err(RowProblem::FieldCount)
    } else if let Some(p) = problem {
        Err(p)
    } else {
        Ok(ImuRow {
            t_s: values[0],
            gyro_rad_s: [values[1], values[2], values[3]],
            accel_m_s2: [values[4], values[5], values[6]],
            temp_c,
            line: line_no,
        })
    };
    (line_end, row)
}

/// Refuses logs whose accelerometer does not look like m/s² or whose gyroscope does not look like rad/s.
fn check_units(rows: &[ImuRow], path: &Path) -> Result<(), ImuCsvError> {
    let mut norms: Vec<f64> = rows.iter().map(|r| norm3(r.accel_m_s2)).collect();
    let mid = norms.len() / 2;
    let (_, median, _) = norms.select_nth_unstable_by(mid, f64::total_cmp);
    let median = *median;
    let units = |column, statistic: &str, value, hint: String| ImuCsvError::Units {
        path: path.to_path_buf(),
        column,
        statistic: statistic.to_string(),
        value,
        hint,
    };
    const ACCEL_COLUMNS: &str = "ax_m_s2,ay_m_s2,az_m_s2";
    const ACCEL_STAT: &str = "median |a| (m/s²)";
    if (ACCEL_LOOKS_LIKE_G_M_S2.0..=ACCEL_LOOKS_LIKE_G_M_S2.1).contains(&median) {
        return Err(units(
            ACCEL_COLUMNS,
            ACCEL_STAT,
            median,
            format!(
                "the accelerometer looks like it is in g, not m/s²; multiply by {STANDARD_GRAVITY_M_S2}"
            ),
        ));
    }
    if !(ACCEL_PLAUSIBLE_MEDIAN_M_S2.0..=ACCEL_PLAUSIBLE_MEDIAN_M_S2.1).contains(&median) {
        return Err(units(
            ACCEL_COLUMNS,
            ACCEL_STAT,
            median,
            format!(
                "expected specific force in m/s² with gravity included (median |a| about {STANDARD_GRAVITY_M_S2}, \
                 allowed {}..{}); check the accelerometer's units and scale, and that gravity was not removed",
                ACCEL_PLAUSIBLE_MEDIAN_M_S2.0, ACCEL_PLAUSIBLE_MEDIAN_M_S2.1
            ),
        ));
    }

    let (max_gyro, max_line) =
        rows.iter()
            .map(|r| (norm3(r.gyro_rad_s), r.line))
            .fold(
                (0.0f64, 0u64),
                |best, cur| if cur.0 > best.0 { cur } else { best },
            );
    if max_gyro > GYRO_MAX_PLAUSIBLE_RAD_S {
        return Err(units(
            "gx_rad_s,gy_rad_s,gz_rad_s",
            &format!("max |ω| (rad/s) at line {max_line}"),
            max_gyro,
            format!(
                "above {GYRO_MAX_PLAUSIBLE_RAD_S} rad/s (≈ 2300 °/s, beyond any consumer gyro; a foot peaks near 12 rad/s): \
                 the gyroscope looks like it is in deg/s; multiply by π/180 = {:.9}",
                std::f64::consts::PI / 180.0
            ),
        ));
    }
    Ok(())
}

/// Index of the first `,` or `\n` in `bytes` at or after `from`, or `bytes.len()` if none.
///
/// Looks at eight bytes at a time (SWAR): CSV fields are a dozen bytes long, too short for
/// `memchr` (used by `str::split`) to pay off, and a byte loop costs one branch per byte.
#[inline]
fn find_comma_or_newline(bytes: &[u8], from: usize) -> usize {
    const ONES: u64 = 0x0101_0101_0101_0101;
    const HIGHS: u64 = 0x8080_8080_8080_8080;
    const COMMAS: u64 = ONES * b',' as u64;
    const NEWLINES: u64 = ONES * b'\n' as u64;
    let mut i = from;
    while let Some(chunk) = bytes.get(i..i + 8) {
        let word = u64::from_le_bytes(chunk.try_into().expect("chunk has 8 bytes"));
        let (c, n) = (word ^ COMMAS, word ^ NEWLINES);
        // Sets the high bit of each zero byte of `c` or `n`; only bytes above the first zero byte
        // can be false positives, so the lowest set bit is exact.
        let hits = ((c.wrapping_sub(ONES) & !c) | (n.wrapping_sub(ONES) & !n)) & HIGHS;
        if hits != 0 {
            return i + (hits.trailing_zeros() / 8) as usize;
        }
        i += 8;
    }
    bytes[i.min(bytes.len())..]
        .iter()
        .position(|&b| b == b',' || b == b'\n')
        .map_or(bytes.len(), |p| i + p)
}

/// Euclidean norm of a 3-vector.
#[inline]
fn norm3(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// Removes one trailing `\r` (CRLF line ends).
#[inline]
fn strip_cr(line: &str) -> &str {
    line.strip_suffix('\r').unwrap_or(line)
}

/// The first `max` characters of `s` (all of it when shorter).
pub(crate) fn truncate_chars(s: &str, max: usize) -> String {
    match s.char_indices().nth(max) {
        Some((end, _)) => s[..end].to_string(),
        None => s.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2";

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
            let log =
                read_imu_csv(&file, &ImuCsvOptions::default()).unwrap_or_else(|e| panic!("{e}"));
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
    fn wrong_header_is_an_error_naming_file_line_and_text() {
        let text = format!("time,gx,gy,gz,ax,ay,az\n{}\n", row(0.0));
        let err = parse_imu_csv(&text, path(), &ImuCsvOptions::default()).unwrap_err();
        assert!(matches!(err, ImuCsvError::Header { .. }), "{err:?}");
        let msg = err.to_string();
        assert_eq!(
            msg,
            "data/imu.csv:1: header must start with \"t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2\" \
             but found \"time,gx,gy,gz,ax,ay,az\""
        );
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
            "t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2,",
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
            "line 3: row \"0.005,0.01,0.02,0.03,0.1,0.2\" is malformed (its field count differs from the header's)"
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
        let text = "0.004998144,0.004951937,-0.0011,,x\n\n1,22,333,4444,55555,666666,7777777,88888888,\näö,ü";
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
            msg.starts_with(
                "data/imu.csv: column ax_m_s2,ay_m_s2,az_m_s2: median |a| (m/s²) = 1.0012"
            ),
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
                assert_eq!(statistic, "max |ω| (rad/s) at line 51");
                assert_eq!(*value, 600.0);
            }
            other => panic!("{other:?}"),
        }
        let msg = err.to_string();
        assert!(msg.starts_with("data/imu.csv: column gx_rad_s,gy_rad_s,gz_rad_s: max |ω| (rad/s) at line 51 = 600.0000"), "{msg}");
        assert!(msg.contains("deg/s"), "{msg}");
        // 12 rad/s (a brisk foot swing) passes.
        let text = replace_line(&good_file(100), 51, "0.245,0,0,12,0.1,0.2,9.8");
        assert!(parse_imu_csv(&text, path(), &ImuCsvOptions::default()).is_ok());
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
    fn invalid_utf8_names_the_line() {
        let dir = std::env::temp_dir().join(format!("corridor-imu-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("bad_utf8.csv");
        let mut bytes = good_file(3).into_bytes();
        bytes.extend_from_slice(b"0.1,0.01,0.02,\xff,0.1,0.2,9.8\n");
        std::fs::write(&file, bytes).unwrap();
        let err = read_imu_csv(&file, &ImuCsvOptions::default()).unwrap_err();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(matches!(err, ImuCsvError::Io { .. }));
        let msg = err.to_string();
        assert!(
            msg.contains("bad_utf8.csv") && msg.contains("line 5: not valid UTF-8"),
            "{msg}"
        );
    }
}
