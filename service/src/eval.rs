//! Trajectory evaluation against surveyed footprint ground truth.
//!
//! A faithful port of the reference evaluator `tools/eval_traj.py` (its `evaluate()`
//! function): the same options, the same figures, the same JSON field names and the same
//! error cases. The method, in short:
//!
//! 1. **Sampling.** For each ground control point (GCP) time the trajectory position is
//!    taken from the trajectory row nearest in time ([`Interp::Nearest`]) or by linear
//!    interpolation ([`Interp::Linear`]). GCP times outside the trajectory's span are
//!    clamped to its ends; those more than 1 ms outside are listed under `warnings`.
//! 2. **Alignment.** [`Align::FirstLeg`] (the headline figure) puts the trajectory's
//!    GCP0 position on GCP0 and rotates about it so that the direction GCP0→GCPk matches
//!    the truth, where k is the first GCP at least `heading_min_dist_m` from GCP0; GCP0
//!    is then left out of the RMS and max. [`Align::Lsq`] fits the least-squares 2-D
//!    rigid transform (rotation + translation, no scale) over all GCPs.
//! 3. **Figures.** RMS / max / final-GCP error, loop-closure error for closed walks,
//!    path lengths, the heading error of every GCP-to-GCP leg at least 5 m long and the
//!    heading drift rate (slope of a least-squares line through those errors).
//!
//! A loop-closure-only truth (all GCPs at one point) reports only the loop-closure error.
//!
//! The script rounds its JSON to 6 decimals when printing; [`evaluate`] does not round.

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

/// Legs (consecutive GCP pairs) shorter than this in the truth get no heading-error entry.
pub const LEG_MIN_DIST_M: f64 = 5.0;

/// GCP times more than this far outside the trajectory's time span are warned about
/// (1 ms: CSV rounding).
const SPAN_SLACK_S: f64 = 1e-3;

/// One ground control point: a surveyed footprint and the time (end of a stance) at
/// which the foot stood on it. Mirrors a row of a data set's `ground_truth.csv`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthGcp {
    /// Time of the GCP on the trajectory's clock, in seconds.
    pub t_s: f64,
    /// Surveyed x position, metres (right-handed frame, z up).
    pub x_m: f64,
    /// Surveyed y position, metres.
    pub y_m: f64,
    /// Stride number from the truth file's optional `stride` column; copied into the
    /// per-GCP rows of the report when present.
    pub stride: Option<i64>,
}

/// How the trajectory is aligned to the truth before errors are taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Align {
    /// Translate onto GCP0 and rotate to match the GCP0→GCPk heading (the headline
    /// figure; `--align first-leg`).
    #[default]
    FirstLeg,
    /// Least-squares rigid transform over all GCPs (`--align lsq`); flatters drift.
    Lsq,
}

/// How the trajectory is sampled at GCP times.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Interp {
    /// The trajectory row nearest in time (`--interp nearest`); ties go to the earlier row.
    #[default]
    Nearest,
    /// Linear interpolation between the bracketing rows (`--interp linear`).
    Linear,
}

impl Align {
    /// The option's spelling on the script's command line and in its JSON.
    pub fn as_str(self) -> &'static str {
        match self {
            Align::FirstLeg => "first-leg",
            Align::Lsq => "lsq",
        }
    }
}

impl Interp {
    /// The option's spelling on the script's command line and in its JSON.
    pub fn as_str(self) -> &'static str {
        match self {
            Interp::Nearest => "nearest",
            Interp::Linear => "linear",
        }
    }
}

impl fmt::Display for Align {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl fmt::Display for Interp {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for Align {
    type Err = EvalError;
    /// Parses `first-leg` or `lsq`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "first-leg" => Ok(Align::FirstLeg),
            "lsq" => Ok(Align::Lsq),
            other => Err(EvalError::UnknownAlign(other.to_owned())),
        }
    }
}

impl FromStr for Interp {
    type Err = EvalError;
    /// Parses `nearest` or `linear`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "nearest" => Ok(Interp::Nearest),
            "linear" => Ok(Interp::Linear),
            other => Err(EvalError::UnknownInterp(other.to_owned())),
        }
    }
}

/// Options of [`evaluate`]; [`Default`] gives the script's defaults.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EvalOptions {
    /// Alignment method (`--align`, default first-leg).
    pub align: Align,
    /// Sampling method (`--interp`, default nearest).
    pub interp: Interp,
    /// First-leg alignment: the heading GCP is the first at least this far from GCP0 in
    /// the truth, metres (`--heading-min-dist`, default 5.0; 0 forces GCP1).
    pub heading_min_dist_m: f64,
    /// The truth is a closed walk if its first and last GCP are at most this far apart,
    /// metres (`--closed-tol`, default 0.01).
    pub closed_tol_m: f64,
    /// Nominal path length for a loop-closure-only truth, metres (`--path-length-m`);
    /// `None` (or 0) uses the trajectory's own path length as the percentage basis.
    pub path_length_m: Option<f64>,
}

impl Default for EvalOptions {
    fn default() -> Self {
        Self {
            align: Align::FirstLeg,
            interp: Interp::Nearest,
            heading_min_dist_m: 5.0,
            closed_tol_m: 0.01,
            path_length_m: None,
        }
    }
}

/// Heading error of one GCP-to-GCP leg (an element of the report's `legs`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Leg {
    /// Index of the leg's first GCP.
    pub from: usize,
    /// Index of the leg's second GCP (`from + 1`).
    pub to: usize,
    /// Mid-time of the leg, seconds.
    pub t_mid_s: f64,
    /// Length of the leg in the truth, metres.
    pub length_m: f64,
    /// Estimated minus true direction of the leg after alignment, degrees,
    /// counter-clockwise positive, wrapped to [-180, 180).
    pub heading_err_deg: f64,
}

/// Per-GCP row of the report (an element of `gcp`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GcpRow {
    /// Index of the GCP in the truth.
    pub index: usize,
    /// GCP time, seconds.
    pub t_s: f64,
    /// Surveyed position, metres.
    pub truth_xy: [f64; 2],
    /// Aligned trajectory position at the GCP time, metres.
    pub est_xy: [f64; 2],
    /// `est_xy - truth_xy`, metres.
    pub err_xy: [f64; 2],
    /// Length of `err_xy`, metres.
    pub err_m: f64,
    /// Stride number, when the truth has one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stride: Option<i64>,
}

