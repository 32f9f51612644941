//! The suite file (`configs/eval/*.toml`): its recordings, read and checked in one pass.
//!
//! What a recording needs is its IMU log, its footprint truth and its sensor configuration; the
//! map knowledge a user has of the walk is its start heading (the corridor it starts in) and the
//! building's grid. A recording that leaves `start_heading_deg` out gets it from the truth the
//! way this suite's own were chosen: the direction of the first surveyed stride, on the grid
//! ([`start_heading_from_truth`]). One that leaves `suspect_legs` out gets the legs the data
//! set's `meta.json` beside its truth flags, when there is one (a `meta.json` that is there but
//! unreadable is an error naming it; `suspect_legs = []` opts out). `suspect_legs` are checked
//! against the truth here, for every command that reads a suite (eval, its ensemble and sweep,
//! the detection matrix): a suite file's own strictly, the data set's flags leniently (legs this
//! truth cannot be scored before are said and left out; the walk is still scored).

use super::SuiteError;
use crate::eval::EvalOptions;
use corridor_shared::config::{BiasPrior, ConfigOverrides, Mode};
use corridor_shared::truth_csv::{TruthPoint, read_truth_csv};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A surveyed stride shorter than this does not give a start heading (a shuffle, a foot set
/// down again): the first footprint at least this far from the first one does.
pub const FIRST_STRIDE_MIN_M: f64 = 0.5;

/// The entry of a gdins `meta.json` that lists the truth legs its consistency check flags.
pub const FLAGGED_LEGS_KEY: &str = "legs_ratio_outside_0.85_1.15";

/// The suite file, read and checked.
#[derive(Debug, Clone)]
pub struct SuiteFile {
    /// Injected bias for the recovery rows, rad/s (default the paper's [0.001, 0.001, 0.005]).
    pub inject_gyro_bias_rad_s: Option<[f64; 3]>,
    /// The mode reported as "best" (default `eskf`).
    pub best_mode: Option<Mode>,
    /// Recordings.
    pub recordings: Vec<SuiteRecording>,
}

/// One recording of the suite; paths are relative to the suite file.
#[derive(Debug, Clone)]
pub struct SuiteRecording {
    /// Short name.
    pub name: String,
    /// IMU log.
    pub imu: PathBuf,
    /// Footprint truth.
    pub truth: PathBuf,
    /// Sensor configuration (one per sensor).
    pub config: PathBuf,
    /// Configuration of the ZUPT baselines (rows 1, 1b, 2), when their noise set differs from
    /// the default's (one per sensor; default: `config`).
    pub baseline_config: Option<PathBuf>,
    /// Walking direction of the first leg in the map frame, degrees (map knowledge).
    pub start_heading_deg: f64,
    /// Where `start_heading_deg` came from.
    pub start_heading: StartHeading,
    /// Grid orientation, degrees.
    pub grid_deg: f64,
    /// Gait of the walk: fast or varying gait is reported but kept out of the normal-gait
    /// summary.
    pub gait: Gait,
    /// Legs of the truth (leg k: footprint k − 1 → k) that the data set's own consistency check
    /// flags: a plain dead reckoning fitted to the footprints gives the leg a length outside
    /// 0.85–1.15 of the surveyed one (`legs_ratio_outside_0.85_1.15` in the recording's
    /// `meta.json`; read from the `meta.json` beside the truth when the suite file leaves the
    /// key out). The reference figure keeps every footprint; the default and the baseline are
    /// also scored on the footprints before the first of these legs.
    pub suspect_legs: Vec<usize>,
    /// Strides (the truth's `stride` column) whose listed stance end the data set's authors
    /// placed by hand from |a| and |ω|; the others are the last zero-velocity sample of another
    /// detector (PyShoe's LSTM, in the gdins walks). The stance table scores the two apart.
    pub hand_placed_strides: Vec<u32>,
}

/// Where a recording's start heading came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StartHeading {
    /// `start_heading_deg` in the suite file.
    Given,
    /// Left out: the first surveyed stride's direction on the grid.
    FirstStride,
}

/// The gait of a suite recording, as its data set documents it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Gait {
    /// Normal walking.
    #[default]
    Normal,
    /// Fast or varying gait.
    Fast,
}

impl Gait {
    /// The name in the tables (as in the suite file).
    pub fn name(self) -> &'static str {
        match self {
            Gait::Normal => "normal",
            Gait::Fast => "fast",
        }
    }
}

