//! The power of a walk for a bias step or ramp: the smallest change of the gyro bias that the
//! bias-change test ([`super::bias_change`]) detects on this walk at the ranking's false-alarm
//! rate.
//!
//! The test is a χ² of the standardised block changes of the filter's bias estimate along each
//! tested direction (B blocks; Šidák over the directions). A bias change of size `s` that the
//! filter follows moves block `k`'s standardised change by `s·δₖ`, so along a direction the
//! statistic is a noncentral χ² with B degrees and noncentrality `λ = s²·Σδₖ²`. The detectable
//! size is the `s` whose χ² reaches the test's critical value half the time (its median there),
//! as the power fits' sizes are the ones whose expected score is the threshold
//! ([`super::power::MDE_Z`]). The slopes `δₖ` come from a probe ([`DriftProbe`]): the walk run
//! again with a step on the sensor's z axis at the middle of the walk, or a ramp from a tenth of
//! it (the detection matrix's injections), its block changes against the clean run's, along
//! the directions the clean run's test took.
//!
//! Why the z axis: it lies nearest the vertical on the suite's mountings, the part of a bias
//! only the heading observations see (a horizontal change tilts the sensor, which the
//! zero-velocity updates see within a stance, so the filter follows it fast). A change the
//! filter does not follow within the walk shows in the heading residuals instead (their trend
//! and CUSUM), which these sizes do not cover: they are the sizes of the filter's own test.

use super::SIGNIFICANT;
use super::bias_change::BiasChange;
use crate::stats::chi2_quantile;
use corridor_shared::imu_csv::ImuRow;
use corridor_shared::injection::LogInjection;

/// A bias change on the sensor's z axis whose detectable size is measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DriftProbe {
    /// A step at [`STEP_AT_FRACTION`] of the log, rad/s.
    Step,
    /// A ramp from [`RAMP_FROM_FRACTION`] of the log, rad/s².
    Ramp,
}

/// Where the step lies, as a fraction of the log's duration.
pub const STEP_AT_FRACTION: f64 = 0.5;

/// Where the ramp begins, as a fraction of the log's duration.
pub const RAMP_FROM_FRACTION: f64 = 0.1;

impl DriftProbe {
    /// Both probes.
    pub const ALL: [DriftProbe; 2] = [DriftProbe::Step, DriftProbe::Ramp];

    /// The probe's size: the detection matrix's (0.01 rad/s, 2e-4 rad/s²).
    pub fn probe_size(self) -> f64 {
        match self {
            DriftProbe::Step => 0.01,
            DriftProbe::Ramp => 2e-4,
        }
    }

    /// Larger than any of a working gyro (a step of about 3°/s; a ramp that reaches 0.1 rad/s in
    /// 100 s): a detectable size beyond it means the walk cannot show the change.
    pub fn plausible_max(self) -> f64 {
        match self {
            DriftProbe::Step => 0.05,
            DriftProbe::Ramp => 1e-3,
        }
    }

    /// The unit of the size.
    pub fn unit(self) -> &'static str {
        match self {
            DriftProbe::Step => "rad/s",
            DriftProbe::Ramp => "rad/s²",
        }
    }

    /// Its name in tables.
    pub fn variant(self) -> &'static str {
        match self {
            DriftProbe::Step => "z bias step",
            DriftProbe::Ramp => "z bias ramp",
        }
    }

    /// A size in words: `z bias step at mid-walk 1.2e-2 rad/s`.
    pub fn words(self, size: f64) -> String {
        match self {
            DriftProbe::Step => format!("z bias step at mid-walk {size:.1e} rad/s"),
            DriftProbe::Ramp => format!("z bias ramp from a tenth of the walk {size:.1e} rad/s²"),
        }
    }

    /// The injection of `size` into the log of `rows`.
    pub fn injection(self, rows: &[ImuRow], size: f64) -> LogInjection {
        let t0 = rows.first().map_or(0.0, |r| r.t_s);
        let t1 = rows.last().map_or(0.0, |r| r.t_s);
        match self {
            DriftProbe::Step => LogInjection::BiasStep {
                axis: 2,
                step_rad_s: size,
                at_s: t0 + STEP_AT_FRACTION * (t1 - t0),
            },
            DriftProbe::Ramp => LogInjection::BiasRamp {
                axis: 2,
                rate_rad_s2: size,
                after_s: t0 + RAMP_FROM_FRACTION * (t1 - t0),
            },
        }
    }

    /// The detectable size the test of `c` holds for this probe (`None` until measured).
    pub fn mde_of(self, c: &BiasChange) -> Option<f64> {
        match self {
            DriftProbe::Step => c.step_mde,
            DriftProbe::Ramp => c.ramp_mde,
        }
    }
}