/// The evaluation's result. Serialises to the same JSON object as the script's
/// `evaluate()` (without the CLI's `traj`/`truth` paths and its 6-decimal rounding);
/// fields the script leaves out in a given case are `None` and skipped.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EvalReport {
    /// Number of GCPs.
    pub n_gcp: usize,
    /// Sampling method used.
    pub interp: Interp,
    /// Largest |trajectory time used − GCP time| over the GCPs, seconds (linear: how far
    /// a GCP time was clamped).
    pub max_time_offset_s: f64,
    /// Whether the truth's first and last GCP coincide within the closed tolerance.
    pub closed: bool,
    /// Length of the polyline through the GCPs in order, metres.
    pub truth_path_length_m: f64,
    /// Length of the trajectory's x/y polyline between the first and last GCP times, metres.
    pub traj_path_length_m: f64,
    /// Closed truth only: distance between the trajectory's positions at the first and
    /// last GCP times, metres (needs no alignment).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub loop_closure_error_m: Option<f64>,
    /// `"first-leg"`, `"lsq"` or `"none (loop-closure-only truth)"`.
    pub alignment: String,
    /// Loop-closure-only and closed truth: 100 × loop-closure error / basis length.
    /// `Some(None)` (JSON `null`) when the basis length is not positive.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub loop_closure_pct: Option<Option<f64>>,
    /// Loop-closure-only and closed truth: `"--path-length-m"` or `"traj_path_length_m"`,
    /// the length the percentage is of.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pct_basis: Option<String>,
    /// First-leg: index k of the GCP that set the heading.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heading_gcp_index: Option<usize>,
    /// First-leg: distance GCP0→GCPk in the truth, metres.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heading_baseline_m: Option<f64>,
    /// Rotation applied to the trajectory, degrees in [-180, 180).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rotation_deg: Option<f64>,
    /// Lsq: translation applied after the rotation, metres.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub translation_m: Option<[f64; 2]>,
    /// Heading error of each leg at least [`LEG_MIN_DIST_M`] long (absent for a
    /// loop-closure-only truth; may be empty).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub legs: Option<Vec<Leg>>,
    /// Slope of a least-squares line through the legs' heading errors against their
    /// mid-times, degrees per second (needs two legs at distinct times).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heading_drift_deg_per_s: Option<f64>,
    /// `"all but GCP0"` (first-leg) or `"all"` (lsq).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scored_gcps: Option<String>,
    /// RMS of the scored GCPs' errors, metres.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rms_error_m: Option<f64>,
    /// Largest scored GCP error, metres.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_error_m: Option<f64>,
    /// Index of the GCP with the largest error (the first one on ties).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_error_gcp_index: Option<usize>,
    /// Error at the last GCP, metres.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub final_gcp_error_m: Option<f64>,
    /// 100 × `rms_error_m` / `truth_path_length_m`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rms_error_pct_of_path: Option<f64>,
    /// Per-GCP rows.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gcp: Option<Vec<GcpRow>>,
    /// Human-readable warnings (unsorted trajectory, clamped GCP times).
    pub warnings: Vec<String>,
}

/// Why an evaluation could not be made (the script's `SystemExit` cases, plus input
/// checks that the script's CSV reader makes implicit).
#[derive(thiserror::Error, Debug, Clone, PartialEq)]
pub enum EvalError {
    /// `t_s`, `x_m` and `y_m` have different lengths.
    #[error("trajectory columns differ in length: t_s {t}, x_m {x}, y_m {y}")]
    LengthMismatch {
        /// Length of `t_s`.
        t: usize,
        /// Length of `x_m`.
        x: usize,
        /// Length of `y_m`.
        y: usize,
    },
    /// Fewer than two finite trajectory rows.
    #[error("trajectory has fewer than two rows ({rows} finite)")]
    TooFewTrajRows {
        /// Number of rows with finite t, x and y.
        rows: usize,
    },
    /// Fewer than two finite GCPs.
    #[error("truth needs at least two GCPs ({gcps} finite)")]
    TooFewGcps {
        /// Number of GCPs with finite t, x and y.
        gcps: usize,
    },
    /// First-leg alignment found no GCP far enough from GCP0.
    #[error(
        "no GCP far enough from GCP0 to align heading (need {min_dist_m} m, farthest is {farthest_m} m)"
    )]
    NoHeadingGcp {
        /// The required distance, metres.
        min_dist_m: f64,
        /// The largest distance of any GCP from GCP0 in the truth, metres.
        farthest_m: f64,
    },
    /// The trajectory did not move between GCP0 and the heading GCP.
    #[error(
        "trajectory did not move between GCP0 and the heading GCP (GCP{heading_gcp_index}, moved {moved_m} m)"
    )]
    NoMotionToHeadingGcp {
        /// Index k of the heading GCP.
        heading_gcp_index: usize,
        /// Distance between the trajectory's positions at GCP0 and GCPk, metres.
        moved_m: f64,
    },
    /// A streamed trajectory row did not come after the previous one ([`GcpSampler`]).
    #[error("trajectory row at t = {t_s} s is not after the previous row")]
    NotIncreasing {
        /// The row's time, seconds.
        t_s: f64,
    },
    /// Unknown alignment name given to [`Align::from_str`].
    #[error("unknown --align {0}")]
    UnknownAlign(String),
    /// Unknown interpolation name given to [`Interp::from_str`].
    #[error("unknown --interp {0}")]
    UnknownInterp(String),
}

type P2 = [f64; 2];

fn norm(v: P2) -> f64 {
    (v[0] * v[0] + v[1] * v[1]).sqrt()
}

fn sub(a: P2, b: P2) -> P2 {
    [a[0] - b[0], a[1] - b[1]]
}

/// Rotates `v` by `theta` (counter-clockwise), then adds `t`.
fn rot_add(theta: f64, v: P2, t: P2) -> P2 {
    let (s, c) = theta.sin_cos();
    [c * v[0] - s * v[1] + t[0], s * v[0] + c * v[1] + t[1]]
}

/// Wraps an angle in degrees to [-180, 180), with Python's floored modulo.
pub fn wrap_deg(a: f64) -> f64 {
    let m = (a + 180.0) % 360.0;
    let m = if m < 0.0 { m + 360.0 } else { m };
    m - 180.0
}

