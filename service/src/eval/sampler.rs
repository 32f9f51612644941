//! The streaming evaluation: per GCP only the rows around its time.

use super::geometry::*;
use super::report::{Sampled, report};
use super::*;

/// A sample of a streamed trajectory: time and position.
type Fix = (f64, P2);

/// Evaluates a trajectory as it streams, in memory independent of its length: it keeps, per
/// GCP, only the trajectory rows just before and at or after the GCP time, and the path length
/// as it grows. [`GcpSampler::finish`] gives exactly what [`evaluate`] gives for the same rows
/// (tested), provided the rows come in strictly increasing time, as the estimator emits them
/// (but where its clock stepped back: a GCP time the rows had passed before the step is taken
/// before it, where [`evaluate`] sorts the rows, and the report says so); rows with a
/// non-finite time or position are left out, as [`evaluate`] leaves them out.
#[derive(Debug, Clone)]
pub struct GcpSampler {
    truth: Vec<TruthGcp>,
    opts: EvalOptions,
    /// GCP indices in time order (stable).
    order: Vec<usize>,
    /// Position in `order` of the first GCP whose time no row has reached.
    next: usize,
    /// Per GCP: the last row before its time, the first row at or after it.
    before: Vec<Option<Fix>>,
    after: Vec<Option<Fix>>,
    first: Option<Fix>,
    last: Option<Fix>,
    rows: usize,
    /// Last row between the first and last GCP's times, and the path length through them.
    span_last: Option<P2>,
    span_rows: usize,
    span_len_m: f64,
    /// The first row that did not come after the previous one.
    out_of_order_s: Option<f64>,
    /// The first row that went back before the previous one (the clock stepped back), and how
    /// many did.
    went_back: Option<(f64, usize)>,
    /// The next row may go back ([`GcpSampler::clock_stepped_back`]).
    may_go_back: bool,
}

impl GcpSampler {
    /// A sampler for `truth` (its non-finite GCPs are left out, as [`evaluate`] does).
    pub fn new(truth: &[TruthGcp], opts: &EvalOptions) -> Self {
        let truth: Vec<TruthGcp> = truth
            .iter()
            .filter(|g| g.t_s.is_finite() && g.x_m.is_finite() && g.y_m.is_finite())
            .copied()
            .collect();
        let mut order: Vec<usize> = (0..truth.len()).collect();
        order.sort_by(|&a, &b| truth[a].t_s.total_cmp(&truth[b].t_s));
        Self {
            before: vec![None; truth.len()],
            after: vec![None; truth.len()],
            truth,
            opts: *opts,
            order,
            next: 0,
            first: None,
            last: None,
            rows: 0,
            span_last: None,
            span_rows: 0,
            span_len_m: 0.0,
            out_of_order_s: None,
            went_back: None,
            may_go_back: false,
        }
    }

    /// The next row comes after the estimator's clock stepped back
    /// (`Estimate::clock_stepped_back_s`): it may go back in time.
    pub fn clock_stepped_back(&mut self) {
        self.may_go_back = true;
    }

    /// One trajectory row.
    pub fn push(&mut self, t_s: f64, x_m: f64, y_m: f64) {
        if !(t_s.is_finite() && x_m.is_finite() && y_m.is_finite()) {
            return;
        }
        if let Some((t_last, _)) = self.last
            && t_s <= t_last
        {
            if !std::mem::take(&mut self.may_go_back) {
                self.out_of_order_s.get_or_insert(t_s);
                return;
            }
            // The estimator's clock stepped back: the rows run on from here (from the last
            // row's time too, on a clock that stepped back by whole periods), and the GCPs
            // they pass again were sampled before the step.
            let (_, n) = self.went_back.get_or_insert((t_s, 0));
            *n += 1;
        }
        self.may_go_back = false;
        let p = [x_m, y_m];
        while let Some(&i) = self.order.get(self.next)
            && self.truth[i].t_s <= t_s
        {
            self.before[i] = self.last;
            self.after[i] = Some((t_s, p));
            self.next += 1;
        }
        if let (Some(g0), Some(gn)) = (self.truth.first(), self.truth.last())
            && t_s >= g0.t_s
            && t_s <= gn.t_s
        {
            if let Some(q) = self.span_last {
                self.span_len_m += norm(sub(p, q));
            }
            self.span_last = Some(p);
            self.span_rows += 1;
        }
        self.first.get_or_insert((t_s, p));
        self.last = Some((t_s, p));
        self.rows += 1;
    }

