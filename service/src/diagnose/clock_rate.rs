//! A clock running at the wrong rate, told from a gyro scale factor.
//!
//! Time stamps that run a fraction ε fast stretch every integrated angle by 1 + ε, on every
//! gyro axis alike, and every stride by (1 + ε)²: the velocity a swing builds grows by 1 + ε and
//! so does the time it is integrated over. A gyro scale factor stretches the angles about its
//! own axis only and leaves the strides alone. The heading residuals see the z axis well and
//! the horizontal axes hardly (σ of a percent or more on these walks), so from them alone a
//! clock error is only told apart when it is large; where footprints give the stride scale,
//! and the model's strides are right without one (the rolling-foot stance update), the strides
//! measure ε to about half a percent (the gait's own spread of stride scales), and a scale
//! factor that agrees with them is the clock's. The fix is the same scale-factor states, which absorb the rotation part; the
//! report says which it is, and the strides' part is the stride-length line's.

use super::SIGNIFICANT;
use super::analysis::Analysis;
use super::catalogue::{Effect, Fix};
use super::ranking::{Candidate, Finding};
use super::stride_length::StrideLength;
use corridor_shared::config::ConfigFile;

/// The spread of a walk's stride scale against its survey that comes from the gait, not from
/// the sensor, under a model with the rolling-foot stance update: the 14 normal-gait walks'
/// stride ratios with the default model (`docs/results/results.json`, `stride_ratio`) spread
/// by 0.7 % (standard deviation, about 1.000); taken as 1 %. Chosen on the suite as a whole.
pub const GAIT_SCALE_SD: f64 = 0.01;

/// The clock-rate error the strides measure, `[ε, σ]`: `√k̂ − 1` for a stride scale `k̂`, its σ
/// half the fit's and the gait's spread together (the square root halves a small scale).
/// `None` without footprints, or for a model without the rolling-foot stance update, whose
/// strides are 2 % short with a right clock.
pub fn clock_from_strides(file: &ConfigFile, fit: Option<&StrideLength>) -> Option<[f64; 2]> {
    let rolling = file.eskf.zupt_rolling_height_m.unwrap_or(0.0) > 0.0;
    let fit = fit.filter(|f| rolling && f.ratio > 0.0)?;
    Some([
        fit.ratio.sqrt() - 1.0,
        0.5 * GAIT_SCALE_SD.hypot(fit.std_err),
    ])
}

/// The inverse-variance weighted mean of the measurements `[value, σ]`, and its σ.
fn weighted_mean(m: &[[f64; 2]]) -> (f64, f64) {
    let w: Vec<f64> = m
        .iter()
        .map(|[_, sd]| 1.0 / (sd * sd).max(1e-300))
        .collect();
    let wsum: f64 = w.iter().sum();
    let mean = m.iter().zip(&w).map(|([s, _], w)| s * w).sum::<f64>() / wsum;
    (mean, (1.0 / wsum).sqrt())
}

/// Agreement within 2σ is no evidence where two axes hardly see their scale factor (σ of a
/// percent or more on a walk whose feet roll and pitch little): the common factor `mean` must
/// also fit the per-axis factors `[value, σ]` (and the strides' ε, where given) better (χ²)
/// than one axis alone, the one that shows the most, with the others at zero (a scale factor
/// on one axis leaves the strides alone; both one parameter).
fn common_factor_fits_better(sf: &[[f64; 2]; 3], strides: Option<[f64; 2]>, mean: f64) -> bool {
    let term = |x: f64, m: f64, sd: f64| ((x - m) / sd.max(1e-300)).powi(2);
    let z = |k: usize| (sf[k][0] / sf[k][1].max(1e-300)).abs();
    let lead = (0..3).max_by(|&a, &b| z(a).total_cmp(&z(b))).unwrap_or(2);
    let common: f64 = sf.iter().map(|[s, sd]| term(*s, mean, *sd)).sum::<f64>()
        + strides.map_or(0.0, |[e, sd]| term(e, mean, sd));
    let one_axis: f64 = (0..3)
        .map(|k| {
            term(
                sf[k][0],
                if k == lead { sf[lead][0] } else { 0.0 },
                sf[k][1],
            )
        })
        .sum::<f64>()
        + strides.map_or(0.0, |[e, sd]| term(e, 0.0, sd));
    common < one_axis
}

