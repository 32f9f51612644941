//! What the suite measures of the front end: the stance detectors at fixed thresholds against
//! the adaptive one (stances found against the footprint list), a start without the initial rest,
//! and the clipping model on and off.

use super::figures::{StanceIntervals, StanceMatch};
use super::tables::median;
use super::{Footprint, SuiteRow};
use crate::core::WarmStart;
use crate::core::stance::{StanceDetector, StanceEdge, StanceEvents};
use corridor_shared::config::{Config, DetectorConfig, DetectorKind, Positive};
use corridor_shared::imu_csv::ImuRow;
use corridor_shared::truth_csv::TruthPoint;
use nalgebra::Vector3;
use serde::Serialize;

/// How much of the initial rest the "start without rest" run keeps before the first footprint
/// (the end of that rest), s: less than a walking stance, far less than `min_rest_s`.
pub const KEPT_REST_S: f64 = 0.2;

/// The detectors compared with the configured one: statistic, fixed threshold, and whether the
/// configured adaptive threshold is on. Thresholds in the statistic's own units (σ-normalised, see
/// `core/stance.rs`): for SHOE and ARE 3e4 / 1e5 / 3e5 are a stance rotating at most about
/// 0.3 / 0.55 / 0.95 rad/s; for MV 1e3 / 1e4 / 1e5 an accelerometer spread of about 0.3 / 1 /
/// 3 m/s².
pub const DETECTORS: [(DetectorKind, f64, bool); 9] = [
    (DetectorKind::Shoe, 3e4, false),
    (DetectorKind::Shoe, 1e5, false),
    (DetectorKind::Shoe, 3e5, false),
    (DetectorKind::Are, 3e4, false),
    (DetectorKind::Are, 1e5, false),
    (DetectorKind::Are, 3e5, false),
    (DetectorKind::Mv, 1e3, false),
    (DetectorKind::Mv, 1e4, false),
    (DetectorKind::Mv, 1e5, false),
];

/// Label of one of [`DETECTORS`].
pub fn detector_label(kind: DetectorKind, threshold: f64, adaptive: bool) -> String {
    let name = match kind {
        DetectorKind::Shoe => "SHOE",
        DetectorKind::Are => "ARE",
        DetectorKind::Mv => "MV",
    };
    let tail = if adaptive { " + adaptive" } else { "" };
    format!("{name} {threshold:.0e}{tail}")
}

/// Front-end figures of one recording.
#[derive(Debug, Clone, Serialize)]
pub struct FrontEnd {
    /// Samples with a gyro or accelerometer axis at its rail.
    pub clipped_samples: u64,
    /// The default run with the clipping model off (footprint RMS): neither the attitude
    /// variance about a clipped axis nor the peaks put back.
    pub clipping_off: Footprint,
    /// The default run with the attitude variance about a clipped axis but the peaks cut off by
    /// the rail not put back (`eskf.restore_clipped_peaks = false`).
    pub peaks_not_restored: Footprint,
    /// The default run on the log cut [`KEPT_REST_S`] before its first footprint (the last
    /// [`KEPT_REST_S`] of the initial rest, on a walk that starts with one).
    pub without_rest: Option<Footprint>,
    /// The same run scored in the map frame (as [`super::MapFrame`]): the first-leg alignment
    /// turns a run by its heading error at the end of its first 5 m, which is where a start
    /// without a bias prior is least sure of it.
    pub without_rest_map_frame: Option<Footprint>,
    /// The same cut log started from a checkpoint, as a daemon restarted without a rest: the
    /// bias the other walks of the same sensor configuration ended with ([`checkpoint_from`]).
    pub without_rest_checkpoint: Option<Footprint>,
    /// Each of [`DETECTORS`], then the configured detector, against the footprint list (walks
    /// surveyed at every stride).
    pub detectors: Option<Vec<StanceMatch>>,
}

/// The stances (first, last stance sample) the detector `cfg` finds, pauses of up to its
/// `merge_gap_s` bridged as the estimator does (steps longer than `max_step_s` are gaps); a
/// stance still open at the end of the log counts.
pub fn stance_intervals(rows: &[ImuRow], cfg: &DetectorConfig, max_step_s: f64) -> Vec<(f64, f64)> {
    let mut d = StanceDetector::new(cfg, 9.80665);
    let mut events = StanceEvents::new(cfg.merge_gap_s.get(), max_step_s);
    let mut out = StanceIntervals::default();
    for r in rows {
        let w = Vector3::from(r.gyro_rad_s);
        let f = Vector3::from(r.accel_m_s2);
        let stance = d.push(r.t_s, &w, &f).stance;
        let began = events.push(r.t_s, stance) == StanceEdge::Began;
        out.push(r.t_s, began, stance, None);
    }
    out.get().to_vec()
}

