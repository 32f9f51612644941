//! The suite's summary over the normal-gait recordings and its Markdown tables.

use super::{
    Footprint, Gait, NisFigure, STRAIGHT_DEG, StartHeading, StrideUse, SuiteRow, WEAVE_DEG,
};
use serde::Serialize;

/// How far the default may be worse than the baseline and still count as "not worse", % of path.
pub const NOT_WORSE_TOLERANCE_PCT: f64 = 0.05;

/// The headline over the normal-gait recordings: the default configuration (best mode with the
/// rest-mean prior) against the ZUPT + rest-mean baseline.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Summary {
    /// Normal-gait recordings.
    pub n: usize,
    /// Median footprint RMS of the baseline, % of path.
    pub baseline_median_pct: f64,
    /// Worst footprint RMS of the baseline, % of path.
    pub baseline_worst_pct: f64,
    /// Median footprint RMS of the default, % of path.
    pub default_median_pct: f64,
    /// Worst footprint RMS of the default, % of path.
    pub default_worst_pct: f64,
    /// Recordings on which the default is better than the baseline.
    pub default_better: usize,
    /// Recordings on which the default is worse than the baseline by more than
    /// [`NOT_WORSE_TOLERANCE_PCT`].
    pub default_worse: usize,
    /// The same count with the recordings whose truth has legs the data set's own check flags
    /// scored on their footprints before the first such leg ([`super::BeforeSuspect`]).
    pub default_worse_before_suspect: usize,
    /// The convergence flag without a prior (injection from the start) and with the prior
    /// (injection after the rest).
    pub flag: [FlagSummary; 2],
}

/// The convergence flag of one injection protocol over the normal-gait recordings.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct FlagSummary {
    /// Recordings on which it rose.
    pub rose: usize,
    /// Of those, the ones where the recovery was within ±5 % on every axis when it rose.
    pub agrees: usize,
    /// Median seconds of walking before it rose (over the ones where it rose).
    pub median_walking_s: f64,
    /// Recordings on which it rose within 15 s of walking and agreed.
    pub agrees_within_15_s: usize,
}

impl FlagSummary {
    fn of<'a>(c: impl Iterator<Item = &'a super::Convergence>) -> Self {
        let mut rose = 0;
        let mut agrees = 0;
        let mut early = 0;
        let mut walking = Vec::new();
        for c in c {
            if let Some(w) = c.flag_after_walking_s() {
                rose += 1;
                walking.push(w);
                if c.agrees() {
                    agrees += 1;
                    if w <= 15.0 {
                        early += 1;
                    }
                }
            }
        }
        Self {
            rose,
            agrees,
            median_walking_s: median(&mut walking),
            agrees_within_15_s: early,
        }
    }
}

pub(super) use crate::stats::median;

/// The largest of `v` (NaN when empty).
fn worst(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::NAN, f64::max)
}

/// The summary over the normal-gait rows.
pub fn summary(rows: &[SuiteRow]) -> Summary {
    let normal: Vec<&SuiteRow> = rows.iter().filter(|r| r.gait == Gait::Normal).collect();
    let mut base: Vec<f64> = normal.iter().map(|r| r.zupt_rest.rms_pct).collect();
    let mut def: Vec<f64> = normal.iter().map(|r| r.best_rest.rms_pct).collect();
    Summary {
        n: normal.len(),
        baseline_worst_pct: worst(&base),
        default_worst_pct: worst(&def),
        baseline_median_pct: median(&mut base),
        default_median_pct: median(&mut def),
        default_better: normal
            .iter()
            .filter(|r| r.best_rest.rms_pct < r.zupt_rest.rms_pct)
            .count(),
        default_worse: normal
            .iter()
            .filter(|r| r.best_rest.rms_pct > r.zupt_rest.rms_pct + NOT_WORSE_TOLERANCE_PCT)
            .count(),
        default_worse_before_suspect: normal
            .iter()
            .filter(|r| {
                let (d, b) = r
                    .before_suspect
                    .map_or((r.best_rest, r.zupt_rest), |x| (x.default, x.baseline));
                d.rms_pct > b.rms_pct + NOT_WORSE_TOLERANCE_PCT
            })
            .count(),
        flag: [
            FlagSummary::of(normal.iter().map(|r| &r.best_convergence)),
            FlagSummary::of(normal.iter().map(|r| &r.best_convergence_prior_late)),
        ],
    }
}

