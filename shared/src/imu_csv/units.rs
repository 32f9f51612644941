//! The units check over the accepted rows: accelerometers in g, gyroscopes in deg/s (at the end
//! of the log, and over the rows so far on request: [`ImuCsvReader::check_units_so_far`]).

use super::*;

/// Bands of |a| (m/s²) that decide the units check: below "g", "g", between, plausible, above.
/// The median's band decides; the bands' bounds are those of [`check_units`] (g and plausible
/// inclusive).
pub(super) fn accel_band(norm: f64) -> usize {
    if norm < ACCEL_LOOKS_LIKE_G_M_S2.0 {
        0
    } else if norm <= ACCEL_LOOKS_LIKE_G_M_S2.1 {
        1
    } else if norm < ACCEL_PLAUSIBLE_MEDIAN_M_S2.0 {
        2
    } else if norm <= ACCEL_PLAUSIBLE_MEDIAN_M_S2.1 {
        3
    } else {
        4
    }
}

/// Bins per octave of the |a| histogram (a power of two: mantissa bits of a key).
pub(super) const HIST_BITS: u32 = 10;
/// The histogram spans |a| in [2^HIST_MIN_EXP, 2^HIST_MAX_EXP) m/s²; values outside fall in the
/// first or last bin.
pub(super) const HIST_MIN_EXP: i32 = -10;
pub(super) const HIST_MAX_EXP: i32 = 16;

/// The units statistics of the accepted rows, in memory independent of their number.
#[derive(Debug, Default)]
pub(super) struct UnitsStats {
    /// |a| of every row while there are at most [`EXACT_MEDIAN_ROWS`].
    pub(super) norms: Vec<f64>,
    /// Rows per [`accel_band`].
    pub(super) bands: [u64; 5],
    /// |a| histogram, once `norms` overflowed.
    pub(super) hist: Vec<u32>,
    /// Largest |ω| and its line (the first on ties).
    pub(super) max_gyro: (f64, u64),
    /// Rows whose |ω| lies above [`GYRO_MAX_PLAUSIBLE_RAD_S`].
    pub(super) gyro_over: u64,
}

/// A gyro in deg/s reads above [`GYRO_MAX_PLAUSIBLE_RAD_S`] on many rows (every swing of a
/// foot); at least this fraction of them says "units", fewer are single bad values, which the
/// sensor's plausibility check refuses and counts (one corrupt value refused the whole file).
pub(super) const GYRO_UNITS_MIN_FRACTION: f64 = 0.01;

/// What it takes to say "deg/s" before the end of the log: at least this many rows read, and
/// of them at least [`GYRO_UNITS_MIN_FRACTION_EARLY`] above [`GYRO_MAX_PLAUSIBLE_RAD_S`]. A
/// walk in deg/s has one row in two above it (4,099 of exp17's 6,601); a burst of bad values
/// does not (the end's 1 % alone refused a 25-row burst among `corridor run`'s 2,002 rows read
/// ahead, 0.1 s of exp36, which the end of the log's check passes: a review).
pub(super) const GYRO_UNITS_MIN_ROWS_SEEN_EARLY: u64 = 500;

/// Rows it takes to judge an accelerometer off scale before the end of the log (the read-ahead
/// can end after a few rows, at a forward time jump: a review).
pub(super) const ACCEL_MIN_ROWS_SEEN_EARLY: u64 = 200;

/// See [`GYRO_UNITS_MIN_ROWS_SEEN_EARLY`].
pub(super) const GYRO_UNITS_MIN_FRACTION_EARLY: f64 = 0.1;

impl UnitsStats {
    pub(super) fn hist_index(norm: f64) -> usize {
        let lo = 2f64.powi(HIST_MIN_EXP);
        let shift = 52 - HIST_BITS;
        let n_bins = ((HIST_MAX_EXP - HIST_MIN_EXP) as usize) << HIST_BITS;
        if norm.is_nan() || norm < lo {
            return 0;
        }
        let i = ((norm.to_bits() - lo.to_bits()) >> shift) as usize;
        i.min(n_bins - 1)
    }

