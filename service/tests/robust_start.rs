//! A log that starts mid-walk (a daemon started while the wearer walks). exp29 cut 3 s before
//! its second corner: the first stance long enough to be taken as the initial rest is the
//! corner, where the foot pivots about the vertical at about 0.24 rad/s. Its mean rate used to
//! become the rest-mean bias prior: a bias beyond `sensor.max_gyro_bias_rad_s` (0.2 rad/s), a
//! state the health check refused from the first sample on, and every state after it: the run
//! stayed at the origin for the remaining 93 s, with no error (found by cutting every bundled
//! walk at 30 % of its footprints, session 21).

use corridor_service::core::estimator::{Counters, Phase};
use corridor_service::eval::EvalOptions;
use corridor_service::runner::{RunOutcome, heading_aid, run_log};
use corridor_shared::config::{BiasPrior, Config, ConfigFile, ConfigOverrides};
use corridor_shared::imu_csv::{ImuCsvOptions, ImuLog, read_imu_csv};
use corridor_shared::injection::BiasInjection;
use corridor_shared::truth_csv::{TruthPoint, read_truth_csv};
use std::path::{Path, PathBuf};

/// The run of `log`, and the largest finite bias it output on any axis, rad/s.
fn run_with_largest_bias(log: &ImuLog, cfg: &Config) -> (RunOutcome, f64) {
    let aid = heading_aid(cfg, None).unwrap();
    let mut largest_bias = 0.0f64;
    let out = run_log(log, cfg, &aid, &BiasInjection::default(), |_, e| {
        largest_bias = e
            .gyro_bias_rad_s
            .iter()
            .filter(|v| v.is_finite())
            .fold(largest_bias, |m, v| m.max(v.abs()));
    });
    (out, largest_bias)
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The run of `log`: its footprint RMS against `truth`, % of path, and its counters.
fn scored(log: &ImuLog, cfg: &Config, truth: &[TruthPoint]) -> (f64, Counters) {
    let aid = heading_aid(cfg, None).unwrap();
    let out = run_log(log, cfg, &aid, &BiasInjection::default(), |_, _| {});
    let report = out.trace.evaluate(truth, &EvalOptions::default()).unwrap();
    (report.rms_error_pct_of_path.unwrap(), out.counters)
}

/// `configs/gdins.toml`, the walks starting along the map's x axis.
fn shipped_config() -> Config {
    edited_config(|_| {})
}

/// `configs/gdins.toml` with `edit` applied to the file, the walks starting along x.
fn edited_config(edit: impl FnOnce(&mut ConfigFile)) -> Config {
    let path = root().join("configs/gdins.toml");
    let mut file = ConfigFile::read(&path).unwrap();
    edit(&mut file);
    ConfigOverrides {
        start_heading_deg: Some(0.0),
        ..Default::default()
    }
    .validate(&file, &path)
    .unwrap()
}

/// A bundled walk (`tests/data/<name>`): its log and its footprints.
fn walk(name: &str) -> (ImuLog, Vec<TruthPoint>) {
    let dir = root().join("tests/data").join(name);
    let log = read_imu_csv(&dir.join("imu.csv"), &ImuCsvOptions::default()).unwrap();
    (log, read_truth_csv(&dir.join("ground_truth.csv")).unwrap())
}

/// A bundled walk's log from `t_s` on, and its footprints after it.
fn cut_at(name: &str, t_s: f64) -> (ImuLog, Vec<TruthPoint>) {
    let (mut log, mut truth) = walk(name);
    log.rows.retain(|r| r.t_s >= t_s);
    truth.retain(|p| p.t_s > t_s + 0.05);
    (log, truth)
}

/// The cut: between exp29's first two surveyed corners after the start (11.70 s).
const CUT_S: f64 = 11.7;

#[test]
fn a_rest_that_turns_faster_than_any_bias_is_not_the_bias_prior() {
    let dir = root().join("tests/data/gdins_exp29_corridor_circuit");
    let mut log = read_imu_csv(&dir.join("imu.csv"), &ImuCsvOptions::default()).unwrap();
    log.rows.retain(|r| r.t_s >= CUT_S);
    let truth: Vec<_> = read_truth_csv(&dir.join("ground_truth.csv"))
        .unwrap()
        .into_iter()
        .filter(|p| p.t_s > CUT_S)
        .collect();
    // The ZUPT baseline's configuration: its alignment keeps the pivot's blocks (the default's
    // `rest_max_rate_change_rad_s` happens to leave most of them out).
    let path = root().join("configs/gdins_zupt_baseline.toml");
    let cfg = ConfigOverrides {
        gyro_bias_prior: Some(BiasPrior::RestMean),
        // The corridor walked from the first corner on.
        start_heading_deg: Some(-90.0),
        ..Default::default()
    }
    .validate(&ConfigFile::read(&path).unwrap(), &path)
    .unwrap();
    let (out, largest_bias) = run_with_largest_bias(&log, &cfg);
    assert_eq!(out.counters.health_restores, 0, "the state was refused");
    assert!(
        largest_bias <= cfg.sensor.max_gyro_bias_rad_s(),
        "bias {largest_bias} rad/s"
    );
    // It navigates: the ZUPT filter's footprint error on the 93 s left, as on whole walks.
    let report = out.trace.evaluate(&truth, &EvalOptions::default()).unwrap();
    let pct = report.rms_error_pct_of_path.unwrap();
    assert!(pct < 3.0, "footprint RMS {pct:.2} % of path");
    // And says why it started without a prior.
    assert!(
        out.counters.rest_prior_refused,
        "the pivot's mean rate was taken as the bias prior"
    );
}

/// A rest through which the foot pivots slowly about the vertical (the wearer turning on the
/// spot): nothing but its mean rate shows it. exp36's rest with 0.05 rad/s added about its up
/// axis: taken as the prior, the walk ended 20 % of path off; with
/// `alignment.max_prior_rate_rad_s` it is refused. The shipped configuration leaves the key out
/// (it would refuse a sensor whose real rate at rest is as large: see `configs/gdins.toml`).
const MAX_PRIOR_RATE_RAD_S: f64 = 0.03;

#[test]
fn a_rest_through_which_the_foot_pivots_is_not_the_bias_prior() {
    let (mut log, truth) = walk("gdins_exp36_corridor_out_and_back");
    // The rest's up axis in the sensor frame, from its first half second.
    let rest: Vec<_> = log.rows.iter().filter(|r| r.t_s < 0.5).collect();
    let up: [f64; 3] = std::array::from_fn(|i| rest.iter().map(|r| r.accel_m_s2[i]).sum::<f64>());
    let norm = up.iter().map(|v| v * v).sum::<f64>().sqrt();
    let pivot_until_s = truth[0].t_s - 0.1;
    for r in log.rows.iter_mut().filter(|r| r.t_s < pivot_until_s) {
        for (g, u) in r.gyro_rad_s.iter_mut().zip(up) {
            *g += 0.05 * u / norm;
        }
    }
    let path = root().join("configs/gdins.toml");
    let mut file = ConfigFile::read(&path).unwrap();
    file.alignment.max_prior_rate_rad_s = Some(MAX_PRIOR_RATE_RAD_S);
    let cfg = ConfigOverrides {
        start_heading_deg: Some(0.0),
        ..Default::default()
    }
    .validate(&file, &path)
    .unwrap();
    let aid = heading_aid(&cfg, None).unwrap();
    let out = run_log(&log, &cfg, &aid, &BiasInjection::default(), |_, _| {});
    let report = out.trace.evaluate(&truth, &EvalOptions::default()).unwrap();
    let pct = report.rms_error_pct_of_path.unwrap();
    // As without a prior (0.33 % on the clean walk).
    assert!(pct < 1.0, "footprint RMS {pct:.2} % of path");
    assert!(out.counters.rest_prior_refused);
}

/// A loss that begins in the initial rest and ends in the walk (2.25 s of exp17 from 0.395 s:
/// 0.4 s of rest, then the walk's first stance). The rest used to be timed across the loss,
/// so the first stance after it was taken for the rest's last 2 s: its mean rate became a bias
/// prior of [−0.033, −0.076, 0.030] rad/s, the stance updates pushed the bias beyond
/// `sensor.max_gyro_bias_rad_s`, and the health check restored the same prior again and again
/// for the rest of the walk (1,256 restores; found by a review's torture runs, session 28).
/// A loss while aligning starts the alignment again after it (here on the walk's first stance,
/// as a start without a rest).
#[test]
fn a_loss_from_the_initial_rest_into_the_walk_starts_the_alignment_again() {
    let dir = root().join("tests/data/gdins_exp17_rect_loop_small");
    let mut log = read_imu_csv(&dir.join("imu.csv"), &ImuCsvOptions::default()).unwrap();
    let (first, last) = (log.rows[79].t_s, log.rows[528].t_s);
    assert!(first > 0.39 && last > 2.6, "{first} {last}");
    log.rows.drain(79..529);
    // Scored on the footprints after the loss, as a walk started there (see the test above).
    let truth: Vec<_> = read_truth_csv(&dir.join("ground_truth.csv"))
        .unwrap()
        .into_iter()
        .filter(|p| p.t_s > last)
        .collect();
    let cfg = shipped_config();
    let (out, largest_bias) = run_with_largest_bias(&log, &cfg);
    let aid = heading_aid(&cfg, None).unwrap();
    assert_eq!(out.counters.health_restores, 0, "{:?}", out.counters);
    assert!(largest_bias < 0.02, "bias {largest_bias} rad/s");
    assert!(
        out.counters.started_without_rest && out.counters.alignment_restarts >= 1,
        "{:?}",
        out.counters
    );
    // It navigates as the walk started after the loss does (0.137 % of path; 7.6 % with the
    // filter started on the rest before the loss).
    let mut cut = log.clone();
    cut.rows.drain(..79);
    let cut = run_log(&cut, &cfg, &aid, &BiasInjection::default(), |_, _| {});
    let pct = |o: &RunOutcome| {
        o.trace
            .evaluate(&truth, &EvalOptions::default())
            .unwrap()
            .rms_error_pct_of_path
            .unwrap()
    };
    let (lossy, started_after) = (pct(&out), pct(&cut));
    assert!(
        (lossy - started_after).abs() < 0.01 && lossy < 0.5,
        "{lossy} % of path, started after the loss {started_after} %"
    );
}

/// A rest that is mostly motion: exp17 from 0.55 s, the last 0.65 s of its initial rest, in
/// which the foot shifts before its first step ("stance" to the detector throughout; its first
/// 0.55 s are still). That mean rate, tens of mrad/s off, used to be the bias prior, with the σ
/// of its spread but taken whole: the walk ended 12.1 % of path off (0.21 % from its whole
/// rest; 0.28 % now). The rest's mean is now fused with the sensor's own spread of biases
/// (`eskf.gyro_bias_initial_sd_rad_s` about zero), which a mean that uncertain barely moves.
#[test]
fn a_rest_that_is_mostly_motion_does_not_set_the_bias() {
    let (mut log, truth) = walk("gdins_exp17_rect_loop_small");
    log.rows.retain(|r| r.t_s >= 0.55);
    let cfg = shipped_config();
    let (out, largest_bias) = run_with_largest_bias(&log, &cfg);
    assert!(
        !out.counters.started_without_rest && out.counters.initial_rest_moving_blocks > 0,
        "{:?}",
        out.counters
    );
    // 0.18 rad/s with the mean taken whole, 0.023 now.
    assert!(largest_bias < 0.05, "bias {largest_bias} rad/s");
    let report = out.trace.evaluate(&truth, &EvalOptions::default()).unwrap();
    let pct = report.rms_error_pct_of_path.unwrap();
    assert!(pct < 0.5, "footprint RMS {pct:.2} % of path");
}

/// A loss early in the initial rest that the rest goes on after: exp40 with 0.2 s lost 0.43 s
/// into its 1.43 s rest (0.6 s of quiet, then 0.7 s in which the foot rocks). The alignment
/// used to start again at any loss after less than `alignment.min_rest_s` of rest, which left
/// only the rocking for the bias prior and the tilt: 9.5 % of path (15.9 % before the prior was
/// fused with the sensor's spread of biases). It starts again only when less than
/// `min_rest_s` of rest comes after the loss as well; here the rest is kept whole and its
/// quiet first part anchors the motion test that leaves the rocking out.
#[test]
fn a_loss_early_in_the_initial_rest_keeps_the_rest_that_goes_on_after_it() {
    let (mut log, truth) = walk("gdins_exp40_serpentine_return");
    let cfg = shipped_config();
    let pct = |log: &ImuLog| scored(log, &cfg, &truth);
    let (clean, clean_counters) = pct(&log);
    let first = log.rows.partition_point(|r| r.t_s < 0.43);
    log.rows.drain(first..first + 40);
    let (lossy, counters) = pct(&log);
    assert_eq!(counters.alignment_restarts, 0, "{counters:?}");
    // The same rocking left out as from the whole rest.
    assert_eq!(
        counters.initial_rest_moving_blocks,
        clean_counters.initial_rest_moving_blocks
    );
    assert!(
        lossy < clean + 0.1,
        "{lossy:.2} % of path, {clean:.2} % without the loss"
    );
}

/// A short rest with a loss in its middle: exp37's last 0.95 s of initial rest, 0.2 s of it
/// lost halfway. Less than `alignment.min_rest_s` of rest lies on either side of the loss, so
/// the alignment used to start again from the loss, with too little rest after it for a
/// prior: a start without a rest, 1.10 % of path against 0.54 % from the same short rest
/// without the loss. The two parts last `min_rest_s` together and agree (mean force within
/// 1°, still rate within `alignment.rest_max_rate_change_rad_s`): one rest, kept whole.
#[test]
fn a_short_rest_with_a_loss_in_its_middle_is_one_rest() {
    let (mut log, truth) = walk("gdins_exp37_spiral_and_corridor");
    let cfg = shipped_config();
    // The rest ends at 5.15 s (its alignment phase in the whole walk).
    log.rows.retain(|r| r.t_s >= 5.15 - 0.95);
    let run = |log: &ImuLog| scored(log, &cfg, &truth);
    let (short, _) = run(&log);
    let middle = log.rows.partition_point(|r| r.t_s < 5.15 - 0.95 / 2.0);
    log.rows.drain(middle..middle + 40);
    let (lossy, counters) = run(&log);
    assert!(
        !counters.started_without_rest && counters.alignment_restarts == 0 && counters.gaps == 1,
        "{counters:?}"
    );
    assert!(
        lossy < short + 0.1,
        "{lossy:.2} % of path, {short:.2} % without the loss"
    );
}

/// A log that starts with the wearer's first step: exp24 from 2.0 s, where its initial rest
/// ends. The first stance of the walk aligns, without a rest. Its mean specific force holds
/// what the foot still accelerates (the tilt of the walking stances of 0.1–0.2 s lies a median
/// 1.4° off the filter's converged attitude, of the 0.2–0.4 s ones 0.7°), and that tilt used
/// to be trusted as a rest's, to 0.5°: the ZUPTs put the difference into the horizontal bias,
/// which the health check refused, and the filter was restored 12 times (in 10 of 1,600 starts
/// of `docs/experiments/start-cuts.py`, 8 of its 960 losses). Known to
/// `alignment.start_stance_tilt_sd_rad`, the tilt is what the ZUPTs correct.
#[test]
fn a_walking_stance_that_aligns_is_not_trusted_as_a_rest() {
    let (log, truth) = cut_at("gdins_exp24_square_two_laps", 2.0);
    let (pct, counters) = scored(&log, &shipped_config(), &truth);
    assert!(
        counters.started_without_rest && counters.health_restores == 0,
        "{counters:?}"
    );
    assert!(pct < 0.5, "footprint RMS {pct:.2} % of path");
    // Shown without the unit's typical bias: started from it, the bias is near enough that
    // this cut no longer drives it beyond the health check even with the tilt trusted (the
    // mechanism is the same; the start stance's σ is what guards a unit without one).
    let as_a_rest = edited_config(|f| {
        f.alignment.start_stance_tilt_sd_rad = f.eskf.initial_tilt_sd_rad;
        f.alignment.typical_gyro_bias_rad_s = None;
        f.alignment.typical_gyro_bias_sd_rad_s = None;
    });
    let (_, counters) = scored(&log, &as_a_rest, &truth);
    assert!(counters.health_restores > 0, "{counters:?}");
}

/// The time of the first estimate after the alignment, when there is one.
fn started_at_s(log: &ImuLog, cfg: &Config) -> Option<f64> {
    first_estimate(log, cfg).0.map(|(t_s, _)| t_s)
}

/// The first estimate after the alignment (its time and position), when there is one, and the
/// run's counters.
fn first_estimate(log: &ImuLog, cfg: &Config) -> (Option<(f64, [f64; 3])>, Counters) {
    let aid = heading_aid(cfg, None).unwrap();
    let mut first = None;
    let out = run_log(log, cfg, &aid, &BiasInjection::default(), |_, e| {
        if e.phase != Phase::Aligning {
            first.get_or_insert((e.t_s, e.p_m));
        }
    });
    (first, out.counters)
}

/// A daemon started while the wearer walks fast: exp38 from 19.08 s (the stance end nearest 30 %
/// of its footprints' time). Its stances last 0.03–0.1 s, all shorter than
/// `alignment.min_start_stance_s` (a normal walk's short stances are splits and shuffles, whose
/// tilt lies 3–5° off), and the filter started only 14.8 s after the cut, at a rare longer
/// stance (everything the foot did before it lost: the footprint evaluation failed). A stance that the
/// detector saw whole, in which it had raised its threshold over a whole look-back (the gait
/// it adapts to is fast), may be as short as `alignment.fast_gait_start_stance_s`.
#[test]
fn a_fast_walk_without_a_rest_starts() {
    const CUT_S: f64 = 19.084;
    let (log, truth) = cut_at("gdins_exp38_zigzag_extreme", CUT_S);
    let cfg = shipped_config();
    let t_s = started_at_s(&log, &cfg).expect("never started");
    // 1.72 s: the detector's look-back (`detector.adaptive_window_s`, 1.5 s) first.
    assert!(
        t_s - CUT_S < 2.5,
        "started {:.2} s after the cut",
        t_s - CUT_S
    );
    let (pct, counters) = scored(&log, &cfg, &truth);
    assert_eq!(counters.health_restores, 0, "{counters:?}");
    assert!(pct < 10.0, "footprint RMS {pct:.2} % of path");
    let waiting = edited_config(|f| {
        f.alignment.fast_gait_start_stance_s = f.alignment.min_start_stance_s;
    });
    let waited_s = started_at_s(&log, &waiting).map_or(f64::INFINITY, |t| t - CUT_S);
    assert!(waited_s > 10.0, "started {waited_s:.2} s after the cut");
}

/// The same cut: the gait is known to be fast only a look-back after it, and the filter starts
/// 1.72 s after the cut. It used to start from there, the stride and a half since the cut lost
/// (and with them where the foot was when the daemon started). It now goes back to the first
/// stance the fast-gait rule takes (`alignment.fast_gait_replay_s`), here the first footfall
/// after the cut, aligns there and runs over the samples since: its first estimate is as far
/// from its origin as the footprints say the foot walked in between.
#[test]
fn a_start_in_fast_gait_goes_back_to_the_first_footfall_after_the_cut() {
    const CUT_S: f64 = 19.084;
    let (log, truth) = cut_at("gdins_exp38_zigzag_extreme", CUT_S);
    let (first, counters) = first_estimate(&log, &shipped_config());
    let (t_s, p_m) = first.expect("never started");
    let back_s = counters.start_replayed_ms as f64 * 1e-3;
    // The start went back to the stance whose end is the first listed footprint (19.91 s).
    let start_s = t_s - back_s;
    assert!(
        (start_s - truth[0].t_s).abs() < 0.1,
        "started at {start_s:.2} s (went back {back_s:.2} s), first footprint {:.2} s",
        truth[0].t_s
    );
    // What the foot walked from there to the footprint nearest the first estimate.
    let reached = truth
        .iter()
        .min_by(|a, b| (a.t_s - t_s).abs().total_cmp(&(b.t_s - t_s).abs()))
        .unwrap();
    let walked_m = (reached.x_m - truth[0].x_m).hypot(reached.y_m - truth[0].y_m);
    let moved_m = p_m[0].hypot(p_m[1]);
    assert!(
        walked_m > 1.0 && (moved_m - walked_m).abs() < 0.2,
        "first estimate {moved_m:.2} m from its origin, the footprints {walked_m:.2} m"
    );
    // Without going back, the filter starts where it aligns: nothing of that walk in it.
    let live = edited_config(|f| f.alignment.fast_gait_replay_s = Some(0.0));
    let (first, counters) = first_estimate(&log, &live);
    let (t_live_s, p_m) = first.expect("never started");
    assert_eq!((t_live_s, counters.start_replayed_ms), (t_s, 0));
    assert!(p_m[0].hypot(p_m[1]) < 0.1, "{p_m:?}");
}
