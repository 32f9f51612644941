//! One data row: split at the commas, parsed, checked.

use super::*;

/// What is wrong with one data row.
pub(super) enum RowProblem<'a> {
    /// The field count differs from the header's: the row's.
    FieldCount(usize),
    /// The first bad field: its index, its (trimmed) text and why.
    Field {
        index: usize,
        text: &'a str,
        reason: RejectReason,
    },
}

/// Parses one non-blank data line (without its line end), in one pass over its bytes; time
/// ordering is checked by the caller. `unnamed_last`: the header's last column has no name (a
/// trailing comma), and a row may leave it out.
#[inline]
pub(super) fn parse_row(
    text: &str,
    line_no: u64,
    n_fields: usize,
    unnamed_last: bool,
    temp_index: Option<usize>,
) -> Result<ImuRow, RowProblem<'_>> {
    let bytes = text.as_bytes();
    let mut values = [0.0f64; 7];
    let mut temp_c: Option<f64> = None;
    let mut problem: Option<RowProblem<'_>> = None;
    let mut index = 0usize;
    let mut field_start = 0;
    loop {
        let field_end = find_comma_or_newline(bytes, field_start);
        // Keep counting fields after a problem: a wrong count outranks a bad field.
        if problem.is_none() && Some(index) == temp_index {
            // The temperature is carried, never used by the estimator: a field that is no
            // finite number (empty where a sensor logs it at 1 Hz, NaN, text) leaves it unknown
            // and costs the sample nothing (it rejected the row, a review of session 38).
            let field = unquote(&text[field_start..field_end]);
            temp_c = field.parse::<f64>().ok().filter(|v| v.is_finite());
        } else if problem.is_none() && index < values.len() {
            // `,` is ASCII, so both ends are char boundaries.
            let field = unquote(&text[field_start..field_end]);
            match field.parse::<f64>() {
                Ok(v) if v.is_finite() => values[index] = v,
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
        if field_end == bytes.len() {
            break;
        }
        field_start = field_end + 1;
    }
    if index != n_fields && !(unnamed_last && index + 1 == n_fields) {
        Err(RowProblem::FieldCount(index))
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
    }
}

/// Index of the first `,` or `\n` in `bytes` at or after `from`, or `bytes.len()` if none.
///
/// Looks at eight bytes at a time (SWAR): CSV fields are a dozen bytes long, too short for
/// `memchr` (used by `str::split`) to pay off, and a byte loop costs one branch per byte.
#[inline]
pub(super) fn find_comma_or_newline(bytes: &[u8], from: usize) -> usize {
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
pub(super) fn norm3(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// A field without the white space around it and without one pair of double quotes around
/// that (as spreadsheets and `csv.QUOTE_ALL` write them; a quoted comma still splits the field).
#[inline]
pub(crate) fn unquote(field: &str) -> &str {
    let field = field.trim_ascii();
    match field.as_bytes() {
        [b'"', .., b'"'] => field[1..field.len() - 1].trim_ascii(),
        _ => field,
    }
}

/// Removes one trailing `\r` (CRLF line ends).
#[inline]
pub(super) fn strip_cr(line: &str) -> &str {
    line.strip_suffix('\r').unwrap_or(line)
}

/// A time held as a number (a held row's, rejected once a later row decides it), as a message
/// quotes it: as Rust prints it when that is short (`1000000000`, `0.49`), else in scientific
/// notation (a first `t_s = -1e308` was quoted with its 309 digits, beyond the 64-character
/// limit on a quoted value).
pub(super) fn time_text(t_s: f64) -> String {
    let plain = t_s.to_string();
    if plain.len() <= MAX_TIME_CHARS {
        plain
    } else {
        format!("{t_s:e}")
    }
}

/// Longest time [`time_text`] writes in plain notation, characters: the 17 significant digits
/// of an `f64` with a sign, a point and a few zeros.
const MAX_TIME_CHARS: usize = 24;

/// The first `max` characters of `s` (all of it when shorter).
pub(crate) fn truncate_chars(s: &str, max: usize) -> String {
    match s.char_indices().nth(max) {
        Some((end, _)) => s[..end].to_string(),
        None => s.to_string(),
    }
}