    pub(super) fn add(&mut self, row: &ImuRow) {
        let a = norm3(row.accel_m_s2);
        self.bands[accel_band(a)] += 1;
        if self.hist.is_empty() {
            if self.norms.len() < EXACT_MEDIAN_ROWS {
                self.norms.push(a);
            } else {
                self.hist = vec![0; ((HIST_MAX_EXP - HIST_MIN_EXP) as usize) << HIST_BITS];
                for n in std::mem::take(&mut self.norms) {
                    self.hist[Self::hist_index(n)] += 1;
                }
            }
        }
        if !self.hist.is_empty() {
            self.hist[Self::hist_index(a)] += 1;
        }
        let w = norm3(row.gyro_rad_s);
        if w > self.max_gyro.0 {
            self.max_gyro = (w, row.line);
        }
        self.gyro_over += u64::from(w > GYRO_MAX_PLAUSIBLE_RAD_S);
    }

    /// The median |a| (exact while the norms are kept) and the statistic's name.
    pub(super) fn median(&mut self) -> (f64, &'static str) {
        if self.hist.is_empty() {
            let mid = self.norms.len() / 2;
            let (_, median, _) = self.norms.select_nth_unstable_by(mid, f64::total_cmp);
            return (*median, "median |a| (m/s²)");
        }
        let n: u64 = self.bands.iter().sum();
        let mut left = n / 2;
        let lo = 2f64.powi(HIST_MIN_EXP).to_bits();
        let shift = 52 - HIST_BITS;
        for (i, &c) in self.hist.iter().enumerate() {
            if left < u64::from(c) {
                // The bin's middle.
                let bits = lo + ((i as u64) << shift) + (1 << (shift - 1));
                return (f64::from_bits(bits), "median |a| (m/s², to 0.07 %)");
            }
            left -= u64::from(c);
        }
        unreachable!("the histogram holds every row")
    }

    /// The [`accel_band`] of the median |a| (exact for any length).
    pub(super) fn median_band(&self) -> usize {
        let n: u64 = self.bands.iter().sum();
        let mut rank = n / 2;
        for (i, &c) in self.bands.iter().enumerate() {
            if rank < c {
                return i;
            }
            rank -= c;
        }
        0
    }

    /// Whether the median |a| lies in a band no working accelerometer in m/s² reads over any
    /// stretch of a walk: the band of a log in g, or, over at least
    /// [`ACCEL_MIN_ROWS_SEEN_EARLY`] rows (a few rows of a foot struck hard are no stretch),
    /// the one between g and the plausible band (a wrong scale: 0.4 × m/s² reads 3.9) or the
    /// one above it (mg, ft/s²). Not the band below g: an accelerometer that starts late reads
    /// 0 for its first rows.
    pub(super) fn accel_units_wrong_early(&self) -> bool {
        let n: u64 = self.bands.iter().sum();
        match self.median_band() {
            1 => true,
            2 | 4 => n >= ACCEL_MIN_ROWS_SEEN_EARLY,
            _ => false,
        }
    }

    /// Whether the rows so far read like a gyro in deg/s, judged before the end of the log
    /// ([`GYRO_UNITS_MIN_ROWS_SEEN_EARLY`] rows, a tenth of them above the plausible rate), so
    /// that a burst of corrupt values is not taken for units.
    pub(super) fn looks_like_deg_s_early(&self) -> bool {
        let n: u64 = self.bands.iter().sum();
        n >= GYRO_UNITS_MIN_ROWS_SEEN_EARLY
            && self.gyro_over as f64 >= GYRO_UNITS_MIN_FRACTION_EARLY * n as f64
    }

    /// Refuses logs whose accelerometer does not look like m/s² or whose gyroscope does not
    /// look like rad/s. The decision is the median's band, exact for any length.
    pub(super) fn check(&mut self, path: &Path) -> Result<(), ImuCsvError> {
        self.check_accel(path)?;
        self.check_gyro(path)
    }

    fn units_error(
        path: &Path,
        column: &'static str,
        statistic: &str,
        value: f64,
        hint: String,
    ) -> ImuCsvError {
        ImuCsvError::Units {
            path: path.to_path_buf(),
            column,
            statistic: statistic.to_string(),
            value,
            hint,
        }
    }

