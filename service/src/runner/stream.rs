//! `corridor run`: the streamed run, what it keeps for the summary ([`super::Summary`]), its
//! staged outputs and its progress bar.

use super::*;
use corridor_shared::config::TypicalGyroBias;

/// What a streamed run keeps of its estimates: memory independent of the log's length.
struct Kept {
    /// Bias and σ of the last estimate.
    last: Option<([f64; 3], [f64; 3])>,
    /// The time of the last estimate, s.
    last_t_s: Option<f64>,
    /// Sum and count of the bias from the first converged sample on.
    converged_sum: [f64; 3],
    converged_n: usize,
    /// Positions next to the footprint times, when truth was given.
    gcps: Option<GcpSampler>,
    /// The figures' traces, with `--plots`.
    plot: Option<PlotTrace>,
}

impl Kept {
    fn new(truth: Option<&[TruthGcp]>, plots: bool) -> Self {
        Self {
            last: None,
            last_t_s: None,
            converged_sum: [0.0; 3],
            converged_n: 0,
            gcps: truth.map(|t| GcpSampler::new(t, &EvalOptions::default())),
            plot: plots.then(PlotTrace::new),
        }
    }

    /// One estimate; `converged_at_s` is the estimator's after it (the same sum as
    /// [`Trace::mean_bias_from`] over the whole trace).
    fn push(&mut self, e: &Estimate, converged_at_s: Option<f64>) {
        self.last = Some((e.gyro_bias_rad_s, e.gyro_bias_sd_rad_s));
        self.last_t_s = Some(e.t_s);
        if converged_at_s.is_some_and(|t| e.t_s >= t) {
            for k in 0..3 {
                self.converged_sum[k] += e.gyro_bias_rad_s[k];
            }
            self.converged_n += 1;
        }
        if let Some(g) = &mut self.gcps {
            if e.clock_stepped_back_s.is_some() {
                g.clock_stepped_back();
            }
            g.push(e.t_s, e.p_m[0], e.p_m[1]);
        }
        if let Some(p) = &mut self.plot {
            p.push(e);
        }
    }

    fn mean_bias_converged(&self) -> Option<[f64; 3]> {
        let n = self.converged_n;
        (n > 0).then(|| self.converged_sum.map(|s| s / n as f64))
    }
}

/// How many samples of each trace `--plots` keeps at most (about 2.4 MB a trace): a log up to
/// this length is drawn sample by sample, a longer one decimated evenly.
pub const PLOT_POINTS: usize = 1 << 15;

/// A trace of at most [`PLOT_POINTS`] samples: every `stride`-th estimate; when full, every
/// other sample is dropped and the stride doubles.
struct PlotTrace {
    trace: Trace,
    stride: u64,
    seen: u64,
}

impl PlotTrace {
    fn new() -> Self {
        let n = PLOT_POINTS;
        Self {
            trace: Trace {
                t_s: Vec::with_capacity(n),
                xy_m: Vec::with_capacity(n),
                bias_rad_s: Vec::with_capacity(n),
                bias_sd_rad_s: Vec::with_capacity(n),
                converged: Vec::with_capacity(n),
            },
            stride: 1,
            seen: 0,
        }
    }

    fn push(&mut self, e: &Estimate) {
        if self.seen.is_multiple_of(self.stride) {
            if self.trace.len() == PLOT_POINTS {
                self.trace.halve();
                self.stride *= 2;
            }
            if self.seen.is_multiple_of(self.stride) {
                self.trace.push(e);
            }
        }
        self.seen += 1;
    }
}

/// Every file `corridor run` writes into its output directory. One that an earlier run wrote
/// (its `summary.json` lists it) and a successful run did not write again (the figures of a run
/// with `--plots`) is removed then: left, it passed for this run's (reviews of session 38; a
/// file of these names that no run of ours listed is the user's, and stays).
pub(super) const RUN_OUTPUT_FILES: [&str; 6] = [
    "estimates.csv",
    "innovations.csv",
    "summary.json",
    "trajectory.svg",
    "bias.svg",
    "covariance.svg",
];