/// Median of a noncentral χ² with `k` degrees and noncentrality `lambda` (Patnaik's scaled
/// χ² with the Wilson–Hilferty median): `(k + λ)·(1 − 2(k + 2λ) / (9(k + λ)²))³`.
pub fn noncentral_chi2_median(k: f64, lambda: f64) -> f64 {
    let m = k + lambda;
    m * (1.0 - 2.0 * (k + 2.0 * lambda) / (9.0 * m * m)).powi(3)
}

/// The noncentrality at which a χ² with `k` degrees reaches `critical` half the time.
fn noncentrality_for_median(k: f64, critical: f64) -> f64 {
    let (mut lo, mut hi) = (0.0_f64, critical.max(1.0) * 4.0);
    while noncentral_chi2_median(k, hi) < critical {
        hi *= 2.0;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if noncentral_chi2_median(k, mid) < critical {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The per-direction false-alarm rate that makes the test's Šidák-combined rate over `n`
/// directions the ranking's threshold (p = 10^−[`SIGNIFICANT`]).
fn per_direction_alpha(n: usize) -> f64 {
    let alpha = 10f64.powf(-SIGNIFICANT);
    -((-alpha).ln_1p() / n as f64).exp_m1()
}

/// The size detectable half the time on this walk, from the clean run's test and the probe run's
/// (the same log with a [`DriftProbe`] of `probe_size`): along each of the clean test's
/// directions, the slopes of the blocks' standardised changes per unit of the probe, and the
/// size at which their noncentral χ² reaches the critical value at its median; the smallest over
/// the directions. `None` when the runs' blocks differ or the probe moved nothing.
pub fn drift_mde(clean: &BiasChange, probe: &BiasChange, probe_size: f64) -> Option<f64> {
    if clean.blocks_per_axis.len() != probe.blocks_per_axis.len() || clean.directions.is_empty() {
        return None;
    }
    let alpha = per_direction_alpha(clean.directions.len());
    clean
        .directions
        .iter()
        .filter_map(|dir| {
            let slopes: Vec<f64> = clean
                .blocks_per_axis
                .iter()
                .zip(&probe.blocks_per_axis)
                .filter_map(|(c, p)| Some((p.z_along(dir)? - c.z_along(dir)?) / probe_size))
                .collect();
            let sum_sq: f64 = slopes.iter().map(|d| d * d).sum();
            if slopes.is_empty() || sum_sq.is_nan() || sum_sq <= 0.0 {
                return None;
            }
            let k = slopes.len() as f64;
            let critical = chi2_quantile(1.0 - alpha, k);
            let lambda = noncentrality_for_median(k, critical);
            Some((lambda / sum_sq).sqrt())
        })
        .filter(|m| m.is_finite())
        .min_by(f64::total_cmp)
}

#[cfg(test)]
mod tests {
    use super::super::bias_change::{BiasChange, BlockChange, FirstBlock};
    use super::*;
    use crate::stats::chi2_sf;

    fn change(blocks: Vec<BlockChange>, directions: Vec<[f64; 3]>) -> BiasChange {
        BiasChange {
            score: 0.0,
            direction: directions[0],
            chi2: 0.0,
            blocks: blocks.len(),
            largest: (0.0, 0.0),
            largest_share: 0.0,
            first_block: FirstBlock {
                span_s: (0.0, 0.0),
                change_rad_s: [0.0; 3],
                var_rad2_s2: [1.0; 3],
            },
            directions,
            blocks_per_axis: blocks,
            step_mde: None,
            ramp_mde: None,
        }
    }

    const AXES: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

    /// A deterministic standard normal (xorshift and Box–Muller).
    struct Normal(u64);
    impl Normal {
        fn uniform(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        }
        fn next(&mut self) -> f64 {
            let (u, v) = (self.uniform(), self.uniform());
            (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
        }
    }

    #[test]
    fn the_noncentral_median_matches_a_simulation() {
        let mut n = Normal(0x9e37_79b9_7f4a_7c15);
        for (k, lambda) in [(1usize, 0.0_f64), (3, 10.0), (3, 25.0), (6, 16.0)] {
            let mut draws: Vec<f64> = (0..20_000)
                .map(|_| {
                    (0..k)
                        .map(|i| {
                            let mean = if i == 0 { lambda.sqrt() } else { 0.0 };
                            (n.next() + mean).powi(2)
                        })
                        .sum()
                })
                .collect();
            draws.sort_by(f64::total_cmp);
            let simulated = draws[draws.len() / 2];
            let m = noncentral_chi2_median(k as f64, lambda);
            assert!(
                (m - simulated).abs() < 0.03 * simulated.max(1.0),
                "k {k} λ {lambda}: {m} against {simulated}"
            );
        }
    }

    #[test]
    fn the_detectable_step_is_detected_half_the_time() {
        // Three blocks of one σ each; the probe's step moves the second block by 4σ on z.
        let sd = 1e-3;
        let block = |z: f64| BlockChange {
            change_rad_s: [0.0, 0.0, z * sd],
            var_rad2_s2: [sd * sd; 3],
        };
        let clean = change(vec![block(0.0); 3], AXES.to_vec());
        let probe = change(vec![block(0.0), block(4.0), block(0.0)], AXES.to_vec());
        let m = drift_mde(&clean, &probe, 0.01).unwrap();
        // at that size the z axis's χ² (3 degrees) is detected (Šidák over the 3 axes at 10⁻³)
        // in about half of the draws
        let shift = 4.0 * m / 0.01;
        let mut n = Normal(7);
        let trials = 20_000;
        let detected = (0..trials)
            .filter(|_| {
                let chi2: f64 = (0..3)
                    .map(|k| (n.next() + if k == 1 { shift } else { 0.0 }).powi(2))
                    .sum();
                let p = chi2_sf(chi2, 3.0);
                1.0 - (1.0 - p).powi(3) <= 1e-3
            })
            .count();
        let share = detected as f64 / trials as f64;
        assert!((share - 0.5).abs() < 0.03, "{share}");
        // twice the step moves the blocks twice as far: half the size
        let probe2 = change(vec![block(0.0), block(8.0), block(0.0)], AXES.to_vec());
        let m2 = drift_mde(&clean, &probe2, 0.01).unwrap();
        assert!((m2 - m / 2.0).abs() < 1e-12 * m, "{m2} {m}");
        // a probe that moved nothing predicts nothing; blocks that differ are not compared
        assert!(drift_mde(&clean, &clean, 0.01).is_none());
        let short = change(vec![block(0.0); 2], AXES.to_vec());
        assert!(drift_mde(&clean, &short, 0.01).is_none());
    }

    #[test]
    fn the_probes_are_placed_on_z_at_the_matrixs_times() {
        let rows: Vec<ImuRow> = (0..=100)
            .map(|k| ImuRow {
                t_s: 10.0 + 0.5 * k as f64,
                gyro_rad_s: [0.0; 3],
                accel_m_s2: [0.0, 0.0, 9.81],
                temp_c: None,
                line: k + 2,
            })
            .collect();
        assert_eq!(
            DriftProbe::Step.injection(&rows, 0.02),
            LogInjection::BiasStep {
                axis: 2,
                step_rad_s: 0.02,
                at_s: 35.0
            }
        );
        assert_eq!(
            DriftProbe::Ramp.injection(&rows, 1e-4),
            LogInjection::BiasRamp {
                axis: 2,
                rate_rad_s2: 1e-4,
                after_s: 15.0
            }
        );
    }
}