/// [`DETECTORS`] on one log, with the window, σ and minimum stance of `cfg`.
pub fn compare_detectors(rows: &[ImuRow], truth: &[TruthPoint], cfg: &Config) -> Vec<StanceMatch> {
    DETECTORS
        .iter()
        .map(|&(kind, threshold, adaptive)| {
            let mut d = cfg.detector.clone();
            d.kind = kind;
            d.threshold =
                Positive::new("detector.threshold", threshold).expect("a positive table value");
            if !adaptive {
                d.adaptive_factor = None;
            }
            StanceMatch::of(truth, &stance_intervals(rows, &d, cfg.max_dt_s.get()), &[])
        })
        .chain(std::iter::once(StanceMatch::of(
            truth,
            &stance_intervals(rows, &cfg.detector, cfg.max_dt_s.get()),
            &[],
        )))
        .collect()
}

/// The checkpoint a walk's restart would find, from the final biases (sensor axes) of the
/// other walks of the same sensor: per axis their median, with σ their spread (1.4826 × the
/// median absolute deviation, at least `floor_sd_rad_s`), as a daemon's checkpoint carries a
/// bias and its covariance. `None` with fewer than three walks to take it from.
pub fn checkpoint_from(others: &[[f64; 3]], floor_sd_rad_s: f64) -> Option<WarmStart> {
    if others.len() < 3 {
        return None;
    }
    let mut ws = WarmStart {
        gyro_bias_rad_s: [0.0; 3],
        gyro_bias_cov: [[0.0; 3]; 3],
    };
    for k in 0..3 {
        let m = median(&mut others.iter().map(|b| b[k]).collect::<Vec<_>>());
        let mad = median(&mut others.iter().map(|b| (b[k] - m).abs()).collect::<Vec<_>>());
        ws.gyro_bias_rad_s[k] = m;
        ws.gyro_bias_cov[k][k] = (1.4826 * mad).max(floor_sd_rad_s).powi(2);
    }
    Some(ws)
}

/// The rows of `rows` from [`KEPT_REST_S`] before the first footprint on.
pub fn without_rest<'a>(rows: &'a [ImuRow], truth: &[TruthPoint]) -> Option<&'a [ImuRow]> {
    let t0 = truth.first()?.t_s - KEPT_REST_S;
    let k = rows.partition_point(|r| r.t_s < t0);
    (k > 0).then(|| &rows[k..])
}

/// The front-end tables as Markdown.
pub fn front_end_markdown(rows: &[SuiteRow]) -> String {
    let mut s = format!(
        "Start without rest (the log cut {KEPT_REST_S} s before its first footprint, which on a walk that \
         starts with a rest leaves the last {KEPT_REST_S} s of it: alignment on that short stance, no rest-mean prior: the bias starts at the configuration's \
         `alignment.typical_gyro_bias_rad_s`, or zero), the same start from a checkpoint (a daemon restarted while the wearer \
         walks: the bias the other walks of the sensor ended with, per axis their median with their spread \
         as σ, none of this walk's own), and the clipping model (the attitude variance about a clipped gyro \
         axis, and the peaks the rail cut off put back: `eskf.restore_clipped_peaks`) off, and with the \
         variance alone, footprint RMS, % of path. The start without rest is also scored in the map frame (as the \
         map-frame table above: translated onto the first footprint, its own heading kept), against the \
         default run's map-frame figure: the first-leg alignment turns a run by its heading error at the \
         end of its first 5 m, where a start without a rest is least sure of it.\n\n\
         | recording | default | without rest | difference | map frame: default | without rest | difference | from a checkpoint | difference | clipped samples | clipping model off | peaks not put back |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n"
    );
    for r in rows {
        let fe = &r.front_end;
        let cut = fe
            .without_rest
            .map_or("—".into(), |f| format!("{:.2} %", f.rms_pct));
        let diff = |f: Option<Footprint>| {
            f.map_or("—".into(), |f| {
                format!("{:+.2}", f.rms_pct - r.best_rest.rms_pct)
            })
        };
        let warm = fe
            .without_rest_checkpoint
            .map_or("—".into(), |f| format!("{:.2} %", f.rms_pct));
        let map = r.map_frame.default.rms_pct;
        let (cut_map, diff_map) =
            fe.without_rest_map_frame
                .map_or(("—".into(), "—".into()), |f| {
                    (
                        format!("{:.2} %", f.rms_pct),
                        format!("{:+.2}", f.rms_pct - map),
                    )
                });
        s.push_str(&format!(
            "| {} | {:.2} % | {} | {} | {map:.2} % | {cut_map} | {diff_map} | {} | {} | {} | {:.2} % | {:.2} % |\n",
            r.recording,
            r.best_rest.rms_pct,
            cut,
            diff(fe.without_rest),
            warm,
            diff(fe.without_rest_checkpoint),
            fe.clipped_samples,
            fe.clipping_off.rms_pct,
            fe.peaks_not_restored.rms_pct
        ));
    }
    s.push_str(
        "\nStance detectors against the footprint list (walks surveyed at every stride): recall / precision of \
         the stance ends within ±50 ms, the detector alone (window, σ and minimum stance of the sensor's \
         configuration; the last column is the configured detector itself).\n\n| recording |",
    );
    for &(k, t, a) in &DETECTORS {
        s.push_str(&format!(" {} |", detector_label(k, t, a)));
    }
    s.push_str(" configured |");
    s.push_str("\n|---|");
    s.push_str(&"---|".repeat(DETECTORS.len() + 1));
    s.push('\n');
    for r in rows {
        let Some(d) = &r.front_end.detectors else {
            continue;
        };
        s.push_str(&format!("| {} |", r.recording));
        for m in d {
            s.push_str(&format!(
                " {:.0} / {:.0} |",
                100.0 * m.recall(),
                100.0 * m.precision()
            ));
        }
        s.push('\n');
    }
    s.push_str(&stance_misses_markdown(rows));
    s
}