    /// The evaluation of the rows pushed so far.
    pub fn finish(&self) -> Result<EvalReport, EvalError> {
        let (Some((t0, p0)), Some((t1, p1))) = (self.first, self.last) else {
            return Err(EvalError::TooFewTrajRows { rows: self.rows });
        };
        if self.rows < 2 {
            return Err(EvalError::TooFewTrajRows { rows: self.rows });
        }
        if self.truth.len() < 2 {
            return Err(EvalError::TooFewGcps {
                gcps: self.truth.len(),
            });
        }
        if let Some(t_s) = self.out_of_order_s {
            return Err(EvalError::NotIncreasing { t_s });
        }
        let gcp_t: Vec<f64> = self.truth.iter().map(|g| g.t_s).collect();
        super::check_overlap(&gcp_t, t0, t1)?;
        let n = self.truth.len();
        let (mut p, mut dt_used) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for (i, g) in self.truth.iter().enumerate() {
            let q = g.t_s;
            let (pos, dt) = match self.opts.interp {
                // As `sample_traj`: the nearest row, ties to the earlier; clamped to the ends.
                Interp::Nearest => match (self.before[i], self.after[i]) {
                    (_, None) => (p1, (t1 - q).abs()),
                    (None, Some(_)) => (p0, (t0 - q).abs()),
                    (Some((tb, pb)), Some((ta, pa))) => {
                        if q - tb <= ta - q {
                            (pb, (tb - q).abs())
                        } else {
                            (pa, (ta - q).abs())
                        }
                    }
                },
                // As `interp` on the clamped time.
                Interp::Linear => {
                    let qc = q.clamp(t0, t1);
                    let pos = match (self.before[i], self.after[i]) {
                        _ if qc >= t1 => p1,
                        (_, Some((ta, pa))) if ta == qc => pa,
                        (Some(b), Some(a)) => [lerp(qc, b, a, 0), lerp(qc, b, a, 1)],
                        _ => p0,
                    };
                    (pos, (q - qc).abs())
                }
            };
            p.push(pos);
            dt_used.push(dt);
        }
        let sampled = Sampled {
            p,
            dt_used,
            t_first: t0,
            t_last: t1,
            traj_len_m: if self.span_rows >= 2 {
                self.span_len_m
            } else {
                0.0
            },
        };
        let went_back = self.went_back.map(|(t_s, n)| {
            format!(
                "trajectory time went back {n} time(s), first at t = {t_s} s (the clock stepped \
                 back): footprint times the rows had passed were sampled before the step"
            )
        });
        let in_gaps: Vec<(usize, f64)> = (0..n)
            .filter_map(|i| match (self.before[i], self.after[i]) {
                // A footprint on a row is scored there exactly.
                (Some((tb, _)), Some((ta, _)))
                    if ta != self.truth[i].t_s && ta - tb > super::GAP_WARN_S =>
                {
                    Some((i, ta - tb))
                }
                _ => None,
            })
            .collect();
        let warnings = went_back
            .into_iter()
            .chain(super::gap_warning(&in_gaps))
            .collect();
        report(sampled, &self.truth, &self.opts, warnings)
    }
}

/// Coordinate `c` at `x` between the rows `b` and `a` (`b.0 < x < a.0`), with the arithmetic
/// of [`interp`].
fn lerp(x: f64, b: Fix, a: Fix, c: usize) -> f64 {
    let slope = (a.1[c] - b.1[c]) / (a.0 - b.0);
    let mut r = slope * (x - b.0) + b.1[c];
    if r.is_nan() {
        r = slope * (x - a.0) + a.1[c];
        if r.is_nan() && b.1[c] == a.1[c] {
            r = b.1[c];
        }
    }
    r
}