/// Refuses a run whose output would replace one of its inputs (`--imu out/estimates.csv
/// --out out` replaced the log with its estimates, exit 0: a review).
fn refuse_inputs_as_outputs(opts: &RunOptions) -> Result<(), RunError> {
    let inputs: Vec<PathBuf> = [Some(&opts.imu), opts.truth.as_ref(), opts.map.as_ref()]
        .into_iter()
        .flatten()
        .filter_map(|p| std::fs::canonicalize(p).ok())
        .collect();
    // The staging names too (`NAME.partial`, created first: an input of that name was
    // truncated before it was read, a review).
    for name in RUN_OUTPUT_FILES {
        for out in [
            opts.out_dir.join(name),
            opts.out_dir.join(format!("{name}.partial")),
        ] {
            if let Ok(canonical) = std::fs::canonicalize(&out)
                && inputs.contains(&canonical)
            {
                return Err(RunError::OutputIsInput { path: out });
            }
        }
    }
    Ok(())
}

/// Outputs written as `NAME.partial` and renamed to `NAME` by [`Staged::commit`]; dropped
/// without it (a failed run), the partial files are removed.
struct Staged {
    /// The final paths.
    files: Vec<PathBuf>,
    committed: bool,
}

impl Staged {
    fn new() -> Self {
        Self {
            files: Vec::new(),
            committed: false,
        }
    }

    fn partial(path: &Path) -> PathBuf {
        let mut name = path.as_os_str().to_owned();
        name.push(".partial");
        PathBuf::from(name)
    }

    /// The temporary path to write `path` under.
    fn stage(&mut self, path: PathBuf) -> PathBuf {
        let partial = Self::partial(&path);
        self.files.push(path);
        partial
    }

    /// Creates `path`'s temporary file for buffered writing.
    fn create(
        &mut self,
        path: PathBuf,
    ) -> Result<(std::io::BufWriter<std::fs::File>, PathBuf), RunError> {
        let partial = self.stage(path);
        Ok((create(&partial)?, partial))
    }

    /// Renames every file to its final name, then removes what an earlier run in `dir` wrote
    /// (`earlier`, from its summary) and this one did not. The run has succeeded by then: a
    /// file that cannot be removed is warned of, not an error.
    fn commit(mut self, dir: &Path, earlier: &[String]) -> Result<(), RunError> {
        // A directory in the way fails a rename: found before the first one, so that a failed
        // run leaves the earlier outputs whole rather than half replaced (a review).
        if let Some(f) = self.files.iter().find(|f| f.is_dir()) {
            let e = std::io::Error::new(
                std::io::ErrorKind::IsADirectory,
                "a directory stands where this output goes",
            );
            return Err(io_at(f)(e));
        }
        for f in &self.files {
            std::fs::rename(Self::partial(f), f).map_err(io_at(f))?;
        }
        self.committed = true;
        for name in earlier {
            let stale = dir.join(name);
            if self.files.contains(&stale) {
                continue;
            }
            match std::fs::remove_file(&stale) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                    tracing::warn!(
                        "{}: an earlier run's output, not written by this one, could not be removed: {e}",
                        stale.display()
                    );
                }
                _ => {}
            }
        }
        Ok(())
    }
}

/// The outputs an earlier run listed in `dir/summary.json` (only names of
/// [`RUN_OUTPUT_FILES`]); none when there is no such summary or it lists none.
fn earlier_outputs(dir: &Path) -> Vec<String> {
    let Ok(text) = std::fs::read_to_string(dir.join("summary.json")) else {
        return Vec::new();
    };
    let Ok(json) = serde_json::from_str::<serde_json::Value>(&text) else {
        return Vec::new();
    };
    json.get("outputs")
        .and_then(|v| v.as_array())
        .into_iter()
        .flatten()
        .filter_map(|v| v.as_str())
        .filter(|n| RUN_OUTPUT_FILES.contains(n))
        .map(str::to_owned)
        .collect()
}

impl Drop for Staged {
    fn drop(&mut self) {
        if !self.committed {
            for f in &self.files {
                // Files not yet created, or already renamed, are not there: nothing to do.
                let _ = std::fs::remove_file(Self::partial(f));
            }
        }
    }
}

/// Everything `corridor run` needs.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// IMU log.
    pub imu: PathBuf,
    /// Validated configuration (with command-line overrides applied).
    pub config: Config,
    /// Corridor map file.
    pub map: Option<PathBuf>,
    /// Ground truth.
    pub truth: Option<PathBuf>,
    /// Synthetic bias injection.
    pub injection: BiasInjection,
    /// Write the figures.
    pub plots: bool,
    /// Output directory.
    pub out_dir: PathBuf,
    /// Reader options.
    pub csv: corridor_shared::imu_csv::ImuCsvOptions,
    /// A saved bias state to start from, as the daemon starts from its checkpoint.
    pub warm_start: Option<crate::core::WarmStart>,
}