/// Where the default run's stances miss the footprint list: a footfall found with its end
/// more than ±50 ms from the listed one is a timing difference, not a missed footfall; the
/// listed ends placed by hand scored apart from the others (another detector's).
fn stance_misses_markdown(rows: &[SuiteRow]) -> String {
    let mut s = String::from(
        "\nThe default run's stances against the footprint list, the misses taken apart: a listed footprint \
         is found (a stance ends within ±50 ms of it), found with its end further off (the nearest stance end \
         lies beyond ±50 ms but nearer than half the way to a neighbouring footprint: the footfall was \
         detected, its end placed differently), or missed; a detected stance that is no listed \
         footprint's nearest by those limits is extra. A footfall the detector missed and the \
         estimator updated late (`detector.late_stance_min_s`, `detector.overdue_stride_factor`) \
         counts as a stance ending at its quietest sample. The listed ends are the data set's: the last \
         zero-velocity sample of PyShoe's LSTM detector (the last footprint: the log's last sample), except \
         the strides its authors placed by hand from |a| and |ω| where the LSTM missed or misplaced one (`hand_placed_strides` in the suite \
         file, from the data set's `own_data.py`); the two are scored apart in the last columns.\n\n\
         | recording | listed | found | end further off | missed | extra stances | \
         median end offset (detected − listed) | placed by hand: found | the others: found |\n\
         |---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let Some(m) = r.stances_found else {
            continue;
        };
        let others = match m.listed - m.hand_placed {
            0 => "—".to_string(),
            n => {
                let found = m.found - m.hand_placed_found;
                format!("{found} of {n} ({:.0} %)", 100.0 * found as f64 / n as f64)
            }
        };
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {:+.0} ms | {} | {others} |\n",
            r.recording,
            m.listed,
            m.found,
            m.timing,
            m.missed(),
            m.extra,
            1000.0 * m.median_end_offset_s,
            match m.hand_placed {
                0 => "—".to_string(),
                n => format!("{} of {n}", m.hand_placed_found),
            },
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::checkpoint_from;

    #[test]
    fn a_checkpoint_is_the_median_of_the_other_walks_with_their_spread() {
        let others = [
            [1.0e-3, -2.0e-3, 5.0e-3],
            [2.0e-3, -1.0e-3, 4.0e-3],
            [3.0e-3, -3.0e-3, 4.5e-3],
            [9.0e-3, -2.5e-3, 5.0e-3],
        ];
        let ws = checkpoint_from(&others, 5e-4).expect("four walks");
        // Medians: x between 2 and 3 (the outlier 9 does not pull it), y −2.25, z 4.75 mrad/s.
        let b = ws.gyro_bias_rad_s;
        assert!((b[0] - 2.5e-3).abs() < 1e-12 && (b[1] + 2.25e-3).abs() < 1e-12);
        assert!((b[2] - 4.75e-3).abs() < 1e-12);
        // x: deviations 1.5, 0.5, 0.5, 6.5 → MAD 1.0 mrad/s; z: 0.25 each → MAD 0.25, below the
        // floor of 0.5 mrad/s.
        assert!((ws.gyro_bias_cov[0][0].sqrt() - 1.4826e-3).abs() < 1e-12);
        assert!((ws.gyro_bias_cov[2][2].sqrt() - 5e-4).abs() < 1e-12);
        assert_eq!(ws.gyro_bias_cov[0][1], 0.0);
        assert!(checkpoint_from(&others[..2], 5e-4).is_none());
    }
}