impl SuiteRecording {
    /// The recording's map knowledge with the mode and prior of one suite row.
    pub fn overrides(&self, mode: Mode, prior: Option<BiasPrior>) -> ConfigOverrides {
        ConfigOverrides {
            mode: Some(mode),
            gyro_bias_prior: prior,
            start_heading_deg: Some(self.start_heading_deg),
            grid_deg: Some(self.grid_deg),
        }
    }
}

// The largest injected bias a suite may ask for is the command line's.
use corridor_shared::injection::MAX_INJECTED_BIAS_RAD_S;

/// The suite file as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileToml {
    #[serde(default)]
    inject_gyro_bias_rad_s: Option<[f64; 3]>,
    #[serde(default)]
    best_mode: Option<Mode>,
    #[serde(rename = "recording")]
    recordings: Vec<RecordingToml>,
}

/// One `[[recording]]` as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RecordingToml {
    name: String,
    imu: PathBuf,
    truth: PathBuf,
    config: PathBuf,
    #[serde(default)]
    baseline_config: Option<PathBuf>,
    #[serde(default)]
    start_heading_deg: Option<f64>,
    #[serde(default)]
    grid_deg: f64,
    #[serde(default)]
    gait: Gait,
    #[serde(default)]
    suspect_legs: Option<Vec<usize>>,
    #[serde(default)]
    hand_placed_strides: Vec<u32>,
}

/// Reads a suite file: every recording's start heading given or derived from its truth, its
/// `suspect_legs` checked against its truth. Errors name the file, the recording and the key.
pub fn read_suite(path: &Path) -> Result<SuiteFile, SuiteError> {
    let error = |message: String| SuiteError::File {
        path: path.to_owned(),
        message,
    };
    let text = corridor_shared::text_file::read_text(path).map_err(|e| error(e.to_string()))?;
    let file: FileToml = toml::from_str(&text).map_err(|e| error(e.to_string()))?;
    if file.recordings.is_empty() {
        return Err(error("no [[recording]]: a suite needs at least one".into()));
    }
    if let Some(b) = file.inject_gyro_bias_rad_s
        && let Some(v) = b
            .iter()
            .find(|v| !v.is_finite() || v.abs() > MAX_INJECTED_BIAS_RAD_S)
    {
        return Err(error(format!(
            "inject_gyro_bias_rad_s: {v:?} must be a finite number within ±{MAX_INJECTED_BIAS_RAD_S} rad/s"
        )));
    }
    // A name labels its rows in every table: blank, the rows had no label (`name = ""` was
    // taken); a '|' or a line break splits a Markdown row.
    for (i, r) in file.recordings.iter().enumerate() {
        let why = if r.name.trim().is_empty() {
            "must not be empty"
        } else if r.name.contains(|c: char| c == '|' || c.is_control()) {
            "must not hold a '|' or a control character (it labels a Markdown table row)"
        } else if r.name.trim() != r.name {
            "must not begin or end with white space (\"a\" and \"a \" would be two rows that look one)"
        } else {
            continue;
        };
        return Err(error(format!(
            "[[recording]] {} of {} (imu = {:?}): name = {:?} {why}",
            i + 1,
            file.recordings.len(),
            r.imu.display().to_string(),
            r.name
        )));
    }
    // Tables and results are keyed by name: two of one name would be one row twice. Reports
    // go into a directory named after the recording (`--loops`): two names of one directory
    // would overwrite, and the loop's removal of an earlier report remove, each other's.
    let mut names: Vec<(String, &str)> = file
        .recordings
        .iter()
        .map(|r| (report_dir_name(&r.name), r.name.as_str()))
        .collect();
    names.sort_unstable();
    if let Some(w) = names.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(error(if w[0].1 == w[1].1 {
            format!(
                "two recordings are named {:?}: names must be unique",
                w[0].1
            )
        } else {
            format!(
                "recordings {:?} and {:?} would share the report directory {:?} (letters, \
                 digits, '-', '_' and '.' kept, anything else '_'): names must differ there",
                w[0].1, w[1].1, w[0].0
            )
        }));
    }
    // A bare file name's parent is "" (the message then named an empty folder): ".".
    let base = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let recordings = file
        .recordings
        .into_iter()
        .map(|r| resolve(base, r))
        .collect::<Result<Vec<_>, String>>()
        .map_err(error)?;
    Ok(SuiteFile {
        inject_gyro_bias_rad_s: file.inject_gyro_bias_rad_s,
        best_mode: file.best_mode,
        recordings,
    })
}

