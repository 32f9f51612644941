//! The reader's lines: each read up to [`MAX_LINE_BYTES`], the rest of a longer one skipped
//! unread, and the rejection of a data row so cut.

use super::*;
use std::io::Read as _;

/// Longest line the reader keeps, bytes (a data row is about 150, a header with a few dozen
/// extra columns a few hundred). A line was read whole into memory: a file without line ends
/// (a binary dump, `/dev/zero`) grew the buffer until the run aborted with "memory allocation
/// failed". A longer header is refused; a longer data row is rejected, its rest skipped unread.
pub(super) const MAX_LINE_BYTES: usize = 1 << 16;

/// What lay beyond [`MAX_LINE_BYTES`] of a line that was cut.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct LineCut {
    /// Commas in the part skipped (for the row's field count).
    pub(super) commas: usize,
}

impl<R: BufRead> ImuCsvReader<R> {
    /// Reads the next line into `self.line` without its `\n`; `false` at the end of the source.
    /// A line longer than [`MAX_LINE_BYTES`] is cut there (`self.line_cut`), its rest left
    /// unread: [`Self::skip_rest`] reads past it.
    pub(super) fn read_line(&mut self) -> Result<bool, ImuCsvError> {
        self.line.clear();
        self.line_cut = None;
        // One byte more than the longest line: its `\n`.
        let limit = MAX_LINE_BYTES as u64 + 1;
        let n = (&mut self.src)
            .take(limit)
            .read_until(b'\n', &mut self.line)
            .map_err(|source| ImuCsvError::Io {
                path: self.path.clone(),
                source,
            })?;
        if n == 0 {
            return Ok(false);
        }
        self.bytes_read += n as u64;
        self.line_no += 1;
        if self.line.last() == Some(&b'\n') {
            self.line.pop();
        } else if n as u64 == limit {
            // A CRLF line of exactly the bound reads its CR as the byte beyond it: its LF comes
            // next, and it is kept as the same line with LF alone is (it was cut, and its
            // last field, "9.8\r", named as malformed: a review).
            if self.line.last() == Some(&b'\r') && self.next_byte_is(b'\n')? {
                self.src.consume(1);
                self.bytes_read += 1;
            } else {
                self.line_cut = Some(LineCut::default());
            }
        }
        if self.line_no == 1 && self.line.starts_with("\u{feff}".as_bytes()) {
            self.line.drain(..3);
        }
        Ok(true)
    }

    /// Whether the next byte of the source is `byte` (not consumed).
    fn next_byte_is(&mut self, byte: u8) -> Result<bool, ImuCsvError> {
        loop {
            match self.src.fill_buf() {
                Ok(buf) => return Ok(buf.first() == Some(&byte)),
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(source) => {
                    return Err(ImuCsvError::Io {
                        path: self.path.clone(),
                        source,
                    });
                }
            }
        }
    }

    /// Reads past the rest of a line cut at [`MAX_LINE_BYTES`], to its `\n`, counting its commas
    /// (in memory independent of its length).
    pub(super) fn skip_rest(&mut self) -> Result<(), ImuCsvError> {
        let Some(cut) = &mut self.line_cut else {
            return Ok(());
        };
        loop {
            let buf = match self.src.fill_buf() {
                Ok(buf) => buf,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(source) => {
                    return Err(ImuCsvError::Io {
                        path: self.path.clone(),
                        source,
                    });
                }
            };
            if buf.is_empty() {
                return Ok(());
            }
            let (n, end) = match buf.iter().position(|&b| b == b'\n') {
                Some(i) => (i + 1, true),
                None => (buf.len(), false),
            };
            cut.commas += buf[..n].iter().filter(|&&b| b == b',').count();
            self.src.consume(n);
            self.bytes_read += n as u64;
            if end {
                return Ok(());
            }
        }
    }

    /// The rejection of a data row cut at [`MAX_LINE_BYTES`] (`self.line`, its first bytes):
    /// its field count when that differs from the header's, else the field the cut falls in.
    pub(super) fn cut_row(&self, line_no: u64, n_fields: usize, cut: LineCut) -> RejectedRow {
        let text = Self::line_str(&self.line);
        let kept_commas = text.matches(',').count();
        let fields = kept_commas + cut.commas + 1;
        let (column, value, field_counts) = if fields != n_fields {
            (String::new(), text.as_ref(), Some((fields, n_fields)))
        } else {
            let field = text.rsplit(',').next().unwrap_or_default();
            (self.names[kept_commas].clone(), unquote(field), None)
        };
        RejectedRow {
            line: line_no,
            column,
            value: truncate_chars(value, MAX_VALUE_CHARS),
            reason: RejectReason::Malformed,
            field_counts,
            // (The line's end was not kept.)
            ends_with_comma: false,
        }
    }
}
