//! The regression of a power fit: weighted least squares of the stance residuals on an
//! effect's signature, one intercept per residual kind, with a Newey–West standard error
//! (consecutive stances share accumulated gyro error). See `power/mod.rs` for what the signature is.

/// Bartlett-kernel lags of the Newey–West standard error, in residual rows (two rows per
/// stance: about four stances, the run of stances between two used observations after a turn).
pub const HAC_LAGS: usize = 8;

/// One residual of a signature fit.
#[derive(Debug, Clone, Copy)]
pub struct Row {
    /// Residual kind (its own intercept and variance).
    pub group: usize,
    /// Association weight.
    pub weight: f64,
    /// Residual, rad.
    pub y: f64,
    /// Signature: residual change per unit of the effect.
    pub x: f64,
}

/// A signature fit.
#[derive(Debug, Clone)]
pub struct SignatureFit {
    /// Estimated size of the effect.
    pub beta: f64,
    /// Newey–West standard error.
    pub std_err: f64,
    /// The intercept of each group.
    pub intercepts: Vec<f64>,
}

/// Weighted least squares of `y` on `x` with one intercept per group, weights
/// `weight/σ²_group` (σ² the group's weighted residual variance), and a Newey–West standard
/// error over `lags` rows (rows in time order). `None` when the signature is flat.
pub fn fit_signature(rows: &[Row], lags: usize) -> Option<SignatureFit> {
    let groups = rows.iter().map(|r| r.group).max()? + 1;
    let mut wsum = vec![0.0; groups];
    let mut ym = vec![0.0; groups];
    let mut xm = vec![0.0; groups];
    for r in rows {
        wsum[r.group] += r.weight;
        ym[r.group] += r.weight * r.y;
        xm[r.group] += r.weight * r.x;
    }
    for g in 0..groups {
        if wsum[g] > 0.0 {
            ym[g] /= wsum[g];
            xm[g] /= wsum[g];
        }
    }
    let mut var = vec![0.0; groups];
    for r in rows {
        var[r.group] += r.weight * (r.y - ym[r.group]).powi(2);
    }
    for g in 0..groups {
        var[g] = if wsum[g] > 0.0 { var[g] / wsum[g] } else { 0.0 };
    }
    let w = |r: &Row| {
        if var[r.group] > 0.0 {
            r.weight / var[r.group]
        } else {
            0.0
        }
    };
    let (mut sxx, mut sxy) = (0.0, 0.0);
    for r in rows {
        let (x, y) = (r.x - xm[r.group], r.y - ym[r.group]);
        sxx += w(r) * x * x;
        sxy += w(r) * x * y;
    }
    if sxx.is_nan() || sxx <= 0.0 {
        return None;
    }
    let beta = sxy / sxx;
    let u: Vec<f64> = rows
        .iter()
        .map(|r| {
            let (x, y) = (r.x - xm[r.group], r.y - ym[r.group]);
            w(r) * x * (y - beta * x)
        })
        .collect();
    let mut s: f64 = u.iter().map(|v| v * v).sum();
    for l in 1..=lags.min(u.len().saturating_sub(1)) {
        let k = 1.0 - l as f64 / (lags + 1) as f64;
        s += 2.0 * k * u.iter().zip(&u[l..]).map(|(a, b)| a * b).sum::<f64>();
    }
    let std_err = s.max(0.0).sqrt() / sxx;
    let intercepts = (0..groups).map(|g| ym[g] - beta * xm[g]).collect();
    (std_err > 0.0 && std_err.is_finite()).then_some(SignatureFit {
        beta,
        std_err,
        intercepts,
    })
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// Deterministic test noise, shared with `power`'s tests.
    pub(in crate::diagnose) fn noise(i: usize) -> f64 {
        // deterministic, zero-mean, roughly uniform on ±1
        let v = ((i as f64 * 12.9898).sin() * 43758.5453).fract();
        2.0 * v.abs() - 1.0
    }

    #[test]
    fn the_fit_recovers_a_size_and_its_detectable_size_scales_with_the_noise() {
        let x = |i: usize| match (i % 10, i % 20) {
            (0, 0) => -1.5,
            (0, _) => 1.5,
            _ => 0.0,
        };
        let rows = |beta: f64, sd: f64| -> Vec<Row> {
            (0..400)
                .map(|i| Row {
                    group: i % 2,
                    weight: 1.0,
                    y: beta * x(i) + sd * noise(i) + 0.01 * (i % 2) as f64,
                    x: x(i),
                })
                .collect()
        };
        let f = fit_signature(&rows(0.02, 0.01), 0).unwrap();
        assert!((f.beta - 0.02).abs() < 3.0 * f.std_err, "{f:?}");
        assert!(f.beta / f.std_err > 10.0, "{f:?}");
        // twice the noise, about twice the standard error (and so the detectable size)
        let a = fit_signature(&rows(0.0, 0.01), 0).unwrap();
        let b = fit_signature(&rows(0.0, 0.02), 0).unwrap();
        let ratio = b.std_err / a.std_err;
        assert!((1.6..2.4).contains(&ratio), "{ratio}");
        // a flat signature has no fit
        let flat: Vec<Row> = (0..50)
            .map(|i| Row {
                group: 0,
                weight: 1.0,
                y: noise(i),
                x: 3.0,
            })
            .collect();
        assert!(fit_signature(&flat, 4).is_none());
    }

    #[test]
    fn correlated_residuals_widen_the_standard_error() {
        // The same noise repeated over runs of four rows: four times fewer independent values.
        let rows: Vec<Row> = (0..400)
            .map(|i| Row {
                group: 0,
                weight: 1.0,
                y: noise(i / 4),
                x: if (i / 4) % 2 == 0 { 1.0 } else { -1.0 },
            })
            .collect();
        let plain = fit_signature(&rows, 0).unwrap();
        let hac = fit_signature(&rows, 8).unwrap();
        assert!(hac.std_err > 1.5 * plain.std_err, "{plain:?} {hac:?}");
    }
}
