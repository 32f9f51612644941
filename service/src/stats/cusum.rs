//! CUSUM range test and sliding mean, for slow drifts and steps.

use super::*;
use serde::Serialize;

/// Normalised cumulative-sum range test for a drift or a step (see [`cusum`]).
#[derive(Debug, Clone, Serialize)]
pub struct Cusum {
    /// max_k |S_k| / (σ̂ √N), S_k = Σ_{i≤k} (x_i − x̄): asymptotically sup|Brownian bridge|
    /// for a series without drift.
    pub max_abs_normalised: f64,
    /// Index in the input (non-finite entries included) of the sample at which |S_k| peaks:
    /// for a step, the last sample before it.
    pub argmax: usize,
    /// The σ̂ used: from successive differences, √(Σ(x_{i+1} − x_i)² / (2(N−1))).
    pub sigma: f64,
    /// P(sup|B| > max_abs_normalised) from the Kolmogorov distribution.
    pub p_value: f64,
    /// The 5 % threshold, [`KOLMOGOROV_95`].
    pub threshold: f64,
    /// Number of finite samples N.
    pub n: usize,
    /// Number of non-finite samples removed.
    pub nan_count: usize,
    /// `max_abs_normalised > threshold`.
    pub drift_detected: bool,
}

/// Two-sided drift/step detector for a residual series, preferably standardised
/// (r/√S): the **normalised cumulative-sum range test** (not Page's sequential CUSUM, whose
/// false-alarm rate grows with the series length).
///
/// S_k = Σ_{i≤k} (x_i − x̄) is the cumulative sum of the demeaned series; under "constant
/// mean, white noise", max_k |S_k| / (σ √N) tends to the supremum of a Brownian bridge
/// (Kolmogorov distribution, 5 % point 1.358). A ramp bends S_k into a parabola, a step into
/// a tent whose peak is at the step. The mean itself is removed, so a constant offset is
/// *not* a drift (test it with [`group_means`] or the NIS). σ is estimated from successive
/// differences so that the drift or step being tested does not inflate it; a positively
/// autocorrelated series also trips the test (its long-run variance exceeds σ²), so read it
/// together with [`whiteness`].
///
/// Non-finite samples are removed (and counted); `argmax` indexes the original input.
/// Errors: fewer than five finite samples ([`StatsError::TooFewSamples`]). A constant
/// series gives `max_abs_normalised = 0` and no drift.
pub fn cusum(x: &[f64]) -> StatsResult<Cusum> {
    let idx: Vec<usize> = (0..x.len()).filter(|&i| x[i].is_finite()).collect();
    let n = idx.len();
    let nan_count = x.len() - n;
    if n < 5 {
        return Err(StatsError::TooFewSamples { needed: 5, got: n });
    }
    let v: Vec<f64> = idx.iter().map(|&i| x[i]).collect();
    let m = mean(&v);
    let sigma =
        (v.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<f64>() / (2.0 * (n - 1) as f64)).sqrt();
    let mut s = 0.0;
    let mut best = 0.0;
    let mut arg = 0;
    for (j, vi) in v.iter().enumerate() {
        s += vi - m;
        if s.abs() > best {
            best = s.abs();
            arg = j;
        }
    }
    let stat = if sigma > 0.0 {
        best / (sigma * (n as f64).sqrt())
    } else {
        0.0
    };
    let p_value = kolmogorov_sf(stat);
    Ok(Cusum {
        max_abs_normalised: stat,
        argmax: idx[arg],
        sigma,
        p_value,
        threshold: KOLMOGOROV_95,
        n,
        nan_count,
        drift_detected: stat > KOLMOGOROV_95,
    })
}

