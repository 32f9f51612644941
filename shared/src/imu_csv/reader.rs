//! [`ImuCsvReader`]: the log row by row, in memory independent of its length.

use super::lines::{LineCut, MAX_LINE_BYTES};
use super::*;
use std::borrow::Cow;

/// A streaming reader of an IMU CSV log: an iterator of the accepted rows in file order, in
/// memory independent of the log's length (one line buffer, the counters, the first
/// [`REJECTED_ROWS_KEPT`] rejected rows and the units statistics).
///
/// It applies exactly the rules of [`parse_imu_csv`]: bad rows are rejected, counted by reason
/// and kept with line, column and value; the checks that need the whole log (more than
/// [`ImuCsvOptions::max_rejected_fraction`] rejected, no sample, the units) are made at its end,
/// where the iterator yields the error as its last item instead of ending. A consumer must
/// therefore treat what it did with the rows as provisional until the iterator has ended
/// without an error. An unreadable source (an IO error) is an error; a line that is not UTF-8
/// is read with U+FFFD in place of its bad bytes (see `line_str`).
#[derive(Debug)]
pub struct ImuCsvReader<R> {
    pub(super) src: R,
    pub(super) path: PathBuf,
    pub(super) max_rejected_fraction: f64,
    pub(super) check_units: bool,
    /// Header column names, trimmed.
    pub(super) names: Vec<String>,
    pub(super) temp_index: Option<usize>,
    /// Data rows whose `temp_c` field was empty or no finite number (their temperature unknown).
    pub(super) temperature_missing: u64,
    /// 1-based number of the last line read.
    pub(super) line_no: u64,
    pub(super) line: Vec<u8>,
    /// The last line was longer than [`MAX_LINE_BYTES`]: `line` holds its first bytes (one
    /// more than that).
    pub(super) line_cut: Option<LineCut>,
    pub(super) bytes_read: u64,
    /// Bytes of the first data line (for [`Self::rows_hint`]).
    pub(super) first_row_bytes: u64,
    /// Length of the source when known (a file's size), bytes.
    pub(super) len_bytes: Option<u64>,
    pub(super) time: TimeGuard,
    /// The largest time step the rule takes, s ([`ImuCsvOptions::max_dt_s`]).
    pub(super) max_dt_s: f64,
    /// The first and last `t_s` of the rows that parsed, and their count (whatever the time
    /// rule said of them): the raw step a refused log advances by ([`Self::time_unit_hint`]).
    pub(super) parsed_t: Option<(f64, f64, u64)>,
    /// Blank lines since the last non-blank one: (first line, count). Fine at the end of the
    /// file; rejected as malformed when a data row follows.
    pub(super) blank: Option<(u64, u64)>,
    /// Data rows (accepted and rejected).
    pub(super) total: u64,
    pub(super) rejected_counts: [u64; RejectReason::ALL.len()],
    /// The first accepted row, held back until a row follows its time (a first time stamp that
    /// the next rows contradict is the outlier: [`TimeVerdict::Rebase`]), and a row after a gap,
    /// held until the next row shows whether it was a stamp glitch ([`TimeVerdict::Glitch`]).
    pub(super) held: Option<ImuRow>,
    /// A row refused as a time jump, held until the next row: when that row follows it, the
    /// jump was a real gap, and it goes out before it (a reader of the stream judges it as a
    /// live stream's would be judged: `corridor run`'s estimator refuses it until the next
    /// sample confirms it, as the daemon does); otherwise it is rejected.
    pub(super) jumped: Option<(ImuRow, RejectedRow)>,
    /// The same for a row refused as going back: it goes out when the next row follows it (the
    /// clock stepped back, [`TimeVerdict::StepBack`]). Two slots, as the time rule keeps two
    /// candidates.
    pub(super) went_back: Option<(ImuRow, RejectedRow)>,
    /// Rows passed on that way, and the first of them as a rejection: the estimator behind the
    /// reader refuses each, so they count with the rejected rows in the checks over the whole
    /// log ([`Self::finish`]).
    pub(super) passed_refused: (u64, Option<RejectedRow>),
    /// Of those, the jumps (for the time-unit hint).
    pub(super) jumps_passed: u64,
    /// Rows to return before reading on, in order (those released with the current one).
    pub(super) ready: VecDeque<ImuRow>,
    /// The rows since a jump that the next row confirmed, while the time rule's run after it
    /// is open ([`TimeGuard::jump_run`]): a later row that goes back and follows the row before
    /// the jump shows them to be glitched stamps ([`TimeVerdict::GlitchRun`]), and they are
    /// rejected; otherwise they go out when the run closes (at most `max_dt_s` of rows, and
    /// [`crate::sensor::JUMP_RUN_MAX_SAMPLES`]). The first is the jumped row, whose rejection
    /// is in `run_jumps` (an estimator behind the reader refuses it, as it does on a live
    /// stream), with that of a second jump within the run.
    pub(super) run: Vec<ImuRow>,
    pub(super) run_jumps: Vec<RejectedRow>,
    pub(super) rejected: Vec<RejectedRow>,
    pub(super) keep_rejected: usize,
    pub(super) accepted: u64,
    pub(super) units: UnitsStats,
    pub(super) done: bool,
}

