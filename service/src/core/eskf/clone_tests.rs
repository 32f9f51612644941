//! Tests of the footprint clones with `stride_look_ahead` (two clones): the shift at a new
//! footprint against its dense formula, and which stride the direction update observes.

use super::tests::{all_ext, dense, level_filter};
use super::*;

#[test]
fn a_new_footprint_with_look_ahead_shifts_the_clones_as_the_dense_formula_says() {
    // x' = T·x: the previous clone takes the newest clone, the newest the position, the rest
    // stays; P' = T·P·Tᵀ.
    let mut f = level_filter(0.01, all_ext());
    let lay = Layout::new(&all_ext());
    let (c, a) = (lay.clone.unwrap(), lay.clone_prev.unwrap());
    for k in 0..3 {
        for _ in 0..40 {
            f.propagate(
                &Vector3::new(0.4, -1.0, 0.3),
                &Vector3::new(1.0 + k as f64, 0.5, 9.8),
                0.005,
            );
        }
        f.zupt();
        f.heading_update(0.3, 0.05, &Vector3::x());
        f.stride_direction_update(0.1, 0.05);
        f.clone_footprint();
    }
    for _ in 0..40 {
        f.propagate(
            &Vector3::new(0.1, 0.2, 0.5),
            &Vector3::new(2.0, 0.0, 9.8),
            0.005,
        );
    }
    let n = f.dim();
    let before = dense(&f);
    let (newest, position) = (f.footprint_xy_m, [f.p_m.x, f.p_m.y]);
    f.clone_footprint();
    let mut t = nalgebra::DMatrix::<f64>::identity(n, n);
    for k in 0..2 {
        t[(a + k, a + k)] = 0.0;
        t[(a + k, c + k)] = 1.0;
        t[(c + k, c + k)] = 0.0;
        t[(c + k, P0 + k)] = 1.0;
    }
    let want = &t * before * t.transpose();
    let err = (want - dense(&f)).abs().max();
    assert!(err < 1e-15, "{err}");
    assert_eq!(f.prev_footprint_xy_m, newest);
    assert_eq!(f.footprint_xy_m, position);
}

#[test]
fn with_look_ahead_the_stride_observed_is_the_one_between_the_two_clones() {
    let mut f = level_filter(0.01, all_ext());
    // A stride: half a second of propagation (the position's variance grows), then the
    // nominal position put at its end.
    let walk = |f: &mut Eskf, to: [f64; 2]| {
        for _ in 0..100 {
            f.propagate(&Vector3::zeros(), &Vector3::new(0.0, 0.0, 9.81), 0.005);
        }
        f.p_m.x = to[0];
        f.p_m.y = to[1];
    };
    f.clone_footprint(); // at the origin
    walk(&mut f, [1.0, 0.0]);
    f.clone_footprint();
    walk(&mut f, [1.5, 1.0]);
    // Only one stride is complete between clones: the first, along x.
    let (len, dir, var) = f.stride_prediction().unwrap();
    assert!(
        (len - 1.0).abs() < 1e-12 && dir.abs() < 1e-12,
        "{len} {dir}"
    );
    assert!(var > 0.0);
    // Its update moves the clones apart, not the position alone: an observed direction of
    // 0.1 rad turns the stride between them towards it.
    f.stride_direction_update(0.1, 0.01).unwrap();
    let (_, dir_after, _) = f.stride_prediction().unwrap();
    assert!(dir_after > 0.0 && dir_after < 0.1, "{dir_after}");
    // Without look-ahead the same geometry observes the stride since the newest clone.
    let one = Extensions {
        stride_look_ahead: false,
        ..all_ext()
    };
    let mut g = level_filter(0.01, one);
    g.clone_footprint();
    walk(&mut g, [1.0, 0.0]);
    g.clone_footprint();
    walk(&mut g, [1.5, 1.0]);
    let (_, dir, _) = g.stride_prediction().unwrap();
    assert!((dir - 1.0f64.atan2(0.5)).abs() < 1e-12, "{dir}");
}

#[test]
fn a_copy_from_before_a_clone_says_so_and_forgotten_footprints_observe_no_stride() {
    let mut f = level_filter(0.01, all_ext());
    let before = f.clone();
    f.clone_footprint();
    f.p_m.x = 1.0;
    f.clone_footprint();
    f.p_m.x = 2.0;
    assert_eq!(f.footprints_cloned, 2);
    assert!(f.stride_prediction().is_some());
    let mut g = f.clone();
    g.copy_state_from(&before);
    assert_eq!(g.footprints_cloned, 0);
    f.forget_footprints();
    assert!(f.stride_prediction().is_none());
    // One new footprint is not enough with look-ahead: the stride needs two.
    f.clone_footprint();
    assert!(f.stride_prediction().is_none());
    f.p_m.x = 3.0;
    f.clone_footprint();
    let (len, _, _) = f.stride_prediction().unwrap();
    assert!((len - 1.0).abs() < 1e-12, "{len}");
}