fn polyline_length(xy: &[P2]) -> f64 {
    xy.windows(2).map(|w| norm(sub(w[1], w[0]))).sum()
}

fn mean(xy: &[P2]) -> P2 {
    let n = xy.len() as f64;
    let s = xy
        .iter()
        .fold([0.0, 0.0], |a, p| [a[0] + p[0], a[1] + p[1]]);
    [s[0] / n, s[1] / n]
}

/// Trajectory positions at the query times, and |time used − query time| per query.
/// `t` must be sorted and hold at least two rows.
fn sample_traj(t: &[f64], xy: &[P2], tq: &[f64], mode: Interp) -> (Vec<P2>, Vec<f64>) {
    let (t0, t1) = (t[0], t[t.len() - 1]);
    let mut pos = Vec::with_capacity(tq.len());
    let mut dt = Vec::with_capacity(tq.len());
    for &q in tq {
        let qc = q.clamp(t0, t1);
        match mode {
            Interp::Linear => {
                pos.push([interp(qc, t, xy, 0), interp(qc, t, xy, 1)]);
                dt.push((q - qc).abs());
            }
            Interp::Nearest => {
                // numpy: searchsorted(side="left"), clip to [1, n-1], ties to the left.
                let j = t.partition_point(|&v| v < qc).clamp(1, t.len() - 1);
                let j = if qc - t[j - 1] <= t[j] - qc { j - 1 } else { j };
                pos.push(xy[j]);
                dt.push((t[j] - q).abs());
            }
        }
    }
    (pos, dt)
}

/// `numpy.interp(x, t, xy[:, c])` for x inside [t[0], t[-1]].
fn interp(x: f64, t: &[f64], xy: &[P2], c: usize) -> f64 {
    let n = t.len();
    if x >= t[n - 1] {
        return xy[n - 1][c];
    }
    if x < t[0] {
        return xy[0][c];
    }
    // Last index j with t[j] <= x, as numpy's binary search.
    let j = t.partition_point(|&v| v <= x) - 1;
    if t[j] == x {
        return xy[j][c];
    }
    let slope = (xy[j + 1][c] - xy[j][c]) / (t[j + 1] - t[j]);
    let mut r = slope * (x - t[j]) + xy[j][c];
    if r.is_nan() {
        r = slope * (x - t[j + 1]) + xy[j + 1][c];
        if r.is_nan() && xy[j][c] == xy[j + 1][c] {
            r = xy[j][c];
        }
    }
    r
}

/// Slope of the least-squares line y = a + b x (what `numpy.polyfit(x, y, 1)[0]` gives).
fn line_slope(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let xm = x.iter().sum::<f64>() / n;
    let ym = y.iter().sum::<f64>() / n;
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - xm) * (b - ym)).sum();
    let sxx: f64 = x.iter().map(|a| (a - xm) * (a - xm)).sum();
    sxy / sxx
}

/// Evaluates a 2-D trajectory against ground-truth GCPs, exactly as the reference
/// script `tools/eval_traj.py` does.
///
/// `t_s`, `x_m`, `y_m` are the trajectory's columns (one row per sample or per stance,
/// on the truth's clock, right-handed x/y frame with arbitrary origin and heading).
/// Rows and GCPs with a non-finite time or coordinate are dropped first, as the
/// script's CSV reader does; unsorted rows are sorted (stable) with a warning.
///
/// # Errors
/// [`EvalError`] when the columns differ in length, fewer than two rows or GCPs are
/// left, or first-leg alignment cannot set a heading.
pub fn evaluate(
    t_s: &[f64],
    x_m: &[f64],
    y_m: &[f64],
    truth: &[TruthGcp],
    opts: &EvalOptions,
) -> Result<EvalReport, EvalError> {
    if t_s.len() != x_m.len() || t_s.len() != y_m.len() {
        return Err(EvalError::LengthMismatch {
            t: t_s.len(),
            x: x_m.len(),
            y: y_m.len(),
        });
    }
    let mut warnings = Vec::new();
    let mut rows: Vec<(f64, P2)> = t_s
        .iter()
        .zip(x_m.iter().zip(y_m))
        .filter(|(t, (x, y))| t.is_finite() && x.is_finite() && y.is_finite())
        .map(|(&t, (&x, &y))| (t, [x, y]))
        .collect();
    if rows.len() < 2 {
        return Err(EvalError::TooFewTrajRows { rows: rows.len() });
    }
    if rows.windows(2).any(|w| w[1].0 < w[0].0) {
        rows.sort_by(|a, b| a.0.total_cmp(&b.0)); // stable, as argsort(kind="stable")
        warnings.push("trajectory rows were not in time order; sorted".to_owned());
    }
    let t: Vec<f64> = rows.iter().map(|r| r.0).collect();
    let xy: Vec<P2> = rows.iter().map(|r| r.1).collect();

    let truth = finite_gcps(truth)?;
    let n = truth.len();
    let tg: Vec<f64> = truth.iter().map(|g| g.t_s).collect();
    let (p, dt_used) = sample_traj(&t, &xy, &tg, opts.interp);
    let in_span: Vec<P2> = t
        .iter()
        .zip(&xy)
        .filter(|&(&tk, _)| tk >= tg[0] && tk <= tg[n - 1])
        .map(|(_, &pk)| pk)
        .collect();
    let traj_len = if in_span.len() >= 2 {
        polyline_length(&in_span)
    } else {
        0.0
    };
    let sampled = Sampled {
        p,
        dt_used,
        t_first: t[0],
        t_last: t[t.len() - 1],
        traj_len_m: traj_len,
    };
    report(sampled, &truth, opts, warnings)
}

/// The GCPs with a finite time and position (at least two).
fn finite_gcps(truth: &[TruthGcp]) -> Result<Vec<TruthGcp>, EvalError> {
    let truth: Vec<TruthGcp> = truth
        .iter()
        .filter(|g| g.t_s.is_finite() && g.x_m.is_finite() && g.y_m.is_finite())
        .copied()
        .collect();
    if truth.len() < 2 {
        return Err(EvalError::TooFewGcps { gcps: truth.len() });
    }
    Ok(truth)
}

/// What the evaluation needs of a trajectory: its positions at the GCP times, how far in time
/// each was taken from its GCP, its time span and its path length between the first and last
/// GCP times. [`evaluate`] takes it from the whole trajectory, [`GcpSampler`] as it streams.
#[derive(Debug, Clone, PartialEq)]
struct Sampled {
    p: Vec<P2>,
    dt_used: Vec<f64>,
    t_first: f64,
    t_last: f64,
    traj_len_m: f64,
}

