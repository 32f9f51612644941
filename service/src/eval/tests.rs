//! Golden tests against the reference evaluator's output.
//!
//! Fixtures live in `service/tests/data/eval/`. Regenerate them from the repository
//! root with (the CSVs first, then the golden JSON):
//!
//! ```sh
//! python3 service/tests/data/eval/gen_fixtures.py
//! D=service/tests/data/eval; E=/work/shared/tools/eval_traj.py
//! python3 $E --traj $D/loop.traj.csv --truth $D/loop.truth.csv --align first-leg --interp nearest > $D/loop.first-leg.nearest.expected.json
//! python3 $E --traj $D/loop.traj.csv --truth $D/loop.truth.csv --align first-leg --interp linear > $D/loop.first-leg.linear.expected.json
//! python3 $E --traj $D/loop.traj.csv --truth $D/loop.truth.csv --align lsq --interp nearest > $D/loop.lsq.nearest.expected.json
//! python3 $E --traj $D/loop.traj.csv --truth $D/loop.truth.csv --align lsq --interp linear > $D/loop.lsq.linear.expected.json
//! python3 $E --traj $D/out_and_back.traj.csv --truth $D/out_and_back.truth.csv --align first-leg --interp nearest > $D/out_and_back.first-leg.nearest.expected.json
//! python3 $E --traj $D/out_and_back.traj.csv --truth $D/out_and_back.truth.csv --align first-leg --interp linear --heading-min-dist 0 > $D/out_and_back.first-leg.linear.hmd0.expected.json
//! python3 $E --traj $D/out_and_back.traj.csv --truth $D/out_and_back.truth.csv --align lsq --interp linear > $D/out_and_back.lsq.linear.expected.json
//! python3 $E --traj $D/closure.traj.csv --truth $D/closure.truth.csv > $D/closure.nearest.expected.json
//! python3 $E --traj $D/closure.traj.csv --truth $D/closure.truth.csv --interp linear --path-length-m 40.2 > $D/closure.linear.pathlen.expected.json
//! ```
//!
//! The script rounds to 6 decimals, so numbers are compared within 1e-6 (absolute or
//! relative).

use super::geometry::rot_add;
use super::*;
use serde_json::Value;
use std::path::PathBuf;

fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/eval")
}

/// Reads the named columns of a headed CSV; `None` for a missing optional column.
fn read_csv(name: &str, cols: &[&str]) -> Vec<Vec<Option<f64>>> {
    let text = std::fs::read_to_string(data_dir().join(name)).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').map(str::trim).collect();
    let idx: Vec<Option<usize>> = cols
        .iter()
        .map(|c| header.iter().position(|h| h == c))
        .collect();
    let mut out = vec![Vec::new(); cols.len()];
    for line in lines.filter(|l| !l.trim().is_empty()) {
        let f: Vec<&str> = line.split(',').collect();
        for (o, i) in out.iter_mut().zip(&idx) {
            o.push(i.map(|i| f[i].trim().parse::<f64>().unwrap()));
        }
    }
    out
}

fn load(stem: &str) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<TruthGcp>) {
    let tr = read_csv(&format!("{stem}.traj.csv"), &["t_s", "x_m", "y_m"]);
    let col = |c: &Vec<Option<f64>>| c.iter().map(|v| v.unwrap()).collect::<Vec<_>>();
    let gt = read_csv(
        &format!("{stem}.truth.csv"),
        &["t_s", "x_m", "y_m", "stride"],
    );
    let truth = (0..gt[0].len())
        .map(|i| TruthGcp {
            t_s: gt[0][i].unwrap(),
            x_m: gt[1][i].unwrap(),
            y_m: gt[2][i].unwrap(),
            stride: gt[3][i].map(|s| s as i64),
        })
        .collect();
    (col(&tr[0]), col(&tr[1]), col(&tr[2]), truth)
}

