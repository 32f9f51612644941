//! Does a choice of the configuration generalise? A leave-one-walk-out check
//! (`corridor eval --suite FILE --sweep SWEEP`).
//!
//! For each parameter of the sweep file, the default run (best mode, rest-mean prior) of every
//! normal-gait recording is repeated at each listed value, the other parameters as configured.
//! Then, for each walk in turn, the value a suite without that walk would have chosen (the
//! lowest mean footprint RMS over the other walks) is applied to it: the walk's *held-out*
//! error. Held-out figures close to the configured ones say the choice does not depend on any
//! one walk; a value whose median is as good but whose worst case jumps says the choice is
//! fragile there. The mean is the criterion because it sees the worst walks, which the median
//! ignores (over this suite the medians of every swept value lie within 0.05 % of each other).

use super::{Ctx, Gait, SuiteError, SuiteRecording, SuiteRun, config_for, read_suite};
use crate::runner::RunError;
use corridor_shared::config::{BiasPrior, ConfigFile, Mode};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::Path;

/// Keys the suite sets on every run ([`SuiteRecording::overrides`]): not sweepable.
const FIXED_BY_THE_SUITE: [&str; 4] = [
    "estimator.mode",
    "alignment.gyro_bias_prior",
    "heading.start_heading_deg",
    "heading.grid_deg",
];

/// The sweep file: `[[parameter]]` tables.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    /// Parameters, each swept alone.
    #[serde(rename = "parameter")]
    pub parameters: Vec<SweepParameter>,
}

/// One parameter and the values it takes.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepParameter {
    /// `section.key` of the configuration file (`heading.stride_sigma_deg`).
    pub key: String,
    /// Values, in the key's type.
    pub values: Vec<toml::Value>,
}

/// The footprint RMS of every normal-gait walk at every value of one parameter.
#[derive(Debug, Clone, Serialize)]
pub struct SweepResult {
    /// `section.key`.
    pub key: String,
    /// Each walk's configured value, as written (`default` when its file leaves it to the
    /// built-in default).
    pub configured_per_walk: Vec<String>,
    /// The values, as written.
    pub values: Vec<String>,
    /// Walk names.
    pub walks: Vec<String>,
    /// Footprint RMS, % of path, `[value][walk]`.
    pub rms_pct: Vec<Vec<f64>>,
}

impl SweepResult {
    /// The configured value, or `mixed (…)` when the walks' configurations differ.
    pub fn configured(&self) -> String {
        let mut each: Vec<&str> = self
            .configured_per_walk
            .iter()
            .map(String::as_str)
            .collect();
        each.sort_unstable();
        each.dedup();
        match each.as_slice() {
            [one] => (*one).to_owned(),
            many => format!("mixed ({})", many.join(", ")),
        }
    }
}

/// What the leave-one-walk-out check finds for one parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct HeldOut {
    /// Per walk, the index of the value chosen without it.
    pub picks: Vec<usize>,
    /// Per walk, its error at that value.
    pub rms_pct: Vec<f64>,
}

/// The value each fold picks (lowest mean over the other walks; the first of equals) and the
/// held-out walk's error there.
pub fn held_out(r: &SweepResult) -> HeldOut {
    let n = r.walks.len();
    let mean_without = |v: usize, w: usize| {
        let s: f64 = (0..n).filter(|&k| k != w).map(|k| r.rms_pct[v][k]).sum();
        s / (n - 1).max(1) as f64
    };
    let picks: Vec<usize> = (0..n)
        .map(|w| {
            (0..r.values.len())
                .min_by(|&a, &b| mean_without(a, w).total_cmp(&mean_without(b, w)))
                .unwrap_or(0)
        })
        .collect();
    let rms_pct = picks
        .iter()
        .enumerate()
        .map(|(w, &v)| r.rms_pct[v][w])
        .collect();
    HeldOut { picks, rms_pct }
}

