//! The association of an observed direction with the dominant directions, weighted by its
//! posterior probability.

use crate::core::heading::{Candidates, HeadingAid, Rejection};
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
    let (dir, candidates) = aid.associate_among(xy, value_rad, gate)?;
    let w = association_weight(
        wrap_pi(dir - value_rad),
        s_rad2,
        h.aligned_prior.get(),
        &candidates,
    );
    if w < h.min_weight.get() || w <= 0.0 {
        return Err(Rejection::Unlikely);
    }
    Ok((dir, w))
}

/// Posterior probability that the walker walks along the associated (nearest) direction, for
/// residual `r_rad` with innovation variance `s_rad2`: against walking along one of the other
/// candidate directions (at `r_rad` plus each one's offset) and against walking in any direction
/// (uniform over the circle, with the weight of as many candidates as there are), with prior
/// `prior` of being aligned with some candidate. When the heading is too uncertain to tell the
/// candidates apart (a long unaided stretch without a bias prior), the weight falls and the
/// observation is not fused with a wrong direction. Where corridors cross, the perpendicular
/// ones are candidates too: a junction's four directions make a stride 10° off one of them less
/// likely aligned than a single corridor's two.
pub fn association_weight(r_rad: f64, s_rad2: f64, prior: f64, candidates: &Candidates) -> f64 {
    let (nearest, total) = association_mixture(r_rad, s_rad2, prior, candidates);
    nearest / total
}

/// The two densities [`association_weight`] is the ratio of, for residual `r_rad` against the
/// nearest direction: walking along the nearest direction (its prior times a normal density),
/// and walking along any candidate or in any direction at all (the mixture's whole density,
/// rad⁻¹). The diagnosis compares fits by the second's likelihood.
pub fn association_mixture(
    r_rad: f64,
    s_rad2: f64,
    prior: f64,
    candidates: &Candidates,
) -> (f64, f64) {
    let density =
        |r: f64| (-0.5 * r * r / s_rad2).exp() / (2.0 * std::f64::consts::PI * s_rad2).sqrt();
    let nearest = prior * density(r_rad);
    match *candidates {
        Candidates::Spaced { spacing_rad } => {
            // Candidates cover the circle once: at most 360 of them, their density vanishes
            // fast.
            let n = (std::f64::consts::TAU / spacing_rad).round().max(1.0) as i64;
            let others: f64 = (1..n)
                .map(|m| {
                    let r = wrap_pi(r_rad + m as f64 * spacing_rad);
                    prior * density(r)
                })
                .sum();
            let anywhere = (1.0 - prior) / spacing_rad;
            (nearest, nearest + others + anywhere)
        }
        Candidates::Listed { offsets_rad, n } => {
            let n = usize::from(n).max(1);
            let others: f64 = offsets_rad[1..n]
                .iter()
                .map(|o| prior * density(wrap_pi(r_rad + o)))
                .sum();
            let anywhere = (1.0 - prior) * n as f64 / std::f64::consts::TAU;
            (nearest, nearest + others + anywhere)
        }
    }
}

#[cfg(test)]
mod association_tests {
    use super::{association_weight, weighted_association};
    use crate::core::heading::{
        Candidates, Corridor, CorridorMap, HeadingAid, MAX_LISTED_DIRECTIONS, Rejection,
    };

    #[test]
    fn the_weight_falls_with_the_residual_and_with_ambiguity() {
        let deg = f64::to_radians;
        let quarter = Candidates::Spaced {
            spacing_rad: deg(90.0),
        };
        let s = deg(2.0).powi(2);
        let on = association_weight(0.0, s, 0.7, &quarter);
        let off = association_weight(deg(8.0), s, 0.7, &quarter);
        assert!(on > 0.95 && off < 0.1, "{on} {off}");
        // A heading σ of 30°: the grid directions 90° apart can no longer be told apart.
        let vague = association_weight(0.0, deg(30.0).powi(2), 0.7, &quarter);
        assert!(vague < on, "{vague}");
        // The weight is a probability.
        for r in [-3.0, -0.5, 0.0, 0.2, 1.5] {
            let w = association_weight(r, s, 0.7, &quarter);
            assert!((0.0..=1.0).contains(&w));
        }
    }