fn assert_close(path: &str, got: &Value, want: &Value) {
    match (got, want) {
        (Value::Number(a), Value::Number(b)) => {
            let (a, b) = (a.as_f64().unwrap(), b.as_f64().unwrap());
            let d = (a - b).abs();
            assert!(
                d <= 1e-6 || d <= 1e-6 * b.abs(),
                "{path}: got {a}, want {b}"
            );
        }
        (Value::Array(a), Value::Array(b)) => {
            assert_eq!(a.len(), b.len(), "{path}: array length");
            for (i, (x, y)) in a.iter().zip(b).enumerate() {
                assert_close(&format!("{path}[{i}]"), x, y);
            }
        }
        (Value::Object(a), Value::Object(b)) => {
            let mut ka: Vec<&String> = a.keys().collect();
            let mut kb: Vec<&String> = b
                .keys()
                .filter(|k| path != "$" || (*k != "traj" && *k != "truth"))
                .collect();
            ka.sort();
            kb.sort();
            assert_eq!(ka, kb, "{path}: keys");
            for k in kb {
                assert_close(&format!("{path}.{k}"), &a[k], &b[k]);
            }
        }
        _ => assert_eq!(got, want, "{path}"),
    }
}

fn golden(stem: &str, expected: &str, opts: EvalOptions) {
    let (t, x, y, truth) = load(stem);
    let rep = evaluate(&t, &x, &y, &truth, &opts).unwrap();
    let got = serde_json::to_value(&rep).unwrap();
    let text = std::fs::read_to_string(data_dir().join(expected)).unwrap();
    let want: Value = serde_json::from_str(&text).unwrap();
    assert_close("$", &got, &want);
}

fn opts(align: Align, interp: Interp) -> EvalOptions {
    EvalOptions {
        align,
        interp,
        ..EvalOptions::default()
    }
}

#[test]
fn golden_loop_first_leg_nearest() {
    golden(
        "loop",
        "loop.first-leg.nearest.expected.json",
        opts(Align::FirstLeg, Interp::Nearest),
    );
}

#[test]
fn golden_loop_first_leg_linear() {
    golden(
        "loop",
        "loop.first-leg.linear.expected.json",
        opts(Align::FirstLeg, Interp::Linear),
    );
}

#[test]
fn golden_loop_lsq_nearest() {
    golden(
        "loop",
        "loop.lsq.nearest.expected.json",
        opts(Align::Lsq, Interp::Nearest),
    );
}

#[test]
fn golden_loop_lsq_linear() {
    golden(
        "loop",
        "loop.lsq.linear.expected.json",
        opts(Align::Lsq, Interp::Linear),
    );
}

#[test]
fn golden_out_and_back_first_leg_nearest() {
    golden(
        "out_and_back",
        "out_and_back.first-leg.nearest.expected.json",
        opts(Align::FirstLeg, Interp::Nearest),
    );
}

#[test]
fn golden_out_and_back_first_leg_linear_min_dist_0() {
    golden(
        "out_and_back",
        "out_and_back.first-leg.linear.hmd0.expected.json",
        EvalOptions {
            heading_min_dist_m: 0.0,
            ..opts(Align::FirstLeg, Interp::Linear)
        },
    );
}

#[test]
fn golden_out_and_back_lsq_linear() {
    golden(
        "out_and_back",
        "out_and_back.lsq.linear.expected.json",
        opts(Align::Lsq, Interp::Linear),
    );
}

#[test]
fn golden_closure_only_nearest() {
    golden(
        "closure",
        "closure.nearest.expected.json",
        EvalOptions::default(),
    );
}

#[test]
fn golden_closure_only_linear_path_length() {
    golden(
        "closure",
        "closure.linear.pathlen.expected.json",
        EvalOptions {
            path_length_m: Some(40.2),
            ..opts(Align::FirstLeg, Interp::Linear)
        },
    );
}

/// A walk with two legs at right angles; GCP times on trajectory rows.
fn l_walk() -> Vec<TruthGcp> {
    [
        (1.0, 0.0, 0.0),
        (9.0, 10.0, 0.0),
        (15.0, 10.0, 6.0),
        (20.0, 4.0, 6.0),
    ]
    .iter()
    .enumerate()
    .map(|(i, &(t_s, x_m, y_m))| TruthGcp {
        t_s,
        x_m,
        y_m,
        stride: Some(i as i64),
    })
    .collect()
}

/// Densely sampled trajectory through the truth's polyline, mapped by `f`.
fn traj_from(truth: &[TruthGcp], f: impl Fn(P2) -> P2) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let (mut t, mut x, mut y) = (Vec::new(), Vec::new(), Vec::new());
    for w in truth.windows(2) {
        for k in 0..20 {
            let a = k as f64 / 20.0;
            let p = f([
                w[0].x_m + a * (w[1].x_m - w[0].x_m),
                w[0].y_m + a * (w[1].y_m - w[0].y_m),
            ]);
            t.push(w[0].t_s + a * (w[1].t_s - w[0].t_s));
            x.push(p[0]);
            y.push(p[1]);
        }
    }
    let last = truth.last().unwrap();
    let p = f([last.x_m, last.y_m]);
    t.push(last.t_s);
    x.push(p[0]);
    y.push(p[1]);
    (t, x, y)
}