impl ImuCsvReader<std::io::BufReader<std::fs::File>> {
    /// Opens the file at `path` and reads its header.
    pub fn open(path: &Path, opts: &ImuCsvOptions) -> Result<Self, ImuCsvError> {
        let io = |source| ImuCsvError::Io {
            path: path.to_path_buf(),
            source,
        };
        let file = std::fs::File::open(path).map_err(io)?;
        let len = file.metadata().map_err(io)?.len();
        let mut reader = Self::new(
            std::io::BufReader::with_capacity(READ_BUFFER_BYTES, file),
            path,
            opts,
        )?;
        reader.len_bytes = Some(len);
        Ok(reader)
    }
}

/// Read buffer of [`ImuCsvReader::open`], bytes.
pub(super) const READ_BUFFER_BYTES: usize = 1 << 16;

impl<R: BufRead> ImuCsvReader<R> {
    /// Reads the header from `src` (the content of `path`, which is only used in messages).
    pub fn new(src: R, path: &Path, opts: &ImuCsvOptions) -> Result<Self, ImuCsvError> {
        let mut reader = Self {
            src,
            path: path.to_path_buf(),
            max_rejected_fraction: opts.max_rejected_fraction,
            check_units: opts.check_units,
            names: Vec::new(),
            temp_index: None,
            temperature_missing: 0,
            line_no: 0,
            line: Vec::new(),
            line_cut: None,
            bytes_read: 0,
            first_row_bytes: 0,
            len_bytes: None,
            time: TimeGuard::new(opts.min_dt_s, opts.max_dt_s, opts.gap_dt_s),
            max_dt_s: opts.max_dt_s,
            parsed_t: None,
            blank: None,
            total: 0,
            rejected_counts: [0; RejectReason::ALL.len()],
            held: None,
            jumped: None,
            went_back: None,
            passed_refused: (0, None),
            jumps_passed: 0,
            ready: VecDeque::new(),
            run: Vec::new(),
            run_jumps: Vec::new(),
            rejected: Vec::new(),
            keep_rejected: REJECTED_ROWS_KEPT,
            accepted: 0,
            units: UnitsStats::default(),
            done: false,
        };
        reader.read_header()?;
        Ok(reader)
    }

    /// The log's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Accepted rows so far.
    pub fn rows_accepted(&self) -> u64 {
        self.accepted
    }

    /// Rejected rows so far.
    pub fn rows_rejected(&self) -> u64 {
        self.rejected_counts.iter().sum()
    }

    /// The first [`REJECTED_ROWS_KEPT`] rejected rows, in the order they were decided (see
    /// [`ImuLog::rejected`]).
    pub fn rejected_rows(&self) -> &[RejectedRow] {
        &self.rejected
    }