/// The headline table (default against the baseline, per recording) and its summary line.
pub fn headline_markdown(rows: &[SuiteRow]) -> String {
    let mut s = String::from(
        "Default configuration (best mode, rest-mean prior) against the ZUPT + rest-mean baseline: footprint RMS, % of path.\n\n\
         | recording | gait | path | baseline | default | default − baseline | stride directions / foot axes used / stances | stride-length ratio | stances found (recall / precision, ±50 ms) |\n\
         |---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s.push_str(&format!(
            "| {} | {} | {:.1} m | {:.2} % | {:.2} % | {:+.2} | {} / {} / {} | {:.3} | {} |\n",
            r.recording,
            r.gait.name(),
            r.path_m,
            r.zupt_rest.rms_pct,
            r.best_rest.rms_pct,
            r.best_rest.rms_pct - r.zupt_rest.rms_pct,
            r.stride_used,
            r.heading_used,
            r.stances,
            r.stride_ratio,
            r.stances_found.map_or("—".to_string(), |m| format!(
                "{} of {} ({:.0} %) / {} of {} ({:.0} %)",
                m.found,
                m.listed,
                100.0 * m.recall(),
                m.matching,
                m.detected,
                100.0 * m.precision()
            )),
        ));
    }
    let m = summary(rows);
    s.push_str(&format!(
        "\nNormal gait ({} recording{}): median {:.2} % (baseline {:.2} %), worst {:.2} % (baseline {:.2} %); \
         default better on {} of {}, worse by more than {:.2} % of path on {}.\n",
        m.n,
        if m.n == 1 { "" } else { "s" },
        m.default_median_pct,
        m.baseline_median_pct,
        m.default_worst_pct,
        m.baseline_worst_pct,
        m.default_better,
        m.n,
        NOT_WORSE_TOLERANCE_PCT,
        m.default_worse
    ));
    let input: Vec<String> = rows
        .iter()
        .filter(|r| !r.input.is_clean())
        .map(|r| {
            let i = r.input;
            let parts = [
                (i.rows_rejected, "row", " rejected"),
                (i.samples_refused, "sample", " refused"),
                (i.gaps, "gap", ""),
                (i.clock_steps_back, "clock step", " back"),
                (i.health_restores, "health-check restore", ""),
            ]
            .iter()
            .filter(|(n, _, _)| *n > 0)
            .map(|&(n, what, done)| format!("{}{done}", crate::runner::count(n, what)))
            .collect::<Vec<_>>();
            format!("{} ({})", r.recording, parts.join(", "))
        })
        .collect();
    s.push_str(&if input.is_empty() {
        "
Input: every row read and every sample taken, no gap, clock step or health-check restore (the default runs).
".to_string()
    } else {
        format!(
            "
Input not taken as it came (the default runs; `results.json`'s `input`): {}.
",
            input.join("; ")
        )
    });
    let clamped: Vec<String> = rows
        .iter()
        .flat_map(|r| {
            r.eval_warnings
                .iter()
                .map(|w| format!("{}: {w}", r.recording))
        })
        .collect();
    if !clamped.is_empty() {
        s.push_str(&format!(
            "
What the footprint evaluation had to do (the default runs; `results.json`'s `eval_warnings`): {}. Those footprints are scored at the log's first or last estimate, as `eval_traj.py` does.
",
            clamped.join("; ")
        ));
    }
    let derived: Vec<String> = rows
        .iter()
        .filter(|r| r.start_heading == StartHeading::FirstStride)
        .map(|r| format!("{} ({:.0}°)", r.recording, r.start_heading_deg))
        .collect();
    if !derived.is_empty() {
        s.push_str(&format!(
            "\nStart heading not in the suite file, taken from the first surveyed stride on the grid: {}.\n",
            derived.join(", ")
        ));
    }
    s.push_str(&suspect_markdown(rows, &m));
    s.push_str(&map_frame_markdown(rows));
    s
}

/// Every recording scored in the map frame as well ([`super::MapFrame`]): the first-leg
/// alignment turns each run by its own error at the end of its first 5 m, which for a walk
/// that starts with turns (exp37's spiral) is most of what the figure measures.
fn map_frame_markdown(rows: &[SuiteRow]) -> String {
    let mut table = String::new();
    let (mut base, mut def, mut worse) = (Vec::new(), Vec::new(), 0);
    for r in rows {
        let (b, d) = (r.map_frame.baseline.rms_pct, r.map_frame.default.rms_pct);
        table.push_str(&format!(
            "| {} | {:.2} % | {:.2} % | {:+.2} | {:.2} % | {:.2} % |\n",
            r.recording,
            b,
            d,
            d - b,
            r.zupt_rest.rms_pct,
            r.best_rest.rms_pct
        ));
        if r.gait == Gait::Normal {
            base.push(b);
            def.push(d);
            worse += usize::from(d > b + NOT_WORSE_TOLERANCE_PCT);
        }
    }
    let (def_worst, base_worst) = (worst(&def), worst(&base));
    format!(
        "\nIn the map frame: each run translated onto the first footprint and scored with its own \
         heading (both start from the map's start heading, in the truth's frame), not turned by its \
         first 5 m as the first-leg figure is. Not the reference evaluator's figure; footprint RMS, \
         % of path.\n\n\
         | recording | baseline, map frame | default, map frame | default − baseline | baseline, first leg | default, first leg |\n\
         |---|---|---|---|---|---|\n{table}\n\
         Normal gait ({} recording{}), map frame: median {:.2} % (baseline {:.2} %), worst {:.2} % \
         (baseline {:.2} %); default worse than the baseline by more than {:.2} % of path on {}.\n",
        def.len(),
        if def.len() == 1 { "" } else { "s" },
        median(&mut def),
        median(&mut base),
        def_worst,
        base_worst,
        NOT_WORSE_TOLERANCE_PCT,
        worse
    )
}

/// The normal-gait recordings whose truth has legs the data set's own check flags, scored also
/// on the footprints before the first of them.
fn suspect_markdown(rows: &[SuiteRow], m: &Summary) -> String {
    let flagged: Vec<String> = rows
        .iter()
        .filter(|r| r.gait == Gait::Normal)
        .filter_map(|r| {
            let x = r.before_suspect?;
            Some(format!(
                "| {} | {} | {} of {} | {:.2} % | {:.2} % | {:+.2} | {:.2} % | {:.2} % | {:+.2} |\n",
                r.recording,
                x.first_leg,
                x.first_leg,
                x.footprints,
                r.zupt_rest.rms_pct,
                r.best_rest.rms_pct,
                r.best_rest.rms_pct - r.zupt_rest.rms_pct,
                x.baseline.rms_pct,
                x.default.rms_pct,
                x.default.rms_pct - x.baseline.rms_pct,
            ))
        })
        .collect();
    if flagged.is_empty() {
        return String::new();
    }
    format!(
        "\nTruth legs that the data set's own consistency check flags (a plain dead reckoning fitted to the \
         footprints gives the leg a length outside 0.85–1.15 of the surveyed one; `meta.json` of each recording): \
         the footprints before the first flagged leg scored alone, % of their own path.\n\n\
         | recording | first flagged leg | footprints before it | baseline, all | default, all | default − baseline | baseline, before it | default, before it | default − baseline |\n\
         |---|---|---|---|---|---|---|---|---|\n{}\n\
         Normal gait, scored before the flagged legs where there are any: default worse than the baseline by more \
         than {:.2} % of path on {} of {}.\n",
        flagged.concat(),
        NOT_WORSE_TOLERANCE_PCT,
        m.default_worse_before_suspect,
        m.n
    )
}

/// The NIS table: mean per degree of freedom of each update type of the default run, and its
/// 95 % band.
pub fn nis_markdown(rows: &[SuiteRow]) -> String {
    let mut s = String::from(
        "Consistency of the default run: mean NIS per degree of freedom [95 % χ² band] (n); ✗ outside the band.\n\n\
         | recording | first ZUPT of each stance | stride direction | foot axis |\n|---|---|---|---|\n",
    );
    let mut inside = [0usize; 3];
    let f = |x: &Option<NisFigure>| {
        x.map_or("—".to_string(), |x| {
            format!(
                "{:.2} [{:.2}, {:.2}] ({}){}",
                x.mean,
                x.lower,
                x.upper,
                x.n,
                if x.in_band() { "" } else { " ✗" }
            )
        })
    };
    for r in rows {
        for (k, x) in r.nis.iter().enumerate() {
            inside[k] += usize::from(x.is_some_and(|x| x.in_band()));
        }
        s.push_str(&format!(
            "| {} | {} | {} | {} |\n",
            r.recording,
            f(&r.nis[0]),
            f(&r.nis[1]),
            f(&r.nis[2])
        ));
    }
    let mut u = StrideUse::default();
    let mut use_rows = String::new();
    for r in rows {
        if let Some(x) = r.stride_use {
            use_rows.push_str(&format!(
                "| {} | {} of {} | {} of {} | {} of {} |\n",
                r.recording,
                x.straight_used,
                x.straight,
                x.weave_used,
                x.weave,
                x.weave_foot_used,
                x.weave
            ));
            if r.gait == Gait::Normal {
                u.straight += x.straight;
                u.straight_used += x.straight_used;
                u.weave += x.weave;
                u.weave_used += x.weave_used;
                u.weave_foot_used += x.weave_foot_used;
            }
        }
    }
    if !use_rows.is_empty() {
        s.push_str(&format!(
            "\nHeading information used on the strides of the walks surveyed at every stride \
             (straight: the stride and both neighbours within {STRAIGHT_DEG}° of one dominant \
             direction; weave: more than {WEAVE_DEG}° off the direction both neighbours follow).\n\n\
             | recording | straight strides with heading information | weave strides whose direction was used | weave strides whose foot axis was used |\n|---|---|---|---|\n{use_rows}\
             | all normal-gait walks | {} of {} ({:.0} %) | {} of {} | {} of {} |\n",
            u.straight_used,
            u.straight,
            100.0 * u.straight_used as f64 / u.straight.max(1) as f64,
            u.weave_used,
            u.weave,
            u.weave_foot_used,
            u.weave
        ));
    }
    s.push_str(&format!(
        "\nInside the band: first ZUPT {} of {}, stride direction {} of {}, foot axis {} of {}.\n",
        inside[0],
        rows.len(),
        inside[1],
        rows.len(),
        inside[2],
        rows.len()
    ));
    s
}

/// The table as Markdown.
pub fn markdown(rows: &[SuiteRow]) -> String {
    let mut s = headline_markdown(rows);
    s.push('\n');
    s.push_str(&nis_markdown(rows));
    s.push('\n');
    s.push_str(&super::front_end_markdown(rows));
    s.push('\n');
    s.push_str("Footprint RMS error after first-leg alignment, metres (% of path); final-GCP error in metres.\n\n");
    s.push_str("| recording | path | (1) ZUPT | (1b) ZUPT + rest mean | (2) injected, uncorrected | (3) paper, injected | (4) best, injected | best, no injection | best + rest mean |\n");
    s.push_str("|---|---|---|---|---|---|---|---|---|\n");
    let f = |x: &Footprint| format!("{:.2} ({:.2} %), {:.2}", x.rms_m, x.rms_pct, x.final_m);
    for r in rows {
        s.push_str(&format!(
            "| {} | {:.1} m | {} | {} | {} | {} | {} | {} | {} |\n",
            r.recording,
            r.path_m,
            f(&r.zupt),
            f(&r.zupt_rest),
            f(&r.zupt_inj),
            f(&r.paper_inj),
            f(&r.best_inj),
            f(&r.best),
            f(&r.best_rest)
        ));
    }
    s.push_str(
        "\nInjected-bias recovery ([0.001, 0.001, 0.005] rad/s), per axis x / y / z, % of the injected value \
         (mean from the convergence flag's rise on, else over the last quarter of the log). The flag rises once the \
         estimate carries less than 5 % of a bias error present when the bias was set (the filter's own closed-loop \
         response, `estimator.converged_unabsorbed`); against hindsight: when it rose (s of walking), the recovery at \
         that instant, and from when on the recovery stays within ±5 % (hindsight, s of the log).\n\n",
    );
    s.push_str("| recording | paper, no prior | best, no prior | best, prior + injection after the rest | paper, no prior: flag rose (recovery then), settled | best, no prior: flag rose (recovery then), settled | best, prior + late: flag rose (recovery then), settled | best vs uncorrected |\n");
    s.push_str("|---|---|---|---|---|---|---|---|\n");
    let p = |v: &[f64; 3]| {
        format!(
            "{:.0} / {:.0} / {:.0}",
            100.0 * v[0],
            100.0 * v[1],
            100.0 * v[2]
        )
    };
    let t = |v: Option<f64>| v.map_or("never".to_string(), |v| format!("{v:.1} s"));
    let flag = |c: &super::Convergence| {
        let then = c.recovered_at_flag.map_or(String::new(), |r| {
            format!(
                " ({:.0}, {:.0}, {:.0} %{})",
                100.0 * r[0],
                100.0 * r[1],
                100.0 * r[2],
                if c.agrees() { "" } else { " ✗" }
            )
        });
        format!(
            "{}{then}, {}",
            t(c.flag_after_walking_s()),
            t(c.settled_at_s)
        )
    };
    for r in rows {
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {:+.0} % |\n",
            r.recording,
            p(&r.paper_recovery),
            p(&r.best_recovery),
            p(&r.best_recovery_prior_late),
            flag(&r.paper_convergence),
            flag(&r.best_convergence),
            flag(&r.best_convergence_prior_late),
            -r.best_reduction_pct
        ));
    }
    let m = summary(rows);
    let line = |f: &FlagSummary| {
        let median = if f.rose == 0 {
            "—".to_string()
        } else {
            format!("{:.1} s", f.median_walking_s)
        };
        format!(
            "rose on {} of {}, within ±5 % on every axis when it rose on {} of those, after a median of {median} of walking \
             (risen and within ±5 % by 15 s of walking: {})",
            f.rose, m.n, f.agrees, f.agrees_within_15_s
        )
    };
    s.push_str(&format!(
        "\nConvergence flag, normal gait: without a prior (injection from the start) it {}; with the prior and the injection after the rest it {}.\n",
        line(&m.flag[0]),
        line(&m.flag[1])
    ));
    s
}