    /// The accelerometer's part of [`UnitsStats::check`].
    fn check_accel(&mut self, path: &Path) -> Result<(), ImuCsvError> {
        let band = self.median_band();
        let units = |column, statistic: &str, value, hint| {
            Self::units_error(path, column, statistic, value, hint)
        };
        const ACCEL_COLUMNS: &str = "ax_m_s2,ay_m_s2,az_m_s2";
        if band == 1 {
            let (median, stat) = self.median();
            return Err(units(
                ACCEL_COLUMNS,
                stat,
                median,
                format!(
                    "the accelerometer looks like it is in g, not m/s²; multiply by {STANDARD_GRAVITY_M_S2}"
                ),
            ));
        }
        if band != 3 {
            let (median, stat) = self.median();
            return Err(units(
                ACCEL_COLUMNS,
                stat,
                median,
                format!(
                    "expected specific force in m/s² with gravity included (median |a| about {STANDARD_GRAVITY_M_S2}, \
                     allowed {}..{}); check the accelerometer's units and scale, and that gravity was not removed",
                    ACCEL_PLAUSIBLE_MEDIAN_M_S2.0, ACCEL_PLAUSIBLE_MEDIAN_M_S2.1
                ),
            ));
        }
        Ok(())
    }

    /// The gyroscope's part of [`UnitsStats::check`].
    pub(super) fn check_gyro(&self, path: &Path) -> Result<(), ImuCsvError> {
        let n: u64 = self.bands.iter().sum();
        let units = |column, statistic: &str, value, hint| {
            Self::units_error(path, column, statistic, value, hint)
        };
        let (max_gyro, max_line) = self.max_gyro;
        if self.gyro_over as f64 >= GYRO_UNITS_MIN_FRACTION * n as f64 && self.gyro_over > 0 {
            return Err(units(
                "gx_rad_s,gy_rad_s,gz_rad_s",
                &format!(
                    "max |ω| (rad/s, {} of {n} rows above {GYRO_MAX_PLAUSIBLE_RAD_S}) at line {max_line}",
                    self.gyro_over
                ),
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
}

impl<R: BufRead> ImuCsvReader<R> {
    /// The units check's verdicts on the accelerometer (in g, or a median |a| between g and the
    /// plausible band or above it) and "in deg/s" ([`ImuCsvError::Units`], the end of the
    /// log's check) over the rows accepted so far, for a caller with a reason to suspect
    /// wrong units before the end: the first rows of the log read (`corridor run` judges them
    /// before it estimates any), the estimator refusing a rest as not gravity or a rate as
    /// implausible. Such a log should say so once, not after a warning per stance or per swing
    /// (a review: 20 warnings of refused rates, gaps and health checks before the deg/s error at
    /// the end; ten of rests not gravity before the scale error). Only those verdicts: a log
    /// whose first rows read nothing (an accelerometer that starts late, or gravity removed) is
    /// judged at the end, on every row, as before (a review found such a log in m/s² refused
    /// early as "gravity removed"), and "deg/s" takes a tenth of at least 500 rows above the
    /// plausible rate (the end: 1 % of all). The statistic names the rows it covers. `Ok` when
    /// the units are not checked, no row was accepted yet, or the rows so far look like
    /// neither.
    pub fn check_units_so_far(&mut self) -> Result<(), ImuCsvError> {
        if !self.check_units || self.accepted == 0 {
            return Ok(());
        }
        if !self.units.accel_units_wrong_early() {
            // (The gyro's statistic counts the rows already: "N of M rows above 40".)
            return if self.units.looks_like_deg_s_early() {
                self.units.check_gyro(&self.path)
            } else {
                Ok(())
            };
        }
        self.units.check(&self.path).map_err(|e| match e {
            ImuCsvError::Units {
                path,
                column,
                statistic,
                value,
                hint,
            } => ImuCsvError::Units {
                path,
                column,
                statistic: format!("{statistic} over the first {} rows", self.accepted),
                value,
                hint,
            },
            other => other,
        })
    }
}