/// The name of a recording's report directory (`corridor eval --loops`, under OUT/diagnose):
/// letters, digits, `-`, `_` and `.` kept, anything else `_`, so that no name reaches outside
/// that directory (`..`, `/`) or makes an odd one; a name of dots alone gets a prefix.
pub fn report_dir_name(name: &str) -> String {
    let dir: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect();
    if dir.chars().all(|c| c == '.') {
        format!("recording_{dir}")
    } else {
        dir
    }
}

/// One recording as written → checked, with its start heading.
fn resolve(base: &Path, r: RecordingToml) -> Result<SuiteRecording, String> {
    // Every file named, before any run: a missing one is named by its key here, not by its
    // path alone after the recordings before it have run. A directory is said to be one (it
    // was "no such file").
    for (key, file) in [
        ("imu", Some(&r.imu)),
        ("truth", Some(&r.truth)),
        ("config", Some(&r.config)),
        ("baseline_config", r.baseline_config.as_ref()),
    ] {
        if let Some(file) = file
            && let Some(why) = corridor_shared::text_file::not_a_file(&base.join(file))
        {
            return Err(format!(
                "recording {}: {key} = {:?}: {why} (relative paths are to the suite file's folder, {})",
                r.name,
                file.display().to_string(),
                base.display()
            ));
        }
    }
    // Where the legs came from, for an error about them.
    let meta = base.join(&r.truth).with_file_name("meta.json");
    let (suspect_legs, source) = match r.suspect_legs {
        Some(legs) => (legs, String::new()),
        None => (
            flagged_legs_beside(&meta).map_err(|e| {
                format!(
                    "recording {}: suspect_legs (left out, so read from {}): {e}; write \
                     `suspect_legs = []` to score every footprint",
                    r.name,
                    meta.display()
                )
            })?,
            format!(
                " (left out, so read from {}; write `suspect_legs = []` to score every footprint)",
                meta.display()
            ),
        ),
    };
    for (key, v) in [
        ("start_heading_deg", r.start_heading_deg.unwrap_or(0.0)),
        ("grid_deg", r.grid_deg),
    ] {
        if !(-360.0..=360.0).contains(&v) {
            return Err(format!(
                "recording {}: {key}: {v:?} must be in [-360, 360]°",
                r.name
            ));
        }
    }
    let needs_truth = r.start_heading_deg.is_none()
        || !suspect_legs.is_empty()
        || !r.hand_placed_strides.is_empty();
    let truth = if needs_truth {
        read_truth_csv(&base.join(&r.truth))
            .map_err(|e| format!("recording {}: truth: {e}", r.name))?
    } else {
        Vec::new()
    };
    let (start_heading_deg, start_heading) = match r.start_heading_deg {
        Some(deg) => (deg, StartHeading::Given),
        None => {
            let deg = start_heading_from_truth(&truth, r.grid_deg).ok_or_else(|| {
                format!(
                    "recording {}: start_heading_deg: not given, and no surveyed footprint lies \
                     {FIRST_STRIDE_MIN_M} m or more from the first one to take it from",
                    r.name
                )
            })?;
            (deg, StartHeading::FirstStride)
        }
    };
    let suspect_legs = if source.is_empty() {
        check_suspect_legs(&r.name, &suspect_legs, &truth)?;
        suspect_legs
    } else {
        flagged_legs_of(&r.name, &suspect_legs, &truth, &meta)
    };
    check_hand_placed(&r.name, &r.hand_placed_strides, &truth)?;
    Ok(SuiteRecording {
        name: r.name,
        imu: r.imu,
        truth: r.truth,
        config: r.config,
        baseline_config: r.baseline_config,
        start_heading_deg,
        start_heading,
        grid_deg: r.grid_deg,
        gait: r.gait,
        suspect_legs,
        hand_placed_strides: r.hand_placed_strides,
    })
}

/// The legs the data set's own consistency check flags, from the `meta.json` beside a truth
/// file (the gdins recordings' `truth.imu_consistency.crude_ins_fit` entry
/// `legs_ratio_outside_0.85_1.15`); none without that file or that entry. A file that is there
/// but cannot be read or parsed is an error (it names the file), not an empty list.
fn flagged_legs_beside(meta: &Path) -> Result<Vec<usize>, String> {
    let text = match corridor_shared::text_file::read_text(meta) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(e.to_string()),
    };
    let value: serde_json::Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
    let legs = &value["truth"]["imu_consistency"]["crude_ins_fit"][FLAGGED_LEGS_KEY];
    if legs.is_null() {
        return Ok(Vec::new());
    }
    serde_json::from_value(legs.clone()).map_err(|e| format!("{FLAGGED_LEGS_KEY}: {e}"))
}

