//! Did the bias move more than the model's random walk allows? A test on the filter's own bias
//! estimate, independent of which heading observations it accepted.
//!
//! In the error-state filter the gyro bias is a random walk (`Φ = I`, process noise `q·dt`) that
//! only the updates move. Under the model, the change of the estimate between two times is the
//! sum of the corrections `K·ν` in between, independent of what came before, with variance
//! `Σ K S Kᵀ = P(t₁) + q·(t₂ − t₁) − P(t₂)` (each update removes from `P` exactly the variance it
//! adds to the estimate). So the change over each block of [`BLOCK_S`], divided by that σ, is a
//! standard normal, and their squares over the walk sum to a χ² with one degree per block. A bias
//! that stepped or drifted faster than the random walk, and that the filter followed, makes it
//! large; residual tests miss that case, because a followed bias leaves no trend in the
//! residuals, and a bias that ran away from the filter leaves only rejected ones.
//!
//! Blocks of 20 s: about the time constant with which the diagnosis model (random walk 1e-4
//! rad/s/√s, 3° observations at about one per second) follows a bias change, `(q/R)^(-1/4)`;
//! 10 s and 30 s gave the same verdicts on the suite's injections. On the 14 clean normal-gait
//! walks the increments come out smaller than the model allows (χ² scores ≤ 1.2): the test is
//! conservative there, where the filter's bias σ is pessimistic.

use super::catalogue::{Effect, Fix};
use super::ranking::Finding;
use serde::Serialize;

/// Length of one block, s.
pub const BLOCK_S: f64 = 20.0;

/// Time after the start of tracking before the first block, s (the bias and its σ are set when
/// tracking starts).
pub const SETTLE_S: f64 = 1.0;

/// The test on one run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BiasChange {
    /// −log₁₀ p of the χ² of the standardised block changes, largest over the axes, with the
    /// three axes' multiplicity taken into account (Šidák).
    pub score: f64,
    /// The axis with that score (0 x, 1 y, 2 z, sensor axes).
    pub axis: usize,
    /// χ² and blocks on that axis.
    pub chi2: f64,
    /// Blocks.
    pub blocks: usize,
    /// The largest standardised change on that axis, and the time its block ends, s.
    pub largest: (f64, f64),
    /// The share of the χ² in the largest block: near 1 for a step, small for a drift.
    pub largest_share: f64,
}

/// Runs the test on a bias trace from `from_s` on: times, estimates and σ per sample, and the
/// bias random walk `rw_rad_s_sqrt_s`. `None` when the trace holds less than two blocks.
pub fn bias_change(
    t_s: &[f64],
    bias_rad_s: &[[f64; 3]],
    bias_sd_rad_s: &[[f64; 3]],
    rw_rad_s_sqrt_s: f64,
    from_s: f64,
) -> Option<BiasChange> {
    let q = rw_rad_s_sqrt_s * rw_rad_s_sqrt_s;
    let start = from_s + SETTLE_S;
    // block boundaries: the first sample at or after each multiple of BLOCK_S from `start`
    let mut edges = Vec::new();
    let mut next = start;
    for (i, &t) in t_s.iter().enumerate() {
        if t >= next {
            edges.push(i);
            next = t + BLOCK_S;
        }
    }
    if edges.len() < 3 {
        return None;
    }
    let mut best: Option<BiasChange> = None;
    for axis in 0..3 {
        let mut chi2 = 0.0;
        let mut largest = (0.0_f64, t_s[edges[1]]);
        let mut largest_sq = 0.0;
        let mut blocks = 0;
        for w in edges.windows(2) {
            let (i, j) = (w[0], w[1]);
            let (p_i, p_j) = (
                bias_sd_rad_s[i][axis].powi(2),
                bias_sd_rad_s[j][axis].powi(2),
            );
            let var = p_i + q * (t_s[j] - t_s[i]) - p_j;
            if var.is_nan() || var <= 0.0 {
                continue;
            }
            let z = (bias_rad_s[j][axis] - bias_rad_s[i][axis]) / var.sqrt();
            if !z.is_finite() {
                continue;
            }
            chi2 += z * z;
            blocks += 1;
            if z * z > largest_sq {
                largest_sq = z * z;
                largest = (z, t_s[j]);
            }
        }
        if blocks == 0 {
            continue;
        }
        let p = crate::stats::chi2_sf(chi2, blocks as f64);
        // Šidák over the three axes: 1 − (1 − p)³, kept accurate for small p
        let p3 = -(3.0 * (-p).ln_1p()).exp_m1();
        let score = if p3 > 0.0 {
            (-p3.log10()).clamp(0.0, 30.0)
        } else {
            30.0
        };
        let c = BiasChange {
            score,
            axis,
            chi2,
            blocks,
            largest,
            largest_share: if chi2 > 0.0 { largest_sq / chi2 } else { 0.0 },
        };
        if best.as_ref().is_none_or(|b| c.score > b.score) {
            best = Some(c);
        }
    }
    best
}

