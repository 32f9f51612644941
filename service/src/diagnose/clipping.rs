//! Does the gyro clip below the range the configuration gives it? A look at the data, not the
//! residuals: a rail is a level the signal runs into again and again and stays on for more than
//! one sample (a flat top), where a smooth peak touches its maximum once.
//!
//! Why it matters: a sample at the rail reads less than the true rate, and the rotation lost
//! there shows up downstream as tilt and heading jumps that the filter blames on the bias (the
//! bias-change test of [`super::bias_change`] then fires, on the horizontal axes the ZUPTs
//! correct). The estimator flags and models clipped samples (`sensor.gyro_range_rad_s`,
//! `eskf.clipped_rate_sd_rad_s`), but only at the configured range; a sensor set to a smaller
//! full scale than the configuration says (or a driver that saturates earlier) clips unseen.
//!
//! Per axis: the largest |ω| of the log, the samples within [`RAIL_TOLERANCE`] of it, and the
//! runs of at least two consecutive such samples. [`MIN_FLAT_TOPS`] or more runs make a rail at
//! the median of those samples. On the 17 bundled logs an axis that never clips has at most 2
//! such runs (a smooth peak sampled at 200 Hz can hold two samples within 0.5 % of its top);
//! the gdins logs that clip often have 6 and 22 at 8.65–8.75 rad/s (range 8.727: a rail at the
//! configured range, flagged already); the matrix's injection at 5 rad/s makes dozens.

use super::catalogue::{Effect, Fix};
use super::ranking::Finding;
use corridor_shared::imu_csv::ImuRow;
use corridor_shared::sensor::CLIP_FRACTION;
use serde::Serialize;

/// Samples within this fraction of an axis's largest |ω| are at its extreme.
pub const RAIL_TOLERANCE: f64 = 0.005;

/// Flat tops (runs of ≥ 2 samples at the extreme) that make a rail.
pub const MIN_FLAT_TOPS: usize = 5;

/// No gyro's full scale is below this, rad/s (≈ 57 °/s): a lower "rail" is an axis that hardly
/// moves (quantised around its largest value), not a clipping sensor.
pub const MIN_RAIL_RAD_S: f64 = 1.0;

/// A rail found on one gyro axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Rail {
    /// Sensor axis (0 x, 1 y, 2 z).
    pub axis: usize,
    /// The rail, rad/s (median |ω| of the samples at the extreme).
    pub level_rad_s: f64,
    /// Samples at the extreme.
    pub samples: usize,
    /// Runs of at least two of them.
    pub flat_tops: usize,
}

/// The rails of a log, one per axis that has one.
pub fn find_rails(rows: &[ImuRow]) -> Vec<Rail> {
    (0..3)
        .filter_map(|axis| {
            let peak = rows
                .iter()
                .map(|r| r.gyro_rad_s[axis].abs())
                .fold(0.0_f64, f64::max);
            if peak.is_nan() || peak <= 0.0 {
                return None;
            }
            let at = |r: &ImuRow| r.gyro_rad_s[axis].abs() >= peak * (1.0 - RAIL_TOLERANCE);
            let mut levels = Vec::new();
            let (mut flat_tops, mut run) = (0, 0usize);
            for r in rows {
                if at(r) {
                    levels.push(r.gyro_rad_s[axis].abs());
                    run += 1;
                    if run == 2 {
                        flat_tops += 1;
                    }
                } else {
                    run = 0;
                }
            }
            if flat_tops < MIN_FLAT_TOPS || peak < MIN_RAIL_RAD_S {
                return None;
            }
            levels.sort_by(f64::total_cmp);
            Some(Rail {
                axis,
                level_rad_s: levels[levels.len() / 2],
                samples: levels.len(),
                flat_tops,
            })
        })
        .collect()
}