/// The evaluation of a sampled trajectory against the (finite) GCPs.
fn report(
    s: Sampled,
    truth: &[TruthGcp],
    opts: &EvalOptions,
    mut warnings: Vec<String>,
) -> Result<EvalReport, EvalError> {
    let Sampled {
        p,
        dt_used,
        t_first,
        t_last,
        traj_len_m: traj_len,
    } = s;
    let n = truth.len();
    let tg: Vec<f64> = truth.iter().map(|g| g.t_s).collect();
    let g: Vec<P2> = truth.iter().map(|g| [g.x_m, g.y_m]).collect();
    let out_of_span: Vec<String> = (0..n)
        .filter(|&i| tg[i] < t_first - SPAN_SLACK_S || tg[i] > t_last + SPAN_SLACK_S)
        .map(|i| i.to_string())
        .collect();
    if !out_of_span.is_empty() {
        warnings.push(format!(
            "GCP time(s) outside the trajectory span, clamped: indices [{}]",
            out_of_span.join(", ")
        ));
    }

    let closed = norm(sub(g[n - 1], g[0])) <= opts.closed_tol_m;
    let truth_len = polyline_length(&g);
    // numpy.max propagates NaN.
    let max_dt = dt_used.iter().copied().fold(f64::NEG_INFINITY, |a, b| {
        if a.is_nan() || b.is_nan() {
            f64::NAN
        } else {
            a.max(b)
        }
    });

    let mut res = EvalReport {
        n_gcp: n,
        interp: opts.interp,
        max_time_offset_s: max_dt,
        closed,
        truth_path_length_m: truth_len,
        traj_path_length_m: traj_len,
        loop_closure_error_m: closed.then(|| norm(sub(p[n - 1], p[0]))),
        alignment: String::new(),
        loop_closure_pct: None,
        pct_basis: None,
        heading_gcp_index: None,
        heading_baseline_m: None,
        rotation_deg: None,
        translation_m: None,
        legs: None,
        heading_drift_deg_per_s: None,
        scored_gcps: None,
        rms_error_m: None,
        max_error_m: None,
        max_error_gcp_index: None,
        final_gcp_error_m: None,
        rms_error_pct_of_path: None,
        gcp: None,
        warnings: Vec::new(),
    };

    // Loop-closure-only truth: every GCP at the start point.
    if truth_len < 1e-9 {
        res.alignment = "none (loop-closure-only truth)".to_owned();
        if let Some(lce) = res.loop_closure_error_m {
            // Python truthiness: None and 0.0 fall back to the trajectory's length.
            let (basis_len, basis) = match opts.path_length_m {
                Some(l) if l != 0.0 => (l, "--path-length-m"),
                _ => (traj_len, "traj_path_length_m"),
            };
            res.loop_closure_pct = Some((basis_len > 0.0).then(|| 100.0 * lce / basis_len));
            res.pct_basis = Some(basis.to_owned());
        }
        res.warnings = warnings;
        return Ok(res);
    }

    let (q, scored_from) = match opts.align {
        Align::FirstLeg => {
            let min_dist = opts.heading_min_dist_m.max(1e-9);
            let d: Vec<f64> = g.iter().map(|&gi| norm(sub(gi, g[0]))).collect();
            let Some(k) = (1..n).find(|&i| d[i] >= min_dist) else {
                return Err(EvalError::NoHeadingGcp {
                    min_dist_m: opts.heading_min_dist_m,
                    farthest_m: d.iter().copied().fold(0.0, f64::max),
                });
            };
            let vt = sub(g[k], g[0]);
            let vp = sub(p[k], p[0]);
            if norm(vp) < 1e-9 {
                return Err(EvalError::NoMotionToHeadingGcp {
                    heading_gcp_index: k,
                    moved_m: norm(vp),
                });
            }
            let theta = vt[1].atan2(vt[0]) - vp[1].atan2(vp[0]);
            let q: Vec<P2> = p
                .iter()
                .map(|&pi| rot_add(theta, sub(pi, p[0]), g[0]))
                .collect();
            res.alignment = Align::FirstLeg.as_str().to_owned();
            res.heading_gcp_index = Some(k);
            res.heading_baseline_m = Some(d[k]);
            res.rotation_deg = Some(wrap_deg(theta.to_degrees()));
            (q, 1)
        }
        Align::Lsq => {
            let (pm, gm) = (mean(&p), mean(&g));
            let (mut num, mut den) = (0.0, 0.0);
            for (pi, gi) in p.iter().zip(&g) {
                let (pc, gc) = (sub(*pi, pm), sub(*gi, gm));
                num += gc[1] * pc[0] - gc[0] * pc[1];
                den += gc[0] * pc[0] + gc[1] * pc[1];
            }
            let theta = num.atan2(den);
            let rpm = rot_add(theta, pm, [0.0, 0.0]);
            let tr = sub(gm, rpm);
            let q: Vec<P2> = p.iter().map(|&pi| rot_add(theta, pi, tr)).collect();
            res.alignment = Align::Lsq.as_str().to_owned();
            res.rotation_deg = Some(wrap_deg(theta.to_degrees()));
            res.translation_m = Some(tr);
            (q, 0)
        }
    };

    let err: Vec<P2> = q.iter().zip(&g).map(|(&qi, &gi)| sub(qi, gi)).collect();
    let en: Vec<f64> = err.iter().map(|&e| norm(e)).collect();
    let gcps: Vec<GcpRow> = (0..n)
        .map(|i| GcpRow {
            index: i,
            t_s: tg[i],
            truth_xy: g[i],
            est_xy: q[i],
            err_xy: err[i],
            err_m: en[i],
            stride: truth[i].stride,
        })
        .collect();
    let sel = &en[scored_from..];
    let rms = (sel.iter().map(|e| e * e).sum::<f64>() / sel.len() as f64).sqrt();
    // numpy.argmax: first maximum, or the first NaN if there is one.
    let mut imax = 0;
    for (i, &e) in sel.iter().enumerate() {
        if e.is_nan() {
            imax = i;
            break;
        }
        if e > sel[imax] {
            imax = i;
        }
    }

    let mut legs = Vec::new();
    for i in 0..n - 1 {
        let vt = sub(g[i + 1], g[i]);
        let vq = sub(q[i + 1], q[i]);
        if norm(vt) >= LEG_MIN_DIST_M && norm(vq) > 1e-9 {
            let dpsi = vq[1].atan2(vq[0]) - vt[1].atan2(vt[0]);
            legs.push(Leg {
                from: i,
                to: i + 1,
                t_mid_s: 0.5 * (tg[i] + tg[i + 1]),
                length_m: norm(vt),
                heading_err_deg: wrap_deg(dpsi.to_degrees()),
            });
        }
    }
    if legs.len() >= 2 {
        let tl: Vec<f64> = legs.iter().map(|l| l.t_mid_s).collect();
        let hl: Vec<f64> = legs.iter().map(|l| l.heading_err_deg).collect();
        let (lo, hi) = tl
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        if hi - lo > 0.0 {
            res.heading_drift_deg_per_s = Some(line_slope(&tl, &hl));
        }
    }
    res.legs = Some(legs);
    res.scored_gcps = Some(
        match opts.align {
            Align::FirstLeg => "all but GCP0",
            Align::Lsq => "all",
        }
        .to_owned(),
    );
    res.rms_error_m = Some(rms);
    res.max_error_m = Some(sel[imax]);
    res.max_error_gcp_index = Some(scored_from + imax);
    res.final_gcp_error_m = Some(en[n - 1]);
    res.rms_error_pct_of_path = Some(100.0 * rms / truth_len);
    res.gcp = Some(gcps);
    res.warnings = warnings;
    Ok(res)
}

