//! A stride direction is fused only where it was walked along its corridor.
//!
//! The walks of normal gait whose every footprint is surveyed give each stride's true
//! direction. Two of the ways in which strides were fused off their corridor:
//! - exp37 (MicroStrain 3DM-GX5-25) starts with a square spiral of 25 strides, most of which
//!   turn the foot by 60–90°. The mounting-yaw calibration ends inside the spiral, and the
//!   footprint-line test needs four footprints of tracking before it can say whether the walk is
//!   straight. One of the strides in between (footprint 19, walked at −7° after a turn of the
//!   foot by about 26°) was fused as a stride along the 0° corridor and turned the whole
//!   estimate by about 4°.
//! - On every such walk of normal gait, a stride is fused one stance late, once the footprint
//!   after it shows whether it lay on a straight stretch (`heading.stride_look_ahead`). Without
//!   that, exp36's stride ending at footprint 42 was fused 5.3° from the
//!   direction it was walked.
//!
//! The foot axis is fused at the stance itself, so no footprint after it can judge it; it is
//! fused only when the stride that brought the foot there runs along the same corridor
//! (`heading.foot_axis_stride_max_deg`). Without that, the foot axis was fused at the end of
//! one weave stride on exp36 and one on exp40 (whose walker walks at −10° for three strides with
//! the foot at −5 to −7°: those foot axes, fused towards 0°, turned the estimate by 3°).

use corridor_service::runner::{heading_aid, run_log};
use corridor_shared::config::{ConfigFile, ConfigOverrides};
use corridor_shared::imu_csv::{ImuCsvOptions, read_imu_csv};
use corridor_shared::injection::BiasInjection;
use corridor_shared::truth_csv::{TruthPoint, read_truth_csv};
use std::path::Path;

/// Largest angle between a fused stride's direction and the direction it was walked, degrees
/// (five times the configured stride σ of 1°).
const MAX_OFF_DEG: f64 = 5.0;

/// Which observation to collect.
#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Stride,
    FootAxis,
}

/// The walk's footprints and the stride directions (or foot axes) the shipped configuration
/// fused on it: (time of the footprint ending the stride, or of the stance, direction fused
/// as, rad).
fn fused(recording: &str, kind: Kind) -> (Vec<TruthPoint>, Vec<(f64, f64)>) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let dir = root.join("tests/data").join(recording);
    let log = read_imu_csv(&dir.join("imu.csv"), &ImuCsvOptions::default()).unwrap();
    let truth = read_truth_csv(&dir.join("ground_truth.csv")).unwrap();
    let path = root.join("configs/gdins.toml");
    // The suite's start heading for these walks: their first stride, on the building grid.
    let cfg = ConfigOverrides {
        start_heading_deg: Some(0.0),
        grid_deg: Some(0.0),
        ..Default::default()
    }
    .validate(&ConfigFile::read(&path).unwrap(), &path)
    .unwrap();
    let aid = heading_aid(&cfg, None).unwrap();
    let mut fused = Vec::new();
    run_log(&log, &cfg, &aid, &BiasInjection::default(), |_, est| {
        // A stride observed one stance late ended at its `observed_t_s`.
        let ev = match kind {
            Kind::Stride => &est.stride,
            Kind::FootAxis => &est.heading,
        };
        if let Some(ev) = ev
            && ev.outcome.is_ok()
        {
            fused.push((ev.observed_t_s, ev.direction_rad));
        }
    });
    (truth, fused)
}

/// How far the stride ending at `t_s` was walked from `dir`, degrees, and its footprint index.
fn walked_off_deg(truth: &[TruthPoint], t_s: f64, dir: f64) -> (f64, usize) {
    // The stride ends at the stance whose listed end is the first at or after it.
    let j = truth
        .iter()
        .position(|f| f.t_s >= t_s - 0.01)
        .expect("a footprint after the stride");
    assert!(
        j > 0,
        "a stride fused at {t_s} s, before the first footprint"
    );
    let walked = (truth[j].y_m - truth[j - 1].y_m).atan2(truth[j].x_m - truth[j - 1].x_m);
    let off = corridor_service::core::rotation::wrap_pi(dir - walked).to_degrees();
    (off, j)
}

/// The walks of normal gait whose every footprint is surveyed.
const SURVEYED_AT_EVERY_STRIDE: [&str; 5] = [
    "gdins_exp31_corridor_back_and_forth",
    "gdins_exp32_box_and_corridor",
    "gdins_exp36_corridor_out_and_back",
    "gdins_exp37_spiral_and_corridor",
    "gdins_exp40_serpentine_return",
];

#[test]
fn every_stride_fused_on_the_walks_surveyed_at_every_stride_was_walked_along_its_corridor() {
    let mut checked = 0;
    for recording in SURVEYED_AT_EVERY_STRIDE {
        let (truth, fused) = fused(recording, Kind::Stride);
        for &(t_s, dir) in &fused {
            let (off_deg, j) = walked_off_deg(&truth, t_s, dir);
            assert!(
                off_deg.abs() <= MAX_OFF_DEG,
                "{recording}: the stride ending at footprint {j} ({t_s:.2} s) was fused along \
                 {:.0}° but walked {off_deg:.1}° away from it",
                dir.to_degrees()
            );
        }
        checked += fused.len();
    }
    // The walks have long straight corridors: there is plenty to check.
    assert!(checked >= 40, "only {checked} stride directions fused");
}

/// A weave stride points more than this far off the corridor that the strides before and after
/// it follow (within it), degrees: the suite's definition (`corridor_service::suite`).
const WEAVE_DEG: f64 = 10.0;

/// The weave strides of a walk: (time of the footprint before, time of its own footprint).
fn weaves(truth: &[TruthPoint]) -> Vec<(f64, f64)> {
    let quarter = std::f64::consts::FRAC_PI_2;
    // Each stride's nearest grid direction (0/90/180/270°) and its deviation from it, degrees.
    let legs: Vec<(i64, f64)> = truth
        .windows(2)
        .map(|w| {
            let d = (w[1].y_m - w[0].y_m).atan2(w[1].x_m - w[0].x_m);
            let k = (d / quarter).round();
            (
                (k as i64).rem_euclid(4),
                (d - k * quarter).abs().to_degrees(),
            )
        })
        .collect();
    (1..legs.len().saturating_sub(1))
        .filter(|&i| {
            let (p, c, n) = (legs[i - 1], legs[i], legs[i + 1]);
            p.0 == n.0 && p.1 <= WEAVE_DEG && n.1 <= WEAVE_DEG && (c.0 != p.0 || c.1 > WEAVE_DEG)
        })
        .map(|i| (truth[i].t_s, truth[i + 1].t_s))
        .collect()
}

#[test]
fn no_foot_axis_is_fused_at_the_end_of_a_weave_stride() {
    let (mut weave_strides, mut foot_axes) = (0, 0);
    for recording in SURVEYED_AT_EVERY_STRIDE {
        let (truth, fused) = fused(recording, Kind::FootAxis);
        let weaves = weaves(&truth);
        for &(t_s, dir) in &fused {
            assert!(
                !weaves.iter().any(|&(a, b)| t_s > a && t_s <= b),
                "{recording}: the foot axis at {t_s:.2} s was fused along {:.0}° at the end of a \
                 weave stride",
                dir.to_degrees()
            );
        }
        weave_strides += weaves.len();
        foot_axes += fused.len();
    }
    // Both sides of the test are there: weaves to refuse and foot axes that were fused.
    assert!(weave_strides >= 8, "only {weave_strides} weave strides");
    assert!(foot_axes >= 80, "only {foot_axes} foot axes fused");
}
