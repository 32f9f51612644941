//! Reader for IMU logs in the corridor CSV format.
//!
//! The header's first seven columns must be exactly [`IMU_HEADER`]
//! (`t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2`). More columns may follow, for example
//! `mx_gauss,my_gauss,mz_gauss` or `temp_c`; a `temp_c` column is read into [`ImuRow::temp_c`], the
//! others are kept only by name in [`ImuLog::extra_columns`] and their values are not parsed.
//!
//! The reader tolerates a UTF-8 byte-order mark, CRLF line ends, blank lines at the end of the file,
//! spaces or tabs around fields, and bytes that are not UTF-8 in columns it does not read (in a
//! number they make the row malformed). A file that is not text is refused at its header, a
//! compressed one (gzip, xz, zstd, zip, bzip2, known by its first bytes) with the command that
//! decompresses it; bytes quoted from a file in a message have their control characters and
//! bytes that are not UTF-8 escaped. It is a hand-rolled single pass over the bytes of each line
//! (fields split at `,` eight bytes at a time, numbers read with [`str::parse::<f64>`]); on the
//! 21 001-row exp29 log it parses about 3 million rows per second on one core
//! (`cargo bench -p corridor-shared --bench csv_parse`).
//!
//! [`ImuCsvReader`] streams a log row by row in memory independent of its length (the offline
//! runner uses it); [`read_imu_csv`] and [`parse_imu_csv`] collect the same reader into an
//! [`ImuLog`] for the callers that want every row at hand (the suite, the diagnosis, replay).
//!
//! Bad rows are never dropped silently. A row with the wrong number of fields, a field that is not a
//! number (a row longer than 64 KiB is not parsed: the field its cut falls in, or its field count,
//! is named), a non-finite value or a timestamp that does not increase is moved to
//! [`ImuLog::rejected`] with its line, column, text and [`RejectReason`] (a row after a time jump
//! or a step back of the clock that the next row confirms goes out, for the estimator behind the
//! reader to refuse as a live stream's would be). If more than
//! [`ImuCsvOptions::max_rejected_fraction`] of the data rows are rejected, the whole file is
//! refused with [`ImuCsvError::TooManyRejected`]. Finally a units check on the accepted rows
//! refuses accelerometers logged in g and gyroscopes logged in deg/s ([`ImuCsvError::Units`]).
//! The checks over the whole log come at its end, also when streaming: the decision is exact at
//! any length; the median |a| quoted in the message is exact up to 16 384 rows and read from a
//! 0.07 % histogram beyond.
//!
//! Map of the module:
//! - this file: the types ([`ImuRow`], [`ImuLog`], [`RejectedRow`], [`ImuCsvOptions`],
//!   [`ImuCsvError`]) and [`read_imu_csv`];
//! - `reader`: [`ImuCsvReader`], the log row by row;
//! - `row`: one data row, split at the commas, parsed and checked;
//! - `sniff`: files that are not CSV text (compressed ones by their first bytes), and bytes
//!   quoted in messages (control characters and bytes that are not UTF-8 escaped);
//! - `units`: the units check over the accepted rows (g, deg/s).

use crate::sensor::{TimeGuard, TimeVerdict};
use serde::Serialize;
use std::collections::{BTreeMap, VecDeque};
use std::fmt;
use std::io::BufRead;
use std::path::{Path, PathBuf};

mod lines;
mod reader;
mod row;
mod sniff;
mod units;