/// The log's first seconds whose units are judged before any row is estimated
/// ([`ImuCsvReader::check_units_so_far`]): they hold the first strides of every bundled walk
/// (exp17's first swing comes 1.2 s in). A log that rests longer is judged again at each
/// refusal as not gravity or implausible.
const UNITS_AHEAD_S: f64 = 10.0;

/// At most this many rows are read ahead for it (8 s of a 2 kHz sensor; 80 B each, 1.3 MB,
/// a power of two so that the buffer does not double past it): the runner's peak heap does not
/// grow with the log (`run_memory.rs`).
const UNITS_AHEAD_ROWS: usize = 16_384;

/// Streams a log through the estimator and writes `estimates.csv`, `innovations.csv`,
/// `summary.json` (and the figures); see the module's documentation for what is kept and what
/// a failed run leaves.
pub fn run(opts: &RunOptions) -> Result<Summary, RunError> {
    let csv = corridor_shared::imu_csv::ImuCsvOptions {
        min_dt_s: opts.config.sensor.min_dt_s(),
        max_dt_s: opts.config.sensor.max_dt_s(),
        gap_dt_s: opts.config.max_dt_s.get(),
        ..opts.csv.clone()
    };
    let mut reader = ImuCsvReader::open(&opts.imu, &csv)?;
    let truth = opts
        .truth
        .as_deref()
        .map(corridor_shared::truth_csv::read_truth_csv)
        .transpose()?;
    let gcps: Option<Vec<TruthGcp>> = truth.as_ref().map(|t| t.iter().map(to_gcp).collect());
    let aid = heading_aid(&opts.config, opts.map.as_deref())?;
    std::fs::create_dir_all(&opts.out_dir).map_err(|source| RunError::OutDir {
        path: opts.out_dir.clone(),
        source,
    })?;
    refuse_inputs_as_outputs(opts)?;
    let mut staged = Staged::new();
    let (mut est_w, est_path) = staged.create(opts.out_dir.join("estimates.csv"))?;
    let (mut inn_w, inn_path) = staged.create(opts.out_dir.join("innovations.csv"))?;
    writeln!(est_w, "{ESTIMATES_HEADER}").map_err(io_at(&est_path))?;
    writeln!(inn_w, "{INNOVATIONS_HEADER}").map_err(io_at(&inn_path))?;

    let mut feed = Feed::new(&opts.config, &aid, &opts.injection, &opts.imu);
    if let Some(ws) = opts.warm_start {
        feed.est.set_warm_start(ws)?;
    }
    let mut kept = Kept::new(gcps.as_deref(), opts.plots);
    // "Before" for the figures: the same rows through the ZUPT filter alone, without any bias
    // correction, in the same pass.
    let mut before = opts.plots.then(|| {
        let mut base = opts.config.clone();
        base.mode = corridor_shared::config::Mode::Zupt;
        base.alignment.gyro_bias_prior = corridor_shared::config::BiasPrior::None;
        (
            Feed::new(&base, &HeadingAid::None, &opts.injection, &opts.imu).quiet(),
            Kept::new(gcps.as_deref(), true),
        )
    });
    let mut progress = Progress::new(reader.progress_bytes().1.unwrap_or(0));
    let mut logged = 0;
    let mut next_row = |reader: &mut ImuCsvReader<_>| {
        let item = reader.next();
        while logged < reader.rejected_rows().len().min(REJECTED_ROWS_LOGGED) {
            tracing::warn!(
                "rejected input row: {}",
                reader.rejected_rows()[logged].located(reader.path())
            );
            logged += 1;
        }
        item
    };
    // The log's first `UNITS_AHEAD_S` are read before any row is estimated, and their units
    // judged (a gyro in deg/s, an accelerometer in g): such a log fails with the units error
    // alone, not after the warnings its rows cause (refused rates, gaps, health checks: 20 of
    // them before the error at the end, a review).
    let mut ahead = std::collections::VecDeque::with_capacity(256);
    while let Some(row) = next_row(&mut reader) {
        let row = row?;
        let first_t_s = ahead.front().map_or(row.t_s, |r: &ImuRow| r.t_s);
        let full = row.t_s - first_t_s >= UNITS_AHEAD_S || ahead.len() + 1 >= UNITS_AHEAD_ROWS;
        ahead.push_back(row);
        if full {
            break;
        }
    }
    reader.check_units_so_far()?;
    loop {
        let item = match ahead.pop_front() {
            Some(row) => Some(Ok(row)),
            None => next_row(&mut reader),
        };
        let Some(row) = item else { break };
        let row = row?;
        progress.show(reader.progress_bytes().0);
        if let Some((input, e, converged_at_s)) =
            feed.step_checked(&row, || reader.check_units_so_far())?
        {
            write_estimate_row(&mut est_w, e).map_err(io_at(&est_path))?;
            write_innovation_rows(&mut inn_w, &input, e).map_err(io_at(&inn_path))?;
            kept.push(e, converged_at_s);
        }
        if let Some((feed, kept)) = &mut before
            && let Some((_, e, converged_at_s)) = feed.step(&row)
        {
            kept.push(e, converged_at_s);
        }
    }
    progress.finish();
    est_w.flush().map_err(io_at(&est_path))?;
    inn_w.flush().map_err(io_at(&inn_path))?;
    drop((est_w, inn_w));
    feed.est.end_stream();
    let c = *feed.est.counters();
    let refused = c.refused();
    // The counts go to summary.json only when the run succeeds: these lines point at it then,
    // and a run that fails says them without the pointer.
    let nothing_accepted = c.samples == 0 && refused > 0;
    let never_aligned = c.samples > 0 && feed.est.mount_yaw_rad().is_none() && c.stances == 0;
    let more: Vec<String> = [
        (
            reader.rows_rejected().saturating_sub(logged as u64),
            "rejected rows",
        ),
        (
            refused.saturating_sub(MAX_REFUSED_EXAMPLES as u64),
            "refused samples",
        ),
        (
            feed.warned.saturating_sub(MAX_REFUSED_EXAMPLES) as u64,
            "gaps and health-check failures",
        ),
    ]
    .iter()
    .filter(|(n, _)| *n > 0)
    .map(|(n, what)| format!("{n} more {what}"))
    .collect();
    let say_more = |where_counted: &str| {
        for m in &more {
            tracing::warn!("{m}{where_counted}");
        }
    };
    if nothing_accepted {
        say_more("");
        return Err(RunError::NothingAccepted {
            path: opts.imu.clone(),
            samples: refused,
            // "line N: why": the error names the log once (the refusal was kept as "PATH:N: why").
            first: feed.refused.first().map_or_else(String::new, |f| {
                let path = format!("{}:", opts.imu.display());
                f.strip_prefix(&path)
                    .map_or_else(|| f.clone(), |rest| format!("line {rest}"))
            }),
        });
    }
    if never_aligned {
        say_more("");
        return Err(RunError::NeverAligned {
            path: opts.imu.clone(),
            min_rest_s: opts.config.alignment.min_rest_s.get(),
            not_gravity: c.alignment_not_gravity,
        });
    }
    let eval = match (&kept.gcps, &opts.truth) {
        (Some(g), Some(path)) => Some(
            g.finish()
                .map_err(|source| RunError::Eval {
                    truth: path.clone(),
                    source,
                })
                .inspect_err(|_| say_more(""))?,
        ),
        _ => None,
    };
    // What the evaluation had to do (footprints outside the log's time span clamped, as the
    // reference evaluation does) is said here too, not only in summary.json.
    if let (Some(e), Some(path)) = (&eval, &opts.truth) {
        for w in &e.warnings {
            tracing::warn!("{}: {w}", path.display());
        }
    }
    if let (Some((_, b)), Some(after)) = (&before, &kept.plot) {
        let eval_before = b.gcps.as_ref().and_then(|g| g.finish().ok());
        let before_trace = &b.plot.as_ref().expect("the before run keeps a trace").trace;
        write_figures_to(
            &mut |name| staged.stage(opts.out_dir.join(name)),
            before_trace,
            &after.trace,
            truth.as_deref(),
            (eval_before.as_ref(), eval.as_ref()),
        )
        .inspect_err(|_| say_more(""))?;
    }
    let mut summary = Summary {
        imu: opts.imu.display().to_string(),
        mode: opts.config.mode.name(),
        heading_aid: aid.name(),
        bias_rad_s: kept.last.map_or([f64::NAN; 3], |l| l.0),
        bias_sd_rad_s: kept.last.map_or([f64::NAN; 3], |l| l.1),
        bias_mean_converged_rad_s: kept.mean_bias_converged(),
        converged_at_s: feed.est.converged_at_s(),
        mount_yaw_deg: feed.est.mount_yaw_rad().map(f64::to_degrees),
        injected_gyro_bias_rad_s: opts.injection.constant_rad_s,
        injected_gyro_bias_ramp_rad_s2: opts.injection.ramp_rad_s2,
        injected_after_s: opts.injection.after_s,
        injected_rows: feed.injected_rows,
        first_t_s: feed.first_t_s,
        samples_read: reader.rows_accepted(),
        samples: c.samples,
        stances: c.stances,
        zupts: c.zupts,
        gaps: c.gaps,
        gaps_bridged: c.gaps_bridged,
        gaps_filled: c.gaps_filled,
        gaps_clock_steps: c.gaps_clock_steps,
        clock_steps_back: c.clock_steps_back,
        heading_observations_used: c.heading_used,
        heading_observations_rejected: BTreeMap::from([
            ("not_straight", c.heading_not_straight),
            ("outside_gate", c.heading_outside_gate),
            ("outside_map", c.heading_outside_map),
            ("unlikely", c.heading_unlikely),
            ("off_stride", c.heading_off_stride),
        ]),
        stride_observations_used: c.stride_used,
        stride_observations_rejected: c.stride_rejected,
        input_rows_rejected: reader.rejected_counts(),
        input_temperature_missing: reader.temperature_missing(),
        input_rows_rejected_examples: reader
            .rejected_rows()
            .iter()
            .take(10)
            .map(|r: &RejectedRow| r.located(reader.path()).to_string())
            .collect(),
        samples_refused_counts: BTreeMap::from([
            ("non_finite", c.rejected_non_finite),
            ("time_not_increasing", c.rejected_time),
            ("implausible", c.rejected_implausible),
            ("time_jump", c.rejected_time_jump),
        ]),
        samples_refused: feed.refused,
        clipped_samples: c.clipped_samples,
        clipped_peaks_restored: c.clipped_peaks_restored,
        clipped_peaks_not_restored: c.clipped_peaks_not_restored,
        health_restores: c.health_restores,
        footprints_forgotten: c.footprints_forgotten,
        velocity_resets: c.velocity_resets,
        relevels: c.relevels,
        heading_reacquisitions: c.heading_reacquisitions,
        jittery_clock_samples: c.jittery_clock_samples,
        headings_refused: c.headings_refused,
        headings_superseded: c.headings_superseded,
        headings_outside_gate: c.headings_outside_gate,
        headings_expired: c.headings_expired,
        headings_undone: c.headings_undone,
        started_without_rest: c.started_without_rest,
        alignment_not_gravity: c.alignment_not_gravity,
        specific_force_off_gravity: c.specific_force_off_gravity,
        rest_specific_force_m_s2: feed.est.rest_specific_force_m_s2(),
        stance_specific_force_m_s2: feed.est.stance_specific_force_m_s2(),
        specific_force_off_gravity_at_end: feed.est.specific_force_off_gravity_now(),
        start_replayed_ms: c.start_replayed_ms,
        rest_prior_refused: c.rest_prior_refused,
        initial_rest_moving_blocks: c.initial_rest_moving_blocks,
        bias_from_typical_sd: bias_from_typical_sd(
            kept.last.map(|l| l.0),
            opts.config.alignment.typical_gyro_bias,
            &opts.injection,
            kept.last_t_s.zip(feed.first_t_s).map(|(t, t0)| t - t0),
        ),
        zero_rate_updates: c.zero_rate_updates,
        zero_rate_refused: c.zero_rate_refused,
        late_footfalls: c.late_footfalls,
        late_footfalls_dropped: c.late_footfalls_dropped,
        notes: Vec::new(),
        eval,
        outputs: Vec::new(),
    };
    summary.notes = super::notes::notes(&summary);
    let sum_path = staged.stage(opts.out_dir.join("summary.json"));
    summary.outputs = staged
        .files
        .iter()
        .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    // What an earlier run here wrote, by its own summary (nothing else is ever removed).
    let earlier = earlier_outputs(&opts.out_dir);
    let json = serde_json::to_string_pretty(&summary).expect("summary serialises");
    std::fs::write(&sum_path, json + "\n")
        .map_err(io_at(&sum_path))
        .and_then(|()| staged.commit(&opts.out_dir, &earlier))
        .inspect_err(|_| say_more(""))?;
    say_more(" (counts in summary.json)");
    Ok(summary)
}

