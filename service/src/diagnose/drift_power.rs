//! The power of a walk for a bias step or ramp: the smallest change of the gyro bias that the
//! bias-change test ([`super::bias_change`]) detects on this walk at the ranking's false-alarm
//! rate.
//!
//! The test is a χ² of the standardised block changes of the filter's bias estimate along each
//! tested direction (B blocks; Šidák over the directions). A bias change of size `s` that the
//! filter follows moves block `k`'s standardised change by `s·δₖ`, so along a direction the
//! statistic is a noncentral χ² with B degrees and noncentrality `λ = s²·Σδₖ²`. The detectable
//! size is the `s` at which the test (any direction beyond its critical value) fires half the
//! time, as the power fits' sizes are the ones whose expected score is the threshold
//! ([`super::power::MDE_Z`]). The slopes `δₖ` come from a probe ([`DriftProbe`]): the walk run
//! again with a step on the sensor's z axis at the middle of the walk, or a ramp from a tenth of
//! it (the detection matrix's injections), its block changes against the clean run's, along
//! the directions the clean run's test took. (On walks whose tracking begins late the ramp has
//! already begun when the test's first block starts.)
//!
//! Why the z axis: it lies nearest the vertical on the suite's mountings, the part of a bias
//! only the heading observations see (a horizontal change tilts the sensor, which the
//! zero-velocity updates see within a stance, so the filter follows it fast). A change the
//! filter does not follow within the walk shows in the heading residuals instead (their trend
//! and CUSUM), which these sizes do not cover: they are the sizes of the filter's own test.

use super::SIGNIFICANT;
use super::analysis::{Analysis, analyse};
use super::bias_change::{BLOCK_S, BiasChange};
use super::catalogue::Effect;
use super::power::format_unit;
use crate::runner::RunError;
use crate::stats::{chi2_quantile, noncentral_chi2_sf};
use corridor_shared::config::ConfigFile;
use corridor_shared::imu_csv::{ImuLog, ImuRow};
use corridor_shared::injection::LogInjection;
use std::path::Path;

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

    /// A size in words: `z bias step at mid-walk 1.20e-2 rad/s`.
    pub fn words(self, size: f64) -> String {
        let size = format_unit(self.unit(), size);
        match self {
            DriftProbe::Step => format!("z bias step at mid-walk {size}"),
            DriftProbe::Ramp => format!("z bias ramp from a tenth of the walk {size}"),
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
            DriftProbe::Step => c.step_mde_rad_s,
            DriftProbe::Ramp => c.ramp_mde_rad_s2,
        }
    }
}

/// The per-direction false-alarm rate that makes the test's Šidák-combined rate over `n`
/// directions the ranking's threshold (p = 10^−[`SIGNIFICANT`]).
fn per_direction_alpha(n: usize) -> f64 {
    let alpha = 10f64.powf(-SIGNIFICANT);
    -((-alpha).ln_1p() / n as f64).exp_m1()
}

/// One direction of the test under a change of unit size: its degrees (blocks), the
/// noncentrality per unit² (`Σδₖ²`) and its critical χ².
#[derive(Debug, Clone, Copy)]
struct DirectionPower {
    blocks: f64,
    lambda_per_unit2: f64,
    critical: f64,
}

/// The probability that the test fires on a change of `size`: any of its directions, each a
/// noncentral χ² (taken as independent, as the test's Šidák combination takes them).
fn detection_probability(dirs: &[DirectionPower], size: f64) -> f64 {
    1.0 - dirs
        .iter()
        .map(|d| 1.0 - noncentral_chi2_sf(d.critical, d.blocks, size * size * d.lambda_per_unit2))
        .product::<f64>()
}