pub use reader::ImuCsvReader;
use row::*;
pub(crate) use row::{truncate_chars, unquote};
pub(crate) use sniff::escape_controls;
use units::*;

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
    /// Sample time in seconds (strictly increasing over the accepted rows, but where the clock
    /// stepped back: [`crate::sensor::TimeVerdict::StepBack`]).
    pub t_s: f64,
    /// Angular rate about the body x, y, z axes in rad/s.
    pub gyro_rad_s: [f64; 3],
    /// Specific force along the body x, y, z axes in m/s² (points up at rest).
    pub accel_m_s2: [f64; 3],
    /// Sensor temperature in °C; `Some` when the file has a `temp_c` column and this row's
    /// field in it is a finite number.
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
    /// `t_s` is not greater than the previous accepted row's `t_s` (duplicates included), and
    /// not the first row after a step back of the clock.
    TimeNotIncreasing,
    /// `t_s` jumps forward by more than [`ImuCsvOptions::max_dt_s`] and the next row does not
    /// follow it (an outlier such as `1e30`). The first row after a real gap, which the next
    /// row follows, is passed on (an estimator behind the reader refuses it until that row
    /// confirms it, as on a live stream), unless it comes right after the first row: the first
    /// row is then the outlier ([`RejectReason::TimeOutlier`]) and it is rejected with it.
    TimeJump,
    /// The first row's `t_s`, which the next two rows contradict while following each other:
    /// the first stamp was the outlier (found only after the row that exposed it was rejected
    /// as not increasing or as a jump).
    TimeOutlier,
    /// A row after a gap (a step beyond [`ImuCsvOptions::gap_dt_s`]) that the next row
    /// contradicts by going back and following the row before the gap: the gap was one glitched
    /// stamp (found only when that next row was read). Also each row of a run after a jump
    /// (two or more rows beyond [`ImuCsvOptions::max_dt_s`]) that a row within `max_dt_s` of
    /// it contradicts in the same way ([`crate::sensor::TimeVerdict::GlitchRun`]).
    TimeGlitch,
}

impl RejectReason {
    /// All reasons, in the order used by [`ImuLog::rejected_counts`].
    pub const ALL: [RejectReason; 6] = [
        RejectReason::Malformed,
        RejectReason::NonFinite,
        RejectReason::TimeNotIncreasing,
        RejectReason::TimeJump,
        RejectReason::TimeOutlier,
        RejectReason::TimeGlitch,
    ];

    /// Position in [`RejectReason::ALL`] (and in the reader's counts).
    pub fn index(self) -> usize {
        RejectReason::ALL
            .iter()
            .position(|r| *r == self)
            .expect("every reason is in ALL")
    }

