//! Ordinary least squares with an intercept: coefficients, standard errors, t-statistics and
//! exact Student-t p-values; constant or collinear regressors are reported as dropped.

use super::*;
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

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
/// Errors: a regressor whose length differs from y ([`StatsError::LengthMismatch`]);
/// fewer rows than kept coefficients + 1 ([`StatsError::TooFewSamples`]).
pub fn regress(y: &[f64], regressors: &[(&str, &[f64])]) -> StatsResult<Regression> {
    for (name, x) in regressors {
        check_len(&format!("regressor {name}"), y.len(), x.len())?;
    }
    let rows: Vec<usize> = (0..y.len())
        .filter(|&i| y[i].is_finite() && regressors.iter().all(|(_, x)| x[i].is_finite()))
        .collect();
    let n = rows.len();
    let nan_count = y.len() - n;
    if n < 2 {
        return Err(StatsError::TooFewSamples { needed: 2, got: n });
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
        return Err(StatsError::TooFewSamples {
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
        .ok_or_else(|| StatsError::Degenerate("singular design matrix".to_string()))?;
    let r_inv = r
        .solve_upper_triangular(&DMatrix::identity(p, p))
        .ok_or_else(|| StatsError::Degenerate("singular design matrix".to_string()))?;
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
/// Errors: as [`regress`], and [`StatsError::Degenerate`] when x is constant.
pub fn simple_regression(y: &[f64], x: &[f64]) -> StatsResult<SimpleRegression> {
    let reg = regress(y, &[("x", x)])?;
    let (Some(a), Some(b)) = (reg.coef("intercept"), reg.coef("x")) else {
        return Err(StatsError::Degenerate(
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::test_util::*;

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
            Err(StatsError::Degenerate(_))
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
            Err(StatsError::LengthMismatch {
                expected: 6,
                got: 5,
                ..
            })
        ));
        assert_eq!(
            regress(&[], &[]).unwrap_err(),
            StatsError::TooFewSamples { needed: 2, got: 0 }
        );
        assert_eq!(
            simple_regression(&[1.0, 2.0], &[0.0, 1.0]).unwrap_err(),
            StatsError::TooFewSamples { needed: 3, got: 2 }
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
}
