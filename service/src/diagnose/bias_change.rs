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
//!
//! The onset of walking ([`onset_change`]): a bias has no reason to change when the walk begins,
//! a rate error that depends on the motion (a g-sensitivity) does, along the specific force the
//! walking adds (a stride's mean specific force minus the rest's, about 3 m/s² along the sensor's
//! x axis on the suite's walks). The first block's change along that force, over its σ, is a
//! standard normal under the model. Over the detection matrix's walks an injected
//! 0.02 rad/s per m/s² moves it by 8–14σ on 10 of 11, every other injection by less than 3.5σ
//! but a gyro clipped at ±5 rad/s (up to 18σ either way; its rail's finding goes first), the
//! clean walks by less than 1.5σ. Where it is significant and the change points along the
//! force (cosine ≥ [`ONSET_MIN_COS`]), the drift test runs across that direction
//! ([`BiasTrace::change_across`]); the filter keeps following the offset for minutes, so the drift can
//! still reach the cap, and among equal scores the motion's explanation goes first.

use super::catalogue::{Effect, Fix};
use super::ranking::Finding;
use nalgebra::Vector3;
use serde::Serialize;

/// Length of one block, s.
pub const BLOCK_S: f64 = 20.0;

/// Time after the start of tracking before the first block, s (the bias and its σ are set when
/// tracking starts).
pub const SETTLE_S: f64 = 1.0;

/// The test on one run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BiasChange {
    /// −log₁₀ p of the χ² of the standardised block changes, largest over the directions
    /// tested, with their multiplicity taken into account (Šidák).
    pub score: f64,
    /// The direction with that score, a unit vector in sensor axes (an axis unless the onset
    /// direction was taken out: [`BiasTrace::change_across`]).
    pub direction: [f64; 3],
    /// χ² and blocks along that direction.
    pub chi2: f64,
    /// Blocks.
    pub blocks: usize,
    /// The largest standardised change along that direction, and the time its block ends, s.
    pub largest: (f64, f64),
    /// The share of the χ² in the largest block: near 1 for a step, small for a drift.
    pub largest_share: f64,
    /// The first block's change on every axis, for the onset test ([`onset_change`]).
    pub first_block: FirstBlock,
    /// The directions tested (sensor axes, unit vectors).
    #[serde(skip)]
    pub directions: Vec<[f64; 3]>,
    /// Every block's change and its variance under the model, per axis: the test along any
    /// direction, for the detectable step and ramp ([`super::drift_power`]).
    #[serde(skip)]
    pub blocks_per_axis: Vec<BlockChange>,
    /// The time each block ends, s (the probe's blocks must be the same ones).
    #[serde(skip)]
    pub block_end_s: Vec<f64>,
    /// The bias step on the sensor's z axis at the middle of the walk that this test detects
    /// half the time, rad/s (from a probe injection: [`super::drift_power::drift_mde`]);
    /// `None` until measured, or when the probe's run gave no comparable test.
    pub step_mde_rad_s: Option<f64>,
    /// The same for a bias ramp on z from a tenth of the walk, rad/s².
    pub ramp_mde_rad_s2: Option<f64>,
}

/// One block's change of the bias estimate and the variance the model allows it, per axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockChange {
    /// Change, rad/s, sensor axes.
    pub change_rad_s: [f64; 3],
    /// Its variance under the random walk, (rad/s)².
    pub var_rad2_s2: [f64; 3],
}

impl BlockChange {
    /// The standardised change along `dir` (unit vector, sensor axes; the axes' variances
    /// combined as if independent, only the axes the direction has: a NaN σ elsewhere does not
    /// matter); `None` where the variance is not positive.
    pub fn standardised_along(&self, dir: &[f64; 3]) -> Option<f64> {
        let (mut change, mut var) = (0.0, 0.0);
        for a in (0..3).filter(|&a| dir[a] != 0.0) {
            change += dir[a] * self.change_rad_s[a];
            var += dir[a] * dir[a] * self.var_rad2_s2[a];
        }
        if var.is_nan() || var <= 0.0 {
            return None;
        }
        let z = change / var.sqrt();
        z.is_finite().then_some(z)
    }
}