/// The clock-rate error `[ε, σ]` when the per-axis scale factors `sf` (`[value, σ]`) and the
/// strides' ε (where given) are one factor: the gyro axes each within 2σ of their weighted
/// mean, that mean a σ from zero the strides' way and the strides not showing less of it
/// (below), the common factor fitting better than one axis alone, and the mean of all of them
/// different from zero by 3σ.
///
/// The fitted scale factors are shrunk towards zero (the states' prior, and the heading aid
/// taking part of the error into the heading and the bias: a 3 % clock is fitted at 1.4–2.7 %
/// on the five walks with footprints at every stride), the strides' ε is not: the strides may
/// show more of the factor than the gyro axes, but not less beyond 2σ, nor the other sign.
pub fn clock_rate_error(sf: &[[f64; 2]; 3], strides: Option<[f64; 2]>) -> Option<[f64; 2]> {
    let (gyro, gyro_sd) = weighted_mean(sf);
    let gyro_agree = sf.iter().all(|[s, sd]| (s - gyro).abs() <= 2.0 * sd);
    // The gyro axes must show the factor too, their mean a σ from zero the strides' way:
    // strides alone are a stride scale (an accelerometer's, or the gait's), not a clock.
    let strides_agree = strides.is_none_or(|[e, sd]| {
        gyro * e.signum() >= gyro_sd && e * gyro.signum() >= gyro.abs() - 2.0 * gyro_sd.hypot(sd)
    });
    let mut m = sf.to_vec();
    m.extend(strides);
    let (mean, mean_sd) = weighted_mean(&m);
    (gyro_agree
        && strides_agree
        && common_factor_fits_better(sf, strides, mean)
        && mean.abs() > 3.0 * mean_sd)
        .then_some([mean, mean_sd])
}

/// Where the scale-factor model that explains the residuals is a clock-rate error
/// ([`clock_rate_error`], with the strides of `base` where `file`, its model, and the
/// footprints let them speak), `timing` takes the scale factor's score and fix among `base`'s
/// effects and the scale factor keeps half.
pub fn split_timing_from_scale(
    base: &mut Analysis,
    candidates: &mut Vec<Candidate>,
    file: &ConfigFile,
) {
    let fit = base.stride_length;
    let effects = &mut base.effects;
    let Some(sf_candidate) = candidates
        .iter()
        .find(|c| c.effect == Effect::GyroScaleFactor)
    else {
        return;
    };
    let Some(sf) = sf_candidate.analysis.scale_factor else {
        return;
    };
    let Some(i) = effects
        .iter()
        .position(|e| e.name == Effect::GyroScaleFactor)
    else {
        return;
    };
    // The strides only say which of the two a significant scale factor is: by themselves they
    // name no clock error (an accelerometer scale error stretches them too, which is the
    // stride-length line's).
    let strides =
        clock_from_strides(file, fit.as_ref()).filter(|_| effects[i].score >= SIGNIFICANT);
    let detail = format!(
        "scale factors of the fitted model ({:+.4} ± {:.4}, {:+.4} ± {:.4}, {:+.4} ± {:.4})",
        sf[0][0], sf[0][1], sf[1][0], sf[1][1], sf[2][0], sf[2][1]
    );
    let Some([mean, mean_sd]) = clock_rate_error(&sf, strides) else {
        effects[i].evidence = format!("{}; {detail}", effects[i].evidence);
        return;
    };
    let sc = effects[i].score;
    effects[i].evidence = format!(
        "{}; {detail}: the same on every axis{}",
        effects[i].evidence,
        if strides.is_some() {
            " and in the strides"
        } else {
            ""
        }
    );
    effects[i].score = 0.5 * sc;
    let stride_words = match (strides, fit) {
        (Some([e, sd]), Some(fit)) => format!(
            ", and the strides come out {:+.2} % against the survey, as a clock error ε = {:+.4} ± {:.4} stretches them ((1 + ε)²)",
            100.0 * (fit.ratio - 1.0),
            e,
            sd
        ),
        _ => String::new(),
    };
    // (The time-step test leaves no finding, and so no candidate, where the residuals could not
    // be regressed, e.g. too few used observations, while the scale factor comes from every
    // stance's residual: the clock's candidate is then the scale factor's model.)
    if !candidates.iter().any(|c| c.effect == Effect::Timing) {
        let clock = Candidate {
            effect: Effect::Timing,
            ..sf_candidate.clone()
        };
        candidates.push(clock);
    }
    let t = match effects.iter().position(|e| e.name == Effect::Timing) {
        Some(t) => t,
        None => {
            effects.push(Finding {
                name: Effect::Timing,
                score: 0.0,
                evidence:
                    "time-step deviations not tested: the used residuals could not be regressed"
                        .into(),
                fix: None,
                mde: None,
            });
            effects.len() - 1
        }
    };
    let t = &mut effects[t];
    // (The time-step test's own score stays when it is the higher.)
    t.score = t.score.max(sc);
    t.fix = Some(Fix::ScaleFactor);
    t.evidence = format!(
        "{}; every gyro axis shows the same scale factor{stride_words}: {:+.4} ± {:.4}, time stamps running {:.2} % {} (a clock-rate error)",
        t.evidence,
        mean,
        mean_sd,
        100.0 * mean.abs(),
        if mean > 0.0 { "fast" } else { "slow" }
    );
}

