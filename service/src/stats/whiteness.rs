//! Autocorrelation and whiteness: the normalised autocorrelation, the ±1.96/√N band and the
//! Ljung–Box portmanteau test.

use super::*;
use serde::Serialize;

/// Normalised sample autocorrelation r_0 … r_L of `x` (r_0 = 1):
/// r_k = Σ_t d_t d_{t+k} / Σ_t d_t², with d_t = x_t − mean over the finite values.
///
/// Lags count sample positions; a non-finite sample contributes d_t = 0 (it is skipped
/// without shifting the series). `max_lag` is clipped to (number of finite values − 1).
/// Errors: fewer than two finite values ([`StatsError::TooFewSamples`]); zero variance
/// ([`StatsError::Degenerate`]).
pub fn autocorrelation(x: &[f64], max_lag: usize) -> StatsResult<Vec<f64>> {
    Ok(acf_impl(x, max_lag)?.0)
}

/// (acf, finite count, non-finite count)
fn acf_impl(x: &[f64], max_lag: usize) -> StatsResult<(Vec<f64>, usize, usize)> {
    let (v, nan_count) = finite_values(x);
    let n = v.len();
    if n < 2 {
        return Err(StatsError::TooFewSamples { needed: 2, got: n });
    }
    let m = mean(&v);
    let d: Vec<f64> = x
        .iter()
        .map(|&xi| if xi.is_finite() { xi - m } else { 0.0 })
        .collect();
    let c0: f64 = d.iter().map(|v| v * v).sum();
    if c0.is_nan() || c0 <= 0.0 {
        return Err(StatsError::Degenerate(
            "autocorrelation of a constant series".to_string(),
        ));
    }
    let lags = max_lag.min(n - 1);
    let acf = (0..=lags)
        .map(|k| {
            if k == 0 {
                1.0
            } else {
                d[..d.len() - k]
                    .iter()
                    .zip(&d[k..])
                    .map(|(a, b)| a * b)
                    .sum::<f64>()
                    / c0
            }
        })
        .collect();
    Ok((acf, n, nan_count))
}

/// Whiteness of a residual series (see [`whiteness`]).
#[derive(Debug, Clone, Serialize)]
pub struct Whiteness {
    /// Normalised autocorrelation at lags 0 … L (`acf[0] = 1`).
    pub acf: Vec<f64>,
    /// The ±1.96/√N band of a white series' autocorrelation.
    pub bound: f64,
    /// Fraction of lags 1 … L with |acf| above `bound` (about 5 % for white noise).
    pub fraction_outside: f64,
    /// Ljung–Box statistic Q = N(N+2) Σ_{k=1}^{L} r_k² / (N − k).
    pub ljung_box_q: f64,
    /// P(χ²(L) > Q).
    pub ljung_box_p: f64,
    /// Number of lags L used (after clipping).
    pub lags: usize,
    /// Number of finite samples N.
    pub n: usize,
    /// Number of non-finite samples removed.
    pub nan_count: usize,
    /// `ljung_box_p >= ALPHA`: whiteness not rejected at 5 %.
    pub white: bool,
}