    /// Stable snake_case name of the reason (`malformed`, `non_finite`, `time_not_increasing`,
    /// `time_jump`, `time_outlier`, `time_glitch`).
    pub fn name(self) -> &'static str {
        match self {
            RejectReason::Malformed => "malformed",
            RejectReason::NonFinite => "non_finite",
            RejectReason::TimeNotIncreasing => "time_not_increasing",
            RejectReason::TimeJump => "time_jump",
            RejectReason::TimeOutlier => "time_outlier",
            RejectReason::TimeGlitch => "time_glitch",
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
            RejectReason::TimeOutlier => {
                "is the first time stamp, and the rows after it do not follow it (they follow \
                 each other)"
            }
            RejectReason::TimeGlitch => {
                "came after a gap or a jump, and a later row goes back and follows the row \
                 before it (a glitched stamp)"
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
    /// For a row whose field count differs from the header's: (the row's, the header's), which
    /// the message gives (the row in `value` may be cut before its extra fields).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub field_counts: Option<(usize, usize)>,
    /// For such a row: it ends with a comma (an empty last field), which the message says (it
    /// gave "8 fields, the header has 7" for a row of seven numbers and a trailing comma, whose
    /// comma `value` may have cut off: a review).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub ends_with_comma: bool,
}

impl RejectedRow {
    /// Displays the rejection prefixed with the file, as `data/imu.csv:1523 column gy_rad_s: value "nan" is not finite`.
    pub fn located<'a>(&'a self, path: &'a Path) -> impl fmt::Display + 'a {
        Located { row: self, path }
    }

    /// Writes everything after the line number: ` column c: value "v" reason` or `: row "v" reason`
    /// (control characters in the value escaped).
    fn fmt_tail(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let value = escape_controls(&self.value);
        if self.column.is_empty() {
            write!(f, ": row \"{value}\" {}", self.reason)?;
            match self.field_counts {
                Some((row, header)) if self.ends_with_comma => write!(
                    f,
                    " ({row} fields, the header has {header}: the row ends with a comma, an \
                     empty field {row}{})",
                    if row > header {
                        " the header does not have"
                    } else {
                        ""
                    }
                )?,
                Some((row, header)) => {
                    let fields = if row == 1 { "field" } else { "fields" };
                    write!(f, " ({row} {fields}, the header has {header}")?;
                    // One field: the row has no comma (`value` may be cut, but a separator
                    // other than the comma falls within its first 64 characters).
                    if row == 1
                        && let Some(hint) = sniff::other_separator(&self.value, "row")
                    {
                        write!(f, ": {hint}")?;
                    }
                    f.write_str(")")?
                }
                None if self.reason == RejectReason::Malformed => {
                    f.write_str(" (its field count differs from the header's)")?
                }
                None => {}
            }
        } else {
            write!(
                f,
                " column {}: value \"{value}\" {}",
                self.column, self.reason
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
    /// Accepted samples in file order; `t_s` is strictly increasing but where the clock stepped
    /// back (within `max_dt_s`, a row after it confirming it), so code that searches the times
    /// (the suite's cuts, the diagnosis) assumes a log without one, as the bundled ones are.
    pub rows: Vec<ImuRow>,
    /// Rejected data rows, each with its reason, in the order they were decided: file order,
    /// but for a row held until the next row (a first time, a gap's far side, a time jump)
    /// whose rejection follows that of rows rejected in between.
    pub rejected: Vec<RejectedRow>,
    /// Whether the file has a `temp_c` column (then a row has `temp_c: Some(_)` where its field
    /// held a finite number).
    pub has_temperature: bool,
    /// Data rows whose `temp_c` field was empty or no finite number (a temperature logged at a
    /// lower rate than the rest): their temperature is unknown, nothing else of them.
    pub temperature_missing: u64,
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

    /// Logs the rejected rows: the first `named` with their place, then how many more, each line
    /// ending in `note` (`", not sent"`; the counts stay in the log). `corridor run`'s in-memory
    /// paths and `corridor-replay` alike.
    pub fn warn_rejected(&self, named: usize, note: &str) {
        for r in self.rejected.iter().take(named) {
            tracing::warn!("rejected input row{note}: {}", r.located(&self.path));
        }
        if self.rejected.len() > named {
            let more = self.rejected.len() - named;
            tracing::warn!("{}: {more} more rejected rows{note}", self.path.display());
        }
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
    /// A row more than this after the previous accepted one is a time jump, passed on only when
    /// the next row confirms it ([`crate::sensor::TimeGuard`]; an estimator behind the reader
    /// refuses it until then, as on a live stream), s. Default
    /// [`crate::sensor::DEFAULT_MAX_DT_S`].
    pub max_dt_s: f64,
    /// A row more than this after the previous accepted one (a gap, within `max_dt_s`) is held
    /// until the next row: when that row goes back and follows the one before the gap, the held
    /// row's time was a glitch and it is rejected (`time_glitch`), s. The estimator's gap
    /// threshold (`estimator.max_dt_s`); default [`crate::config::defaults::ESTIMATOR_MAX_DT_S`].
    pub gap_dt_s: f64,
}

impl Default for ImuCsvOptions {
    fn default() -> Self {
        Self {
            max_rejected_fraction: 0.01,
            check_units: true,
            min_dt_s: 0.0,
            max_dt_s: crate::sensor::DEFAULT_MAX_DT_S,
            gap_dt_s: crate::config::defaults::ESTIMATOR_MAX_DT_S,
        }
    }
}

/// An IMU CSV file that could not be used. Every message names the file, and where relevant the
/// line, column and value.
#[derive(Debug, thiserror::Error)]
pub enum ImuCsvError {
    /// The file could not be read.
    #[error("{path}: cannot read IMU CSV: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS or decoding error.
        source: std::io::Error,
    },
    /// The header (line 1) is missing or does not start with the required columns, or it has an
    /// empty or repeated column name, or the file is not text (compressed, not UTF-8, lines that
    /// end in CR alone, no line end within 64 KiB).
    #[error(
        "{path}:{line}: header {problem}: it must start with \"{expected}\", found \"{found}\""
    )]
    Header {
        /// The file.
        path: PathBuf,
        /// The header's line (after leading blank lines).
        line: u64,
        /// What is wrong with it (for a compressed file, with the command that decompresses it).
        problem: std::borrow::Cow<'static, str>,
        /// The header line as found, up to a CR, at most 200 characters (control characters
        /// and bytes that are not UTF-8 escaped, NULs left out); a compressed file's first 8
        /// bytes.
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
        "{path}: {rejected} of {total} data rows rejected, more than the allowed fraction {max_rejected_fraction}; first: {}{hint}",
        .first.located(.path)
    )]
    TooManyRejected {
        /// The file.
        path: PathBuf,
        /// Number of rejected data rows, with the rows passed on after a time jump (a real
        /// gap's far side, which an estimator behind the reader refuses until the next row).
        rejected: u64,
        /// Number of data rows (accepted + rejected).
        total: u64,
        /// The allowed fraction ([`ImuCsvOptions::max_rejected_fraction`]).
        max_rejected_fraction: f64,
        /// The first rejected row (boxed: it keeps the error small).
        first: Box<RejectedRow>,
        /// What the rows' times probably are, when they look like another unit than seconds
        /// (starts with a space), else empty.
        hint: String,
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

/// How many rejected rows an [`ImuCsvReader`] keeps with their text (the first ones); the
/// others are only counted. [`parse_imu_csv`] and [`read_imu_csv`] keep every one.
pub const REJECTED_ROWS_KEPT: usize = 20;

/// Up to this many accepted rows the units check takes the exact median of |a| (their norms are
/// kept, 8 bytes a row); beyond, the decision is still exact (counts per band) and the median in
/// the message is read from a histogram with 1/1024-octave bins (0.07 %).
const EXACT_MEDIAN_ROWS: usize = 1 << 14;

/// Reads and parses the IMU CSV file at `path` into memory; see [`parse_imu_csv`]. A long log
/// is better streamed with [`ImuCsvReader::open`].
pub fn read_imu_csv(path: &Path, opts: &ImuCsvOptions) -> Result<ImuLog, ImuCsvError> {
    let mut reader = ImuCsvReader::open(path, opts)?;
    reader.keep_rejected = usize::MAX;
    collect(reader)
}

/// Parses IMU CSV `text` (the content of the file `path`, which is only used in messages).
///
/// Steps: header check, row parsing with rejection, rejected-fraction check, units check (the
/// same [`ImuCsvReader`] the streaming runner uses, collected).
/// Returns [`ImuCsvError::Empty`] when there is no data row or no accepted row.
pub fn parse_imu_csv(text: &str, path: &Path, opts: &ImuCsvOptions) -> Result<ImuLog, ImuCsvError> {
    let mut reader = ImuCsvReader::new(text.as_bytes(), path, opts)?;
    reader.keep_rejected = usize::MAX;
    reader.len_bytes = Some(text.len() as u64);
    collect(reader)
}

/// Every row of `reader` into an [`ImuLog`].
fn collect<R: BufRead>(mut reader: ImuCsvReader<R>) -> Result<ImuLog, ImuCsvError> {
    let mut rows = Vec::new();
    while let Some(row) = reader.next() {
        let row = row?;
        if rows.capacity() == 0 {
            // A guess from the file's length and its first row: a large file whose first row
            // is short asked for more than the machine has, and the reservation aborted the
            // run (a sparse 200 GB file: "memory allocation of 1207959553280 bytes failed").
            // Refused, the rows are collected as they come.
            let _ = rows.try_reserve(reader.rows_hint());
        }
        rows.push(row);
    }
    Ok(ImuLog {
        path: reader.path,
        rows,
        rejected: reader.rejected,
        has_temperature: reader.temp_index.is_some(),
        temperature_missing: reader.temperature_missing,
        extra_columns: reader.names.split_off(REQUIRED_COLUMNS.len()),
    })
}

#[cfg(test)]
mod tests;