/// Reads the sweep file and runs it on the suite's normal-gait recordings: one result per
/// parameter, in the sweep file's order. A recording that fails is named (`failed`) and left
/// out of every parameter's folds; with fewer than two left, the sweep fails, naming them all.
pub fn run_sweep(
    suite_path: &Path,
    sweep_path: &Path,
) -> Result<SuiteRun<SweepResult>, SuiteError> {
    let suite = read_suite(suite_path)?;
    let base = suite_path.parent().unwrap_or(Path::new("."));
    let file_err = |message: String| SuiteError::File {
        path: sweep_path.to_owned(),
        message,
    };
    let text =
        corridor_shared::text_file::read_text(sweep_path).map_err(|e| file_err(e.to_string()))?;
    let sweep: SweepFile = toml::from_str(&text).map_err(|e| file_err(e.to_string()))?;
    let best = suite.best_mode.unwrap_or(Mode::Eskf);
    let recs: Vec<&SuiteRecording> = suite
        .recordings
        .iter()
        .filter(|r| r.gait == Gait::Normal)
        .collect();
    if recs.len() < 2 {
        return Err(SuiteError::File {
            path: suite_path.to_owned(),
            message: format!(
                "a leave-one-walk-out check needs at least 2 normal-gait recordings, the suite \
                 has {}",
                recs.len()
            ),
        });
    }
    for p in &sweep.parameters {
        if p.values.is_empty() {
            return Err(file_err(format!("parameter {}: no values", p.key)));
        }
        if FIXED_BY_THE_SUITE.contains(&p.key.as_str()) {
            return Err(file_err(format!(
                "parameter {}: set by the suite for every run (its mode, prior and map \
                 knowledge), so sweeping it would change nothing",
                p.key
            )));
        }
    }
    // Every value checked before any run, on every configuration of the suite that is valid
    // as it stands (a value one refuses was found only inside a recording's run, after the
    // recordings before it, and not at all when they failed; one that is invalid without the
    // sweep fails its recordings' runs, which name it: reviews).
    let mut checked: Vec<&Path> = Vec::new();
    for r in &recs {
        if checked.contains(&r.config.as_path()) {
            continue;
        }
        checked.push(&r.config);
        let path = base.join(&r.config);
        // Valid as the runs judge it: the file as it is (`read_recording`), then with the
        // suite's overrides.
        let Ok(file) = ConfigFile::read(&path) else {
            continue;
        };
        if file.validate().is_err()
            || config_for(&file, &path, r, best, BiasPrior::RestMean).is_err()
        {
            continue;
        }
        for p in &sweep.parameters {
            configured(&file, &p.key).map_err(&file_err)?;
            for value in &p.values {
                swept_config((&file, &path), r, best, (p, value), sweep_path)?;
            }
        }
    }
    // Per recording, its footprint RMS at every value of every parameter (`[parameter][value]`),
    // or its failure: a recording that fails is left out of every fold and named.
    let run = SuiteRun::each(&recs, |r| {
        let wrap = |source: RunError| SuiteError::Run {
            name: r.name.clone(),
            source: Box::new(source),
        };
        let ctx = Ctx::open(base, r, super::RejectedRows::Say).map_err(wrap)?;
        // What the input cost is said with the recording's first run.
        let mut say = Some("its first run of the sweep");
        let mut walk = Vec::with_capacity(sweep.parameters.len());
        for p in &sweep.parameters {
            let configured = configured(&ctx.config, &p.key).map_err(&file_err)?;
            let mut at = Vec::with_capacity(p.values.len());
            let path = base.join(&r.config);
            for value in &p.values {
                let cfg = swept_config((&ctx.config, &path), r, best, (p, value), sweep_path)?;
                at.push(ctx.footprint_at(&cfg, say.take()).map_err(wrap)?.rms_pct);
            }
            walk.push((configured, at));
        }
        Ok((r.name.clone(), walk))
    })?;
    if run.rows.len() < 2 {
        // Fewer than two walks scored: no fold to hold one out of, and no table.
        let failed: Vec<String> = run.failed.iter().map(ToString::to_string).collect();
        // The suite's walks, not the sweep file, are what is missing.
        return Err(SuiteError::File {
            path: suite_path.to_owned(),
            message: format!(
                "a leave-one-walk-out check needs at least 2 normal-gait walks that run; {} of {} did{}",
                run.rows.len(),
                recs.len(),
                if failed.is_empty() {
                    String::new()
                } else {
                    format!(", and these failed: {}", failed.join("; "))
                }
            ),
        });
    }
    let out = sweep
        .parameters
        .iter()
        .enumerate()
        .map(|(k, p)| SweepResult {
            key: p.key.clone(),
            configured_per_walk: run.rows.iter().map(|(_, w)| w[k].0.clone()).collect(),
            values: p.values.iter().map(|v| v.to_string()).collect(),
            walks: run.rows.iter().map(|(name, _)| name.clone()).collect(),
            rms_pct: (0..p.values.len())
                .map(|v| run.rows.iter().map(|(_, walk)| walk[k].1[v]).collect())
                .collect(),
        })
        .collect();
    Ok(SuiteRun {
        rows: out,
        failed: run.failed,
    })
}