/// The finding: a rail below the configured range (`range_rad_s`, the level from which
/// [`CLIP_FRACTION`] of it counts as clipped) is named, with the fix that moves the range to the
/// lowest such rail; a rail at the range is reported as flagged. `None` without a rail.
pub fn clipping_finding(rails: &[Rail], range_rad_s: f64, clip_model_on: bool) -> Option<Finding> {
    if rails.is_empty() {
        return None;
    }
    let words: Vec<String> = rails
        .iter()
        .map(|r| {
            format!(
                "axis {}: {} samples in {} flat tops at {:.3} rad/s",
                ["x", "y", "z"][r.axis],
                r.samples,
                r.flat_tops,
                r.level_rad_s
            )
        })
        .collect();
    let below: Option<&Rail> = rails
        .iter()
        .filter(|r| r.level_rad_s < CLIP_FRACTION * range_rad_s)
        .min_by(|a, b| a.level_rad_s.total_cmp(&b.level_rad_s));
    Some(match below {
        Some(r) => Finding {
            name: Effect::GyroClipping,
            // a level the signal keeps running into is not a chance event
            score: super::ranking::MAX_SCORE,
            evidence: format!(
                "the gyro clips below its configured range {range_rad_s:.3} rad/s ({}): those \
                 samples are not flagged, and the rotation lost there is not modelled",
                words.join("; ")
            ),
            fix: Some(Fix::GyroRail {
                milli_rad_s: (r.level_rad_s * 1000.0).round() as u32,
            }),
            mde: None,
        },
        None => Finding {
            name: Effect::GyroClipping,
            score: 0.0,
            evidence: format!(
                "the gyro reaches its configured range {range_rad_s:.3} rad/s ({}): flagged as \
                 clipped{}",
                words.join("; "),
                if clip_model_on {
                    ", the lost rotation modelled (eskf.clipped_rate_sd_rad_s, \
                     eskf.restore_clipped_peaks)"
                } else {
                    "; the lost rotation is not modelled (eskf.clipped_rate_sd_rad_s = 0 and \
                     eskf.restore_clipped_peaks = false, or the paper's filter)"
                }
            ),
            fix: None,
            mde: None,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 200 Hz, a swing every second, mostly on y: a half-sine whose height changes from swing
    /// to swing in 2 % steps (as strides differ), y clipped at `clip`.
    fn swings(amp: f64, clip: f64) -> Vec<ImuRow> {
        (0..4000)
            .map(|k| {
                let t = k as f64 * 0.005;
                let phase = t.fract();
                let height = amp * (1.0 + 0.02 * ((k / 200 * 37) % 11) as f64);
                let w = if phase < 0.3 {
                    height * (std::f64::consts::PI * phase / 0.3).sin()
                } else {
                    0.0
                };
                ImuRow {
                    t_s: t,
                    gyro_rad_s: [0.1 * w, w.clamp(-clip, clip), 0.01],
                    accel_m_s2: [0.0, 0.0, 9.81],
                    temp_c: None,
                    line: k as u64 + 2,
                }
            })
            .collect()
    }

    #[test]
    fn a_smooth_peak_is_no_rail() {
        // The highest swings touch their maximum with a sample or two each: not a rail.
        let rows = swings(8.0, f64::INFINITY);
        assert!(find_rails(&rows).is_empty(), "{:?}", find_rails(&rows));
        // An axis that hardly moves, its top quantised into flat runs, is not a clipping gyro.
        let rows = swings(0.5, 0.3);
        assert!(find_rails(&rows).is_empty(), "{:?}", find_rails(&rows));
        // The same swings all cut at one level are.
        let rows = swings(8.0, 7.0);
        let rails = find_rails(&rows);
        assert_eq!(rails.len(), 1, "{rails:?}");
        assert_eq!((rails[0].axis, rails[0].level_rad_s), (1, 7.0));
    }

    #[test]
    fn a_rail_below_the_range_is_named_with_its_level() {
        let rows = swings(8.0, 5.0);
        let rails = find_rails(&rows);
        assert_eq!(rails.len(), 1, "{rails:?}");
        assert_eq!(rails[0].axis, 1);
        assert!((rails[0].level_rad_s - 5.0).abs() < 1e-12);
        assert!(rails[0].flat_tops >= 19, "{rails:?}");
        let f = clipping_finding(&rails, 8.727, true).unwrap();
        assert_eq!(f.name, Effect::GyroClipping);
        assert!(f.score >= super::super::SIGNIFICANT);
        assert_eq!(f.fix, Some(Fix::GyroRail { milli_rad_s: 5000 }));
        // At the configured range: flagged already, not named.
        let at_range = clipping_finding(&rails, 5.05, false).unwrap();
        assert_eq!(at_range.score, 0.0);
        assert!(
            at_range.evidence.contains("not modelled"),
            "{}",
            at_range.evidence
        );
        assert!(clipping_finding(&[], 8.727, true).is_none());
    }
}