    /// Rejected rows per reason name, every reason present (as [`ImuLog::rejected_counts`]).
    pub fn rejected_counts(&self) -> BTreeMap<&'static str, u64> {
        RejectReason::ALL
            .iter()
            .zip(self.rejected_counts)
            .map(|(r, n)| (r.name(), n))
            .collect()
    }

    /// Bytes read so far and the source's length when known (progress).
    pub fn progress_bytes(&self) -> (u64, Option<u64>) {
        (self.bytes_read, self.len_bytes)
    }

    /// Whether the file has a `temp_c` column.
    pub fn has_temperature(&self) -> bool {
        self.temp_index.is_some()
    }

    /// Data rows so far whose `temp_c` field was empty or no finite number: their temperature
    /// is unknown (NaN on the wire); the rows themselves are read as any other.
    pub fn temperature_missing(&self) -> u64 {
        self.temperature_missing
    }

    /// A guess of the number of rows from the length and the first row (for a collecting caller).
    pub(super) fn rows_hint(&self) -> usize {
        match (self.len_bytes, self.first_row_bytes) {
            (Some(len), first) if first > 0 => {
                usize::try_from((len / first).saturating_mul(9) / 8 + 16).unwrap_or(usize::MAX)
            }
            _ => 0,
        }
    }

    /// A line as text: bytes that are not UTF-8 become U+FFFD, so that a field holding one is
    /// not a number (the row is rejected, counted and named) and one in a column the reader
    /// does not use costs nothing (a stray byte used to stop the whole run). Borrowed, not
    /// copied, when the line is valid.
    pub(super) fn line_str(line: &[u8]) -> std::borrow::Cow<'_, str> {
        // `from_utf8` first: `from_utf8_lossy`'s own check made the reader 17 % slower.
        match std::str::from_utf8(line) {
            Ok(text) => std::borrow::Cow::Borrowed(text),
            Err(_) => String::from_utf8_lossy(line),
        }
    }

    /// Reads and checks line 1.
    pub(super) fn read_header(&mut self) -> Result<(), ImuCsvError> {
        let path = self.path.clone();
        let empty = || ImuCsvError::Empty { path: path.clone() };
        if !self.read_line()? {
            return Err(empty());
        }
        // Blank lines before the header: an empty file if nothing but white space follows.
        while Self::line_str(&self.line).trim().is_empty() {
            self.skip_rest()?;
            if !self.read_line()? {
                return Err(empty());
            }
        }
        let header = strip_cr(&Self::line_str(&self.line)).to_string();
        let names: Vec<&str> = header.split(',').map(unquote).collect();
        // The header proper: up to a CR, after which a file whose lines end in CR alone goes on.
        let proper = self.line.split(|&b| b == b'\r').next().unwrap_or_default();
        let compressed = sniff::compressed(&self.line, &self.path);
        // Up to a CR (the rest of a CR-only file), escaped: a terminal would act on a control
        // character rather than show it. Of a compressed file, its first bytes: its magic.
        let found = match compressed {
            Some(_) => sniff::first_bytes(&self.line),
            None => sniff::excerpt(proper, MAX_HEADER_CHARS),
        };
        // Every line of the file read as one, its lines ending in CR alone: said as such when
        // that line is cut at the bound too (a file of more than 64 KiB, any real log, was
        // called "longer than 65536 bytes without a line end (a binary file?)": a review).
        let cr_alone =
            header.contains('\r') && !Self::line_str(proper).contains(['\u{fffd}', '\0']);
        let problem: Option<Cow<'static, str>> = if let Some(problem) = compressed {
            Some(problem.into())
        } else if self.line_cut.is_some() && !cr_alone {
            // Its rest is left unread: a source without line ends may have no end either.
            Some(
                format!(
                    "is longer than {MAX_LINE_BYTES} bytes without a line end (a binary file?)"
                )
                .into(),
            )
        } else if Self::line_str(proper).contains(['\u{fffd}', '\0']) {
            // UTF-16 (a NUL byte in every other place), another 8-bit encoding, binary bytes
            // (whose CR, if any, says nothing of line ends).
            Some("is not UTF-8 text (a UTF-16 file, another encoding, or binary?)".into())
        } else if cr_alone {
            // Every line of the file, read as one: its lines end in CR alone (old Mac files).
            Some("holds a CR inside it: the file's lines end in CR alone, not LF or CRLF".into())
        } else if names.len() < REQUIRED_COLUMNS.len()
            || !names.iter().zip(REQUIRED_COLUMNS).all(|(a, b)| *a == b)
        {
            match sniff::other_separator(&header, "header") {
                Some(hint) => {
                    Some(format!("does not start with the required columns ({hint})").into())
                }
                None => Some("does not start with the required columns".into()),
            }
        } else if names[..names.len() - 1].iter().any(|n| n.is_empty()) {
            // A last name empty is a trailing comma (spreadsheet exports write one on every
            // line): an unnamed column, ignored as any other extra one (it refused the file).
            Some("has an empty column name".into())
        } else if names
            .iter()
            .enumerate()
            .any(|(i, n)| names[..i].contains(n))
        {
            Some("repeats a column name".into())
        } else {
            None
        };
        if let Some(problem) = problem {
            return Err(ImuCsvError::Header {
                path: self.path.clone(),
                line: self.line_no,
                problem,
                found,
                expected: IMU_HEADER,
            });
        }
        self.temp_index = names.iter().position(|n| *n == TEMPERATURE_COLUMN);
        self.names = names.into_iter().map(str::to_string).collect();
        Ok(())
    }

    /// Counts a rejected row and keeps it while fewer than `keep_rejected` are kept.
    pub(super) fn reject(&mut self, row: RejectedRow) {
        self.rejected_counts[row.reason.index()] += 1;
        if self.rejected.len() < self.keep_rejected {
            self.rejected.push(row);
        }
    }

    /// The run after a confirmed jump goes out: nothing showed it to be glitched stamps.
    #[inline]
    fn release_run(&mut self) {
        if self.run.is_empty() && self.run_jumps.is_empty() {
            return;
        }
        self.release_run_rows();
    }

    #[cold]
    #[inline(never)]
    fn release_run_rows(&mut self) {
        for rejected in self.run_jumps.drain(..) {
            self.passed_refused.0 += 1;
            self.passed_refused.1.get_or_insert(rejected);
            self.jumps_passed += 1;
        }
        self.ready.extend(self.run.drain(..));
    }

    /// The run after a confirmed jump was glitched stamps: each of its rows is rejected.
    #[cold]
    fn reject_run(&mut self) {
        let mut run = std::mem::take(&mut self.run);
        let jumped = std::mem::take(&mut self.run_jumps);
        for row in run.drain(..) {
            let rejected = RejectedRow {
                line: row.line,
                column: REQUIRED_COLUMNS[0].to_string(),
                value: time_text(row.t_s),
                reason: RejectReason::TimeGlitch,
                field_counts: None,
                ends_with_comma: false,
            };
            // A jumped row with the value as it was read.
            let rejected = match jumped.iter().find(|j| j.line == row.line) {
                Some(j) => RejectedRow {
                    reason: RejectReason::TimeGlitch,
                    ..j.clone()
                },
                None => rejected,
            };
            self.reject(rejected);
        }
        self.run = run;
    }

    /// The next accepted row, or an error, or `None` at the end of the source.
    pub(super) fn next_row(&mut self) -> Result<Option<ImuRow>, ImuCsvError> {
        if let Some(row) = self.ready.pop_front() {
            return Ok(Some(self.emit(row)));
        }
        let n_fields = self.names.len();
        // A header that ends in a comma: rows may leave that unnamed last field out.
        let unnamed_last = self.names.last().is_some_and(String::is_empty);
        loop {
            if !self.read_line()? {
                // A jump on the last row was never confirmed. A one-row log: its only time had
                // nothing to contradict it. A run after a confirmed jump goes out.
                for (_, rejected) in [self.jumped.take(), self.went_back.take()]
                    .into_iter()
                    .flatten()
                {
                    self.reject(rejected);
                }
                self.release_run();
                self.ready.extend(self.held.take());
                return Ok(self.ready.pop_front().map(|row| self.emit(row)));
            }
            let line_no = self.line_no;
            // Only the first bytes of a line cut at MAX_LINE_BYTES are kept: the rest is read
            // past, its commas counted.
            self.skip_rest()?;
            if self.line.iter().all(u8::is_ascii_whitespace) {
                // Blank lines are fine at the end of the file; in the middle they are malformed.
                self.blank.get_or_insert((line_no, 0)).1 += 1;
                continue;
            }
            if let Some((first, n)) = self.blank.take() {
                for blank in first..first + n {
                    self.total += 1;
                    self.reject(RejectedRow {
                        line: blank,
                        column: String::new(),
                        value: String::new(),
                        reason: RejectReason::Malformed,
                        field_counts: None,
                        ends_with_comma: false,
                    });
                }
            }
            self.total += 1;
            if let Some(cut) = self.line_cut.take() {
                // Never parsed: a number cut short would read as another.
                let rejected = self.cut_row(line_no, n_fields, cut);
                self.reject(rejected);
                continue;
            }
            if self.first_row_bytes == 0 {
                self.first_row_bytes = self.line.len() as u64 + 1;
            }
            let line = std::mem::take(&mut self.line);
            let raw = Self::line_str(&line);
            let text = strip_cr(&raw);
            let parsed = parse_row(text, line_no, n_fields, unnamed_last, self.temp_index);
            if let Ok(row) = &parsed {
                if self.temp_index.is_some() && row.temp_c.is_none() {
                    self.temperature_missing += 1;
                }
                let (first, _, n) = self.parsed_t.unwrap_or((row.t_s, row.t_s, 0));
                self.parsed_t = Some((first, row.t_s, n + 1));
            }
            // Ok: the row, with the row refused as a jump that it shows to be a real gap's far
            // side. Err: the rejection, with the row when it was refused as a jump.
            let verdict = match parsed {
                Ok(row) => match self.time.check(row.t_s) {
                    verdict @ (TimeVerdict::Accept
                    | TimeVerdict::NewBase
                    | TimeVerdict::Rebase
                    | TimeVerdict::Glitch
                    | TimeVerdict::GlitchRun
                    | TimeVerdict::StepBack) => {
                        // The held jump was a real gap's far side, or the held row the first
                        // after the clock stepped back: this row follows it. (A step back is
                        // taken here whatever the rates: the estimator judges it again.)
                        let (jump, back) = (self.jumped.take(), self.went_back.take());
                        let (passed, dropped) = match verdict {
                            TimeVerdict::NewBase => (jump, [back, None]),
                            TimeVerdict::StepBack => (back, [jump, None]),
                            _ => (None, [jump, back]),
                        };
                        // In line order: the run's rows came before those held in the slots.
                        if verdict == TimeVerdict::GlitchRun {
                            self.reject_run();
                        }
                        for (_, rejected) in dropped.into_iter().flatten() {
                            self.reject(rejected);
                        }
                        // A confirmed jump's row opens the run after it, or joins the run
                        // within which it came (see `run`); this row, the first after a step
                        // back, is passed on now.
                        let jumped = passed.map(|(j, rejected)| {
                            if verdict == TimeVerdict::NewBase {
                                self.run_jumps.push(rejected);
                            } else {
                                self.passed_refused.0 += 1;
                                self.passed_refused.1.get_or_insert(rejected);
                            }
                            j
                        });
                        self.time.accept(row.t_s);
                        if matches!(verdict, TimeVerdict::Rebase | TimeVerdict::Glitch)
                            && let Some(first) = self.held.take()
                        {
                            self.reject(RejectedRow {
                                line: first.line,
                                column: REQUIRED_COLUMNS[0].to_string(),
                                value: time_text(first.t_s),
                                reason: if verdict == TimeVerdict::Glitch {
                                    RejectReason::TimeGlitch
                                } else {
                                    RejectReason::TimeOutlier
                                },
                                field_counts: None,
                                ends_with_comma: false,
                            });
                        }
                        Ok((row, jumped))
                    }
                    verdict => Err((
                        matches!(verdict, TimeVerdict::Jump | TimeVerdict::NotIncreasing)
                            .then_some(row),
                        RejectedRow {
                            line: line_no,
                            column: REQUIRED_COLUMNS[0].to_string(),
                            value: truncate_chars(
                                unquote(text.split(',').next().unwrap_or("")),
                                MAX_VALUE_CHARS,
                            ),
                            reason: if verdict == TimeVerdict::Jump {
                                RejectReason::TimeJump
                            } else {
                                RejectReason::TimeNotIncreasing
                            },
                            field_counts: None,
                            ends_with_comma: false,
                        },
                    )),
                },
                Err(RowProblem::FieldCount(fields)) => Err((
                    None,
                    RejectedRow {
                        line: line_no,
                        column: String::new(),
                        value: truncate_chars(text, MAX_VALUE_CHARS),
                        reason: RejectReason::Malformed,
                        field_counts: Some((fields, n_fields)),
                        ends_with_comma: text.trim_end().ends_with(','),
                    },
                )),
                Err(RowProblem::Field {
                    index,
                    text,
                    reason,
                }) => Err((
                    None,
                    RejectedRow {
                        line: line_no,
                        column: self.names[index].clone(),
                        value: truncate_chars(text, MAX_VALUE_CHARS),
                        reason,
                        field_counts: None,
                        ends_with_comma: false,
                    },
                )),
            };
            self.line = line;
            match verdict {
                // The run after a confirmed jump, while it is open: held (a row held before it,
                // a gap's far side, goes out).
                Ok((row, jumped)) if let Some(run) = self.time.jump_run() => {
                    // A gap's far side that this row follows opens a run too: the held row is
                    // its first.
                    match self.held.take() {
                        Some(far) if self.run.is_empty() && far.t_s == run.first_s => {
                            self.run.push(far);
                        }
                        held => self.ready.extend(held),
                    }
                    self.run.extend(jumped);
                    self.run.push(row);
                }
                // The very first time, or a time after a gap: held until a row follows it. A
                // row held before (the first row, or a gap's far side, now followed by a gap)
                // goes out, after a run that closed.
                Ok((row, None)) if !self.time.confirmed() || self.time.provisional() => {
                    self.release_run();
                    self.ready.extend(self.held.replace(row));
                }
                // Nearly every row: nothing held before it, out at once (through the queue it
                // cost 5.7 % more instructions per row).
                Ok((row, None))
                    if self.held.is_none() && self.run.is_empty() && self.ready.is_empty() =>
                {
                    return Ok(Some(self.emit(row)));
                }
                // Out in order: a run that closed, a held row, a jumped one this row confirmed,
                // this row.
                Ok((row, jumped)) => {
                    self.release_run();
                    self.ready
                        .extend([self.held.take(), jumped, Some(row)].into_iter().flatten());
                }
                // A jump or a time that went back: held until the next row says whether it was
                // a gap's far side or the clock's step back (a row held before is rejected when
                // the next row was not judged: a jump or a going back again).
                // A row that went back leaves a held jump, as the time rule keeps its candidate;
                // a jump drops a held row that went back, as the rule drops that candidate.
                Err((Some(row), rejected)) => {
                    let jump = rejected.reason == RejectReason::TimeJump;
                    let (slot, other) = if jump {
                        (&mut self.jumped, self.went_back.take())
                    } else {
                        (&mut self.went_back, None)
                    };
                    let before = slot.replace((row, rejected));
                    for (_, rejected) in [before, other].into_iter().flatten() {
                        self.reject(rejected);
                    }
                }
                Err((None, rejected)) => self.reject(rejected),
            }
            if let Some(row) = self.ready.pop_front() {
                return Ok(Some(self.emit(row)));
            }
        }
    }

    /// Counts an accepted row on its way out.
    fn emit(&mut self, row: ImuRow) -> ImuRow {
        self.accepted += 1;
        if self.check_units {
            self.units.add(&row);
        }
        row
    }

    /// For a log whose rows were refused mostly as time jumps: whether its `t_s` advance by a
    /// step the time rule would take in milliseconds, microseconds or nanoseconds (the mean
    /// step over the rows that parsed, scaled); empty otherwise.
    fn time_unit_hint(&self, n_rejected: u64) -> String {
        let jumps = self.rejected_counts[RejectReason::TimeJump.index()] + self.jumps_passed;
        let Some((first, last, n)) = self.parsed_t else {
            return String::new();
        };
        if 2 * jumps <= n_rejected || n < 3 {
            return String::new();
        }
        let step = (last - first) / (n - 1) as f64;
        [
            (1e-3, "milliseconds"),
            (1e-6, "microseconds"),
            (1e-9, "nanoseconds"),
        ]
        .iter()
        .find(|(scale, _)| step > self.max_dt_s && step * scale <= self.max_dt_s)
        .map_or(String::new(), |(scale, unit)| {
            format!(
                " (the rows' t_s advance by {step:.4} on average: {:.4} s if they are \
                     {unit}; t_s must be in seconds)",
                step * scale
            )
        })
    }

    /// The checks over the whole log, in the order of [`parse_imu_csv`].
    pub(super) fn finish(&mut self) -> Result<(), ImuCsvError> {
        let path = || self.path.clone();
        if self.total == 0 {
            return Err(ImuCsvError::Empty { path: path() });
        }
        let max_fraction = if self.max_rejected_fraction.is_nan() {
            0.0
        } else {
            self.max_rejected_fraction
        };
        // The rows passed on after a time jump or before a step back count: the estimator
        // refuses them.
        let n_rejected = self.rows_rejected() + self.passed_refused.0;
        if n_rejected as f64 > max_fraction * self.total as f64 {
            let first = self
                .rejected
                .iter()
                .chain(&self.passed_refused.1)
                .min_by_key(|r| r.line)
                .cloned()
                .expect("a rejected row or a row passed on after a jump or before a step back");
            return Err(ImuCsvError::TooManyRejected {
                path: path(),
                rejected: n_rejected,
                total: self.total,
                max_rejected_fraction: self.max_rejected_fraction,
                first: Box::new(first),
                hint: self.time_unit_hint(n_rejected),
            });
        }
        if self.accepted == 0 {
            return Err(ImuCsvError::Empty { path: path() });
        }
        if self.check_units {
            self.units.check(&self.path)?;
        }
        Ok(())
    }
}

impl<R: BufRead> Iterator for ImuCsvReader<R> {
    type Item = Result<ImuRow, ImuCsvError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        let result = match self.next_row() {
            Ok(Some(row)) => return Some(Ok(row)),
            Ok(None) => self.finish(),
            Err(e) => Err(e),
        };
        self.done = true;
        result.err().map(Err)
    }
}