/// Whiteness test of `x` over lags 1 … `max_lag`: the normalised autocorrelation
/// ([`autocorrelation`]), the fraction of lags outside ±1.96/√N, and the Ljung–Box
/// portmanteau test with its χ²(L) p-value. `white` is decided by Ljung–Box at
/// [`ALPHA`] (the per-lag band is reported, not combined, so the false-alarm rate stays 5 %).
///
/// Errors: `max_lag == 0` ([`StatsError::InvalidArgument`]), fewer than three finite values
/// ([`StatsError::TooFewSamples`]), zero variance ([`StatsError::Degenerate`]).
pub fn whiteness(x: &[f64], max_lag: usize) -> StatsResult<Whiteness> {
    if max_lag == 0 {
        return Err(StatsError::InvalidArgument {
            name: "max_lag",
            value: "0".to_string(),
            rule: "must be at least 1",
        });
    }
    let finite = x.iter().filter(|v| v.is_finite()).count();
    if finite < 3 {
        return Err(StatsError::TooFewSamples {
            needed: 3,
            got: finite,
        });
    }
    let (acf, n, nan_count) = acf_impl(x, max_lag)?;
    let lags = acf.len() - 1;
    let nf = n as f64;
    let bound = 1.96 / nf.sqrt();
    let outside = acf[1..].iter().filter(|r| r.abs() > bound).count();
    let q = nf
        * (nf + 2.0)
        * acf[1..]
            .iter()
            .enumerate()
            .map(|(i, r)| r * r / (nf - (i + 1) as f64))
            .sum::<f64>();
    let p = chi2_sf(q, lags as f64);
    Ok(Whiteness {
        acf,
        bound,
        fraction_outside: outside as f64 / lags as f64,
        ljung_box_q: q,
        ljung_box_p: p,
        lags,
        n,
        nan_count,
        white: p >= ALPHA,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::test_util::*;

    #[test]
    fn autocorrelation_of_known_series() {
        let acf = autocorrelation(&[1.0, -1.0, 1.0, -1.0, 1.0, -1.0], 2).unwrap();
        assert_eq!(acf.len(), 3);
        assert!(close(acf[0], 1.0, 0.0));
        assert!(close(acf[1], -5.0 / 6.0, 1e-12) && close(acf[2], 4.0 / 6.0, 1e-12));
        // max_lag is clipped.
        assert_eq!(autocorrelation(&[1.0, 2.0, 4.0], 10).unwrap().len(), 3);
        assert!(matches!(
            autocorrelation(&[2.0; 5], 2),
            Err(StatsError::Degenerate(_))
        ));
        assert_eq!(
            autocorrelation(&[], 2).unwrap_err(),
            StatsError::TooFewSamples { needed: 2, got: 0 }
        );
        // A NaN is skipped in place: lags keep their meaning.
        let acf = autocorrelation(&[1.0, -1.0, f64::NAN, -1.0, 1.0, -1.0, 1.0], 1).unwrap();
        assert!(acf[1] < -0.4);
    }

    #[test]
    fn white_noise_passes_whiteness_at_nominal_rate() {
        let mut outside = 0.0;
        let rate = rejection_rate(200, |rng| {
            let w = whiteness(&rng.normals(500), 20).unwrap();
            outside += w.fraction_outside;
            !w.white
        });
        assert!((0.02..=0.09).contains(&rate), "rejection rate {rate}");
        let mean_outside = outside / 200.0;
        assert!(
            (0.02..=0.08).contains(&mean_outside),
            "mean fraction outside the band {mean_outside}"
        );
    }

    #[test]
    fn ar1_fails_whiteness() {
        for seed in 0..20 {
            let mut rng = Rng::new(seed);
            let mut x = Vec::with_capacity(500);
            let mut prev = 0.0;
            for _ in 0..500 {
                prev = 0.8 * prev + rng.normal();
                x.push(prev);
            }
            let w = whiteness(&x, 20).unwrap();
            assert!(!w.white, "seed {seed}: p = {}", w.ljung_box_p);
            assert!(w.ljung_box_p < 1e-10);
            assert!((w.acf[1] - 0.8).abs() < 0.1, "lag-1 acf {}", w.acf[1]);
            assert!(w.fraction_outside > 0.2);
        }
    }

    #[test]
    fn whiteness_counts_nan_and_rejects_bad_arguments() {
        let mut rng = Rng::new(3);
        let mut x = rng.normals(300);
        x[10] = f64::NAN;
        x[20] = f64::NEG_INFINITY;
        let w = whiteness(&x, 10).unwrap();
        assert_eq!((w.n, w.nan_count, w.lags, w.acf.len()), (298, 2, 10, 11));
        assert!(close(w.bound, 1.96 / 298f64.sqrt(), 1e-15));
        assert!(matches!(
            whiteness(&x, 0),
            Err(StatsError::InvalidArgument { .. })
        ));
        assert_eq!(
            whiteness(&[1.0, f64::NAN], 3).unwrap_err(),
            StatsError::TooFewSamples { needed: 3, got: 1 }
        );
    }
}