/// Trailing ("valid") moving average: element i is the mean of the finite values of
/// `x[i .. i + window]`, so the output has `x.len() − window + 1` elements and element i is
/// centred on sample i + (window − 1)/2. A window without any finite value gives NaN.
///
/// Errors: `window == 0` ([`StatsError::InvalidArgument`]); `x.len() < window`
/// ([`StatsError::TooFewSamples`]).
pub fn sliding_mean(x: &[f64], window: usize) -> StatsResult<Vec<f64>> {
    if window == 0 {
        return Err(StatsError::InvalidArgument {
            name: "window",
            value: "0".to_string(),
            rule: "must be at least 1",
        });
    }
    if x.len() < window {
        return Err(StatsError::TooFewSamples {
            needed: window,
            got: x.len(),
        });
    }
    // Prefix sums of the finite values and of their count.
    let mut sum = Vec::with_capacity(x.len() + 1);
    let mut cnt = Vec::with_capacity(x.len() + 1);
    sum.push(0.0);
    cnt.push(0usize);
    for &xi in x {
        let (s, c) = (*sum.last().unwrap_or(&0.0), *cnt.last().unwrap_or(&0));
        if xi.is_finite() {
            sum.push(s + xi);
            cnt.push(c + 1);
        } else {
            sum.push(s);
            cnt.push(c);
        }
    }
    Ok((0..=x.len() - window)
        .map(|i| {
            let c = cnt[i + window] - cnt[i];
            if c == 0 {
                f64::NAN
            } else {
                (sum[i + window] - sum[i]) / c as f64
            }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::test_util::*;

    #[test]
    fn cusum_false_alarm_rate_on_white_noise() {
        let rate = rejection_rate(200, |rng| cusum(&rng.normals(400)).unwrap().drift_detected);
        assert!((0.01..=0.09).contains(&rate), "false-alarm rate {rate}");
    }

    #[test]
    fn cusum_detects_ramp_and_regression_recovers_its_slope() {
        let slope = 0.01; // 5 σ over 500 samples
        for seed in 0..20 {
            let mut rng = Rng::new(seed);
            let t: Vec<f64> = (0..500).map(|i| i as f64).collect();
            let y: Vec<f64> = t.iter().map(|ti| slope * ti + rng.normal()).collect();
            let c = cusum(&y).unwrap();
            assert!(c.drift_detected, "seed {seed}: {}", c.max_abs_normalised);
            // The parabola of a demeaned ramp peaks in the middle third.
            assert!((150..350).contains(&c.argmax), "argmax {}", c.argmax);
            let reg = regress(&y, &[("time", &t)]).unwrap();
            let b = reg.coef("time").unwrap();
            assert!((b.value - slope).abs() < 3.0 * b.std_err, "seed {seed}");
            assert!(b.p_value < 1e-6);
            let s = simple_regression(&y, &t).unwrap();
            assert!(close(s.slope, b.value, 1e-12) && close(s.std_err, b.std_err, 1e-12));
            // Standard error by the textbook formula σ̂/√Σ(t − t̄)².
            let sxx: f64 = t.iter().map(|ti| (ti - 249.5).powi(2)).sum();
            assert!(close(s.std_err, reg.residual_std / sxx.sqrt(), 1e-12));
        }
    }

    #[test]
    fn cusum_locates_step_halfway() {
        for seed in 0..20 {
            let mut rng = Rng::new(seed);
            let x: Vec<f64> = (0..500)
                .map(|i| rng.normal() + if i >= 250 { 1.0 } else { 0.0 })
                .collect();
            let c = cusum(&x).unwrap();
            assert!(c.drift_detected && c.p_value < 1e-6, "seed {seed}");
            assert!(
                (225..=275).contains(&c.argmax),
                "seed {seed}: argmax {}",
                c.argmax
            );
            // σ from differences is not inflated by the step.
            assert!((c.sigma - 1.0).abs() < 0.15, "sigma {}", c.sigma);
        }
    }

    #[test]
    fn cusum_nan_constant_and_short_inputs() {
        let mut x: Vec<f64> = (0..100).map(|i| if i >= 50 { 5.0 } else { 0.0 }).collect();
        // Add a little noise so σ̂ > 0, and NaNs before the step: argmax indexes the input.
        let mut rng = Rng::new(11);
        for v in &mut x {
            *v += 0.1 * rng.normal();
        }
        x[5] = f64::NAN;
        x[6] = f64::NAN;
        let c = cusum(&x).unwrap();
        assert_eq!((c.n, c.nan_count), (98, 2));
        assert!((48..=51).contains(&c.argmax), "argmax {}", c.argmax);
        let flat = cusum(&[3.0; 10]).unwrap();
        assert!(!flat.drift_detected && flat.max_abs_normalised == 0.0);
        assert_eq!(
            cusum(&[1.0, 2.0, f64::NAN]).unwrap_err(),
            StatsError::TooFewSamples { needed: 5, got: 2 }
        );
    }

    #[test]
    fn sliding_mean_valid_windows() {
        let m = sliding_mean(&[1.0, 2.0, 3.0, 4.0, 5.0], 2).unwrap();
        assert_eq!(m, vec![1.5, 2.5, 3.5, 4.5]);
        let m = sliding_mean(&[1.0, f64::NAN, 3.0, f64::NAN, f64::NAN], 2).unwrap();
        assert_eq!(&m[..3], &[1.0, 3.0, 3.0]);
        assert!(m[3].is_nan());
        assert_eq!(sliding_mean(&[1.0, 2.0], 2).unwrap(), vec![1.5]);
        assert_eq!(
            sliding_mean(&[1.0], 2).unwrap_err(),
            StatsError::TooFewSamples { needed: 2, got: 1 }
        );
        assert!(matches!(
            sliding_mean(&[1.0], 0),
            Err(StatsError::InvalidArgument { .. })
        ));
    }
}
