//! Residual statistics for the diagnosis of a Kalman filter (issue 4): pure functions, no IO.
//!
//! The building blocks `corridor diagnose` uses to test a filter's innovations:
//! - [`nis_consistency`]: time-averaged NIS against two-sided χ² bounds;
//! - [`autocorrelation`] and [`whiteness`]: normalised autocorrelation, the ±1.96/√N band and
//!   the Ljung–Box portmanteau test;
//! - [`cusum`] (normalised cumulative-sum range test) and [`sliding_mean`] for slow drifts and
//!   steps;
//! - [`regress`] and [`simple_regression`]: ordinary least squares with an intercept, standard
//!   errors, t-statistics and exact Student-t p-values; constant or collinear regressors are
//!   reported as dropped;
//! - [`group_means`] and [`anova_oneway`]: per-group means (e.g. ψ legs against ψ + π legs) and
//!   the one-way ANOVA F test of equal means.
//!
//! The distribution functions they need (log-gamma, regularized incomplete gamma and beta,
//! χ², Student t, F, normal and Kolmogorov) are implemented here and public, so that callers
//! can score evidence with the same numbers.
//!
//! Conventions: non-finite inputs (NaN, ±∞) are removed and counted in the result's
//! `nan_count`; an input with too few finite values gives
//! [`ResidualError::TooFewSamples`]. Result types serialise with serde; undefined statistics
//! (e.g. the standard error of a one-sample group) are NaN, which `serde_json` writes as `null`.
#![warn(missing_docs)]

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// Why a residual statistic could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ResidualError {
    /// Fewer finite samples than the statistic needs.
    #[error("too few samples: needed {needed}, got {got} (after removing non-finite values)")]
    TooFewSamples {
        /// Minimum number of finite samples (or rows) required.
        needed: usize,
        /// Number of finite samples (or rows) available.
        got: usize,
    },
    /// Two inputs that must be paired have different lengths.
    #[error("length mismatch: {what} has {got} values, expected {expected}")]
    LengthMismatch {
        /// Which input is too short or too long.
        what: String,
        /// Expected length (that of the first input).
        expected: usize,
        /// Actual length.
        got: usize,
    },
    /// An argument is outside its domain.
    #[error("invalid argument {name} = {value}: {rule}")]
    InvalidArgument {
        /// Name of the argument.
        name: &'static str,
        /// Its value, formatted.
        value: String,
        /// The rule it breaks.
        rule: &'static str,
    },
    /// Fewer than two groups with data (ANOVA).
    #[error("too few groups: needed {needed}, got {got}")]
    TooFewGroups {
        /// Minimum number of groups.
        needed: usize,
        /// Number of groups with at least one finite value.
        got: usize,
    },
    /// The input is degenerate for this statistic (e.g. zero variance).
    #[error("degenerate input: {0}")]
    Degenerate(String),
}

/// Result alias of this module.
pub type ResidualResult<T> = std::result::Result<T, ResidualError>;

/// Significance level of the pass/fail flags ([`Whiteness::white`], [`Cusum::drift_detected`],
/// [`Anova::equal_means`]): 5 %.
pub const ALPHA: f64 = 0.05;

/// Kolmogorov 95 % critical value of sup|Brownian bridge| (the [`cusum`] threshold).
pub const KOLMOGOROV_95: f64 = 1.358_098_8;

// ---------------------------------------------------------------------------------------------
// Special functions and distributions
// ---------------------------------------------------------------------------------------------

const EPS: f64 = 1e-15;
const FPMIN: f64 = 1e-300;

/// Iteration cap of the series and continued fractions: their terms need O(√a) iterations
/// when the argument is near the shape parameter a.
fn iteration_cap(a: f64) -> usize {
    200 + (20.0 * a.max(1.0).sqrt()) as usize
}