/// Adds the test to the bias-drift finding: its score when larger, the fix a step (most of the
/// χ² in one block) or a drift calls for, and the figures in the evidence.
pub fn apply_bias_change(effects: &mut [Finding], c: &BiasChange) {
    let Some(f) = effects.iter_mut().find(|f| f.name == Effect::BiasDrift) else {
        return;
    };
    let step_like = c.largest_share > 0.5;
    f.evidence = format!(
        "{}; the filter's bias against its random walk, axis {}: χ² {:.1} over {} blocks of \
         {BLOCK_S:.0} s (score {:.1}), largest change {:+.1}σ in the block ending at {:.1} s \
         ({:.0} % of the χ²: {})",
        f.evidence,
        ["x", "y", "z"][c.axis],
        c.chi2,
        c.blocks,
        c.score,
        c.largest.0,
        c.largest.1,
        100.0 * c.largest_share,
        if step_like { "step-like" } else { "drift-like" }
    );
    if c.score > f.score {
        f.score = c.score;
        f.fix = Some(if step_like {
            Fix::BiasRandomWalkTimes10
        } else {
            Fix::BiasRate
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A trace sampled at 10 Hz for `secs` seconds: a filter that has settled to σ `sd` and
    /// whose estimate moves by `moves(t)` (the same on every axis).
    fn trace(
        secs: f64,
        sd: f64,
        moves: impl Fn(f64) -> f64,
    ) -> (Vec<f64>, Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let t: Vec<f64> = (0..(secs * 10.0) as usize)
            .map(|k| k as f64 * 0.1)
            .collect();
        let b = t.iter().map(|&t| [moves(t); 3]).collect();
        let s = t.iter().map(|_| [sd; 3]).collect();
        (t, b, s)
    }

    #[test]
    fn a_bias_that_moves_as_the_random_walk_allows_scores_low() {
        // settled σ: the block variance is q·20 s; changes of one σ per block alternate in sign
        let rw = 1e-4;
        let sd_block = rw * BLOCK_S.sqrt();
        let (t, b, s) = trace(200.0, 5e-4, |t| {
            if ((t - SETTLE_S) / BLOCK_S).floor() as i64 % 2 == 0 {
                0.0
            } else {
                sd_block
            }
        });
        let c = bias_change(&t, &b, &s, rw, 0.0).unwrap();
        assert!(c.blocks >= 8, "{c:?}");
        assert!(c.score < 1.0, "{c:?}");
    }

    #[test]
    fn a_step_the_filter_followed_scores_high_and_is_placed() {
        let rw = 1e-4;
        let (t, b, s) = trace(200.0, 5e-4, |t| if t >= 100.0 { 0.01 } else { 0.0 });
        let c = bias_change(&t, &b, &s, rw, 0.0).unwrap();
        assert!(c.score >= 10.0, "{c:?}");
        assert!(c.largest_share > 0.9, "a step: {c:?}");
        assert!((c.largest.1 - 101.0).abs() <= BLOCK_S, "{c:?}");
        // the same step under a random walk ten times faster is what the model allows
        let fast = bias_change(&t, &b, &s, 1e-2, 0.0).unwrap();
        assert!(fast.score < 1.0, "{fast:?}");
    }

    #[test]
    fn a_drift_spreads_over_the_blocks() {
        let rw = 1e-4;
        let (t, b, s) = trace(200.0, 5e-4, |t| 1e-4 * t);
        let c = bias_change(&t, &b, &s, rw, 0.0).unwrap();
        assert!(c.score >= 10.0, "{c:?}");
        assert!(c.largest_share < 0.3, "a drift: {c:?}");
    }

    #[test]
    fn a_shrinking_sigma_allows_the_change_it_explains() {
        // From the prior's σ 1e-2 down to 1e-3 in the first block: a change of 5e-3 there is
        // half a σ of what that update may move, not a bias change.
        let rw = 1e-4;
        let t: Vec<f64> = (0..2000).map(|k| k as f64 * 0.1).collect();
        let s: Vec<[f64; 3]> = t
            .iter()
            .map(|&t| [if t < 10.0 { 1e-2 } else { 1e-3 }; 3])
            .collect();
        let b: Vec<[f64; 3]> = t
            .iter()
            .map(|&t| [if t < 10.0 { 0.0 } else { 5e-3 }; 3])
            .collect();
        let c = bias_change(&t, &b, &s, rw, 0.0).unwrap();
        assert!(c.score < 1.0, "{c:?}");
        assert!(
            bias_change(&t[..300], &b[..300], &s[..300], rw, 0.0).is_none(),
            "one block"
        );
    }
}
