//! The figures of a sampled trajectory against the GCPs.

use super::geometry::*;
use super::*;

/// What the evaluation needs of a trajectory: its positions at the GCP times, how far in time
/// each was taken from its GCP, its time span and its path length between the first and last
/// GCP times. [`evaluate`] takes it from the whole trajectory, [`GcpSampler`] as it streams.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Sampled {
    pub(super) p: Vec<P2>,
    pub(super) dt_used: Vec<f64>,
    pub(super) t_first: f64,
    pub(super) t_last: f64,
    pub(super) traj_len_m: f64,
}

/// The evaluation of a sampled trajectory against the (finite) GCPs.
pub(super) fn report(
    s: Sampled,
    truth: &[TruthGcp],
    opts: &EvalOptions,
    mut warnings: Vec<String>,
) -> Result<EvalReport, EvalError> {
    let Sampled {
        p,
        dt_used,
        t_first,
        t_last,
        traj_len_m: traj_len,
    } = s;
    let n = truth.len();
    let tg: Vec<f64> = truth.iter().map(|g| g.t_s).collect();
    let g: Vec<P2> = truth.iter().map(|g| [g.x_m, g.y_m]).collect();
    let out_of_span: Vec<String> = (0..n)
        .filter(|&i| tg[i] < t_first - SPAN_SLACK_S || tg[i] > t_last + SPAN_SLACK_S)
        .map(|i| i.to_string())
        .collect();
    if !out_of_span.is_empty() {
        warnings.push(format!(
            "GCP time(s) outside the trajectory span, clamped: indices [{}]",
            out_of_span.join(", ")
        ));
    }

    let closed = norm(sub(g[n - 1], g[0])) <= opts.closed_tol_m;
    let truth_len = polyline_length(&g);
    // numpy.max propagates NaN.
    let max_dt = dt_used.iter().copied().fold(f64::NEG_INFINITY, |a, b| {
        if a.is_nan() || b.is_nan() {
            f64::NAN
        } else {
            a.max(b)
        }
    });

    let mut res = EvalReport {
        n_gcp: n,
        interp: opts.interp,
        max_time_offset_s: max_dt,
        closed,
        truth_path_length_m: truth_len,
        traj_path_length_m: traj_len,
        loop_closure_error_m: closed.then(|| norm(sub(p[n - 1], p[0]))),
        alignment: String::new(),
        loop_closure_pct: None,
        pct_basis: None,
        heading_gcp_index: None,
        heading_baseline_m: None,
        rotation_deg: None,
        translation_m: None,
        legs: None,
        heading_drift_deg_per_s: None,
        scored_gcps: None,
        rms_error_m: None,
        max_error_m: None,
        max_error_gcp_index: None,
        final_gcp_error_m: None,
        rms_error_pct_of_path: None,
        gcp: None,
        warnings: Vec::new(),
    };

    // Loop-closure-only truth: every GCP at the start point.
    if truth_len < 1e-9 {
        res.alignment = "none (loop-closure-only truth)".to_owned();
        if let Some(lce) = res.loop_closure_error_m {
            // Python truthiness: None and 0.0 fall back to the trajectory's length.
            let (basis_len, basis) = match opts.path_length_m {
                Some(l) if l != 0.0 => (l, "--path-length-m"),
                _ => (traj_len, "traj_path_length_m"),
            };
            res.loop_closure_pct = Some((basis_len > 0.0).then(|| 100.0 * lce / basis_len));
            res.pct_basis = Some(basis.to_owned());
        }
        res.warnings = warnings;
        return Ok(res);
    }

    let (q, scored_from) = match opts.align {
        Align::FirstLeg => {
            let min_dist = opts.heading_min_dist_m.max(1e-9);
            let d: Vec<f64> = g.iter().map(|&gi| norm(sub(gi, g[0]))).collect();
            let Some(k) = (1..n).find(|&i| d[i] >= min_dist) else {
                return Err(EvalError::NoHeadingGcp {
                    min_dist_m: opts.heading_min_dist_m,
                    farthest_m: d.iter().copied().fold(0.0, f64::max),
                });
            };
            let vt = sub(g[k], g[0]);
            let vp = sub(p[k], p[0]);
            if norm(vp) < 1e-9 {
                return Err(EvalError::NoMotionToHeadingGcp {
                    heading_gcp_index: k,
                    moved_m: norm(vp),
                });
            }
            let theta = vt[1].atan2(vt[0]) - vp[1].atan2(vp[0]);
            let q: Vec<P2> = p
                .iter()
                .map(|&pi| rot_add(theta, sub(pi, p[0]), g[0]))
                .collect();
            res.alignment = Align::FirstLeg.as_str().to_owned();
            res.heading_gcp_index = Some(k);
            res.heading_baseline_m = Some(d[k]);
            res.rotation_deg = Some(wrap_deg(theta.to_degrees()));
            (q, 1)
        }
        Align::Translation => {
            let [sx, sy] = sub(g[0], p[0]);
            let q: Vec<P2> = p.iter().map(|&[x, y]| [x + sx, y + sy]).collect();
            res.alignment = Align::Translation.as_str().to_owned();
            res.rotation_deg = Some(0.0);
            (q, 1)
        }
        Align::Lsq => {
            let (pm, gm) = (mean(&p), mean(&g));
            let (mut num, mut den) = (0.0, 0.0);
            for (pi, gi) in p.iter().zip(&g) {
                let (pc, gc) = (sub(*pi, pm), sub(*gi, gm));
                num += gc[1] * pc[0] - gc[0] * pc[1];
                den += gc[0] * pc[0] + gc[1] * pc[1];
            }
            let theta = num.atan2(den);
            let rpm = rot_add(theta, pm, [0.0, 0.0]);
            let tr = sub(gm, rpm);
            let q: Vec<P2> = p.iter().map(|&pi| rot_add(theta, pi, tr)).collect();
            res.alignment = Align::Lsq.as_str().to_owned();
            res.rotation_deg = Some(wrap_deg(theta.to_degrees()));
            res.translation_m = Some(tr);
            (q, 0)
        }
    };

    let err: Vec<P2> = q.iter().zip(&g).map(|(&qi, &gi)| sub(qi, gi)).collect();
    let en: Vec<f64> = err.iter().map(|&e| norm(e)).collect();
    let gcps: Vec<GcpRow> = (0..n)
        .map(|i| GcpRow {
            index: i,
            t_s: tg[i],
            truth_xy: g[i],
            est_xy: q[i],
            err_xy: err[i],
            err_m: en[i],
            stride: truth[i].stride,
        })
        .collect();
    let sel = &en[scored_from..];
    let rms = (sel.iter().map(|e| e * e).sum::<f64>() / sel.len() as f64).sqrt();
    // numpy.argmax: first maximum, or the first NaN if there is one.
    let mut imax = 0;
    for (i, &e) in sel.iter().enumerate() {
        if e.is_nan() {
            imax = i;
            break;
        }
        if e > sel[imax] {
            imax = i;
        }
    }

    let mut legs = Vec::new();
    for i in 0..n - 1 {
        let vt = sub(g[i + 1], g[i]);
        let vq = sub(q[i + 1], q[i]);
        if norm(vt) >= LEG_MIN_DIST_M && norm(vq) > 1e-9 {
            let dpsi = vq[1].atan2(vq[0]) - vt[1].atan2(vt[0]);
            legs.push(Leg {
                from: i,
                to: i + 1,
                t_mid_s: 0.5 * (tg[i] + tg[i + 1]),
                length_m: norm(vt),
                heading_err_deg: wrap_deg(dpsi.to_degrees()),
            });
        }
    }
    if legs.len() >= 2 {
        let tl: Vec<f64> = legs.iter().map(|l| l.t_mid_s).collect();
        let hl: Vec<f64> = legs.iter().map(|l| l.heading_err_deg).collect();
        let (lo, hi) = tl
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        if hi - lo > 0.0 {
            res.heading_drift_deg_per_s = Some(line_slope(&tl, &hl));
        }
    }
    res.legs = Some(legs);
    res.scored_gcps = Some(
        match opts.align {
            Align::FirstLeg | Align::Translation => "all but GCP0",
            Align::Lsq => "all",
        }
        .to_owned(),
    );
    res.rms_error_m = Some(rms);
    res.max_error_m = Some(sel[imax]);
    res.max_error_gcp_index = Some(scored_from + imax);
    res.final_gcp_error_m = Some(en[n - 1]);
    res.rms_error_pct_of_path = Some(100.0 * rms / truth_len);
    res.gcp = Some(gcps);
    res.warnings = warnings;
    Ok(res)
}