fn assert_zero_error(rep: &EvalReport) {
    assert!(rep.rms_error_m.unwrap() < 1e-9, "{rep:?}");
    assert!(rep.max_error_m.unwrap() < 1e-9);
    assert!(rep.final_gcp_error_m.unwrap() < 1e-9);
    for leg in rep.legs.as_ref().unwrap() {
        assert!(leg.heading_err_deg.abs() < 1e-7, "{leg:?}");
    }
    assert!(rep.heading_drift_deg_per_s.unwrap().abs() < 1e-9);
    assert!(rep.warnings.is_empty());
}

#[test]
fn trajectory_equal_to_truth_has_zero_error() {
    let truth = l_walk();
    let (t, x, y) = traj_from(&truth, |p| p);
    for align in [Align::FirstLeg, Align::Lsq] {
        for interp in [Interp::Nearest, Interp::Linear] {
            let rep = evaluate(&t, &x, &y, &truth, &opts(align, interp)).unwrap();
            assert_zero_error(&rep);
            assert!(rep.rotation_deg.unwrap().abs() < 1e-9);
            assert_eq!(rep.max_time_offset_s, 0.0);
            assert!(!rep.closed);
            assert_eq!(rep.truth_path_length_m, 10.0 + 6.0 + 6.0);
            assert!((rep.traj_path_length_m - 22.0).abs() < 1e-9);
            assert_eq!(rep.legs.as_ref().unwrap().len(), 3);
            assert_eq!(rep.gcp.as_ref().unwrap()[2].stride, Some(2));
        }
    }
}

#[test]
fn rigid_motion_of_truth_has_zero_error_under_lsq() {
    let truth = l_walk();
    let (ang, off) = (-2.1_f64, [35.0, -12.5]);
    let (t, x, y) = traj_from(&truth, |p| rot_add(ang, p, off));
    let rep = evaluate(&t, &x, &y, &truth, &opts(Align::Lsq, Interp::Linear)).unwrap();
    assert_zero_error(&rep);
    assert!((rep.rotation_deg.unwrap() - (-ang).to_degrees()).abs() < 1e-9);
    // Undoing the motion: translation = -R(-ang) off.
    let back = rot_add(-ang, off, [0.0, 0.0]);
    let tr = rep.translation_m.unwrap();
    assert!((tr[0] + back[0]).abs() < 1e-9 && (tr[1] + back[1]).abs() < 1e-9);
    assert_eq!(rep.scored_gcps.as_deref(), Some("all"));
    // First-leg recovers the same rotation and is exact too.
    let rep = evaluate(&t, &x, &y, &truth, &opts(Align::FirstLeg, Interp::Nearest)).unwrap();
    assert_zero_error(&rep);
}

#[test]
fn translation_alignment_scores_the_trajectorys_own_heading() {
    let truth = l_walk();
    let map_frame = |(t, x, y): &(Vec<f64>, Vec<f64>, Vec<f64>)| {
        evaluate(t, x, y, &truth, &opts(Align::Translation, Interp::Nearest)).unwrap()
    };
    // Moved only: nothing to score.
    let rep = map_frame(&traj_from(&truth, |p| [p[0] + 7.0, p[1] - 3.0]));
    assert_zero_error(&rep);
    assert_eq!(rep.alignment, "translation");
    assert_eq!(rep.scored_gcps.as_deref(), Some("all but GCP0"));
    // Turned by 3° about the start: the first leg takes it out, the map frame keeps it, each
    // footprint off by its distance from the start times 2·sin(1.5°).
    let ang = 3.0_f64.to_radians();
    let g0 = [truth[0].x_m, truth[0].y_m];
    let (t, x, y) = traj_from(&truth, |p| rot_add(ang, [p[0] - g0[0], p[1] - g0[1]], g0));
    let first = evaluate(&t, &x, &y, &truth, &opts(Align::FirstLeg, Interp::Nearest)).unwrap();
    assert_zero_error(&first);
    let map = map_frame(&(t, x, y));
    let far = truth
        .iter()
        .map(|g| (g.x_m - g0[0]).hypot(g.y_m - g0[1]))
        .fold(0.0, f64::max);
    let expected = far * 2.0 * (ang / 2.0).sin();
    assert!(
        (map.max_error_m.unwrap() - expected).abs() < 1e-9,
        "{map:?}"
    );
    assert_eq!("translation".parse::<Align>().unwrap(), Align::Translation);
}