/// A sample of a streamed trajectory: time and position.
type Fix = (f64, P2);

/// Evaluates a trajectory as it streams, in memory independent of its length: it keeps, per
/// GCP, only the trajectory rows just before and at or after the GCP time, and the path length
/// as it grows. [`GcpSampler::finish`] gives exactly what [`evaluate`] gives for the same rows
/// (tested), provided the rows come in strictly increasing time, as the estimator emits them;
/// rows with a non-finite time or position are left out, as [`evaluate`] leaves them out.
#[derive(Debug, Clone)]
pub struct GcpSampler {
    truth: Vec<TruthGcp>,
    opts: EvalOptions,
    /// GCP indices in time order (stable).
    order: Vec<usize>,
    /// Position in `order` of the first GCP whose time no row has reached.
    next: usize,
    /// Per GCP: the last row before its time, the first row at or after it.
    before: Vec<Option<Fix>>,
    after: Vec<Option<Fix>>,
    first: Option<Fix>,
    last: Option<Fix>,
    rows: usize,
    /// Last row between the first and last GCP's times, and the path length through them.
    span_last: Option<P2>,
    span_rows: usize,
    span_len_m: f64,
    /// The first row that did not come after the previous one.
    out_of_order_s: Option<f64>,
}

impl GcpSampler {
    /// A sampler for `truth` (its non-finite GCPs are left out, as [`evaluate`] does).
    pub fn new(truth: &[TruthGcp], opts: &EvalOptions) -> Self {
        let truth: Vec<TruthGcp> = truth
            .iter()
            .filter(|g| g.t_s.is_finite() && g.x_m.is_finite() && g.y_m.is_finite())
            .copied()
            .collect();
        let mut order: Vec<usize> = (0..truth.len()).collect();
        order.sort_by(|&a, &b| truth[a].t_s.total_cmp(&truth[b].t_s));
        Self {
            before: vec![None; truth.len()],
            after: vec![None; truth.len()],
            truth,
            opts: *opts,
            order,
            next: 0,
            first: None,
            last: None,
            rows: 0,
            span_last: None,
            span_rows: 0,
            span_len_m: 0.0,
            out_of_order_s: None,
        }
    }

    /// One trajectory row.
    pub fn push(&mut self, t_s: f64, x_m: f64, y_m: f64) {
        if !(t_s.is_finite() && x_m.is_finite() && y_m.is_finite()) {
            return;
        }
        if let Some((t_last, _)) = self.last
            && t_s <= t_last
        {
            self.out_of_order_s.get_or_insert(t_s);
            return;
        }
        let p = [x_m, y_m];
        while let Some(&i) = self.order.get(self.next)
            && self.truth[i].t_s <= t_s
        {
            self.before[i] = self.last;
            self.after[i] = Some((t_s, p));
            self.next += 1;
        }
        if let (Some(g0), Some(gn)) = (self.truth.first(), self.truth.last())
            && t_s >= g0.t_s
            && t_s <= gn.t_s
        {
            if let Some(q) = self.span_last {
                self.span_len_m += norm(sub(p, q));
            }
            self.span_last = Some(p);
            self.span_rows += 1;
        }
        self.first.get_or_insert((t_s, p));
        self.last = Some((t_s, p));
        self.rows += 1;
    }

    /// The evaluation of the rows pushed so far.
    pub fn finish(&self) -> Result<EvalReport, EvalError> {
        let (Some((t0, p0)), Some((t1, p1))) = (self.first, self.last) else {
            return Err(EvalError::TooFewTrajRows { rows: self.rows });
        };
        if self.rows < 2 {
            return Err(EvalError::TooFewTrajRows { rows: self.rows });
        }
        if self.truth.len() < 2 {
            return Err(EvalError::TooFewGcps {
                gcps: self.truth.len(),
            });
        }
        if let Some(t_s) = self.out_of_order_s {
            return Err(EvalError::NotIncreasing { t_s });
        }
        let n = self.truth.len();
        let (mut p, mut dt_used) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for (i, g) in self.truth.iter().enumerate() {
            let q = g.t_s;
            let (pos, dt) = match self.opts.interp {
                // As `sample_traj`: the nearest row, ties to the earlier; clamped to the ends.
                Interp::Nearest => match (self.before[i], self.after[i]) {
                    (_, None) => (p1, (t1 - q).abs()),
                    (None, Some(_)) => (p0, (t0 - q).abs()),
                    (Some((tb, pb)), Some((ta, pa))) => {
                        if q - tb <= ta - q {
                            (pb, (tb - q).abs())
                        } else {
                            (pa, (ta - q).abs())
                        }
                    }
                },
                // As `interp` on the clamped time.
                Interp::Linear => {
                    let qc = q.clamp(t0, t1);
                    let pos = match (self.before[i], self.after[i]) {
                        _ if qc >= t1 => p1,
                        (_, Some((ta, pa))) if ta == qc => pa,
                        (Some(b), Some(a)) => [lerp(qc, b, a, 0), lerp(qc, b, a, 1)],
                        _ => p0,
                    };
                    (pos, (q - qc).abs())
                }
            };
            p.push(pos);
            dt_used.push(dt);
        }
        let sampled = Sampled {
            p,
            dt_used,
            t_first: t0,
            t_last: t1,
            traj_len_m: if self.span_rows >= 2 {
                self.span_len_m
            } else {
                0.0
            },
        };
        report(sampled, &self.truth, &self.opts, Vec::new())
    }
}