/// The size detectable half the time on this walk, from the clean run's test and the probe run's
/// (the same log with a [`DriftProbe`] of `probe_size`): along each of the clean test's
/// directions, the slopes of the blocks' standardised changes per unit of the probe, each
/// direction's χ² noncentral with `size²·Σδₖ²`, and the size at which the test (any direction
/// beyond its Šidák critical value) fires with probability ½. `None` when the runs' blocks are
/// not the same ones (count and end times) or the probe moved nothing.
pub fn drift_mde(clean: &BiasChange, probe: &BiasChange, probe_size: f64) -> Option<f64> {
    if clean.block_end_s != probe.block_end_s || clean.directions.is_empty() {
        return None;
    }
    let alpha = per_direction_alpha(clean.directions.len());
    let dirs: Vec<DirectionPower> = clean
        .directions
        .iter()
        .filter_map(|dir| {
            let slopes: Vec<f64> = clean
                .blocks_per_axis
                .iter()
                .zip(&probe.blocks_per_axis)
                .filter_map(|(c, p)| {
                    Some((p.standardised_along(dir)? - c.standardised_along(dir)?) / probe_size)
                })
                .collect();
            let lambda_per_unit2: f64 = slopes.iter().map(|d| d * d).sum();
            if slopes.is_empty() || lambda_per_unit2.is_nan() || lambda_per_unit2 <= 0.0 {
                return None;
            }
            let blocks = slopes.len() as f64;
            Some(DirectionPower {
                blocks,
                lambda_per_unit2,
                critical: chi2_quantile(1.0 - alpha, blocks),
            })
        })
        .collect();
    if dirs.is_empty() {
        return None;
    }
    // bracket the size from the most responsive direction's own scale, then bisect
    let scale = dirs
        .iter()
        .map(|d| (d.critical / d.lambda_per_unit2).sqrt())
        .fold(f64::INFINITY, f64::min);
    let (mut lo, mut hi) = (0.0, scale);
    while detection_probability(&dirs, hi) < 0.5 {
        hi *= 2.0;
        if !hi.is_finite() {
            return None;
        }
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if detection_probability(&dirs, mid) < 0.5 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

/// Measures the detectable step and ramp of `a`'s bias-change test: the log run again with each
/// probe, on the model of `file` ([`drift_mde`]); the bias drift's finding takes the step's size
/// where it is plausible.
pub fn calibrate_drift(
    log: &ImuLog,
    file: &ConfigFile,
    map: Option<&Path>,
    a: &mut Analysis,
) -> Result<(), RunError> {
    let Some(clean) = a.bias_change.as_mut() else {
        return Ok(());
    };
    for kind in DriftProbe::ALL {
        let mut injected = log.clone();
        kind.injection(&injected.rows, kind.probe_size())
            .apply(&mut injected.rows);
        let m = analyse(&injected, file, None, map)?
            .bias_change
            .and_then(|probe| drift_mde(clean, &probe, kind.probe_size()));
        match kind {
            DriftProbe::Step => clean.step_mde_rad_s = m,
            DriftProbe::Ramp => clean.ramp_mde_rad_s2 = m,
        }
    }
    let step = clean
        .step_mde_rad_s
        .filter(|&m| m <= DriftProbe::Step.plausible_max());
    if let Some(f) = a.effects.iter_mut().find(|f| f.name == Effect::BiasDrift) {
        f.mde = step;
    }
    Ok(())
}

/// The drift's part of a verdict without a significant effect: the sizes the walk shows
/// (`nothing above …`) and what it cannot show with the reason. `applies`: the model's bias is
/// one the test is made for (a random walk in the error-state filter, tracking began); without
/// it nothing is said (the residual tests stand for the drift there).
pub fn drift_words(c: Option<&BiasChange>, applies: bool) -> (Vec<String>, Vec<String>) {
    let (mut shown, mut cannot) = (Vec::new(), Vec::new());
    let Some(c) = c else {
        if applies {
            cannot.push(format!(
                "a bias step or ramp in the filter's bias (its test needs two blocks of \
                 {BLOCK_S:.0} s, with a usable σ, after tracking began)"
            ));
        }
        return (shown, cannot);
    };
    for kind in DriftProbe::ALL {
        match kind.mde_of(c) {
            Some(m) if m <= kind.plausible_max() => {
                shown.push(format!("{} (the filter's bias)", kind.words(m)));
            }
            Some(m) => cannot.push(format!(
                "a {} in the filter's bias (the smallest it shows would be {}, beyond any \
                 plausible {})",
                kind.variant(),
                format_unit(kind.unit(), m),
                format_unit(kind.unit(), kind.plausible_max())
            )),
            None => cannot.push(format!(
                "a {} in the filter's bias (not measured: the probe injection's run gave no test \
                 with the same blocks, or did not move it)",
                kind.variant()
            )),
        }
    }
    (shown, cannot)
}

#[cfg(test)]
mod tests {
    use super::super::bias_change::{BlockChange, FirstBlock, sidak_score};
    use super::*;
    use crate::stats::chi2_sf;

    fn change(blocks: Vec<BlockChange>) -> BiasChange {
        let n = blocks.len();
        BiasChange {
            score: 0.0,
            direction: AXES[0],
            chi2: 0.0,
            blocks: n,
            largest: (0.0, 0.0),
            largest_share: 0.0,
            first_block: FirstBlock {
                span_s: (0.0, 0.0),
                change_rad_s: [0.0; 3],
                var_rad2_s2: [1.0; 3],
            },
            directions: AXES.to_vec(),
            blocks_per_axis: blocks,
            block_end_s: (1..=n).map(|k| 20.0 * k as f64).collect(),
            step_mde_rad_s: None,
            ramp_mde_rad_s2: None,
        }
    }

    const AXES: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    const SD: f64 = 1e-3;

    /// A block whose standardised change is `z` per axis.
    fn block(z: [f64; 3]) -> BlockChange {
        BlockChange {
            change_rad_s: z.map(|z| z * SD),
            var_rad2_s2: [SD * SD; 3],
        }
    }

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
    fn the_detectable_change_fires_the_test_half_the_time() {
        // The clean walk's own block changes, and a probe of 0.01 that moves z's second block by
        // 4σ and x's first by 3σ: two directions respond, and the size is where the test (any
        // of the three, Šidák at 10⁻³) fires in half of the draws.
        let clean_z = [
            [0.3, -1.1, 0.4],
            [-0.7, 0.2, 1.2],
            [1.5, 0.6, -0.2],
            [0.1, -0.4, 0.9],
        ];
        let response = [
            [3.0, 0.0, 0.0],
            [0.0, 0.0, 4.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ];
        let clean = change(clean_z.iter().map(|&z| block(z)).collect());
        let probe = change(
            clean_z
                .iter()
                .zip(&response)
                .map(|(c, r)| block(std::array::from_fn(|a| c[a] + r[a])))
                .collect(),
        );
        let m = drift_mde(&clean, &probe, 0.01).unwrap();
        let mut n = Normal(0x9e37_79b9_7f4a_7c15);
        let trials = 20_000;
        let fired = (0..trials)
            .filter(|_| {
                (0..3).any(|a| {
                    let chi2: f64 = response
                        .iter()
                        .map(|r| (n.next() + m / 0.01 * r[a]).powi(2))
                        .sum();
                    sidak_score(chi2_sf(chi2, 4.0), 3) >= SIGNIFICANT
                })
            })
            .count();
        let share = fired as f64 / trials as f64;
        assert!((share - 0.5).abs() < 0.015, "{share}");
        // the probe moved the blocks twice as far: half the size
        let probe2 = change(
            clean_z
                .iter()
                .zip(&response)
                .map(|(c, r)| block(std::array::from_fn(|a| c[a] + 2.0 * r[a])))
                .collect(),
        );
        let m2 = drift_mde(&clean, &probe2, 0.01).unwrap();
        assert!((m2 - m / 2.0).abs() < 1e-9 * m, "{m2} {m}");
        // nothing moved: no size; other blocks (later ones, or fewer): not compared
        assert!(drift_mde(&clean, &clean, 0.01).is_none());
        let mut later = probe.clone();
        later.block_end_s.iter_mut().for_each(|t| *t += 0.5);
        assert!(drift_mde(&clean, &later, 0.01).is_none());
        let mut fewer = probe.clone();
        fewer.blocks_per_axis.pop();
        fewer.block_end_s.pop();
        assert!(drift_mde(&clean, &fewer, 0.01).is_none());
    }

    #[test]
    fn the_verdict_says_what_the_walk_shows_and_why_not() {
        let mut c = change(vec![block([0.0; 3]); 3]);
        c.step_mde_rad_s = Some(0.012);
        c.ramp_mde_rad_s2 = Some(2e-3);
        let (shown, cannot) = drift_words(Some(&c), true);
        assert_eq!(
            shown,
            ["z bias step at mid-walk 1.20e-2 rad/s (the filter's bias)"]
        );
        assert!(
            cannot.len() == 1 && cannot[0].contains("beyond any plausible 1.00e-3 rad/s²"),
            "{cannot:?}"
        );
        c.step_mde_rad_s = None;
        let (_, cannot) = drift_words(Some(&c), true);
        assert!(
            cannot[0].contains("z bias step in the filter's bias (not measured"),
            "{cannot:?}"
        );
        let (shown, cannot) = drift_words(None, true);
        assert!(
            shown.is_empty() && cannot[0].contains("needs two blocks"),
            "{cannot:?}"
        );
        // a model the test is not made for (the paper's): nothing said
        assert_eq!(drift_words(None, false), (vec![], vec![]));
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