#[test]
fn wrap_deg_matches_python_modulo() {
    assert_eq!(wrap_deg(180.0), -180.0);
    assert_eq!(wrap_deg(-180.0), -180.0);
    assert_eq!(wrap_deg(190.0), -170.0);
    assert_eq!(wrap_deg(-190.0), 170.0);
    assert_eq!(wrap_deg(540.0), -180.0);
    assert_eq!(wrap_deg(-0.0), 0.0);
    assert_eq!(wrap_deg(359.0), -1.0);
}

#[test]
fn errors_carry_the_facts() {
    let truth = l_walk();
    let (t, x, y) = traj_from(&truth, |p| p);
    let o = EvalOptions::default();
    assert_eq!(
        evaluate(&t[..3], &x, &y, &truth, &o).unwrap_err(),
        EvalError::LengthMismatch {
            t: 3,
            x: x.len(),
            y: y.len()
        }
    );
    assert_eq!(
        evaluate(&[1.0, f64::NAN], &[0.0, 1.0], &[0.0, 1.0], &truth, &o).unwrap_err(),
        EvalError::TooFewTrajRows { rows: 1 }
    );
    assert_eq!(
        evaluate(&t, &x, &y, &truth[..1], &o).unwrap_err(),
        EvalError::TooFewGcps { gcps: 1 }
    );
    let far = EvalOptions {
        heading_min_dist_m: 50.0,
        ..o
    };
    match evaluate(&t, &x, &y, &truth, &far).unwrap_err() {
        EvalError::NoHeadingGcp {
            min_dist_m,
            farthest_m,
        } => {
            assert_eq!(min_dist_m, 50.0);
            assert!((farthest_m - 136.0_f64.sqrt()).abs() < 1e-12);
        }
        e => panic!("{e}"),
    }
    // Said in the README's words, in centimetres (it said "no GCP far enough from GCP0 …
    // farthest is 11.661903789690601 m").
    assert_eq!(
        evaluate(&t, &x, &y, &truth, &far).unwrap_err().to_string(),
        "no footprint far enough from the first to align the heading on (need 50 m, the \
         farthest is 11.66 m)"
    );
    // A footprint just short of the distance needed reads short of it (it said "need 5 m, the
    // farthest is 5.00 m" of 4.996 m: a review).
    let short = [(0.0, 0.0), (4.996, 0.0)];
    let short_truth: Vec<TruthGcp> = short
        .iter()
        .zip([1.0, 9.0])
        .map(|(&(x_m, y_m), t_s)| TruthGcp {
            t_s,
            x_m,
            y_m,
            stride: None,
        })
        .collect();
    let five = EvalOptions {
        heading_min_dist_m: 5.0,
        ..o
    };
    assert_eq!(
        evaluate(&t, &x, &y, &short_truth, &five)
            .unwrap_err()
            .to_string(),
        "no footprint far enough from the first to align the heading on (need 5 m, the \
         farthest is 4.996 m)"
    );
    let still = vec![0.0; t.len()];
    match evaluate(&t, &still, &still, &truth, &o).unwrap_err() {
        EvalError::NoMotionToHeadingGcp {
            heading_gcp_index, ..
        } => assert_eq!(heading_gcp_index, 1),
        e => panic!("{e}"),
    }
    assert_eq!("lsq".parse::<Align>().unwrap(), Align::Lsq);
    assert_eq!(
        "median".parse::<Interp>().unwrap_err().to_string(),
        "unknown --interp median"
    );
}

/// The streamed evaluation of `t, x, y`.
fn streamed(
    t: &[f64],
    x: &[f64],
    y: &[f64],
    truth: &[TruthGcp],
    o: &EvalOptions,
) -> Result<EvalReport, EvalError> {
    let mut s = GcpSampler::new(truth, o);
    for k in 0..t.len() {
        s.push(t[k], x[k], y[k]);
    }
    s.finish()
}