/// The change of the bias estimate over the first block after tracking began, every axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FirstBlock {
    /// Start and end, s.
    pub span_s: (f64, f64),
    /// Change of the estimate, rad/s, sensor axes.
    pub change_rad_s: [f64; 3],
    /// Its variance under the model's random walk, (rad/s)².
    pub var_rad2_s2: [f64; 3],
}

/// Block boundaries of a trace: the first sample at or after every [`BLOCK_S`] from
/// `from_s + SETTLE_S`.
fn block_edges(t_s: &[f64], from_s: f64) -> Vec<usize> {
    let mut edges = Vec::new();
    let mut next = from_s + SETTLE_S;
    for (i, &t) in t_s.iter().enumerate() {
        if t >= next {
            edges.push(i);
            next = t + BLOCK_S;
        }
    }
    edges
}

/// The variance the random walk allows the change between samples `i` and `j` on `axis`.
fn change_var(t_s: &[f64], sd: &[[f64; 3]], q: f64, i: usize, j: usize, axis: usize) -> f64 {
    sd[i][axis].powi(2) + q * (t_s[j] - t_s[i]) - sd[j][axis].powi(2)
}

/// The filter's bias estimate over a run: times, estimates and σ per sample (sensor axes), the
/// bias random walk of the model, and when tracking began.
#[derive(Debug, Clone, Copy)]
pub struct BiasTrace<'a> {
    /// Times, s.
    pub t_s: &'a [f64],
    /// Estimates, rad/s.
    pub bias_rad_s: &'a [[f64; 3]],
    /// Their σ, rad/s.
    pub bias_sd_rad_s: &'a [[f64; 3]],
    /// The model's bias random walk, rad/s/√s.
    pub rw_rad_s_sqrt_s: f64,
    /// Start of tracking, s.
    pub from_s: f64,
}

