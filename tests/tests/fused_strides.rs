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

use corridor_service::runner::{heading_aid, run_log};
use corridor_shared::config::{ConfigFile, ConfigOverrides};
use corridor_shared::imu_csv::{ImuCsvOptions, read_imu_csv};
use corridor_shared::injection::BiasInjection;
use corridor_shared::truth_csv::{TruthPoint, read_truth_csv};
use std::path::Path;

/// Largest angle between a fused stride's direction and the direction it was walked, degrees
/// (five times the configured stride σ of 1°).
const MAX_OFF_DEG: f64 = 5.0;

/// The walk's footprints and the stride directions the shipped configuration fused on it:
/// (time of the footprint ending the stride, direction fused as, rad).
fn fused_strides(recording: &str) -> (Vec<TruthPoint>, Vec<(f64, f64)>) {
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
        if let Some(ev) = &est.stride
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

#[test]
fn every_stride_fused_on_the_walks_surveyed_at_every_stride_was_walked_along_its_corridor() {
    let mut checked = 0;
    for recording in [
        "gdins_exp31_corridor_back_and_forth",
        "gdins_exp32_box_and_corridor",
        "gdins_exp36_corridor_out_and_back",
        "gdins_exp37_spiral_and_corridor",
        "gdins_exp40_serpentine_return",
    ] {
        let (truth, fused) = fused_strides(recording);
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
