//! The figures of a run (SVG): trajectory before and after, bias, bias σ.

use super::*;

/// The trajectory aligned to the truth as the evaluation aligns it (first leg), or as is.
fn aligned_xy(
    trace: &Trace,
    truth: Option<&[TruthPoint]>,
    rep: Option<&EvalReport>,
) -> (Vec<f64>, Vec<f64>) {
    let (mut xs, mut ys): (Vec<f64>, Vec<f64>) = trace.xy_m.iter().map(|p| (p[0], p[1])).unzip();
    if let (Some(t), Some(r)) = (truth, rep)
        && let (Some(g0), Some(theta)) = (t.first(), r.rotation_deg)
    {
        let i0 = trace
            .t_s
            .partition_point(|&x| x < g0.t_s)
            .min(trace.t_s.len().saturating_sub(1));
        let (px, py) = (xs[i0], ys[i0]);
        let (s, c) = theta.to_radians().sin_cos();
        for (x, y) in xs.iter_mut().zip(ys.iter_mut()) {
            let (dx, dy) = (*x - px, *y - py);
            *x = c * dx - s * dy + g0.x_m;
            *y = s * dx + c * dy + g0.y_m;
        }
    }
    (xs, ys)
}

/// Writes the paper's figures: trajectory before/after with the footprints, the bias per axis
/// with its ±σ band, and the filter's bias σ against time.
pub fn write_figures(
    dir: &Path,
    before: &Trace,
    after: &Trace,
    truth: Option<&[TruthPoint]>,
    evals: (Option<&EvalReport>, Option<&EvalReport>),
) -> Result<(), RunError> {
    write_figures_to(&mut |name| dir.join(name), before, after, truth, evals)
}

/// [`write_figures`], each figure to `path_of(its name)`.
pub(super) fn write_figures_to(
    path_of: &mut dyn FnMut(&str) -> PathBuf,
    before: &Trace,
    after: &Trace,
    truth: Option<&[TruthPoint]>,
    evals: (Option<&EvalReport>, Option<&EvalReport>),
) -> Result<(), RunError> {
    use crate::plot::{Figure, Panel, Series};
    let (bx, by) = aligned_xy(before, truth, evals.0);
    let (ax, ay) = aligned_xy(after, truth, evals.1);
    let mut traj = Panel::new("Trajectory (aligned on the first leg)", "x (m)", "y (m)")
        .with_equal_aspect()
        .with_series(Series::dashed("ZUPT filter, no bias correction", bx, by))
        .with_series(Series::line("corrected", ax, ay));
    if let Some(t) = truth {
        traj = traj.with_series(
            Series::markers(
                "surveyed footprints",
                t.iter().map(|p| p.x_m).collect(),
                t.iter().map(|p| p.y_m).collect(),
            )
            .with_point_labels((0..t.len()).map(|i| i.to_string()).collect()),
        );
    }
    let f = path_of("trajectory.svg");
    Figure::new("corridor: trajectory before and after bias correction")
        .with_panel(traj)
        .with_size(900, 700)
        .write_svg(&f)
        .map_err(io_at(&f))?;

    let mut bias = Figure::new("Gyro-bias estimate (sensor axes) with ±1σ").with_shared_x();
    let mut cov = Figure::new("Bias-filter σ against time").with_shared_x();
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        let b: Vec<f64> = after.bias_rad_s.iter().map(|v| v[k]).collect();
        let sd: Vec<f64> = after.bias_sd_rad_s.iter().map(|v| v[k]).collect();
        bias = bias.with_panel(
            Panel::new(format!("bias {axis}"), "t (s)", "rad/s").with_series(
                Series::line(format!("b_{axis}"), after.t_s.clone(), b).with_band(sd.clone()),
            ),
        );
        cov = cov.with_panel(
            Panel::new(format!("σ {axis}"), "t (s)", "rad/s").with_series(Series::line(
                format!("σ_{axis}"),
                after.t_s.clone(),
                sd,
            )),
        );
    }
    let f = path_of("bias.svg");
    bias.write_svg(&f).map_err(io_at(&f))?;
    let f = path_of("covariance.svg");
    cov.write_svg(&f).map_err(io_at(&f))?;
    Ok(())
}