/// The legs a gdins `meta.json` (`meta`) flags, as legs of `truth`: the data set names each by
/// the stride number of the footprint it ends at ("legs ending at strides [30, 31]"), the
/// truth's `stride` column, which is the leg's own number only where every stride is surveyed
/// (a truth without that column: taken as the leg's number). The data set's flags are extra
/// information: one that no footprint carries, or that this truth cannot be scored before (a
/// leg before the first-leg alignment's footprint), is said and left out, and the recording is
/// still scored.
fn flagged_legs_of(name: &str, flagged: &[usize], truth: &[TruthPoint], meta: &Path) -> Vec<usize> {
    let has_strides = truth.iter().any(|g| g.stride.is_some());
    let mut legs = Vec::new();
    for &stride in flagged {
        let leg = if has_strides {
            truth
                .iter()
                .skip(1)
                .position(|g| g.stride.is_some_and(|s| usize::try_from(s) == Ok(stride)))
                .map(|k| k + 1)
        } else {
            Some(stride)
        };
        let problem = match leg {
            None => format!("recording {name}: no footprint of its truth carries stride {stride}"),
            Some(leg) => match check_suspect_legs(name, &[leg], truth) {
                Ok(()) => {
                    legs.push(leg);
                    continue;
                }
                Err(e) => e,
            },
        };
        tracing::warn!(
            "{problem}: the leg ending at stride {stride} that {} flags is left out (the \
             recording is scored on every footprint, and before the legs left)",
            meta.display()
        );
    }
    legs
}

/// The start heading a user of the map gives a walk, taken from its truth: the direction from
/// the first footprint to the first one at least [`FIRST_STRIDE_MIN_M`] away, turned to the
/// nearest of the grid's four directions (degrees, in (−180, 180]). `None` when no footprint
/// is that far from the first.
pub fn start_heading_from_truth(truth: &[TruthPoint], grid_deg: f64) -> Option<f64> {
    let first = truth.first()?;
    let next = truth
        .iter()
        .find(|g| (g.x_m - first.x_m).hypot(g.y_m - first.y_m) >= FIRST_STRIDE_MIN_M)?;
    let stride_deg = (next.y_m - first.y_m)
        .atan2(next.x_m - first.x_m)
        .to_degrees();
    let on_grid = grid_deg + ((stride_deg - grid_deg) / 90.0).round() * 90.0;
    let wrapped = on_grid.rem_euclid(360.0);
    Some(if wrapped > 180.0 {
        wrapped - 360.0
    } else {
        wrapped
    })
}

/// A recording's `suspect_legs` name legs of its truth, and leave the first-leg alignment
/// footprint (the first one `heading_min_dist_m` from the start) before the first of them.
fn check_suspect_legs(name: &str, legs: &[usize], truth: &[TruthPoint]) -> Result<(), String> {
    let Some(&first) = legs.iter().min() else {
        return Ok(());
    };
    if let Some(&leg) = legs.iter().find(|&&k| k == 0 || k >= truth.len()) {
        return Err(format!(
            "recording {name}: suspect_legs: {leg} is not a leg of its {} footprints (legs 1 to {})",
            truth.len(),
            truth.len().saturating_sub(1)
        ));
    }
    let min_dist_m = EvalOptions::default().heading_min_dist_m;
    let heading_gcp = truth
        .iter()
        .position(|g| (g.x_m - truth[0].x_m).hypot(g.y_m - truth[0].y_m) >= min_dist_m);
    match heading_gcp {
        Some(k) if k < first => Ok(()),
        _ => Err(format!(
            "recording {name}: suspect_legs: leg {first} comes before the footprint {min_dist_m} m \
             from the start that the first-leg alignment needs (nothing would be left to score)"
        )),
    }
}

/// Every hand-placed stride is a stride of the truth, listed once.
fn check_hand_placed(name: &str, strides: &[u32], truth: &[TruthPoint]) -> Result<(), String> {
    for (i, &stride) in strides.iter().enumerate() {
        if strides[..i].contains(&stride) {
            return Err(format!(
                "recording {name}: hand_placed_strides: stride {stride} is listed twice"
            ));
        }
        if !truth.iter().any(|g| g.stride == Some(i64::from(stride))) {
            return Err(format!(
                "recording {name}: hand_placed_strides: stride {stride} is no stride of its truth \
                 (its `stride` column)"
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
#[path = "file_tests.rs"]
mod tests;