/// Natural logarithm of the gamma function for `x > 0` (Lanczos, g = 7, n = 9; relative error
/// about 1e-15). Returns NaN for `x <= 0` or NaN.
pub fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x.is_nan() || x <= 0.0 {
        return f64::NAN;
    }
    if x < 0.5 {
        // Reflection: Γ(x)Γ(1−x) = π / sin(πx), all positive for 0 < x < 0.5.
        return (std::f64::consts::PI / (std::f64::consts::PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularized lower incomplete gamma function P(a, x) = γ(a, x)/Γ(a), `a > 0`, `x >= 0`
/// (series for x < a + 1, Lentz continued fraction otherwise). NaN outside the domain.
pub fn gamma_p(a: f64, x: f64) -> f64 {
    if a.is_nan() || x.is_nan() || a <= 0.0 || x < 0.0 {
        return f64::NAN;
    }
    if x == 0.0 {
        return 0.0;
    }
    if x.is_infinite() {
        return 1.0;
    }
    if x < a + 1.0 {
        gamma_series(a, x)
    } else {
        1.0 - gamma_cf(a, x)
    }
}

/// Regularized upper incomplete gamma function Q(a, x) = 1 − P(a, x), computed directly in
/// the upper tail so that small tail probabilities keep their relative precision.
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if a.is_nan() || x.is_nan() || a <= 0.0 || x < 0.0 {
        return f64::NAN;
    }
    if x == 0.0 {
        return 1.0;
    }
    if x.is_infinite() {
        return 0.0;
    }
    if x < a + 1.0 {
        1.0 - gamma_series(a, x)
    } else {
        gamma_cf(a, x)
    }
}

fn gamma_prefactor(a: f64, x: f64) -> f64 {
    (-x + a * x.ln() - ln_gamma(a)).exp()
}

fn gamma_series(a: f64, x: f64) -> f64 {
    let mut ap = a;
    let mut del = 1.0 / a;
    let mut sum = del;
    for _ in 0..iteration_cap(a) {
        ap += 1.0;
        del *= x / ap;
        sum += del;
        if del.abs() < sum.abs() * EPS {
            break;
        }
    }
    (sum * gamma_prefactor(a, x)).clamp(0.0, 1.0)
}

fn gamma_cf(a: f64, x: f64) -> f64 {
    let mut b = x + 1.0 - a;
    let mut c = 1.0 / FPMIN;
    let mut d = 1.0 / b;
    let mut h = d;
    for i in 1..=iteration_cap(a) {
        let an = -(i as f64) * (i as f64 - a);
        b += 2.0;
        d = an * d + b;
        if d.abs() < FPMIN {
            d = FPMIN;
        }
        c = b + an / c;
        if c.abs() < FPMIN {
            c = FPMIN;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < EPS {
            break;
        }
    }
    (gamma_prefactor(a, x) * h).clamp(0.0, 1.0)
}

/// Regularized incomplete beta function I_x(a, b), `a, b > 0`, `0 <= x <= 1` (continued
/// fraction with the symmetry I_x(a, b) = 1 − I_{1−x}(b, a)). NaN outside the domain.
pub fn beta_reg(a: f64, b: f64, x: f64) -> f64 {
    if a.is_nan() || b.is_nan() || x.is_nan() || a <= 0.0 || b <= 0.0 || !(0.0..=1.0).contains(&x) {
        return f64::NAN;
    }
    if x == 0.0 {
        return 0.0;
    }
    if x == 1.0 {
        return 1.0;
    }
    let ln_bt = ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln();
    let bt = ln_bt.exp();
    let v = if x < (a + 1.0) / (a + b + 2.0) {
        bt * beta_cf(a, b, x) / a
    } else {
        1.0 - bt * beta_cf(b, a, 1.0 - x) / b
    };
    v.clamp(0.0, 1.0)
}

fn beta_cf(a: f64, b: f64, x: f64) -> f64 {
    let qab = a + b;
    let qap = a + 1.0;
    let qam = a - 1.0;
    let fix = |v: f64| if v.abs() < FPMIN { FPMIN } else { v };
    let mut c = 1.0;
    let mut d = 1.0 / fix(1.0 - qab * x / qap);
    let mut h = d;
    for m in 1..=iteration_cap(a.max(b)) {
        let m = m as f64;
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 / fix(1.0 + aa * d);
        c = fix(1.0 + aa / c);
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 / fix(1.0 + aa * d);
        c = fix(1.0 + aa / c);
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < EPS {
            break;
        }
    }
    h
}

/// Cumulative distribution function of χ²(k) at `x` (0 for x ≤ 0). NaN for k ≤ 0.
pub fn chi2_cdf(x: f64, k: f64) -> f64 {
    if k.is_nan() || k <= 0.0 {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 0.0;
    }
    gamma_p(0.5 * k, 0.5 * x)
}

/// Survival function P(X > x) of χ²(k) (1 for x ≤ 0). NaN for k ≤ 0.
pub fn chi2_sf(x: f64, k: f64) -> f64 {
    if k.is_nan() || k <= 0.0 {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 1.0;
    }
    gamma_q(0.5 * k, 0.5 * x)
}

fn chi2_pdf(x: f64, k: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    let h = 0.5 * k;
    ((h - 1.0) * x.ln() - 0.5 * x - h * std::f64::consts::LN_2 - ln_gamma(h)).exp()
}

/// Quantile (inverse CDF) of χ²(k): the x with P(X ≤ x) = p, for 0 < p < 1 and k > 0 (NaN
/// otherwise).
///
/// For k ≥ 30 the Wilson–Hilferty approximation
/// x ≈ k (1 − 2/(9k) + z_p √(2/(9k)))³ is polished by up to four Newton steps on
/// [`chi2_cdf`]; for k < 30 (where Wilson–Hilferty is poor in the lower tail) the CDF is
/// inverted by bisection. Both agree with χ² tables to their printed digits.
pub fn chi2_quantile(p: f64, k: f64) -> f64 {
    if p.is_nan() || k.is_nan() || p <= 0.0 || p >= 1.0 || k <= 0.0 {
        return f64::NAN;
    }
    if k >= 30.0 {
        let z = normal_quantile(p);
        let c = 2.0 / (9.0 * k);
        let mut x = k * (1.0 - c + z * c.sqrt()).powi(3);
        for _ in 0..4 {
            let pdf = chi2_pdf(x, k);
            if pdf.is_nan() || pdf <= 0.0 {
                break;
            }
            let step = (chi2_cdf(x, k) - p) / pdf;
            let next = x - step;
            if !next.is_finite() || next <= 0.0 {
                break;
            }
            x = next;
            if step.abs() <= 1e-13 * x {
                break;
            }
        }
        return x;
    }
    let mut lo = 0.0_f64;
    let mut hi = k.max(1.0);
    while chi2_cdf(hi, k) < p {
        lo = hi;
        hi *= 2.0;
    }
    for _ in 0..400 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi || hi - lo <= 1e-15 * hi {
            break;
        }
        if chi2_cdf(mid, k) < p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Standard normal cumulative distribution function Φ(z) (through the incomplete gamma:
/// erfc(u) = Q(½, u²)).
pub fn normal_cdf(z: f64) -> f64 {
    if z.is_nan() {
        return f64::NAN;
    }
    let u = z / std::f64::consts::SQRT_2;
    if u < 0.0 {
        0.5 * gamma_q(0.5, u * u)
    } else {
        1.0 - 0.5 * gamma_q(0.5, u * u)
    }
}

/// Standard normal quantile Φ⁻¹(p) for 0 < p < 1 (Acklam's rational approximation refined by
/// one Halley step; NaN outside (0, 1)).
pub fn normal_quantile(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    if p.is_nan() || p <= 0.0 || p >= 1.0 {
        return f64::NAN;
    }
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    const P_LOW: f64 = 0.024_25;
    let x = if p < P_LOW {
        tail((-2.0 * p.ln()).sqrt())
    } else if p <= 1.0 - P_LOW {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    } else {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    };
    // One Halley step on Φ(x) − p.
    let e = normal_cdf(x) - p;
    let u = e * (2.0 * std::f64::consts::PI).sqrt() * (0.5 * x * x).exp();
    let refined = x - u / (1.0 + 0.5 * x * u);
    if refined.is_finite() { refined } else { x }
}

/// Two-sided p-value P(|T| ≥ |t|) of Student's t with `df > 0` degrees of freedom, exact
/// through the regularized incomplete beta: p = I_{df/(df+t²)}(df/2, ½).
pub fn student_t_two_sided_p(t: f64, df: f64) -> f64 {
    if t.is_nan() || df.is_nan() || df <= 0.0 {
        return f64::NAN;
    }
    if t.is_infinite() {
        return 0.0;
    }
    beta_reg(0.5 * df, 0.5, df / (df + t * t))
}

/// Survival function P(F > f) of the F distribution with (`d1`, `d2`) degrees of freedom:
/// I_{d2/(d2+d1 f)}(d2/2, d1/2) (1 for f ≤ 0).
pub fn f_sf(f: f64, d1: f64, d2: f64) -> f64 {
    if f.is_nan() || d1.is_nan() || d2.is_nan() || d1 <= 0.0 || d2 <= 0.0 {
        return f64::NAN;
    }
    if f <= 0.0 {
        return 1.0;
    }
    if f.is_infinite() {
        return 0.0;
    }
    beta_reg(0.5 * d2, 0.5 * d1, d2 / (d2 + d1 * f))
}

/// Survival function of the Kolmogorov distribution, P(sup|B(t)| > λ) for a Brownian bridge
/// B: 2 Σ (−1)^{j−1} exp(−2j²λ²) for λ ≥ 1.18, and the equivalent theta-function form
/// 1 − √(2π)/λ Σ exp(−(2j−1)²π²/(8λ²)) below.
pub fn kolmogorov_sf(lambda: f64) -> f64 {
    if lambda.is_nan() {
        return f64::NAN;
    }
    if lambda <= 0.0 {
        return 1.0;
    }
    if lambda < 1.18 {
        let pi2 = std::f64::consts::PI * std::f64::consts::PI;
        let mut s = 0.0;
        for j in 1..=20 {
            let k = (2 * j - 1) as f64;
            s += (-k * k * pi2 / (8.0 * lambda * lambda)).exp();
        }
        (1.0 - (2.0 * std::f64::consts::PI).sqrt() / lambda * s).clamp(0.0, 1.0)
    } else {
        let mut s = 0.0;
        for j in 1..=100u32 {
            let jf = f64::from(j);
            let term = (-2.0 * jf * jf * lambda * lambda).exp();
            s += if j % 2 == 1 { term } else { -term };
            if term < 1e-18 {
                break;
            }
        }
        (2.0 * s).clamp(0.0, 1.0)
    }
}

// ---------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------

/// The finite values of `x` and the number of non-finite ones removed.
fn finite_values(x: &[f64]) -> (Vec<f64>, usize) {
    let v: Vec<f64> = x.iter().copied().filter(|v| v.is_finite()).collect();
    let removed = x.len() - v.len();
    (v, removed)
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len() as f64
}

fn check_len(what: &str, expected: usize, got: usize) -> ResidualResult<()> {
    if expected == got {
        Ok(())
    } else {
        Err(ResidualError::LengthMismatch {
            what: what.to_string(),
            expected,
            got,
        })
    }
}

// ---------------------------------------------------------------------------------------------
// 1. NIS consistency
// ---------------------------------------------------------------------------------------------

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
/// ([`ResidualError::TooFewSamples`]), `dof == 0` or `confidence` outside (0, 1)
/// ([`ResidualError::InvalidArgument`]).
pub fn nis_consistency(nis: &[f64], dof: usize, confidence: f64) -> ResidualResult<NisTest> {
    if dof == 0 {
        return Err(ResidualError::InvalidArgument {
            name: "dof",
            value: dof.to_string(),
            rule: "must be at least 1",
        });
    }
    if !(confidence > 0.0 && confidence < 1.0) {
        return Err(ResidualError::InvalidArgument {
            name: "confidence",
            value: confidence.to_string(),
            rule: "must be in (0, 1)",
        });
    }
    let (v, nan_count) = finite_values(nis);
    if v.is_empty() {
        return Err(ResidualError::TooFewSamples { needed: 1, got: 0 });
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

// ---------------------------------------------------------------------------------------------
// 2. Autocorrelation and whiteness
// ---------------------------------------------------------------------------------------------

/// Normalised sample autocorrelation r_0 … r_L of `x` (r_0 = 1):
/// r_k = Σ_t d_t d_{t+k} / Σ_t d_t², with d_t = x_t − mean over the finite values.
///
/// Lags count sample positions; a non-finite sample contributes d_t = 0 (it is skipped
/// without shifting the series). `max_lag` is clipped to (number of finite values − 1).
/// Errors: fewer than two finite values ([`ResidualError::TooFewSamples`]); zero variance
/// ([`ResidualError::Degenerate`]).
pub fn autocorrelation(x: &[f64], max_lag: usize) -> ResidualResult<Vec<f64>> {
    Ok(acf_impl(x, max_lag)?.0)
}

/// (acf, finite count, non-finite count)
fn acf_impl(x: &[f64], max_lag: usize) -> ResidualResult<(Vec<f64>, usize, usize)> {
    let (v, nan_count) = finite_values(x);
    let n = v.len();
    if n < 2 {
        return Err(ResidualError::TooFewSamples { needed: 2, got: n });
    }
    let m = mean(&v);
    let d: Vec<f64> = x
        .iter()
        .map(|&xi| if xi.is_finite() { xi - m } else { 0.0 })
        .collect();
    let c0: f64 = d.iter().map(|v| v * v).sum();
    if c0.is_nan() || c0 <= 0.0 {
        return Err(ResidualError::Degenerate(
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
/// Errors: `max_lag == 0` ([`ResidualError::InvalidArgument`]), fewer than three finite values
/// ([`ResidualError::TooFewSamples`]), zero variance ([`ResidualError::Degenerate`]).
pub fn whiteness(x: &[f64], max_lag: usize) -> ResidualResult<Whiteness> {
    if max_lag == 0 {
        return Err(ResidualError::InvalidArgument {
            name: "max_lag",
            value: "0".to_string(),
            rule: "must be at least 1",
        });
    }
    let finite = x.iter().filter(|v| v.is_finite()).count();
    if finite < 3 {
        return Err(ResidualError::TooFewSamples {
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

// ---------------------------------------------------------------------------------------------
// 3. CUSUM and sliding mean
// ---------------------------------------------------------------------------------------------

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
/// Errors: fewer than five finite samples ([`ResidualError::TooFewSamples`]). A constant
/// series gives `max_abs_normalised = 0` and no drift.
pub fn cusum(x: &[f64]) -> ResidualResult<Cusum> {
    let idx: Vec<usize> = (0..x.len()).filter(|&i| x[i].is_finite()).collect();
    let n = idx.len();
    let nan_count = x.len() - n;
    if n < 5 {
        return Err(ResidualError::TooFewSamples { needed: 5, got: n });
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
/// Errors: `window == 0` ([`ResidualError::InvalidArgument`]); `x.len() < window`
/// ([`ResidualError::TooFewSamples`]).
pub fn sliding_mean(x: &[f64], window: usize) -> ResidualResult<Vec<f64>> {
    if window == 0 {
        return Err(ResidualError::InvalidArgument {
            name: "window",
            value: "0".to_string(),
            rule: "must be at least 1",
        });
    }
    if x.len() < window {
        return Err(ResidualError::TooFewSamples {
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

// ---------------------------------------------------------------------------------------------
// 4. Linear regression
// ---------------------------------------------------------------------------------------------

/// One estimated coefficient of a [`Regression`].
#[derive(Debug, Clone, Serialize)]
pub struct Coef {
    /// Regressor name (`"intercept"` for the constant term).
    pub name: String,
    /// Estimate.
    pub value: f64,
    /// Standard error √(σ̂² (XᵀX)⁻¹_jj).
    pub std_err: f64,
    /// t-statistic `value / std_err`.
    pub t: f64,
    /// Two-sided p-value of t under Student's t with n − p degrees of freedom (exact, via the
    /// incomplete beta function).
    pub p_value: f64,
}

/// Why a regressor was left out of a [`Regression`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DropReason {
    /// The regressor is constant over the rows used (collinear with the intercept).
    Constant,
    /// The regressor is (numerically) a linear combination of the intercept and the
    /// regressors kept before it.
    Collinear,
}

/// A regressor left out of a [`Regression`].
#[derive(Debug, Clone, Serialize)]
pub struct DroppedRegressor {
    /// Regressor name.
    pub name: String,
    /// Why it was dropped.
    pub reason: DropReason,
}

/// Ordinary least-squares fit with an intercept (see [`regress`]).
#[derive(Debug, Clone, Serialize)]
pub struct Regression {
    /// The intercept first, then the kept regressors in input order.
    pub coefficients: Vec<Coef>,
    /// Regressors left out (constant or collinear), in input order.
    pub dropped: Vec<DroppedRegressor>,
    /// Coefficient of determination 1 − SSR/SST (NaN when y is constant).
    pub r2: f64,
    /// Residual standard deviation σ̂ = √(SSR / (n − p)).
    pub residual_std: f64,
    /// Number of rows used.
    pub n: usize,
    /// Residual degrees of freedom n − p (p counts the intercept).
    pub dof: usize,
    /// Rows removed because y or a regressor was non-finite.
    pub nan_count: usize,
}

impl Regression {
    /// The coefficient called `name`, if it was estimated.
    pub fn coef(&self, name: &str) -> Option<&Coef> {
        self.coefficients.iter().find(|c| c.name == name)
    }
}

/// Relative size below which a standardised regressor's component orthogonal to the columns
/// kept before it counts as zero (collinear).
const COLLINEAR_TOL: f64 = 1e-8;

/// Ordinary least squares y = β₀ + Σ β_j x_j + e with standard errors, t and p-values.
///
/// Rows where y or any regressor is non-finite are removed (counted in `nan_count`).
/// Regressors are centred and scaled internally; one that is constant is dropped
/// ([`DropReason::Constant`]) and one whose part orthogonal to the regressors kept before it
/// is below 1e-8 of its norm is dropped ([`DropReason::Collinear`]), so the order of
/// `regressors` decides which of two collinear regressors is kept. The kept columns are
/// solved by Householder QR (nalgebra), and the covariance σ̂²(XᵀX)⁻¹ = σ̂² R⁻¹R⁻ᵀ is mapped
/// back to the original units.
///
/// Errors: a regressor whose length differs from y ([`ResidualError::LengthMismatch`]);
/// fewer rows than kept coefficients + 1 ([`ResidualError::TooFewSamples`]).
pub fn regress(y: &[f64], regressors: &[(&str, &[f64])]) -> ResidualResult<Regression> {
    for (name, x) in regressors {
        check_len(&format!("regressor {name}"), y.len(), x.len())?;
    }
    let rows: Vec<usize> = (0..y.len())
        .filter(|&i| y[i].is_finite() && regressors.iter().all(|(_, x)| x[i].is_finite()))
        .collect();
    let n = rows.len();
    let nan_count = y.len() - n;
    if n < 2 {
        return Err(ResidualError::TooFewSamples { needed: 2, got: n });
    }
    let nf = n as f64;
    let yv: Vec<f64> = rows.iter().map(|&i| y[i]).collect();

    // Standardise each regressor; keep it only if it adds a direction.
    let mut basis: Vec<DVector<f64>> = Vec::new(); // orthonormal, all orthogonal to 1
    let mut kept: Vec<(String, f64, f64, DVector<f64>)> = Vec::new(); // name, mean, scale, z
    let mut dropped = Vec::new();
    for (name, x) in regressors {
        let col: Vec<f64> = rows.iter().map(|&i| x[i]).collect();
        let m = mean(&col);
        let scale = (col.iter().map(|v| (v - m).powi(2)).sum::<f64>() / nf).sqrt();
        let max_abs = col.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
        if scale.is_nan() || scale <= 1e-12 * max_abs.max(f64::MIN_POSITIVE) {
            dropped.push(DroppedRegressor {
                name: name.to_string(),
                reason: DropReason::Constant,
            });
            continue;
        }
        let z = DVector::from_iterator(n, col.iter().map(|v| (v - m) / scale));
        let mut r = z.clone();
        for _ in 0..2 {
            for q in &basis {
                let proj = q.dot(&r);
                r.axpy(-proj, q, 1.0);
            }
        }
        let rn = r.norm();
        if rn <= COLLINEAR_TOL * z.norm() {
            dropped.push(DroppedRegressor {
                name: name.to_string(),
                reason: DropReason::Collinear,
            });
            continue;
        }
        basis.push(r / rn);
        kept.push((name.to_string(), m, scale, z));
    }

    let p = kept.len() + 1;
    if n < p + 1 {
        return Err(ResidualError::TooFewSamples {
            needed: p + 1,
            got: n,
        });
    }
    let mut xm = DMatrix::<f64>::from_element(n, p, 1.0);
    for (j, (_, _, _, z)) in kept.iter().enumerate() {
        xm.set_column(j + 1, z);
    }
    let yd = DVector::from_vec(yv.clone());
    let qr = xm.clone().qr();
    let r = qr.r();
    let qty = qr.q().transpose() * &yd;
    let gamma = r
        .solve_upper_triangular(&qty)
        .ok_or_else(|| ResidualError::Degenerate("singular design matrix".to_string()))?;
    let r_inv = r
        .solve_upper_triangular(&DMatrix::identity(p, p))
        .ok_or_else(|| ResidualError::Degenerate("singular design matrix".to_string()))?;
    let resid = &yd - &xm * &gamma;
    let ssr = resid.norm_squared();
    let ym = mean(&yv);
    let sst: f64 = yv.iter().map(|v| (v - ym).powi(2)).sum();
    let dof = n - p;
    let s2 = ssr / dof as f64;
    let cov_g = (&r_inv * r_inv.transpose()) * s2;
    // Back to original units: β_j = γ_j / s_j, β₀ = γ₀ − Σ γ_j m_j / s_j.
    let mut t = DMatrix::<f64>::zeros(p, p);
    t[(0, 0)] = 1.0;
    for (j, (_, m, s, _)) in kept.iter().enumerate() {
        t[(0, j + 1)] = -m / s;
        t[(j + 1, j + 1)] = 1.0 / s;
    }
    let beta = &t * &gamma;
    let cov = &t * cov_g * t.transpose();
    let names = std::iter::once("intercept".to_string()).chain(kept.iter().map(|k| k.0.clone()));
    let coefficients = names
        .enumerate()
        .map(|(j, name)| {
            let value = beta[j];
            let std_err = cov[(j, j)].max(0.0).sqrt();
            let t = value / std_err;
            Coef {
                name,
                value,
                std_err,
                t,
                p_value: student_t_two_sided_p(t, dof as f64),
            }
        })
        .collect();
    Ok(Regression {
        coefficients,
        dropped,
        r2: if sst > 0.0 { 1.0 - ssr / sst } else { f64::NAN },
        residual_std: s2.sqrt(),
        n,
        dof,
        nan_count,
    })
}

/// Straight-line fit y = a + b·x (see [`simple_regression`]).
#[derive(Debug, Clone, Serialize)]
pub struct SimpleRegression {
    /// Intercept a.
    pub intercept: f64,
    /// Slope b.
    pub slope: f64,
    /// Standard error of the slope.
    pub std_err: f64,
    /// t-statistic of the slope.
    pub t: f64,
    /// Two-sided p-value of the slope (Student t, n − 2 degrees of freedom, exact).
    pub p_value: f64,
    /// Coefficient of determination (NaN when y is constant).
    pub r2: f64,
    /// Number of rows used.
    pub n: usize,
    /// Rows removed because x or y was non-finite.
    pub nan_count: usize,
}

/// Single-regressor convenience around [`regress`]: slope of y on x with its standard error,
/// t-statistic and exact two-sided Student-t p-value (n − 2 degrees of freedom).
///
/// Errors: as [`regress`], and [`ResidualError::Degenerate`] when x is constant.
pub fn simple_regression(y: &[f64], x: &[f64]) -> ResidualResult<SimpleRegression> {
    let reg = regress(y, &[("x", x)])?;
    let (Some(a), Some(b)) = (reg.coef("intercept"), reg.coef("x")) else {
        return Err(ResidualError::Degenerate(
            "regressor is constant: no slope".to_string(),
        ));
    };
    Ok(SimpleRegression {
        intercept: a.value,
        slope: b.value,
        std_err: b.std_err,
        t: b.t,
        p_value: b.p_value,
        r2: reg.r2,
        n: reg.n,
        nan_count: reg.nan_count,
    })
}

// ---------------------------------------------------------------------------------------------
// 5. Groups
// ---------------------------------------------------------------------------------------------

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
/// Errors: different lengths ([`ResidualError::LengthMismatch`]); no finite value
/// ([`ResidualError::TooFewSamples`]).
pub fn group_means(y: &[f64], group: &[i64]) -> ResidualResult<Vec<GroupStat>> {
    check_len("group", y.len(), group.len())?;
    let mut labels: Vec<i64> = group.to_vec();
    labels.sort_unstable();
    labels.dedup();
    let finite = y.iter().filter(|v| v.is_finite()).count();
    if finite == 0 {
        return Err(ResidualError::TooFewSamples { needed: 1, got: 0 });
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
/// ([`ResidualError::TooFewGroups`]); N ≤ k ([`ResidualError::TooFewSamples`]).
pub fn anova_oneway(y: &[f64], group: &[i64]) -> ResidualResult<Anova> {
    let groups = group_means(y, group)?;
    let nan_count = groups.iter().map(|g| g.nan_count).sum();
    let used: Vec<&GroupStat> = groups.iter().filter(|g| g.n > 0).collect();
    let k = used.len();
    if k < 2 {
        return Err(ResidualError::TooFewGroups { needed: 2, got: k });
    }
    let n: usize = used.iter().map(|g| g.n).sum();
    if n <= k {
        return Err(ResidualError::TooFewSamples {
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

    /// xorshift64* seeded through splitmix64, with Box–Muller normals.
    struct Rng(u64);

    impl Rng {
        fn new(seed: u64) -> Self {
            let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            Rng(z | 1)
        }
        fn next_u64(&mut self) -> u64 {
            let mut x = self.0;
            x ^= x >> 12;
            x ^= x << 25;
            x ^= x >> 27;
            self.0 = x;
            x.wrapping_mul(0x2545_F491_4F6C_DD1D)
        }
        /// Uniform in (0, 1).
        fn uniform(&mut self) -> f64 {
            ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        }
        fn normal(&mut self) -> f64 {
            let (u1, u2) = (self.uniform(), self.uniform());
            (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
        }
        fn normals(&mut self, n: usize) -> Vec<f64> {
            (0..n).map(|_| self.normal()).collect()
        }
    }

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    /// Fraction of `trials` seeds for which `reject` is true.
    fn rejection_rate(trials: u64, mut reject: impl FnMut(&mut Rng) -> bool) -> f64 {
        let hits = (0..trials)
            .filter(|&s| reject(&mut Rng::new(1000 + s)))
            .count();
        hits as f64 / trials as f64
    }

    // --- special functions --------------------------------------------------------------

    #[test]
    fn ln_gamma_matches_factorials_and_half() {
        for (n, fact) in [(1.0, 1.0), (2.0, 1.0), (5.0, 24.0), (11.0, 3_628_800.0_f64)] {
            assert!(close(ln_gamma(n), fact.ln(), 1e-12), "lnΓ({n})");
        }
        assert!(close(
            ln_gamma(0.5),
            std::f64::consts::PI.sqrt().ln(),
            1e-13
        ));
        assert!(close(ln_gamma(0.1), 9.513_507_698_668_732_f64.ln(), 1e-12));
        assert!(ln_gamma(0.0).is_nan() && ln_gamma(-1.0).is_nan());
    }

    #[test]
    fn chi2_quantile_matches_tables() {
        let cases = [
            (0.025, 1.0, 0.000_982, 1e-6),
            (0.975, 1.0, 5.024, 1e-3),
            (0.975, 10.0, 20.483, 1e-3),
            (0.025, 100.0, 74.222, 1e-3),
            (0.975, 100.0, 129.561, 1e-3),
            (0.95, 2.0, 5.991, 1e-3),
            (0.05, 29.0, 17.708, 1e-3),
            (0.95, 30.0, 43.773, 1e-3),
        ];
        for (p, k, want, tol) in cases {
            let got = chi2_quantile(p, k);
            assert!(close(got, want, tol), "χ²_{p}({k}) = {got}, table {want}");
            // And the CDF inverts it.
            assert!(
                close(chi2_cdf(got, k), p, 1e-9),
                "cdf(quantile) at p={p}, k={k}"
            );
        }
        // Exact closed form for k = 2: x = −2 ln(1 − p).
        assert!(close(chi2_quantile(0.3, 2.0), -2.0 * 0.7_f64.ln(), 1e-12));
        // Large k stays consistent with the CDF.
        let x = chi2_quantile(0.975, 200_000.0);
        assert!(close(chi2_cdf(x, 200_000.0), 0.975, 1e-8));
        assert!(chi2_quantile(0.0, 3.0).is_nan() && chi2_quantile(0.5, 0.0).is_nan());
    }

    #[test]
    fn chi2_cdf_and_sf_known_values() {
        // χ²(2): cdf = 1 − exp(−x/2).
        assert!(close(chi2_cdf(3.0, 2.0), 1.0 - (-1.5_f64).exp(), 1e-14));
        assert!(close(chi2_sf(3.0, 2.0), (-1.5_f64).exp(), 1e-14));
        assert!(close(chi2_sf(3.841_458_8, 1.0), 0.05, 1e-8));
        assert!(close(chi2_sf(31.410_432_8, 20.0), 0.05, 1e-8));
        // Far tail keeps relative precision.
        let tail = chi2_sf(200.0, 2.0);
        assert!(close(tail / (-100.0_f64).exp(), 1.0, 1e-10));
    }

    #[test]
    fn normal_student_f_kolmogorov_known_values() {
        assert!(close(normal_cdf(1.959_963_984_540_054), 0.975, 1e-12));
        assert!(close(normal_cdf(-1.0), 0.158_655_253_931_457, 1e-12));
        assert!(close(normal_quantile(0.975), 1.959_963_984_540_054, 1e-12));
        assert!(close(normal_quantile(0.001), -3.090_232_306_167_813, 1e-10));
        assert!(close(normal_quantile(0.5), 0.0, 1e-15));
        // t tables: t_{0.975}(10) = 2.228139, t_{0.975}(1) = 12.7062, t_{0.995}(30) = 2.749996.
        assert!(close(student_t_two_sided_p(2.228_138_85, 10.0), 0.05, 1e-8));
        assert!(close(student_t_two_sided_p(12.706_204_7, 1.0), 0.05, 1e-8));
        assert!(close(student_t_two_sided_p(2.749_995_7, 30.0), 0.01, 1e-7));
        assert!(close(student_t_two_sided_p(0.0, 5.0), 1.0, 1e-14));
        // Large df approaches the normal.
        assert!(close(student_t_two_sided_p(1.96, 1e6), 0.05, 1e-4));
        // F tables: F_{0.95}(2, 30) = 3.3158, F_{0.99}(3, 10) = 6.5523; F(1, d) = t².
        assert!(close(f_sf(3.315_829_6, 2.0, 30.0), 0.05, 1e-7));
        assert!(close(f_sf(6.5523, 3.0, 10.0), 0.01, 1e-5));
        assert!(close(f_sf(2.228_138_85_f64.powi(2), 1.0, 10.0), 0.05, 1e-8));
        // Incomplete beta symmetry and a closed form: I_x(1, b) = 1 − (1 − x)^b.
        assert!(close(beta_reg(1.0, 3.0, 0.2), 1.0 - 0.8_f64.powi(3), 1e-14));
        assert!(close(
            beta_reg(2.5, 4.0, 0.3) + beta_reg(4.0, 2.5, 0.7),
            1.0,
            1e-13
        ));
        // Kolmogorov: both branches, 5 % and 1 % points.
        assert!(close(kolmogorov_sf(KOLMOGOROV_95), 0.05, 1e-6));
        assert!(close(kolmogorov_sf(1.627_62), 0.01, 1e-5));
        assert!(close(kolmogorov_sf(1.0), 0.269_999_6, 1e-6));
        let (below, above) = (kolmogorov_sf(1.179_999), kolmogorov_sf(1.180_001));
        assert!(close(below, above, 1e-5), "branches agree at 1.18");
    }

    // --- NIS ----------------------------------------------------------------------------

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
            ResidualError::TooFewSamples { needed: 1, got: 0 }
        );
        assert!(matches!(
            nis_consistency(&[1.0], 0, 0.95),
            Err(ResidualError::InvalidArgument { name: "dof", .. })
        ));
        assert!(matches!(
            nis_consistency(&[1.0], 1, 1.0),
            Err(ResidualError::InvalidArgument {
                name: "confidence",
                ..
            })
        ));
    }

    // --- whiteness ----------------------------------------------------------------------

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
            Err(ResidualError::Degenerate(_))
        ));
        assert_eq!(
            autocorrelation(&[], 2).unwrap_err(),
            ResidualError::TooFewSamples { needed: 2, got: 0 }
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
            Err(ResidualError::InvalidArgument { .. })
        ));
        assert_eq!(
            whiteness(&[1.0, f64::NAN], 3).unwrap_err(),
            ResidualError::TooFewSamples { needed: 3, got: 1 }
        );
    }

    // --- CUSUM and sliding mean ---------------------------------------------------------

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
            ResidualError::TooFewSamples { needed: 5, got: 2 }
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
            ResidualError::TooFewSamples { needed: 2, got: 1 }
        );
        assert!(matches!(
            sliding_mean(&[1.0], 0),
            Err(ResidualError::InvalidArgument { .. })
        ));
    }

    // --- regression ---------------------------------------------------------------------

    #[test]
    fn regression_recovers_two_coefficients() {
        let mut rng = Rng::new(42);
        let n = 400;
        let x1: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
        // Correlated with x1 and on a very different scale and offset.
        let x2: Vec<f64> = x1
            .iter()
            .map(|a| 1e4 + 300.0 * (0.6 * a + 0.8 * rng.normal()))
            .collect();
        let y: Vec<f64> = x1
            .iter()
            .zip(&x2)
            .map(|(a, b)| 2.0 + 0.5 * a - 0.003 * b + 0.2 * rng.normal())
            .collect();
        let reg = regress(&y, &[("x1", &x1), ("x2", &x2)]).unwrap();
        assert!(reg.dropped.is_empty());
        assert_eq!((reg.n, reg.dof, reg.coefficients.len()), (n, n - 3, 3));
        for (name, truth) in [("intercept", 2.0), ("x1", 0.5), ("x2", -0.003)] {
            let c = reg.coef(name).unwrap();
            assert!(
                (c.value - truth).abs() < 3.0 * c.std_err,
                "{name}: {} ± {} vs {truth}",
                c.value,
                c.std_err
            );
            assert!(close(c.t, c.value / c.std_err, 1e-12));
        }
        assert!(reg.r2 > 0.8 && reg.r2 < 1.0);
        assert!((reg.residual_std - 0.2).abs() < 0.03);
        // Cross-check the intercept standard error against the normal equations in the
        // original units.
        let xm = DMatrix::from_fn(n, 3, |i, j| match j {
            0 => 1.0,
            1 => x1[i],
            _ => x2[i],
        });
        let inv = (xm.transpose() * &xm).try_inverse().unwrap();
        for (j, c) in reg.coefficients.iter().enumerate() {
            let se = reg.residual_std * inv[(j, j)].sqrt();
            assert!(
                close(c.std_err / se, 1.0, 1e-6),
                "{}: {} vs {se}",
                c.name,
                c.std_err
            );
        }
    }

    #[test]
    fn regression_drops_constant_and_collinear_regressors() {
        let mut rng = Rng::new(5);
        let x: Vec<f64> = (0..50).map(|i| i as f64).collect();
        let y: Vec<f64> = x.iter().map(|v| 1.0 + 0.1 * v + rng.normal()).collect();
        let constant = vec![7.0; 50];
        let doubled: Vec<f64> = x.iter().map(|v| 2.0 * v - 3.0).collect();
        let reg = regress(&y, &[("temp", &constant), ("t", &x), ("t2", &doubled)]).unwrap();
        let names: Vec<&str> = reg.coefficients.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["intercept", "t"]);
        assert_eq!(reg.dropped.len(), 2);
        assert_eq!(
            (reg.dropped[0].name.as_str(), reg.dropped[0].reason),
            ("temp", DropReason::Constant)
        );
        assert_eq!(
            (reg.dropped[1].name.as_str(), reg.dropped[1].reason),
            ("t2", DropReason::Collinear)
        );
        // Only regressors, all constant: intercept only, the mean of y.
        let reg = regress(&y, &[("c", &constant)]).unwrap();
        assert_eq!(reg.coefficients.len(), 1);
        assert!(close(reg.coefficients[0].value, mean(&y), 1e-12));
        // The single-regressor form reports a constant regressor as an error, not a panic.
        assert!(matches!(
            simple_regression(&y, &constant),
            Err(ResidualError::Degenerate(_))
        ));
    }

    #[test]
    fn regression_nan_rows_lengths_and_small_inputs() {
        let x = [0.0, 1.0, 2.0, f64::NAN, 4.0, 5.0];
        let y = [1.0, 3.0, 5.0, 7.0, f64::NAN, 11.0];
        let s = simple_regression(&y, &x).unwrap();
        assert_eq!((s.n, s.nan_count), (4, 2));
        assert!(close(s.slope, 2.0, 1e-12) && close(s.intercept, 1.0, 1e-12));
        assert!(close(s.r2, 1.0, 1e-12));
        assert!(matches!(
            regress(&y, &[("x", &x[..5])]),
            Err(ResidualError::LengthMismatch {
                expected: 6,
                got: 5,
                ..
            })
        ));
        assert_eq!(
            regress(&[], &[]).unwrap_err(),
            ResidualError::TooFewSamples { needed: 2, got: 0 }
        );
        assert_eq!(
            simple_regression(&[1.0, 2.0], &[0.0, 1.0]).unwrap_err(),
            ResidualError::TooFewSamples { needed: 3, got: 2 }
        );
    }

    #[test]
    fn slope_p_value_is_uniform_under_the_null() {
        let t: Vec<f64> = (0..60).map(|i| i as f64).collect();
        let rate = rejection_rate(200, |rng| {
            simple_regression(&rng.normals(60), &t).unwrap().p_value < 0.05
        });
        assert!((0.02..=0.09).contains(&rate), "rejection rate {rate}");
    }

    // --- groups and ANOVA ---------------------------------------------------------------

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
            Err(ResidualError::LengthMismatch { .. })
        ));
        assert_eq!(
            group_means(&[], &[]).unwrap_err(),
            ResidualError::TooFewSamples { needed: 1, got: 0 }
        );
        assert_eq!(
            anova_oneway(&[1.0, 2.0], &[0, 0]).unwrap_err(),
            ResidualError::TooFewGroups { needed: 2, got: 1 }
        );
        assert_eq!(
            anova_oneway(&[1.0, 2.0], &[0, 1]).unwrap_err(),
            ResidualError::TooFewSamples { needed: 3, got: 2 }
        );
        // Zero within-group variance.
        let a = anova_oneway(&[1.0, 1.0, 2.0, 2.0], &[0, 0, 1, 1]).unwrap();
        assert!(a.f.is_infinite() && a.p_value == 0.0 && !a.equal_means);
    }

    #[test]
    fn results_serialise_to_json() {
        let mut rng = Rng::new(1);
        let x = rng.normals(50);
        let nis = nis_consistency(&x.iter().map(|v| v * v).collect::<Vec<_>>(), 1, 0.95);
        let json = serde_json::to_value(nis.unwrap()).unwrap();
        assert!(json["verdict"].is_string() && json["mean"].is_number());
        let w = serde_json::to_value(whiteness(&x, 5).unwrap()).unwrap();
        assert_eq!(w["acf"].as_array().unwrap().len(), 6);
        let g = group_means(&[1.0, 2.0], &[0, 1]).unwrap();
        let json = serde_json::to_value(&g).unwrap();
        assert!(json[0]["std_err"].is_null(), "NaN serialises as null");
        let t: Vec<f64> = (0..50).map(f64::from).collect();
        let c = [1.0; 50];
        let r = regress(&x, &[("t", &t), ("c", &c)]).unwrap();
        let json = serde_json::to_value(r).unwrap();
        assert_eq!(json["dropped"][0]["reason"], "constant");
        serde_json::to_string(&cusum(&x).unwrap()).unwrap();
        serde_json::to_string(&anova_oneway(&x, &[[0i64; 25], [1; 25]].concat()).unwrap()).unwrap();
    }
}