/// Coordinate `c` at `x` between the rows `b` and `a` (`b.0 < x < a.0`), with the arithmetic
/// of [`interp`].
fn lerp(x: f64, b: Fix, a: Fix, c: usize) -> f64 {
    let slope = (a.1[c] - b.1[c]) / (a.0 - b.0);
    let mut r = slope * (x - b.0) + b.1[c];
    if r.is_nan() {
        r = slope * (x - a.0) + a.1[c];
        if r.is_nan() && b.1[c] == a.1[c] {
            r = b.1[c];
        }
    }
    r
}

#[cfg(test)]
mod tests {
    //! Golden tests against the reference evaluator's output.
    //!
    //! Fixtures live in `service/tests/data/eval/`. Regenerate them from the repository
    //! root with (the CSVs first, then the golden JSON):
    //!
    //! ```sh
    //! python3 service/tests/data/eval/gen_fixtures.py
    //! D=service/tests/data/eval; E=/work/shared/tools/eval_traj.py
    //! python3 $E --traj $D/loop.traj.csv --truth $D/loop.truth.csv --align first-leg --interp nearest > $D/loop.first-leg.nearest.expected.json
    //! python3 $E --traj $D/loop.traj.csv --truth $D/loop.truth.csv --align first-leg --interp linear > $D/loop.first-leg.linear.expected.json
    //! python3 $E --traj $D/loop.traj.csv --truth $D/loop.truth.csv --align lsq --interp nearest > $D/loop.lsq.nearest.expected.json
    //! python3 $E --traj $D/loop.traj.csv --truth $D/loop.truth.csv --align lsq --interp linear > $D/loop.lsq.linear.expected.json
    //! python3 $E --traj $D/out_and_back.traj.csv --truth $D/out_and_back.truth.csv --align first-leg --interp nearest > $D/out_and_back.first-leg.nearest.expected.json
    //! python3 $E --traj $D/out_and_back.traj.csv --truth $D/out_and_back.truth.csv --align first-leg --interp linear --heading-min-dist 0 > $D/out_and_back.first-leg.linear.hmd0.expected.json
    //! python3 $E --traj $D/out_and_back.traj.csv --truth $D/out_and_back.truth.csv --align lsq --interp linear > $D/out_and_back.lsq.linear.expected.json
    //! python3 $E --traj $D/closure.traj.csv --truth $D/closure.truth.csv > $D/closure.nearest.expected.json
    //! python3 $E --traj $D/closure.traj.csv --truth $D/closure.truth.csv --interp linear --path-length-m 40.2 > $D/closure.linear.pathlen.expected.json
    //! ```
    //!
    //! The script rounds to 6 decimals, so numbers are compared within 1e-6 (absolute or
    //! relative).

    use super::*;
    use serde_json::Value;
    use std::path::PathBuf;

