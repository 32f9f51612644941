//! Statistics for the residual diagnosis of a Kalman filter (issue 4): pure functions, no IO.
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
//! [`StatsError::TooFewSamples`]. Result types serialise with serde; undefined statistics
//! (e.g. the standard error of a one-sample group) are NaN, which `serde_json` writes as `null`.
//!
//! Map of the submodules (each with its unit tests), all re-exported here:
//! - `distributions`: log-gamma, incomplete gamma and beta, χ², normal, Student t, F and
//!   Kolmogorov distribution functions;
//! - `nis`: [`nis_consistency`] and its [`NisVerdict`];
//! - `whiteness`: [`autocorrelation`] and the [`whiteness`] (Ljung–Box) test;
//! - `cusum`: the [`cusum`] range test and [`sliding_mean`];
//! - `regression`: [`regress`] and [`simple_regression`];
//! - `groups`: [`group_means`] and [`anova_oneway`].

mod cusum;
mod distributions;
mod groups;
mod nis;
mod regression;
mod whiteness;

pub use cusum::{Cusum, cusum, sliding_mean};
pub use distributions::{
    beta_reg, chi2_cdf, chi2_quantile, chi2_sf, f_sf, gamma_p, gamma_q, kolmogorov_sf, ln_gamma,
    noncentral_chi2_sf, normal_cdf, normal_quantile, student_t_two_sided_p,
};
pub use groups::{Anova, GroupStat, anova_oneway, group_means};
pub use nis::{NisTest, NisVerdict, nis_consistency};
pub use regression::{
    Coef, DropReason, DroppedRegressor, Regression, SimpleRegression, regress, simple_regression,
};
pub use whiteness::{Whiteness, autocorrelation, whiteness};

/// The median (the mean of the middle two for an even count; NaN for none); sorts `v`.
pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// Why a residual statistic could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StatsError {
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
pub type StatsResult<T> = std::result::Result<T, StatsError>;

/// Significance level of the pass/fail flags ([`Whiteness::white`], [`Cusum::drift_detected`],
/// [`Anova::equal_means`]): 5 %.
pub const ALPHA: f64 = 0.05;

/// Kolmogorov 95 % critical value of sup|Brownian bridge| (the [`cusum`] threshold).
pub const KOLMOGOROV_95: f64 = 1.358_098_8;

/// The finite values of `x` and the number of non-finite ones removed.
fn finite_values(x: &[f64]) -> (Vec<f64>, usize) {
    let v: Vec<f64> = x.iter().copied().filter(|v| v.is_finite()).collect();
    let removed = x.len() - v.len();
    (v, removed)
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len() as f64
}

fn check_len(what: &str, expected: usize, got: usize) -> StatsResult<()> {
    if expected == got {
        Ok(())
    } else {
        Err(StatsError::LengthMismatch {
            what: what.to_string(),
            expected,
            got,
        })
    }
}

#[cfg(test)]
mod test_util {
    //! Shared helpers of the statistics tests: a seeded generator and tolerances.

    /// xorshift64* seeded through splitmix64, with Box–Muller normals.
    pub(crate) struct Rng(u64);

    impl Rng {
        pub(crate) fn new(seed: u64) -> Self {
            let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            Rng(z | 1)
        }
        pub(crate) fn next_u64(&mut self) -> u64 {
            let mut x = self.0;
            x ^= x >> 12;
            x ^= x << 25;
            x ^= x >> 27;
            self.0 = x;
            x.wrapping_mul(0x2545_F491_4F6C_DD1D)
        }
        /// Uniform in (0, 1).
        pub(crate) fn uniform(&mut self) -> f64 {
            ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        }
        pub(crate) fn normal(&mut self) -> f64 {
            let (u1, u2) = (self.uniform(), self.uniform());
            (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
        }
        pub(crate) fn normals(&mut self, n: usize) -> Vec<f64> {
            (0..n).map(|_| self.normal()).collect()
        }
    }

    pub(crate) fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    /// Fraction of `trials` seeds for which `reject` is true.
    pub(crate) fn rejection_rate(trials: u64, mut reject: impl FnMut(&mut Rng) -> bool) -> f64 {
        let hits = (0..trials)
            .filter(|&s| reject(&mut Rng::new(1000 + s)))
            .count();
        hits as f64 / trials as f64
    }
}

#[cfg(test)]
mod tests {
    use super::test_util::Rng;
    use super::*;

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