#[cfg(test)]
mod tests {
    use super::{clock_rate_error, common_factor_fits_better, weighted_mean};

    #[test]
    fn a_factor_on_one_axis_is_not_a_clock_error_even_when_the_others_hardly_see_it() {
        // exp24 with a +5 % z scale factor: x and y within 2σ of the mean only because they are
        // barely measured (%, ± σ). χ² 5.2 for the common factor against 1.2 for z alone.
        let sf = [[1.49, 1.48], [0.60, 1.39], [4.30, 1.06]];
        assert!(!common_factor_fits_better(&sf, None, weighted_mean(&sf).0));
        // A clock error: the same factor on every well-measured axis.
        let clock = [[3.1, 0.5], [2.8, 0.6], [3.0, 0.4]];
        assert!(common_factor_fits_better(
            &clock,
            None,
            weighted_mean(&clock).0
        ));
        // A σ of zero does not make a NaN that silently says "no".
        let exact = [[3.0, 0.0], [3.0, 0.5], [3.0, 0.5]];
        assert!(common_factor_fits_better(&exact, None, 3.0));
    }

    /// The scale factors the diagnosis fitted on exp37 (detection matrix, fractions) with the
    /// rolling-foot stance update, and the clock error its strides say (`√k̂ − 1`, σ 0.5 %).
    #[test]
    fn the_strides_a_clock_error_stretches_tell_it_from_a_z_scale_factor() {
        let strides = |ratio: f64| Some([ratio.sqrt() - 1.0, 0.005]);
        // A 1 % clock error: the gyro axes alone are not one factor different from zero by 3σ
        // (their mean 0.99 ± 0.57 %), with the strides 2.8 % long they are.
        let clock = [[0.0045, 0.0098], [0.0091, 0.0103], [0.0159, 0.0096]];
        assert_eq!(clock_rate_error(&clock, None), None);
        let [e, sd] = clock_rate_error(&clock, strides(1.0283)).unwrap();
        assert!((e - 0.0123).abs() < 0.001 && sd < 0.004, "{e} ± {sd}");
        // A 2 % z scale factor: the strides stay at their length, so it is not the clock's.
        let z_scale = [[-0.0036, 0.0099], [0.0036, 0.0104], [0.0200, 0.0096]];
        assert_eq!(clock_rate_error(&z_scale, strides(1.0076)), None);
        // Strides 2.7 % long under a 2 % accelerometer scale error, no gyro factor: their mean
        // (0.8 ± 0.4 %) is no clock error at 3σ. (A larger one would be, which is why the
        // strides only decide between the two for a scale factor the ranking finds significant:
        // `split_timing_from_scale`.)
        let accel = [[-0.0041, 0.0098], [0.0005, 0.0103], [0.0059, 0.0096]];
        assert_eq!(clock_rate_error(&accel, strides(1.0274)), None);
    }

    /// exp32 with a 3 % clock error: the fitted factors are shrunk (1.9 % on average) and the
    /// strides show the whole of it; strides that show less, or a clock of the other sign,
    /// are no clock error.
    #[test]
    fn the_strides_may_show_more_of_a_clock_error_than_the_shrunk_gyro_factors_not_less() {
        let strides = |ratio: f64| Some([ratio.sqrt() - 1.0, 0.005]);
        let clock = [[0.0043, 0.0113], [0.0237, 0.0121], [0.0303, 0.0115]];
        let [e, _] = clock_rate_error(&clock, strides(1.0681)).unwrap();
        assert!((0.025..0.035).contains(&e), "{e}");
        assert_eq!(clock_rate_error(&clock, strides(1.0)), None);
        assert_eq!(clock_rate_error(&clock, strides(0.94)), None);
    }

    /// Strides 4 % long with gyro factors at zero (a review: the mean 1.15 ± 0.38 % passed
    /// every other test on the strides alone): a stride scale, not a clock.
    #[test]
    fn strides_alone_are_no_clock_error() {
        let none = [[0.0, 0.01], [0.0, 0.01], [0.0, 0.01]];
        assert_eq!(clock_rate_error(&none, Some([0.02, 0.005])), None);
    }
}
