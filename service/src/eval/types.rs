//! What the evaluation takes and gives: the truth, the options, the report, the error.

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

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
    /// Translate onto GCP0 only, keeping the trajectory's own heading (not in the reference
    /// script). For a run that starts from the map's heading in the
    /// truth's frame this is the error in the map frame: a heading aid's absolute heading is
    /// scored instead of being rotated away by the first leg.
    Translation,
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
            Align::Translation => "translation",
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
    /// Parses `first-leg`, `lsq` or `translation`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "first-leg" => Ok(Align::FirstLeg),
            "lsq" => Ok(Align::Lsq),
            "translation" => Ok(Align::Translation),
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

/// Options of [`evaluate`](super::evaluate); [`Default`] gives the script's defaults. The flags the
/// fields name (`--align`, `--closed-tol`, …) are those of the reference script
/// (`shared/tools/eval_traj.py`), not of `corridor`.
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
    /// Heading error of each leg at least [`LEG_MIN_DIST_M`](super::LEG_MIN_DIST_M) long (absent for a
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
    #[error("the truth needs at least two footprints ({gcps} finite)")]
    TooFewGcps {
        /// Number of GCPs with finite t, x and y.
        gcps: usize,
    },
    /// First-leg alignment found no GCP far enough from GCP0. Said in the README's words
    /// (footprints, not GCPs) and in centimetres: it said "farthest is 0.7650653566852966 m";
    /// in millimetres or finer where centimetres would round it up to the distance needed (it
    /// said "need 5 m, the farthest is 5.00 m" of 4.996 m: a review).
    #[error(
        "no footprint far enough from the first to align the heading on (need {min_dist_m} m, \
         the farthest is {} m)", shown_below(*farthest_m, *min_dist_m)
    )]
    NoHeadingGcp {
        /// The required distance, metres.
        min_dist_m: f64,
        /// The largest distance of any GCP from GCP0 in the truth, metres.
        farthest_m: f64,
    },
    /// The trajectory did not move between GCP0 and the heading GCP.
    #[error(
        "the trajectory did not move between the first footprint and the one the heading is \
         aligned on (footprint {heading_gcp_index}, counted from 0; moved {moved_m:.2} m)"
    )]
    NoMotionToHeadingGcp {
        /// Index k of the heading GCP.
        heading_gcp_index: usize,
        /// Distance between the trajectory's positions at GCP0 and GCPk, metres.
        moved_m: f64,
    },
    /// Fewer than two GCP times lie within the trajectory's time span (a truth of another
    /// recording, or on another clock): every GCP would be clamped to an end of the trajectory.
    #[error(
        "the truth's times ({truth_from_s} to {truth_to_s} s) lie outside the trajectory's \
         ({traj_from_s} to {traj_to_s} s; {inside} footprints inside): is it this recording's truth, on its clock?"
    )]
    TruthOutsideTrajectory {
        /// First and last GCP time, s.
        truth_from_s: f64,
        /// See `truth_from_s`.
        truth_to_s: f64,
        /// First and last trajectory time, s.
        traj_from_s: f64,
        /// See `traj_from_s`.
        traj_to_s: f64,
        /// GCPs within the trajectory's span.
        inside: usize,
    },
    /// A streamed trajectory row did not come after the previous one ([`GcpSampler`](super::GcpSampler)).
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

/// `value`, which lies below `limit`, with the fewest decimals from two on at which it still
/// reads below it (as it is, in full, when none up to six does).
fn shown_below(value: f64, limit: f64) -> String {
    (2..=6)
        .map(|decimals| format!("{value:.decimals$}"))
        .find(|text| text.parse::<f64>().is_ok_and(|shown| shown < limit))
        .unwrap_or_else(|| value.to_string())
}