impl BiasTrace<'_> {
    /// The test along each sensor axis. `None` when the trace holds less than two blocks.
    pub fn change(&self) -> Option<BiasChange> {
        self.test_along(&[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    }

    /// The test along the two directions across `u` (sensor axes): the change a motion-
    /// dependent rate error makes along `u` left out (see [`onset_change`]).
    pub fn change_across(&self, u: &[f64; 3]) -> Option<BiasChange> {
        let u = Vector3::from(*u).try_normalize(0.0)?;
        // the axis least aligned with u, made orthogonal to it; then their cross product
        let k = (0..3).min_by(|&a, &b| u[a].abs().total_cmp(&u[b].abs()))?;
        let e1 = (Vector3::ith(k, 1.0) - u * u[k]).normalize();
        let e2 = u.cross(&e1);
        self.test_along(&[e1.into(), e2.into()])
    }

    /// The χ² test of the standardised block changes along each of `dirs` (unit vectors, sensor
    /// axes; the axes' variances combined as if independent), the best with Šidák over `dirs`.
    fn test_along(&self, dirs: &[[f64; 3]]) -> Option<BiasChange> {
        let BiasTrace {
            t_s,
            bias_rad_s,
            bias_sd_rad_s,
            rw_rad_s_sqrt_s,
            from_s,
        } = *self;
        let q = rw_rad_s_sqrt_s * rw_rad_s_sqrt_s;
        let edges = block_edges(t_s, from_s);
        if edges.len() < 3 {
            return None;
        }
        let (i0, i1) = (edges[0], edges[1]);
        let first_block = FirstBlock {
            span_s: (t_s[i0], t_s[i1]),
            change_rad_s: std::array::from_fn(|a| bias_rad_s[i1][a] - bias_rad_s[i0][a]),
            var_rad2_s2: std::array::from_fn(|a| change_var(t_s, bias_sd_rad_s, q, i0, i1, a)),
        };
        let blocks_per_axis: Vec<BlockChange> = edges
            .windows(2)
            .map(|w| {
                let (i, j) = (w[0], w[1]);
                BlockChange {
                    change_rad_s: std::array::from_fn(|a| bias_rad_s[j][a] - bias_rad_s[i][a]),
                    var_rad2_s2: std::array::from_fn(|a| {
                        change_var(t_s, bias_sd_rad_s, q, i, j, a)
                    }),
                }
            })
            .collect();
        let mut best: Option<BiasChange> = None;
        for dir in dirs {
            let mut chi2 = 0.0;
            let mut largest = (0.0_f64, t_s[edges[1]]);
            let mut largest_sq = 0.0;
            let mut blocks = 0;
            for (b, &j) in blocks_per_axis.iter().zip(&edges[1..]) {
                let Some(z) = b.standardised_along(dir) else {
                    continue;
                };
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
            let score = sidak_score(crate::stats::chi2_sf(chi2, blocks as f64), dirs.len());
            if best.as_ref().is_none_or(|b| score > b.score) {
                best = Some(BiasChange {
                    score,
                    direction: *dir,
                    chi2,
                    blocks,
                    largest,
                    largest_share: if chi2 > 0.0 { largest_sq / chi2 } else { 0.0 },
                    first_block,
                    directions: Vec::new(),
                    blocks_per_axis: Vec::new(),
                    block_end_s: Vec::new(),
                    step_mde_rad_s: None,
                    ramp_mde_rad_s2: None,
                });
            }
        }
        // the blocks and directions, for the detectable sizes, once for the best direction
        best.map(|c| BiasChange {
            directions: dirs.to_vec(),
            block_end_s: edges[1..].iter().map(|&j| t_s[j]).collect(),
            blocks_per_axis,
            ..c
        })
    }
}

/// The test's score from one direction's p-value, Šidák over `n` directions: −log₁₀ of
/// 1 − (1 − p)ⁿ (kept accurate for small p), capped at 30.
pub fn sidak_score(p: f64, n: usize) -> f64 {
    let pn = -(n as f64 * (-p).ln_1p()).exp_m1();
    if pn > 0.0 {
        (-pn.log10()).clamp(0.0, 30.0)
    } else {
        30.0
    }
}

/// The direction in words: the axis, or the vector.
fn direction_words(d: &[f64; 3]) -> String {
    match d {
        [x, 0.0, 0.0] if *x == 1.0 => "axis x".into(),
        [0.0, y, 0.0] if *y == 1.0 => "axis y".into(),
        [0.0, 0.0, z] if *z == 1.0 => "axis z".into(),
        _ => format!("along ({:+.2}, {:+.2}, {:+.2})", d[0], d[1], d[2]),
    }
}

/// A rate error that depends on the motion, seen in the bias estimate: the change over the
/// first block after tracking began along the change of the mean specific force between the
/// initial rest and that block.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct OnsetChange {
    /// The first block's bias change along the force change, over its σ.
    pub z: f64,
    /// −log₁₀ of its two-sided p.
    pub score: f64,
    /// Cosine between the first block's bias change and the force change.
    pub cos: f64,
    /// The force change, m/s², sensor axes.
    pub force_m_s2: [f64; 3],
    /// The bias change along the force change per m/s² of it, rad/s per m/s²: the part of a
    /// g-sensitivity the filter took up within the block (a lower bound of its size).
    pub k_taken_up: f64,
    /// The smallest g-sensitivity this test names on this walk, rad/s per m/s² (from an
    /// injection: [`onset_mde`]); `None` until measured.
    pub mde: Option<f64>,
}

/// The g-sensitivity whose expected onset score is the ranking's threshold: `z` moves by
/// `(injected.z − clean.z) / size` per unit of an injected g-sensitivity of `size`, so the
/// detectable size is [`super::power::MDE_Z`] over that slope. `None` when the injection did
/// not move it.
pub fn onset_mde(clean: &OnsetChange, injected: &OnsetChange, size: f64) -> Option<f64> {
    let slope = (injected.z - clean.z) / size;
    let m = super::power::MDE_Z / slope.abs();
    (m.is_finite() && slope != 0.0).then_some(m)
}

/// Below this cosine the first block's bias change does not point along the force change.
pub const ONSET_MIN_COS: f64 = 0.7;

impl OnsetChange {
    /// The change is significant and points along the force change.
    pub fn explains(&self) -> bool {
        self.score >= super::SIGNIFICANT && self.cos.abs() >= ONSET_MIN_COS
    }
}

/// The onset test of `c`'s first block against the force change `force_m_s2` (see
/// [`OnsetChange`]). A bias has no reason to change when walking begins; a g-sensitivity (or
/// any rate error that depends on the motion) does exactly then, along the specific force the
/// walking adds: on the suite's walks about 3 m/s² along the sensor's x axis, the foot pitched
/// on average over a stride.
pub fn onset_change(c: &BiasChange, force_m_s2: &[f64; 3]) -> Option<OnsetChange> {
    let df = Vector3::from(*force_m_s2);
    let u = df.try_normalize(1e-6)?;
    let fb = &c.first_block;
    let db = Vector3::from(fb.change_rad_s);
    let var: f64 = (0..3).map(|a| u[a] * u[a] * fb.var_rad2_s2[a]).sum();
    if var.is_nan() || var <= 0.0 {
        return None;
    }
    let z = db.dot(&u) / var.sqrt();
    let p = 2.0 * (1.0 - crate::stats::normal_cdf(z.abs()));
    Some(OnsetChange {
        z,
        score: (-p.max(1e-30).log10()).clamp(0.0, 30.0),
        cos: db.dot(&u) / db.norm().max(f64::MIN_POSITIVE),
        force_m_s2: *force_m_s2,
        k_taken_up: db.dot(&df) / df.norm_squared(),
        mde: None,
    })
}

/// Adds the onset test to the g-sensitivity finding (its score when larger, its fix, the figures
/// in the evidence), when it [`explains`](OnsetChange::explains) the first block's change. The
/// bias change it explains also raises the bias-drift finding (the filter keeps following the
/// offset for minutes): among equal scores (both at the cap) the motion's explanation goes
/// first, after a gyro rail's, as a rail's goes first among the changes it causes.
pub fn apply_onset_change(effects: &mut Vec<Finding>, o: &OnsetChange) {
    if !o.explains() {
        return;
    }
    let words = format!(
        "the filter's bias moved {:+.1}σ along the specific force walking adds ({:+.2}, {:+.2}, \
         {:+.2}) m/s² in its first {BLOCK_S:.0} s (cosine {:+.2}; score {:.1}): a rate error that \
         came with the motion, at least {:.1e} rad/s per m/s²",
        o.z,
        o.force_m_s2[0],
        o.force_m_s2[1],
        o.force_m_s2[2],
        o.cos,
        o.score,
        o.k_taken_up.abs()
    );
    let mut g = match effects.iter().position(|f| f.name == Effect::GSensitivity) {
        Some(i) => effects.remove(i),
        None => Finding {
            name: Effect::GSensitivity,
            score: 0.0,
            evidence: String::new(),
            fix: None,
            mde: None,
        },
    };
    g.evidence = if g.evidence.is_empty() {
        words
    } else {
        format!("{words}; {}", g.evidence)
    };
    if o.score > g.score {
        g.score = o.score;
        g.fix = Some(Fix::GSensitivity);
    }
    let first = usize::from(
        effects
            .first()
            .is_some_and(|f| f.name == Effect::GyroClipping),
    );
    effects.insert(first, g);
    // stable: the order above holds among equal scores
    effects.sort_by(|a, b| b.score.total_cmp(&a.score));
}

/// Adds the test to the bias-drift finding: its score when larger, the fix a step (most of the
/// χ² in one block) or a drift calls for, and the figures in the evidence.
pub fn apply_bias_change(effects: &mut Vec<Finding>, c: &BiasChange) {
    // The filter's own bias needs no used heading observation: with too few of them to test
    // the residuals, the drift's finding is this test's alone.
    let i = match effects.iter().position(|f| f.name == Effect::BiasDrift) {
        Some(i) => i,
        None => {
            effects.push(Finding {
                name: Effect::BiasDrift,
                score: 0.0,
                evidence: "residual tests: not made (too few used heading observations)".into(),
                fix: None,
                mde: None,
            });
            effects.len() - 1
        }
    };
    let f = &mut effects[i];
    let step_like = c.largest_share > 0.5;
    f.evidence = format!(
        "{}; the filter's bias against its random walk, {}: χ² {:.1} over {} blocks of \
         {BLOCK_S:.0} s (score {:.1}), largest change {:+.1}σ in the block ending at {:.1} s \
         ({:.0} % of the χ²: {})",
        f.evidence,
        direction_words(&c.direction),
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

    fn bias_trace<'a>(
        t_s: &'a [f64],
        bias_rad_s: &'a [[f64; 3]],
        bias_sd_rad_s: &'a [[f64; 3]],
        rw_rad_s_sqrt_s: f64,
    ) -> BiasTrace<'a> {
        BiasTrace {
            t_s,
            bias_rad_s,
            bias_sd_rad_s,
            rw_rad_s_sqrt_s,
            from_s: 0.0,
        }
    }

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
        let c = bias_trace(&t, &b, &s, rw).change().unwrap();
        assert!(c.blocks >= 8, "{c:?}");
        assert!(c.score < 1.0, "{c:?}");
    }

    #[test]
    fn a_step_the_filter_followed_scores_high_and_is_placed() {
        let rw = 1e-4;
        let (t, b, s) = trace(200.0, 5e-4, |t| if t >= 100.0 { 0.01 } else { 0.0 });
        let c = bias_trace(&t, &b, &s, rw).change().unwrap();
        assert!(c.score >= 10.0, "{c:?}");
        assert!(c.largest_share > 0.9, "a step: {c:?}");
        assert!((c.largest.1 - 101.0).abs() <= BLOCK_S, "{c:?}");
        // the same step under a random walk ten times faster is what the model allows
        let fast = bias_trace(&t, &b, &s, 1e-2).change().unwrap();
        assert!(fast.score < 1.0, "{fast:?}");
    }

    #[test]
    fn the_bias_change_names_a_drift_where_the_residuals_could_not_be_tested() {
        // The ranking had too few used heading observations to test the residuals: only
        // `unexplained`. The filter's own bias still shows the step.
        let (t, b, s) = trace(200.0, 5e-4, |t| if t >= 100.0 { 0.01 } else { 0.0 });
        let c = bias_trace(&t, &b, &s, 1e-4).change().unwrap();
        let mut effects = vec![Finding {
            name: Effect::Unexplained,
            score: 0.0,
            evidence: "only 3 heading observations: too few to test".into(),
            fix: None,
            mde: None,
        }];
        apply_bias_change(&mut effects, &c);
        let drift = effects
            .iter()
            .find(|f| f.name == Effect::BiasDrift)
            .unwrap();
        assert_eq!(drift.score, c.score);
        assert_eq!(drift.fix, Some(Fix::BiasRandomWalkTimes10), "a step");
    }

    #[test]
    fn a_drift_spreads_over_the_blocks() {
        let rw = 1e-4;
        let (t, b, s) = trace(200.0, 5e-4, |t| 1e-4 * t);
        let c = bias_trace(&t, &b, &s, rw).change().unwrap();
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
        let c = bias_trace(&t, &b, &s, rw).change().unwrap();
        assert!(c.score < 1.0, "{c:?}");
        assert!(
            bias_trace(&t[..300], &b[..300], &s[..300], rw)
                .change()
                .is_none(),
            "one block"
        );
    }

    /// A trace whose bias moves by `step` (sensor axes) in its first block, then stays.
    fn onset_trace(step: [f64; 3]) -> (Vec<f64>, Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let t: Vec<f64> = (0..1200).map(|k| k as f64 * 0.1).collect();
        let b = t
            .iter()
            .map(|&t| {
                let f = ((t - SETTLE_S) / BLOCK_S).clamp(0.0, 1.0);
                step.map(|s| s * f)
            })
            .collect();
        let s = t.iter().map(|_| [5e-4; 3]).collect();
        (t, b, s)
    }

    #[test]
    fn a_bias_change_along_the_force_of_walking_at_its_onset_is_the_motions() {
        let rw = 1e-4;
        // the force walking adds, mostly along x; a bias change of k times it
        let force = [3.0, 0.5, -0.8];
        let k = 2e-3;
        let (t, b, s) = onset_trace(force.map(|f| k * f));
        let c = bias_trace(&t, &b, &s, rw).change().unwrap();
        assert!(c.score >= 10.0, "the axes see it: {c:?}");
        let o = onset_change(&c, &force).unwrap();
        assert!(o.explains(), "{o:?}");
        assert!(
            (o.cos - 1.0).abs() < 1e-9 && (o.k_taken_up - k).abs() < 1e-12,
            "{o:?}"
        );
        // across the force direction nothing is left
        let across = bias_trace(&t, &b, &s, rw).change_across(&force).unwrap();
        assert!(across.score < 1.0, "{across:?}");
        // a change of the same size across the force direction is no onset, and the test
        // across it still sees it
        let step = Vector3::from(force).cross(&Vector3::z()).normalize() * (k * 3.2);
        let (t, b, s) = onset_trace(step.into());
        let c = bias_trace(&t, &b, &s, rw).change().unwrap();
        let o = onset_change(&c, &force).unwrap();
        assert!(!o.explains() && o.cos.abs() < 1e-9, "{o:?}");
        let across = bias_trace(&t, &b, &s, rw).change_across(&force).unwrap();
        assert!(across.score >= 10.0, "{across:?}");
    }

    #[test]
    fn the_onset_detectable_size_is_the_threshold_over_the_slope() {
        let (t, b, s) = onset_trace([1e-3, 0.0, 0.0]);
        let c = bias_trace(&t, &b, &s, 1e-4).change().unwrap();
        let clean = onset_change(&c, &[3.0, 0.0, 0.0]).unwrap();
        let injected = OnsetChange {
            z: clean.z + 1.0,
            ..clean
        };
        let m = onset_mde(&clean, &injected, 2e-3).unwrap();
        assert!((m - super::super::power::MDE_Z * 2e-3).abs() < 1e-12, "{m}");
        assert!(onset_mde(&clean, &clean, 2e-3).is_none());
    }

    #[test]
    fn the_motion_explains_the_drift_it_causes_but_not_a_rail() {
        let finding = |name, score| Finding {
            name,
            score,
            evidence: String::new(),
            fix: None,
            mde: None,
        };
        let onset = OnsetChange {
            z: 12.0,
            score: 30.0,
            cos: 0.9,
            force_m_s2: [3.0, 0.0, 0.0],
            k_taken_up: 1e-3,
            mde: None,
        };
        let mut effects = vec![
            finding(Effect::GyroClipping, 30.0),
            finding(Effect::BiasDrift, 30.0),
            finding(Effect::GSensitivity, 0.5),
        ];
        apply_onset_change(&mut effects, &onset);
        let names: Vec<Effect> = effects.iter().map(|f| f.name).collect();
        assert_eq!(
            names,
            [
                Effect::GyroClipping,
                Effect::GSensitivity,
                Effect::BiasDrift
            ]
        );
        assert_eq!(effects[1].fix, Some(Fix::GSensitivity));
        // a change that does not point along the force leaves the ranking as it was
        let mut effects = vec![finding(Effect::BiasDrift, 30.0)];
        apply_onset_change(&mut effects, &OnsetChange { cos: 0.3, ..onset });
        assert_eq!(effects.len(), 1);
    }
}