    fn data_dir() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/eval")
    }

    /// Reads the named columns of a headed CSV; `None` for a missing optional column.
    fn read_csv(name: &str, cols: &[&str]) -> Vec<Vec<Option<f64>>> {
        let text = std::fs::read_to_string(data_dir().join(name)).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').map(str::trim).collect();
        let idx: Vec<Option<usize>> = cols
            .iter()
            .map(|c| header.iter().position(|h| h == c))
            .collect();
        let mut out = vec![Vec::new(); cols.len()];
        for line in lines.filter(|l| !l.trim().is_empty()) {
            let f: Vec<&str> = line.split(',').collect();
            for (o, i) in out.iter_mut().zip(&idx) {
                o.push(i.map(|i| f[i].trim().parse::<f64>().unwrap()));
            }
        }
        out
    }

    fn load(stem: &str) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<TruthGcp>) {
        let tr = read_csv(&format!("{stem}.traj.csv"), &["t_s", "x_m", "y_m"]);
        let col = |c: &Vec<Option<f64>>| c.iter().map(|v| v.unwrap()).collect::<Vec<_>>();
        let gt = read_csv(
            &format!("{stem}.truth.csv"),
            &["t_s", "x_m", "y_m", "stride"],
        );
        let truth = (0..gt[0].len())
            .map(|i| TruthGcp {
                t_s: gt[0][i].unwrap(),
                x_m: gt[1][i].unwrap(),
                y_m: gt[2][i].unwrap(),
                stride: gt[3][i].map(|s| s as i64),
            })
            .collect();
        (col(&tr[0]), col(&tr[1]), col(&tr[2]), truth)
    }

    fn assert_close(path: &str, got: &Value, want: &Value) {
        match (got, want) {
            (Value::Number(a), Value::Number(b)) => {
                let (a, b) = (a.as_f64().unwrap(), b.as_f64().unwrap());
                let d = (a - b).abs();
                assert!(
                    d <= 1e-6 || d <= 1e-6 * b.abs(),
                    "{path}: got {a}, want {b}"
                );
            }
            (Value::Array(a), Value::Array(b)) => {
                assert_eq!(a.len(), b.len(), "{path}: array length");
                for (i, (x, y)) in a.iter().zip(b).enumerate() {
                    assert_close(&format!("{path}[{i}]"), x, y);
                }
            }
            (Value::Object(a), Value::Object(b)) => {
                let mut ka: Vec<&String> = a.keys().collect();
                let mut kb: Vec<&String> = b
                    .keys()
                    .filter(|k| path != "$" || (*k != "traj" && *k != "truth"))
                    .collect();
                ka.sort();
                kb.sort();
                assert_eq!(ka, kb, "{path}: keys");
                for k in kb {
                    assert_close(&format!("{path}.{k}"), &a[k], &b[k]);
                }
            }
            _ => assert_eq!(got, want, "{path}"),
        }
    }

    fn golden(stem: &str, expected: &str, opts: EvalOptions) {
        let (t, x, y, truth) = load(stem);
        let rep = evaluate(&t, &x, &y, &truth, &opts).unwrap();
        let got = serde_json::to_value(&rep).unwrap();
        let text = std::fs::read_to_string(data_dir().join(expected)).unwrap();
        let want: Value = serde_json::from_str(&text).unwrap();
        assert_close("$", &got, &want);
    }

    fn opts(align: Align, interp: Interp) -> EvalOptions {
        EvalOptions {
            align,
            interp,
            ..EvalOptions::default()
        }
    }

    #[test]
    fn golden_loop_first_leg_nearest() {
        golden(
            "loop",
            "loop.first-leg.nearest.expected.json",
            opts(Align::FirstLeg, Interp::Nearest),
        );
    }

    #[test]
    fn golden_loop_first_leg_linear() {
        golden(
            "loop",
            "loop.first-leg.linear.expected.json",
            opts(Align::FirstLeg, Interp::Linear),
        );
    }

    #[test]
    fn golden_loop_lsq_nearest() {
        golden(
            "loop",
            "loop.lsq.nearest.expected.json",
            opts(Align::Lsq, Interp::Nearest),
        );
    }

    #[test]
    fn golden_loop_lsq_linear() {
        golden(
            "loop",
            "loop.lsq.linear.expected.json",
            opts(Align::Lsq, Interp::Linear),
        );
    }

    #[test]
    fn golden_out_and_back_first_leg_nearest() {
        golden(
            "out_and_back",
            "out_and_back.first-leg.nearest.expected.json",
            opts(Align::FirstLeg, Interp::Nearest),
        );
    }

    #[test]
    fn golden_out_and_back_first_leg_linear_min_dist_0() {
        golden(
            "out_and_back",
            "out_and_back.first-leg.linear.hmd0.expected.json",
            EvalOptions {
                heading_min_dist_m: 0.0,
                ..opts(Align::FirstLeg, Interp::Linear)
            },
        );
    }

    #[test]
    fn golden_out_and_back_lsq_linear() {
        golden(
            "out_and_back",
            "out_and_back.lsq.linear.expected.json",
            opts(Align::Lsq, Interp::Linear),
        );
    }

    #[test]
    fn golden_closure_only_nearest() {
        golden(
            "closure",
            "closure.nearest.expected.json",
            EvalOptions::default(),
        );
    }

    #[test]
    fn golden_closure_only_linear_path_length() {
        golden(
            "closure",
            "closure.linear.pathlen.expected.json",
            EvalOptions {
                path_length_m: Some(40.2),
                ..opts(Align::FirstLeg, Interp::Linear)
            },
        );
    }

    /// A walk with two legs at right angles; GCP times on trajectory rows.
    fn l_walk() -> Vec<TruthGcp> {
        [
            (1.0, 0.0, 0.0),
            (9.0, 10.0, 0.0),
            (15.0, 10.0, 6.0),
            (20.0, 4.0, 6.0),
        ]
        .iter()
        .enumerate()
        .map(|(i, &(t_s, x_m, y_m))| TruthGcp {
            t_s,
            x_m,
            y_m,
            stride: Some(i as i64),
        })
        .collect()
    }

    /// Densely sampled trajectory through the truth's polyline, mapped by `f`.
    fn traj_from(truth: &[TruthGcp], f: impl Fn(P2) -> P2) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let (mut t, mut x, mut y) = (Vec::new(), Vec::new(), Vec::new());
        for w in truth.windows(2) {
            for k in 0..20 {
                let a = k as f64 / 20.0;
                let p = f([
                    w[0].x_m + a * (w[1].x_m - w[0].x_m),
                    w[0].y_m + a * (w[1].y_m - w[0].y_m),
                ]);
                t.push(w[0].t_s + a * (w[1].t_s - w[0].t_s));
                x.push(p[0]);
                y.push(p[1]);
            }
        }
        let last = truth.last().unwrap();
        let p = f([last.x_m, last.y_m]);
        t.push(last.t_s);
        x.push(p[0]);
        y.push(p[1]);
        (t, x, y)
    }

    fn assert_zero_error(rep: &EvalReport) {
        assert!(rep.rms_error_m.unwrap() < 1e-9, "{rep:?}");
        assert!(rep.max_error_m.unwrap() < 1e-9);
        assert!(rep.final_gcp_error_m.unwrap() < 1e-9);
        for leg in rep.legs.as_ref().unwrap() {
            assert!(leg.heading_err_deg.abs() < 1e-7, "{leg:?}");
        }
        assert!(rep.heading_drift_deg_per_s.unwrap().abs() < 1e-9);
        assert!(rep.warnings.is_empty());
    }

    #[test]
    fn trajectory_equal_to_truth_has_zero_error() {
        let truth = l_walk();
        let (t, x, y) = traj_from(&truth, |p| p);
        for align in [Align::FirstLeg, Align::Lsq] {
            for interp in [Interp::Nearest, Interp::Linear] {
                let rep = evaluate(&t, &x, &y, &truth, &opts(align, interp)).unwrap();
                assert_zero_error(&rep);
                assert!(rep.rotation_deg.unwrap().abs() < 1e-9);
                assert_eq!(rep.max_time_offset_s, 0.0);
                assert!(!rep.closed);
                assert_eq!(rep.truth_path_length_m, 10.0 + 6.0 + 6.0);
                assert!((rep.traj_path_length_m - 22.0).abs() < 1e-9);
                assert_eq!(rep.legs.as_ref().unwrap().len(), 3);
                assert_eq!(rep.gcp.as_ref().unwrap()[2].stride, Some(2));
            }
        }
    }

    #[test]
    fn rigid_motion_of_truth_has_zero_error_under_lsq() {
        let truth = l_walk();
        let (ang, off) = (-2.1_f64, [35.0, -12.5]);
        let (t, x, y) = traj_from(&truth, |p| rot_add(ang, p, off));
        let rep = evaluate(&t, &x, &y, &truth, &opts(Align::Lsq, Interp::Linear)).unwrap();
        assert_zero_error(&rep);
        assert!((rep.rotation_deg.unwrap() - (-ang).to_degrees()).abs() < 1e-9);
        // Undoing the motion: translation = -R(-ang) off.
        let back = rot_add(-ang, off, [0.0, 0.0]);
        let tr = rep.translation_m.unwrap();
        assert!((tr[0] + back[0]).abs() < 1e-9 && (tr[1] + back[1]).abs() < 1e-9);
        assert_eq!(rep.scored_gcps.as_deref(), Some("all"));
        // First-leg recovers the same rotation and is exact too.
        let rep = evaluate(&t, &x, &y, &truth, &opts(Align::FirstLeg, Interp::Nearest)).unwrap();
        assert_zero_error(&rep);
    }

    #[test]
    fn wrap_deg_matches_python_modulo() {
        assert_eq!(wrap_deg(180.0), -180.0);
        assert_eq!(wrap_deg(-180.0), -180.0);
        assert_eq!(wrap_deg(190.0), -170.0);
        assert_eq!(wrap_deg(-190.0), 170.0);
        assert_eq!(wrap_deg(540.0), -180.0);
        assert_eq!(wrap_deg(-0.0), 0.0);
        assert_eq!(wrap_deg(359.0), -1.0);
    }

    #[test]
    fn errors_carry_the_facts() {
        let truth = l_walk();
        let (t, x, y) = traj_from(&truth, |p| p);
        let o = EvalOptions::default();
        assert_eq!(
            evaluate(&t[..3], &x, &y, &truth, &o).unwrap_err(),
            EvalError::LengthMismatch {
                t: 3,
                x: x.len(),
                y: y.len()
            }
        );
        assert_eq!(
            evaluate(&[1.0, f64::NAN], &[0.0, 1.0], &[0.0, 1.0], &truth, &o).unwrap_err(),
            EvalError::TooFewTrajRows { rows: 1 }
        );
        assert_eq!(
            evaluate(&t, &x, &y, &truth[..1], &o).unwrap_err(),
            EvalError::TooFewGcps { gcps: 1 }
        );
        let far = EvalOptions {
            heading_min_dist_m: 50.0,
            ..o
        };
        match evaluate(&t, &x, &y, &truth, &far).unwrap_err() {
            EvalError::NoHeadingGcp {
                min_dist_m,
                farthest_m,
            } => {
                assert_eq!(min_dist_m, 50.0);
                assert!((farthest_m - 136.0_f64.sqrt()).abs() < 1e-12);
            }
            e => panic!("{e}"),
        }
        let still = vec![0.0; t.len()];
        match evaluate(&t, &still, &still, &truth, &o).unwrap_err() {
            EvalError::NoMotionToHeadingGcp {
                heading_gcp_index, ..
            } => assert_eq!(heading_gcp_index, 1),
            e => panic!("{e}"),
        }
        assert_eq!("lsq".parse::<Align>().unwrap(), Align::Lsq);
        assert_eq!(
            "median".parse::<Interp>().unwrap_err().to_string(),
            "unknown --interp median"
        );
    }

    /// The streamed evaluation of `t, x, y`.
    fn streamed(
        t: &[f64],
        x: &[f64],
        y: &[f64],
        truth: &[TruthGcp],
        o: &EvalOptions,
    ) -> Result<EvalReport, EvalError> {
        let mut s = GcpSampler::new(truth, o);
        for k in 0..t.len() {
            s.push(t[k], x[k], y[k]);
        }
        s.finish()
    }

    #[test]
    fn streamed_evaluation_equals_the_whole_trajectorys_on_the_fixtures() {
        for stem in ["loop", "out_and_back", "closure"] {
            // In time order (out_and_back is not, to test the warning): the estimator's order.
            let (t, x, y, truth) = load(stem);
            let mut k: Vec<usize> = (0..t.len()).collect();
            k.sort_by(|&a, &b| t[a].total_cmp(&t[b]));
            let (t, x, y): (Vec<f64>, Vec<f64>, Vec<f64>) = (
                k.iter().map(|&i| t[i]).collect(),
                k.iter().map(|&i| x[i]).collect(),
                k.iter().map(|&i| y[i]).collect(),
            );
            assert!(t.windows(2).all(|w| w[0] < w[1]), "{stem}");
            for align in [Align::FirstLeg, Align::Lsq] {
                for interp in [Interp::Nearest, Interp::Linear] {
                    let o = opts(align, interp);
                    assert_eq!(
                        streamed(&t, &x, &y, &truth, &o),
                        evaluate(&t, &x, &y, &truth, &o),
                        "{stem} {align:?} {interp:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn streamed_evaluation_equals_the_whole_trajectorys_at_the_edges() {
        // GCP times before the first row, after the last, exactly on rows, halfway between two
        // rows (a tie of the nearest), and out of time order; a NaN row and a NaN GCP.
        let truth = l_walk();
        let (mut t, mut x, mut y) = traj_from(&truth, |p| [p[0] * 1.02, p[1] + 0.1 * p[0]]);
        let mut gcps = truth.clone();
        gcps[0].t_s = t[0] - 0.5;
        gcps[3].t_s = t[t.len() - 1] + 2.0;
        gcps.push(TruthGcp {
            t_s: 0.5 * (t[4] + t[5]),
            ..truth[1]
        });
        gcps.push(TruthGcp {
            t_s: t[30],
            ..truth[2]
        });
        gcps.push(TruthGcp {
            t_s: f64::NAN,
            ..truth[2]
        });
        x[10] = f64::NAN;
        for interp in [Interp::Nearest, Interp::Linear] {
            let o = opts(Align::FirstLeg, interp);
            let whole = evaluate(&t, &x, &y, &gcps, &o).unwrap();
            assert_eq!(
                streamed(&t, &x, &y, &gcps, &o).unwrap(),
                whole,
                "{interp:?}"
            );
            assert!(!whole.warnings.is_empty());
        }
        // Too few rows, too few GCPs: the same errors.
        let o = EvalOptions::default();
        assert_eq!(
            streamed(&t[..1], &x[..1], &y[..1], &gcps, &o),
            evaluate(&t[..1], &x[..1], &y[..1], &gcps, &o)
        );
        assert_eq!(
            streamed(&t, &x, &y, &gcps[..1], &o),
            evaluate(&t, &x, &y, &gcps[..1], &o)
        );
        // A row that goes back in time is refused, not silently mis-sampled.
        t.swap(20, 21);
        y.swap(20, 21);
        assert!(matches!(
            streamed(&t, &x, &y, &gcps, &o),
            Err(EvalError::NotIncreasing { .. })
        ));
    }
}