/// The run configuration of recording `r` with the sweep's `value` of parameter `p` in its
/// configuration `file` (at `path`); a value refused is the sweep file's error (it named the
/// sensor configuration, a review), and the pre-run check and the runs say it alike.
fn swept_config(
    (file, path): (&ConfigFile, &Path),
    r: &SuiteRecording,
    best: Mode,
    (p, value): (&SweepParameter, &toml::Value),
    sweep_path: &Path,
) -> Result<corridor_shared::config::Config, SuiteError> {
    let file_err = |message: String| SuiteError::File {
        path: sweep_path.to_owned(),
        message,
    };
    let with = with_value(file, &p.key, value).map_err(file_err)?;
    config_for(&with, path, r, best, BiasPrior::RestMean)
        .map_err(|e| file_err(format!("parameter {} = {value}: {e}", p.key)))
}

/// `file` with `section.key` set to `value`; an unknown key or a value of the wrong type is an
/// error naming both.
fn with_value(file: &ConfigFile, key: &str, value: &toml::Value) -> Result<ConfigFile, String> {
    let (section, name) = key
        .split_once('.')
        .ok_or_else(|| format!("parameter key {key:?}: expected section.key"))?;
    let mut doc = toml::Value::try_from(file).map_err(|e| e.to_string())?;
    let table = doc
        .as_table_mut()
        .and_then(|t| {
            t.entry(section)
                .or_insert_with(|| toml::Value::Table(Default::default()))
                .as_table_mut()
        })
        .ok_or_else(|| format!("parameter key {key:?}: [{section}] is not a table"))?;
    table.insert(name.to_owned(), value.clone());
    doc.try_into()
        .map_err(|e| format!("parameter {key} = {value}: {e}"))
}

/// The configured value of `section.key`, as written.
fn configured(file: &ConfigFile, key: &str) -> Result<String, String> {
    let doc = toml::Value::try_from(file).map_err(|e| e.to_string())?;
    let (section, name) = key
        .split_once('.')
        .ok_or_else(|| format!("parameter key {key:?}: expected section.key"))?;
    Ok(doc
        .get(section)
        .and_then(|s| s.get(name))
        .map_or_else(|| "default".to_owned(), |v| v.to_string()))
}