#[test]
fn streamed_evaluation_equals_the_whole_trajectorys_on_the_fixtures() {
    for stem in ["loop", "out_and_back", "closure"] {
        // In time order (out_and_back is not, to test the warning): the estimator's order.
        let (t, x, y, truth) = load(stem);
        let mut k: Vec<usize> = (0..t.len()).collect();
        k.sort_by(|&a, &b| t[a].total_cmp(&t[b]));
        let (t, x, y): (Vec<f64>, Vec<f64>, Vec<f64>) = (
            k.iter().map(|&i| t[i]).collect(),
            k.iter().map(|&i| x[i]).collect(),
            k.iter().map(|&i| y[i]).collect(),
        );
        assert!(t.windows(2).all(|w| w[0] < w[1]), "{stem}");
        for align in [Align::FirstLeg, Align::Lsq] {
            for interp in [Interp::Nearest, Interp::Linear] {
                let o = opts(align, interp);
                assert_eq!(
                    streamed(&t, &x, &y, &truth, &o),
                    evaluate(&t, &x, &y, &truth, &o),
                    "{stem} {align:?} {interp:?}"
                );
            }
        }
    }
}

#[test]
fn streamed_evaluation_equals_the_whole_trajectorys_at_the_edges() {
    // GCP times before the first row, after the last, exactly on rows, halfway between two
    // rows (a tie of the nearest), and out of time order; a NaN row and a NaN GCP.
    let truth = l_walk();
    let (mut t, mut x, mut y) = traj_from(&truth, |p| [p[0] * 1.02, p[1] + 0.1 * p[0]]);
    let mut gcps = truth.clone();
    gcps[0].t_s = t[0] - 0.5;
    gcps[3].t_s = t[t.len() - 1] + 2.0;
    gcps.push(TruthGcp {
        t_s: 0.5 * (t[4] + t[5]),
        ..truth[1]
    });
    gcps.push(TruthGcp {
        t_s: t[30],
        ..truth[2]
    });
    gcps.push(TruthGcp {
        t_s: f64::NAN,
        ..truth[2]
    });
    x[10] = f64::NAN;
    for interp in [Interp::Nearest, Interp::Linear] {
        let o = opts(Align::FirstLeg, interp);
        let whole = evaluate(&t, &x, &y, &gcps, &o).unwrap();
        assert_eq!(
            streamed(&t, &x, &y, &gcps, &o).unwrap(),
            whole,
            "{interp:?}"
        );
        assert!(!whole.warnings.is_empty());
    }
    // Too few rows, too few GCPs: the same errors.
    let o = EvalOptions::default();
    assert_eq!(
        streamed(&t[..1], &x[..1], &y[..1], &gcps, &o),
        evaluate(&t[..1], &x[..1], &y[..1], &gcps, &o)
    );
    assert_eq!(
        streamed(&t, &x, &y, &gcps[..1], &o),
        evaluate(&t, &x, &y, &gcps[..1], &o)
    );
    // A truth of another clock (every GCP after the trajectory): said so, by both.
    let late: Vec<TruthGcp> = gcps
        .iter()
        .map(|g| TruthGcp {
            t_s: g.t_s + 1000.0,
            ..*g
        })
        .collect();
    for e in [
        evaluate(&t, &x, &y, &late, &o),
        streamed(&t, &x, &y, &late, &o),
    ] {
        assert!(
            matches!(e, Err(EvalError::TruthOutsideTrajectory { inside: 0, .. })),
            "{e:?}"
        );
    }
    // A row that goes back in time is refused, not silently mis-sampled.
    t.swap(20, 21);
    y.swap(20, 21);
    assert!(matches!(
        streamed(&t, &x, &y, &gcps, &o),
        Err(EvalError::NotIncreasing { .. })
    ));
}

