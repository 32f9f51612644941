//! NIS consistency: the time-averaged normalised innovation squared against two-sided χ²
//! bounds.

use super::*;
use serde::Serialize;

/// Verdict of the time-averaged NIS test.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NisVerdict {
    /// The mean NIS is inside the two-sided χ² band.
    Consistent,
    /// The mean NIS is above the band: Q or R too small, or an effect the model lacks.
    TooLarge,
    /// The mean NIS is below the band: the filter is too conservative (or over-correlated
    /// observations are fused as if independent).
    TooSmall,
}

/// Time-averaged NIS against its χ² band (see [`nis_consistency`]).
#[derive(Debug, Clone, Serialize)]
pub struct NisTest {
    /// Mean of the finite NIS values.
    pub mean: f64,
    /// Lower bound: χ²_{(1−c)/2}(N·dof) / N.
    pub lower: f64,
    /// Upper bound: χ²_{(1+c)/2}(N·dof) / N.
    pub upper: f64,
    /// Number of finite NIS values used (N).
    pub n: usize,
    /// Number of non-finite NIS values removed.
    pub nan_count: usize,
    /// Degrees of freedom of one NIS value (the innovation dimension).
    pub dof: usize,
    /// Two-sided confidence of the band.
    pub confidence: f64,
    /// Two-sided p-value of N·mean under χ²(N·dof): 2·min(P(X ≤ N·mean), P(X ≥ N·mean)),
    /// capped at 1.
    pub p_value: f64,
    /// Where the mean falls.
    pub verdict: NisVerdict,
}

/// Time-averaged NIS test (Bar-Shalom): under a consistent filter the sum of N independent NIS
/// values of dimension `dof` is χ²(N·dof), so the mean must lie in
/// [χ²_{(1−c)/2}(N·dof)/N, χ²_{(1+c)/2}(N·dof)/N] with probability `confidence` = c.
///
/// Non-finite values are removed and counted. Errors: no finite value
/// ([`StatsError::TooFewSamples`]), `dof == 0` or `confidence` outside (0, 1)
/// ([`StatsError::InvalidArgument`]).
pub fn nis_consistency(nis: &[f64], dof: usize, confidence: f64) -> StatsResult<NisTest> {
    if dof == 0 {
        return Err(StatsError::InvalidArgument {
            name: "dof",
            value: dof.to_string(),
            rule: "must be at least 1",
        });
    }
    if !(confidence > 0.0 && confidence < 1.0) {
        return Err(StatsError::InvalidArgument {
            name: "confidence",
            value: confidence.to_string(),
            rule: "must be in (0, 1)",
        });
    }
    let (v, nan_count) = finite_values(nis);
    if v.is_empty() {
        return Err(StatsError::TooFewSamples { needed: 1, got: 0 });
    }
    let n = v.len();
    let m = mean(&v);
    let k = (n * dof) as f64;
    let nf = n as f64;
    let lower = chi2_quantile(0.5 * (1.0 - confidence), k) / nf;
    let upper = chi2_quantile(0.5 * (1.0 + confidence), k) / nf;
    let total = m * nf;
    let p_value = (2.0 * chi2_cdf(total, k).min(chi2_sf(total, k))).min(1.0);
    let verdict = if m > upper {
        NisVerdict::TooLarge
    } else if m < lower {
        NisVerdict::TooSmall
    } else {
        NisVerdict::Consistent
    };
    Ok(NisTest {
        mean: m,
        lower,
        upper,
        n,
        nan_count,
        dof,
        confidence,
        p_value,
        verdict,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::test_util::*;

    fn chi2_samples(rng: &mut Rng, n: usize, dof: usize, scale: f64) -> Vec<f64> {
        (0..n)
            .map(|_| scale * (0..dof).map(|_| rng.normal().powi(2)).sum::<f64>())
            .collect()
    }

    #[test]
    fn nis_consistent_at_nominal_rate() {
        let rate = rejection_rate(200, |rng| {
            let nis = chi2_samples(rng, 100, 2, 1.0);
            nis_consistency(&nis, 2, 0.95).unwrap().verdict != NisVerdict::Consistent
        });
        assert!((0.02..=0.09).contains(&rate), "rejection rate {rate}");
        // dof = 1 uses the bisection branch when N·dof < 30.
        let rate = rejection_rate(200, |rng| {
            let nis = chi2_samples(rng, 20, 1, 1.0);
            nis_consistency(&nis, 1, 0.95).unwrap().verdict != NisVerdict::Consistent
        });
        assert!(
            (0.02..=0.09).contains(&rate),
            "rejection rate (N·dof=20) {rate}"
        );
    }

    #[test]
    fn nis_scaled_is_too_large_or_too_small() {
        let mut rng = Rng::new(7);
        let nis = chi2_samples(&mut rng, 100, 3, 1.0);
        let base = nis_consistency(&nis, 3, 0.95).unwrap();
        assert_eq!(base.verdict, NisVerdict::Consistent);
        assert!(base.lower < 3.0 && 3.0 < base.upper);
        let big: Vec<f64> = nis.iter().map(|v| 3.0 * v).collect();
        let t = nis_consistency(&big, 3, 0.95).unwrap();
        assert_eq!(t.verdict, NisVerdict::TooLarge);
        assert!(t.p_value < 1e-6);
        let small: Vec<f64> = nis.iter().map(|v| 0.3 * v).collect();
        assert_eq!(
            nis_consistency(&small, 3, 0.95).unwrap().verdict,
            NisVerdict::TooSmall
        );
    }

    #[test]
    fn nis_bounds_match_tables_and_filters_nan() {
        // N = 10, dof = 10: bounds are χ²(100) quantiles / 10.
        let mut nis = vec![10.0; 10];
        nis.push(f64::NAN);
        nis.push(f64::INFINITY);
        let t = nis_consistency(&nis, 10, 0.95).unwrap();
        assert_eq!((t.n, t.nan_count), (10, 2));
        assert!(close(t.lower, 7.4222, 1e-4) && close(t.upper, 12.9561, 1e-4));
        assert!(close(t.mean, 10.0, 0.0));
        assert_eq!(
            nis_consistency(&[f64::NAN], 1, 0.95).unwrap_err(),
            StatsError::TooFewSamples { needed: 1, got: 0 }
        );
        assert!(matches!(
            nis_consistency(&[1.0], 0, 0.95),
            Err(StatsError::InvalidArgument { name: "dof", .. })
        ));
        assert!(matches!(
            nis_consistency(&[1.0], 1, 1.0),
            Err(StatsError::InvalidArgument {
                name: "confidence",
                ..
            })
        ));
    }
}
