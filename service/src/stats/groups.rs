//! Per-group means and the one-way ANOVA F test of equal means.

use super::*;
use serde::Serialize;

/// Statistics of one group of a residual series (see [`group_means`]).
#[derive(Debug, Clone, Serialize)]
pub struct GroupStat {
    /// Group label (e.g. a leg index or a heading sector).
    pub group: i64,
    /// Number of finite values in the group.
    pub n: usize,
    /// Non-finite values of the group removed.
    pub nan_count: usize,
    /// Mean (NaN if the group has no finite value).
    pub mean: f64,
    /// Sample standard deviation (n − 1 denominator; NaN for n < 2).
    pub std_dev: f64,
    /// Standard error of the mean, std_dev/√n (NaN for n < 2).
    pub std_err: f64,
    /// t-statistic of "mean = 0", mean/std_err.
    pub t: f64,
    /// Two-sided p-value of "mean = 0" (Student t, n − 1 degrees of freedom).
    pub p_value: f64,
}

/// Per-group mean, standard deviation, standard error and a t test of "mean = 0", sorted by
/// group label. Non-finite values of y are removed and counted per group (a group whose values
/// are all non-finite appears with n = 0 and NaN statistics).
///
/// Used for the leg test: a heading offset shows as means of the **same sign** on ψ and
/// ψ + π legs (each significant, [`anova_oneway`] not rejecting equality), an effect that
/// flips with the direction of travel as means of alternating sign.
///
/// Errors: different lengths ([`StatsError::LengthMismatch`]); no finite value
/// ([`StatsError::TooFewSamples`]).
pub fn group_means(y: &[f64], group: &[i64]) -> StatsResult<Vec<GroupStat>> {
    check_len("group", y.len(), group.len())?;
    let mut labels: Vec<i64> = group.to_vec();
    labels.sort_unstable();
    labels.dedup();
    let finite = y.iter().filter(|v| v.is_finite()).count();
    if finite == 0 {
        return Err(StatsError::TooFewSamples { needed: 1, got: 0 });
    }
    Ok(labels
        .into_iter()
        .map(|g| {
            let all: Vec<f64> = y
                .iter()
                .zip(group)
                .filter(|(_, gi)| **gi == g)
                .map(|(v, _)| *v)
                .collect();
            let (v, nan_count) = finite_values(&all);
            let n = v.len();
            let m = if n > 0 { mean(&v) } else { f64::NAN };
            let std_dev = if n > 1 {
                (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
            } else {
                f64::NAN
            };
            let std_err = std_dev / (n as f64).sqrt();
            let t = m / std_err;
            let p_value = if n > 1 {
                student_t_two_sided_p(t, (n - 1) as f64)
            } else {
                f64::NAN
            };
            GroupStat {
                group: g,
                n,
                nan_count,
                mean: m,
                std_dev,
                std_err,
                t,
                p_value,
            }
        })
        .collect())
}

/// One-way analysis of variance (see [`anova_oneway`]).
#[derive(Debug, Clone, Serialize)]
pub struct Anova {
    /// Per-group statistics ([`group_means`]).
    pub groups: Vec<GroupStat>,
    /// F = (SS_between/(k − 1)) / (SS_within/(N − k)).
    pub f: f64,
    /// k − 1 (k = groups with at least one finite value).
    pub df_between: usize,
    /// N − k.
    pub df_within: usize,
    /// P(F(k−1, N−k) > f).
    pub p_value: f64,
    /// Total number of finite values N.
    pub n: usize,
    /// Non-finite values removed.
    pub nan_count: usize,
    /// `p_value >= ALPHA`: equal means not rejected at 5 %.
    pub equal_means: bool,
}

/// One-way ANOVA F test that all groups have the same mean (groups with no finite value are
/// ignored). A zero within-group variance gives F = ∞ and p = 0 if the means differ, F = NaN
/// and p = 1 if they do not.
///
/// Errors: as [`group_means`]; fewer than two groups with data
/// ([`StatsError::TooFewGroups`]); N ≤ k ([`StatsError::TooFewSamples`]).
pub fn anova_oneway(y: &[f64], group: &[i64]) -> StatsResult<Anova> {
    let groups = group_means(y, group)?;
    let nan_count = groups.iter().map(|g| g.nan_count).sum();
    let used: Vec<&GroupStat> = groups.iter().filter(|g| g.n > 0).collect();
    let k = used.len();
    if k < 2 {
        return Err(StatsError::TooFewGroups { needed: 2, got: k });
    }
    let n: usize = used.iter().map(|g| g.n).sum();
    if n <= k {
        return Err(StatsError::TooFewSamples {
            needed: k + 1,
            got: n,
        });
    }
    let grand = used.iter().map(|g| g.mean * g.n as f64).sum::<f64>() / n as f64;
    let ss_between: f64 = used
        .iter()
        .map(|g| g.n as f64 * (g.mean - grand).powi(2))
        .sum();
    // Within: Σ (n_g − 1) s_g², with s_g NaN for n_g = 1 contributing 0.
    let ss_within: f64 = used
        .iter()
        .filter(|g| g.n > 1)
        .map(|g| (g.n - 1) as f64 * g.std_dev.powi(2))
        .sum();
    let (d1, d2) = (k - 1, n - k);
    let (f, p_value) = if ss_within > 0.0 {
        let f = (ss_between / d1 as f64) / (ss_within / d2 as f64);
        (f, f_sf(f, d1 as f64, d2 as f64))
    } else if ss_between > 0.0 {
        (f64::INFINITY, 0.0)
    } else {
        (f64::NAN, 1.0)
    };
    Ok(Anova {
        groups,
        f,
        df_between: d1,
        df_within: d2,
        p_value,
        n,
        nan_count,
        equal_means: p_value >= ALPHA,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::test_util::*;

    fn two_groups(rng: &mut Rng, n: usize, offset_b: f64) -> (Vec<f64>, Vec<i64>) {
        let mut y = Vec::with_capacity(2 * n);
        let mut g = Vec::with_capacity(2 * n);
        for i in 0..2 * n {
            let leg = (i / 10 % 2) as i64; // legs alternate every 10 samples
            y.push(rng.normal() + if leg == 1 { offset_b } else { 0.0 });
            g.push(leg);
        }
        (y, g)
    }

    #[test]
    fn anova_detects_one_sigma_offset() {
        // Power: the two-sample t has noncentrality 1/√(2/50) = 5, so |t| > 1.98 in
        // about 99.9 % of the trials.
        let power = rejection_rate(200, |rng| {
            let (y, g) = two_groups(rng, 50, 1.0);
            !anova_oneway(&y, &g).unwrap().equal_means
        });
        assert!(power >= 0.98, "detection rate {power}");
        for seed in 0..20 {
            let (y, g) = two_groups(&mut Rng::new(seed), 50, 1.0);
            let a = anova_oneway(&y, &g).unwrap();
            assert!(!a.equal_means, "seed {seed}: p {}", a.p_value);
            assert_eq!((a.df_between, a.df_within, a.n), (1, 98, 100));
            // Two groups: F equals the square of the pooled two-sample t.
            let (g0, g1) = (&a.groups[0], &a.groups[1]);
            let sp2 = (49.0 * g0.std_dev.powi(2) + 49.0 * g1.std_dev.powi(2)) / 98.0;
            let t = (g1.mean - g0.mean) / (sp2 * (2.0 / 50.0)).sqrt();
            assert!(close(a.f, t * t, 1e-9 * a.f));
        }
    }

    #[test]
    fn anova_at_zero_offset_rejects_at_nominal_rate() {
        let rate = rejection_rate(200, |rng| {
            let (y, g) = two_groups(rng, 50, 0.0);
            !anova_oneway(&y, &g).unwrap().equal_means
        });
        assert!((0.02..=0.09).contains(&rate), "rejection rate {rate}");
    }

    #[test]
    fn group_means_same_sign_offset_vs_alternating() {
        let mut rng = Rng::new(9);
        // Heading offset: +0.5 on both legs.
        let g: Vec<i64> = (0..200).map(|i| (i / 20 % 2) as i64).collect();
        let same: Vec<f64> = (0..200).map(|_| 0.5 + 0.3 * rng.normal()).collect();
        let stats = group_means(&same, &g).unwrap();
        assert!(stats.iter().all(|s| s.mean > 0.0 && s.p_value < 1e-6));
        assert!(anova_oneway(&same, &g).unwrap().equal_means);
        // An effect that flips with the direction of travel.
        let alt: Vec<f64> = g
            .iter()
            .map(|&leg| if leg == 0 { 0.5 } else { -0.5 } + 0.3 * rng.normal())
            .collect();
        let stats = group_means(&alt, &g).unwrap();
        assert!(stats[0].mean > 0.0 && stats[1].mean < 0.0);
        assert!(!anova_oneway(&alt, &g).unwrap().equal_means);
    }

    #[test]
    fn group_means_values_nan_and_errors() {
        let y = [1.0, 2.0, 3.0, f64::NAN, 10.0, 20.0, f64::NAN];
        let g = [5, 5, 5, 5, -1, -1, 9];
        let s = group_means(&y, &g).unwrap();
        let labels: Vec<i64> = s.iter().map(|s| s.group).collect();
        assert_eq!(labels, [-1, 5, 9]);
        assert_eq!((s[1].n, s[1].nan_count), (3, 1));
        assert!(close(s[1].mean, 2.0, 1e-15) && close(s[1].std_dev, 1.0, 1e-15));
        assert!(close(s[1].std_err, 1.0 / 3f64.sqrt(), 1e-15));
        assert!(close(s[0].mean, 15.0, 1e-15));
        assert_eq!((s[2].n, s[2].nan_count), (0, 1));
        assert!(s[2].mean.is_nan());
        let a = anova_oneway(&y, &g).unwrap();
        assert_eq!((a.df_between, a.df_within, a.nan_count), (1, 3, 2));
        assert!(matches!(
            group_means(&y, &g[..3]),
            Err(StatsError::LengthMismatch { .. })
        ));
        assert_eq!(
            group_means(&[], &[]).unwrap_err(),
            StatsError::TooFewSamples { needed: 1, got: 0 }
        );
        assert_eq!(
            anova_oneway(&[1.0, 2.0], &[0, 0]).unwrap_err(),
            StatsError::TooFewGroups { needed: 2, got: 1 }
        );
        assert_eq!(
            anova_oneway(&[1.0, 2.0], &[0, 1]).unwrap_err(),
            StatsError::TooFewSamples { needed: 3, got: 2 }
        );
        // Zero within-group variance.
        let a = anova_oneway(&[1.0, 1.0, 2.0, 2.0], &[0, 0, 1, 1]).unwrap();
        assert!(a.f.is_infinite() && a.p_value == 0.0 && !a.equal_means);
    }
}