    #[test]
    fn a_junction_weighs_like_a_grid_of_its_directions_not_like_one_corridor() {
        let deg = f64::to_radians;
        let listed = |offsets_deg: &[f64]| {
            let mut offsets_rad = [0.0; MAX_LISTED_DIRECTIONS];
            for (o, d) in offsets_rad.iter_mut().zip(offsets_deg) {
                *o = deg(*d);
            }
            Candidates::Listed {
                offsets_rad,
                n: offsets_deg.len() as u8,
            }
        };
        let junction = listed(&[0.0, 90.0, 180.0, -90.0]);
        let grid = Candidates::Spaced {
            spacing_rad: deg(90.0),
        };
        let corridor = Candidates::Spaced {
            spacing_rad: deg(180.0),
        };
        for (r_deg, sd_deg) in [
            (0.0, 4.2),
            (8.0, 4.2),
            (10.0, 4.2),
            (30.0, 20.0),
            (40.0, 20.0),
        ] {
            let (r, s) = (deg(r_deg), deg(sd_deg).powi(2));
            let at_junction = association_weight(r, s, 0.7, &junction);
            let on_grid = association_weight(r, s, 0.7, &grid);
            assert!(
                (at_junction - on_grid).abs() < 1e-12,
                "{at_junction} {on_grid}"
            );
            // In one corridor only ψ + π competes, and "anywhere" counts two directions.
            let in_corridor = association_weight(r, s, 0.7, &corridor);
            assert!(
                at_junction < in_corridor,
                "{r_deg}: {at_junction} {in_corridor}"
            );
        }
        // The review's case: 40° off with a 20° σ passes min_weight 0.5 in one corridor and
        // not at a junction.
        let (r, s) = (deg(40.0), deg(20.0).powi(2));
        assert!(association_weight(r, s, 0.7, &corridor) > 0.5);
        assert!(association_weight(r, s, 0.7, &junction) < 0.5);
        // One corridor listed as such weighs as one corridor spaced by π.
        let two = listed(&[0.0, 180.0]);
        let w = association_weight(deg(10.0), deg(4.0).powi(2), 0.7, &two);
        let v = association_weight(deg(10.0), deg(4.0).powi(2), 0.7, &corridor);
        assert!((w - v).abs() < 1e-12, "{w} {v}");
    }

    #[test]
    fn an_observation_a_corridor_takes_is_unlikely_at_a_junction() {
        let h = corridor_shared::config::Config::default().heading;
        let corridor = |from_m, to_m| Corridor {
            name: String::new(),
            from_m,
            to_m,
            width_m: 2.0,
        };
        let aid = HeadingAid::Map(CorridorMap {
            corridors: vec![
                corridor([-20.0, 0.0], [20.0, 0.0]),
                corridor([0.0, -20.0], [0.0, 20.0]),
            ],
        });
        // 10° off east with a 4.2° σ (default prior and min_weight): weight 0.70 in the
        // east-west corridor, 0.54 at the junction.
        let (value, s2) = (10f64.to_radians(), 4.2f64.to_radians().powi(2));
        let (dir, w) = weighted_association(&aid, &h, [10.0, 0.0], value, s2, false).unwrap();
        assert_eq!(dir, 0.0);
        assert!((0.6..0.8).contains(&w), "{w}");
        let (_, w) = weighted_association(&aid, &h, [0.0, 0.0], value, s2, false).unwrap();
        assert!((0.5..0.6).contains(&w), "{w}");
        // 11° off: taken in the corridor (0.56), unlikely at the junction (0.39).
        let value = 11f64.to_radians();
        assert!(weighted_association(&aid, &h, [10.0, 0.0], value, s2, false).is_ok());
        assert_eq!(
            weighted_association(&aid, &h, [0.0, 0.0], value, s2, false),
            Err(Rejection::Unlikely)
        );
    }
}