/// A progress bar on stderr over the bytes of the log, shown only when stderr is a terminal and
/// the log is long.
struct Progress {
    total_bytes: u64,
    shown_pct: u64,
    enabled: bool,
}

/// Logs shorter than this get no progress bar (about 100 000 rows), bytes.
const PROGRESS_MIN_BYTES: u64 = 8 << 20;

impl Progress {
    fn new(total_bytes: u64) -> Self {
        use std::io::IsTerminal;
        Self {
            total_bytes,
            shown_pct: 0,
            enabled: total_bytes >= PROGRESS_MIN_BYTES && std::io::stderr().is_terminal(),
        }
    }

    fn show(&mut self, done_bytes: u64) {
        if !self.enabled {
            return;
        }
        let pct = done_bytes * 100 / self.total_bytes.max(1);
        if pct > self.shown_pct {
            self.shown_pct = pct;
            let bar = "#".repeat(pct as usize / 2);
            eprint!(
                "\r[{bar:<50}] {pct:3} % ({} / {} MB)",
                done_bytes >> 20,
                self.total_bytes >> 20
            );
        }
    }

    fn finish(&self) {
        if self.enabled {
            eprintln!();
        }
    }
}

/// [`Summary::bias_from_typical_sd`]: the final bias `bias_rad_s`, estimated `since_start_s`
/// after the log's first sample, against the unit's `typical` one plus what was injected then
/// (nothing, for an injection that starts after the log ends).
fn bias_from_typical_sd(
    bias_rad_s: Option<[f64; 3]>,
    typical: Option<TypicalGyroBias>,
    injection: &BiasInjection,
    since_start_s: Option<f64>,
) -> Option<f64> {
    let (b, t, since_start_s) = (bias_rad_s?, typical?, since_start_s?);
    if injection.ramp_rad_s2 != [0.0; 3] || b.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let injected = injection.bias_at(since_start_s);
    let sd = t.sd_rad_s.get();
    (0..3)
        .map(|k| (b[k] - t.rad_s[k] - injected[k]).abs() / sd)
        .reduce(f64::max)
}

