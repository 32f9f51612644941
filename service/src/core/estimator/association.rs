//! The association of an observed direction with the dominant directions, weighted by its
//! posterior probability.

use crate::core::heading::{HeadingAid, Rejection};
use crate::core::rotation::wrap_pi;
use corridor_shared::config::HeadingConfig;

/// Associates `value_rad` (a walking or foot heading, with innovation variance `s_rad2`)
/// with the nearest dominant direction, and weighs the association: the posterior probability
/// that the walker walks along that direction rather than in some other direction (uniform over
/// the spacing of the candidate directions), with prior `heading.aligned_prior`. Below
/// `heading.min_weight` the observation is rejected as unlikely. `wide_gate`: the gate is at
/// least 3√`s_rad2` (a heading taken as lost, see `reacquire.rs`).
pub(super) fn weighted_association(
    aid: &HeadingAid,
    h: &HeadingConfig,
    xy: [f64; 2],
    value_rad: f64,
    s_rad2: f64,
    wide_gate: bool,
) -> Result<(f64, f64), Rejection> {
    let gate = if wide_gate {
        h.gate_rad.get().max(3.0 * s_rad2.sqrt())
    } else {
        h.gate_rad.get()
    };
    let dir = aid.associate(xy, value_rad, gate)?;
    let w = association_weight(
        wrap_pi(dir - value_rad),
        s_rad2,
        h.aligned_prior.get(),
        aid.spacing_rad(),
    );
    if w < h.min_weight.get() || w <= 0.0 {
        return Err(Rejection::Unlikely);
    }
    Ok((dir, w))
}

/// Posterior probability that the walker walks along the associated (nearest) direction, for
/// residual `r_rad` with innovation variance `s_rad2`: against walking along one of the other
/// candidate directions (`r_rad + m·spacing_rad`, m ≠ 0) and against walking in any direction
/// (uniform over `spacing_rad`), with prior `prior` of being aligned with some candidate. When
/// the heading is too uncertain to tell the candidates apart (a long unaided stretch without a
/// bias prior), the weight falls and the observation is not fused with a wrong direction.
pub fn association_weight(r_rad: f64, s_rad2: f64, prior: f64, spacing_rad: f64) -> f64 {
    let density =
        |r: f64| (-0.5 * r * r / s_rad2).exp() / (2.0 * std::f64::consts::PI * s_rad2).sqrt();
    let nearest = prior * density(r_rad);
    // Candidates cover the circle once: at most 360 of them, their density vanishes fast.
    let n = (std::f64::consts::TAU / spacing_rad).round().max(1.0) as i64;
    let others: f64 = (1..n)
        .map(|m| {
            let r = crate::core::rotation::wrap_pi(r_rad + m as f64 * spacing_rad);
            prior * density(r)
        })
        .sum();
    let anywhere = (1.0 - prior) / spacing_rad;
    nearest / (nearest + others + anywhere)
}

#[cfg(test)]
mod association_tests {
    use super::association_weight;

    #[test]
    fn the_weight_falls_with_the_residual_and_with_ambiguity() {
        let deg = f64::to_radians;
        let quarter = deg(90.0);
        let s = deg(2.0).powi(2);
        let on = association_weight(0.0, s, 0.7, quarter);
        let off = association_weight(deg(8.0), s, 0.7, quarter);
        assert!(on > 0.95 && off < 0.1, "{on} {off}");
        // A heading σ of 30°: the grid directions 90° apart can no longer be told apart.
        let vague = association_weight(0.0, deg(30.0).powi(2), 0.7, quarter);
        assert!(vague < on, "{vague}");
        // The weight is a probability.
        for r in [-3.0, -0.5, 0.0, 0.2, 1.5] {
            let w = association_weight(r, s, 0.7, quarter);
            assert!((0.0..=1.0).contains(&w));
        }
    }
}