/// The sweep as Markdown: per parameter, the mean / median / worst at each value, and the
/// held-out figures against the configured value's.
pub fn sweep_markdown(results: &[SweepResult]) -> String {
    let mut md = String::from(
        "Leave-one-walk-out check of the configuration (normal-gait walks, footprint RMS % of \
         path): each parameter swept alone; for each walk, the value the other walks choose \
         (lowest mean) applied to it.\n\n| parameter | configured | mean / median / worst at \
         each value | values chosen by the folds | held-out mean / median / worst | configured: \
         mean / median / worst |\n|---|---|---|---|---|---|\n",
    );
    for r in results {
        let stats = |x: &[f64]| {
            let mut s = x.to_vec();
            let med = super::tables::median(&mut s);
            let mean = s.iter().sum::<f64>() / s.len().max(1) as f64;
            let worst = s.last().copied().unwrap_or(f64::NAN);
            format!("{mean:.2} / {med:.2} / {worst:.2}")
        };
        let per_value: Vec<String> = r
            .values
            .iter()
            .zip(&r.rms_pct)
            .map(|(v, x)| format!("{v}: {}", stats(x)))
            .collect();
        let h = held_out(r);
        let mut chosen: Vec<usize> = h.picks.clone();
        chosen.sort_unstable();
        chosen.dedup();
        let chosen: Vec<String> = chosen
            .iter()
            .map(|&v| {
                let n = h.picks.iter().filter(|&&p| p == v).count();
                format!("{} ({n})", r.values[v])
            })
            .collect();
        // Each walk at its own configuration's value (the walks' configurations may differ).
        let configured = r
            .configured_per_walk
            .iter()
            .enumerate()
            .map(|(w, c)| {
                let v = r.values.iter().position(|v| v == c)?;
                Some(r.rms_pct[v][w])
            })
            .collect::<Option<Vec<f64>>>()
            .map_or_else(|| "not swept".to_owned(), |x| stats(&x));
        let _ = writeln!(
            md,
            "| `{}` | {} | {} | {} | {} | {} |",
            r.key,
            r.configured(),
            per_value.join("; "),
            chosen.join(", "),
            stats(&h.rms_pct),
            configured
        );
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    fn result(rms: Vec<Vec<f64>>) -> SweepResult {
        SweepResult {
            key: "heading.sigma_deg".into(),
            configured_per_walk: vec!["3.0".into(); rms[0].len()],
            values: vec!["2.0".into(), "3.0".into()],
            walks: (0..rms[0].len()).map(|k| format!("w{k}")).collect(),
            rms_pct: rms,
        }
    }

    #[test]
    fn each_fold_picks_without_its_walk() {
        // Value 0 is better on every walk but the last, where it is far worse: the folds that
        // keep the last walk pick value 1, the fold without it picks value 0.
        let r = result(vec![vec![0.2, 0.2, 0.2, 3.0], vec![0.3, 0.3, 0.3, 0.5]]);
        let h = held_out(&r);
        assert_eq!(h.picks, [1, 1, 1, 0]);
        assert_eq!(h.rms_pct, [0.3, 0.3, 0.3, 3.0]);
        let md = sweep_markdown(&[r]);
        assert!(md.contains("2.0 (1), 3.0 (3)"), "{md}");
    }

    #[test]
    fn walks_configured_differently_are_each_scored_at_their_own_value() {
        // The configured column took the first walk's value for every walk (a review).
        let mut r = result(vec![vec![0.2, 0.4], vec![0.3, 0.5]]);
        r.configured_per_walk = vec!["2.0".into(), "3.0".into()];
        let md = sweep_markdown(&[r.clone()]);
        // Walk 0 at 2.0 (0.2), walk 1 at 3.0 (0.5): mean 0.35, median 0.35, worst 0.50.
        assert!(md.contains("| mixed (2.0, 3.0) |"), "{md}");
        assert!(md.trim_end().ends_with("| 0.35 / 0.35 / 0.50 |"), "{md}");
        r.configured_per_walk[1] = "default".into();
        assert!(sweep_markdown(&[r]).trim_end().ends_with("| not swept |"));
    }

    #[test]
    fn a_value_is_set_by_section_and_key_and_a_wrong_key_is_named() {
        let file = ConfigFile::default();
        let f = with_value(&file, "heading.sigma_deg", &toml::Value::Float(2.5)).unwrap();
        assert_eq!(f.heading.sigma_deg, Some(2.5));
        assert_eq!(configured(&f, "heading.sigma_deg").unwrap(), "2.5");
        assert_eq!(configured(&file, "heading.sigma_deg").unwrap(), "default");
        let e = with_value(&file, "heading.sigma", &toml::Value::Float(2.5)).unwrap_err();
        assert!(e.contains("heading.sigma"), "{e}");
        let e =
            with_value(&file, "heading.sigma_deg", &toml::Value::String("x".into())).unwrap_err();
        assert!(e.contains("heading.sigma_deg"), "{e}");
        assert!(with_value(&file, "sigma_deg", &toml::Value::Float(1.0)).is_err());
    }

    #[test]
    fn the_bundled_suite_reads_and_every_bundled_sweep_value_is_valid_on_its_configurations() {
        // The bounds the configuration keys gained (the sensor limits, the σ floors, the
        // stance thresholds) leave every bundled file as it was.
        let eval = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/eval");
        let suite = read_suite(&eval.join("gdins.toml")).unwrap();
        let text = std::fs::read_to_string(eval.join("gdins_sweep.toml")).unwrap();
        let sweep: SweepFile = toml::from_str(&text).unwrap();
        let mut configs: Vec<&Path> = suite
            .recordings
            .iter()
            .map(|r| r.config.as_path())
            .collect();
        configs.sort_unstable();
        configs.dedup();
        for config in configs {
            let file = ConfigFile::read(&eval.join(config)).unwrap();
            for p in &sweep.parameters {
                for v in &p.values {
                    with_value(&file, &p.key, v)
                        .unwrap()
                        .validate()
                        .unwrap_or_else(|e| panic!("{} = {v}: {e}", p.key));
                }
            }
        }
    }
}