#[cfg(test)]
mod tests {
    use super::bias_from_typical_sd;
    use corridor_shared::config::{Positive, TypicalGyroBias};
    use corridor_shared::injection::BiasInjection;

    #[test]
    fn the_final_bias_is_measured_from_the_typical_one_plus_what_was_injected() {
        let typical = TypicalGyroBias {
            rad_s: [1e-3, -2e-3, 5e-3],
            sd_rad_s: Positive::new("sd", 4e-3).unwrap(),
        };
        let none = BiasInjection::default();
        let end = Some(60.0);
        let off = Some([1e-3, -2e-3, 25e-3]);
        let d = bias_from_typical_sd(off, Some(typical), &none, end).unwrap();
        assert!((d - 5.0).abs() < 1e-9, "{d}");
        let injected = BiasInjection {
            constant_rad_s: [0.0, 0.0, 0.02],
            ..Default::default()
        };
        let d = bias_from_typical_sd(off, Some(typical), &injected, end);
        assert!(d.unwrap() < 1e-9, "{d:?}");
        // An injection that starts after the log ends added nothing.
        let too_late = BiasInjection {
            after_s: 1e6,
            ..injected
        };
        let d = bias_from_typical_sd(off, Some(typical), &too_late, end).unwrap();
        assert!((d - 5.0).abs() < 1e-9, "{d}");
        // Nothing to compare with: no typical bias, no estimate, or a ramp injected.
        assert_eq!(bias_from_typical_sd(Some([0.0; 3]), None, &none, end), None);
        assert_eq!(bias_from_typical_sd(None, Some(typical), &none, end), None);
        let ramp = BiasInjection {
            ramp_rad_s2: [0.0, 0.0, 1e-4],
            ..Default::default()
        };
        assert_eq!(
            bias_from_typical_sd(Some([0.0; 3]), Some(typical), &ramp, end),
            None
        );
    }
}