#[test]
fn a_clock_step_back_told_to_the_streamed_evaluation_samples_each_footprint_once() {
    // The estimator's clock stepped back by 1 s at row 25 (t = 10.5 s): the rows from there
    // run on 1 s earlier, and so do the footprint times after the step. A footprint time in
    // the overlap (10.0 s, before the step) is taken before it.
    let mut truth = l_walk();
    truth.insert(
        2,
        TruthGcp {
            t_s: 10.0,
            x_m: 10.0,
            y_m: 1.67,
            stride: Some(9),
        },
    );
    let (t, x, y) = traj_from(&l_walk(), |p| [p[0] * 1.02, p[1] + 0.1 * p[0]]);
    let (k, back_s) = (25, 1.0);
    assert_eq!(t[k], 10.5);
    let stepped: Vec<f64> = (0..t.len())
        .map(|i| if i >= k { t[i] - back_s } else { t[i] })
        .collect();
    let stepped_truth: Vec<TruthGcp> = truth
        .iter()
        .map(|g| TruthGcp {
            t_s: if g.t_s >= t[k] { g.t_s - back_s } else { g.t_s },
            ..*g
        })
        .collect();
    let o = EvalOptions::default();
    let whole = streamed(&t, &x, &y, &truth, &o).unwrap();
    let mut s = GcpSampler::new(&stepped_truth, &o);
    for i in 0..t.len() {
        if i == k {
            s.clock_stepped_back();
        }
        s.push(stepped[i], x[i], y[i]);
    }
    let rep = s.finish().unwrap();
    assert!(rep.warnings[0].contains("went back 1 time(s), first at t = 9.5 s"));
    // Every footprint sampled where the trajectory without the step samples it (the times of
    // the footprints after the step differ by the step).
    let at = |r: &EvalReport| -> Vec<[f64; 2]> {
        r.gcp.as_ref().unwrap().iter().map(|g| g.est_xy).collect()
    };
    assert_eq!(at(&rep), at(&whole));
    assert_eq!(
        (
            rep.rms_error_m,
            rep.traj_path_length_m,
            rep.max_time_offset_s
        ),
        (
            whole.rms_error_m,
            whole.traj_path_length_m,
            whole.max_time_offset_s
        )
    );
    // Stepped back to the last row's own time (whole periods, a review found it refused): the
    // same footprints.
    let mut s = GcpSampler::new(&truth, &o);
    for i in 0..t.len() {
        if i == k {
            s.clock_stepped_back();
            s.push(t[k - 1], x[k - 1], y[k - 1]);
        }
        s.push(t[i], x[i], y[i]);
    }
    assert_eq!(at(&s.finish().unwrap()), at(&whole));
    // Not told, it is refused as before.
    assert!(matches!(
        streamed(&stepped, &x, &y, &stepped_truth, &o),
        Err(EvalError::NotIncreasing { .. })
    ));
}

#[test]
fn footprints_in_a_gap_of_the_trajectory_are_warned_about_whole_or_streamed() {
    // Rows every 0.1 s over 0–10 s and 20–30 s: the footprints at 12 and 15 s lie in the hole
    // (scored at the rows around it, as eval_traj.py does, and said); those at 5 and 25 s not,
    // nor those on the rows at the hole's edges (10 and 20 s: scored there exactly).
    let t: Vec<f64> = (0..=100)
        .map(|k| f64::from(k) * 0.1)
        .chain((0..=100).map(|k| 20.0 + f64::from(k) * 0.1))
        .collect();
    let x: Vec<f64> = t.clone();
    let y = vec![0.0; t.len()];
    let truth: Vec<TruthGcp> = [0.0, 5.0, 10.0, 12.0, 15.0, 20.0, 25.0, 30.0]
        .iter()
        .map(|&t_s| TruthGcp {
            t_s,
            x_m: t_s,
            y_m: 0.0,
            stride: None,
        })
        .collect();
    let o = EvalOptions::default();
    for rep in [
        evaluate(&t, &x, &y, &truth, &o).unwrap(),
        streamed(&t, &x, &y, &truth, &o).unwrap(),
    ] {
        let w: Vec<&String> = rep.warnings.iter().filter(|w| w.contains("gap")).collect();
        assert_eq!(w.len(), 1, "{:?}", rep.warnings);
        assert!(
            w[0].contains("indices [3, 4]") && w[0].contains("longest gap 10.0 s"),
            "{}",
            w[0]
        );
    }
    // Without the hole: nothing said.
    let t: Vec<f64> = (0..=300).map(|k| f64::from(k) * 0.1).collect();
    let (x, y) = (t.clone(), vec![0.0; t.len()]);
    assert!(
        evaluate(&t, &x, &y, &truth, &o)
            .unwrap()
            .warnings
            .is_empty()
    );
    assert!(
        streamed(&t, &x, &y, &truth, &o)
            .unwrap()
            .warnings
            .is_empty()
    );
}
