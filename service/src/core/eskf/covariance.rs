//! `P ← F P Fᵀ + Q`, written out on the column-major storage for the sparse transition, and
//! the steps that wait between updates (`eskf.covariance_step_s`), summed into one.

use super::*;

/// Row i of `fvt` (−[f]×·dt) times `v`: the skew matrix's zero diagonal term is left out.
#[inline]
fn skew_dot(fvt: &[[f64; 3]; 3], i: usize, v: &[f64; 3]) -> f64 {
    let m = &fvt[i];
    match i {
        0 => m[1] * v[1] + m[2] * v[2],
        1 => m[0] * v[0] + m[2] * v[2],
        _ => m[0] * v[0] + m[1] * v[1],
    }
}

#[inline]
fn dot3(m: &[f64; 3], v: &[f64; 3]) -> f64 {
    m[0] * v[0] + m[1] * v[1] + m[2] * v[2]
}

/// `dst ← F·src` for the first `cols` columns (column-major, stride `MAX_N`) when every
/// extension state is constant between updates (their rows of F are the identity): writes
/// every element of those columns, so `dst` need not hold `src`.
fn f_times_base(
    src: &[f64],
    dst: &mut [f64],
    cols: usize,
    fvt: &[[f64; 3]; 3],
    ftb: &[[f64; 3]; 3],
    dt: f64,
) {
    for col in 0..cols {
        let (s, c) = (
            &src[col * MAX_N..][..MAX_N],
            &mut dst[col * MAX_N..][..MAX_N],
        );
        let p = [s[P0], s[P0 + 1], s[P0 + 2]];
        let v = [s[V0], s[V0 + 1], s[V0 + 2]];
        let th = [s[TH], s[TH + 1], s[TH + 2]];
        let b = [s[BG], s[BG + 1], s[BG + 2]];
        for i in 0..3 {
            c[P0 + i] = p[i] + dt * v[i];
            c[V0 + i] = v[i] + skew_dot(fvt, i, &th);
            c[TH + i] = th[i] + dot3(&ftb[i], &b);
            c[BG + i] = b[i];
        }
        // The extension rows, and the unused ones below them (zero in both): a fixed-size
        // copy, which compiles to a few vector moves.
        c[BASE_N..].copy_from_slice(&s[BASE_N..]);
    }
}

/// `P ← F P₀ Fᵀ` (without Q) for the base 12-state filter plus extension states that are
/// constant between updates: the common case. `F = I + G` changes only the rows and columns of
/// p, v and θ (the first 9 states, "D"); the bias and the extensions ("S") keep their block.
/// Computed on one triangle and mirrored, so `P` stays exactly symmetric:
/// - the columns of S are final after one pass: `P'[:, j] = F·P₀[:, j]` (F's row j is the
///   identity's), rows D computed and rows S copied;
/// - the D×D block is `N = M + M·Gᵀ` with `M = (F P₀)[D, D]` and the bias columns of `F P₀`
///   from the first pass; its upper triangle is kept and mirrored;
/// - the S rows of the D columns are the mirror of the first pass.
///
/// 216 computed elements for the 15-state default filter (54 in the S columns, 81 each of M
/// and N), against 270 for the two full passes of `F·P₀·Fᵀ` this replaced, and no asymmetry
/// from rounding. `a` need not hold `P₀`: every used element is written.
fn propagate_base(
    p0: &[f64; MAX_N * MAX_N],
    a: &mut [f64; MAX_N * MAX_N],
    n: usize,
    fvt: &[[f64; 3]; 3],
    ftb: &[[f64; 3]; 3],
    dt: f64,
) {
    const D: usize = BG;
    // Columns of S (the bias and the extensions): F·P₀, every row.
    f_times_base(
        &p0[BG * MAX_N..],
        &mut a[BG * MAX_N..],
        n - BG,
        fvt,
        ftb,
        dt,
    );
    // M = (F P₀)[D, D], column by column.
    let mut m = [[0.0; D]; D];
    for (col, mc) in m.iter_mut().enumerate() {
        let s = &p0[col * MAX_N..][..BASE_N];
        let v = [s[V0], s[V0 + 1], s[V0 + 2]];
        let th = [s[TH], s[TH + 1], s[TH + 2]];
        let b = [s[BG], s[BG + 1], s[BG + 2]];
        for i in 0..3 {
            mc[P0 + i] = s[P0 + i] + dt * v[i];
            mc[V0 + i] = v[i] + skew_dot(fvt, i, &th);
            mc[TH + i] = th[i] + dot3(&ftb[i], &b);
        }
    }
    // The bias columns of F P₀ on the rows of D, from the first pass.
    let fb: [[f64; D]; 3] = std::array::from_fn(|k| std::array::from_fn(|i| a[ix(i, BG + k)]));
    // N = M·Fᵀ = M + M·Gᵀ: column j of N is column j of M plus G's row j applied to the
    // columns of F P₀ (p ← v: dt; v ← θ: −[f]×dt; θ ← b: −C·dt).
    let mut nn = m;
    for k in 0..3 {
        let [f0, f1, f2] = fvt[k];
        let [b0, b1, b2] = ftb[k];
        for i in 0..D {
            nn[P0 + k][i] += dt * m[V0 + k][i];
            nn[V0 + k][i] += match k {
                0 => f1 * m[TH + 1][i] + f2 * m[TH + 2][i],
                1 => f0 * m[TH][i] + f2 * m[TH + 2][i],
                _ => f0 * m[TH][i] + f1 * m[TH + 1][i],
            };
            nn[TH + k][i] += b0 * fb[0][i] + b1 * fb[1][i] + b2 * fb[2][i];
        }
    }
    // P'[D, D]: N's upper triangle, mirrored.
    for j in 0..D {
        let col = &mut a[j * MAX_N..][..D];
        for (i, c) in col.iter_mut().enumerate() {
            *c = if i <= j { nn[j][i] } else { nn[i][j] };
        }
    }
    // Rows S of the D columns: the mirror of the first pass.
    for i in 0..D {
        for j in BG..n.min(MAX_N) {
            a[ix(j, i)] = a[ix(i, j)];
        }
    }
}

/// The blocks of the transition `F = I + G` over one covariance step (see
/// [`Eskf::propagate_covariance_from`]): one sample's, or the sum of the samples' whose steps
/// were deferred, with the process noise they add. Every block is linear in its sample's
/// interval, so an interval of a few samples is `I` plus the sum of their `G`: first order, as
/// each sample's own `F` is (the products of two samples' blocks, `p←θ` and `v←b`, of order
/// dt², are left out, as within a sample).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Pending {
    /// Samples summed (0: none deferred).
    samples: u32,
    dt: f64,
    /// v←θ: −[f]×·dt.
    fvt: [[f64; 3]; 3],
    /// θ←b: −C·dt (zero when the bias is frozen).
    ftb: [[f64; 3]; 3],
    /// θ←s: −C·diag(ω)·dt (scale-factor states only).
    fts: [[f64; 3]; 3],
    /// θ←k: −C·diag(f)·dt (g-sensitivity states only).
    ftk: [[f64; 3]; 3],
    /// θ←m: the z column of −C·dt times ω_x, ω_y (coupling states only).
    ftm: [[f64; 2]; 3],
    /// The attitude's process noise, Σ σ²·dt (the swing's or the rest's σ, per sample).
    gyro_var: f64,
    /// Attitude noise about particular axes (navigation frame, rad²): the rotation a clipped
    /// gyro axis did not measure ([`Eskf::widen_attitude_about`]), added with the rest of the
    /// interval's noise.
    attitude_var: [[f64; 3]; 3],
    /// The velocity noise of each sample goes into the position over the samples after it, as
    /// one step per sample would take it: Σ dtᵢ·aᵢ and Σ dtᵢ·aᵢ², aᵢ the interval's time after
    /// sample i (the position-velocity and position terms of Q, per unit noise density²).
    accel_pv_s2: f64,
    accel_pp_s3: f64,
}

fn add3(a: &mut [[f64; 3]; 3], b: &[[f64; 3]; 3]) {
    for (ra, rb) in a.iter_mut().zip(b) {
        for (x, y) in ra.iter_mut().zip(rb) {
            *x += y;
        }
    }
}

impl Pending {
    /// `o` (one sample) after the samples summed so far. Inline: out of line (as the code
    /// around it changed in session 47) the sample's blocks went through `memcpy`, 3.5 % more
    /// instructions per sample.
    #[inline(always)]
    fn append(&mut self, o: &Pending) {
        debug_assert_eq!(o.samples, 1);
        let d = o.dt;
        self.accel_pp_s3 += d * (2.0 * self.accel_pv_s2 + d * self.dt);
        self.accel_pv_s2 += d * self.dt;
        self.samples += o.samples;
        self.dt += o.dt;
        add3(&mut self.fvt, &o.fvt);
        add3(&mut self.ftb, &o.ftb);
        add3(&mut self.fts, &o.fts);
        add3(&mut self.ftk, &o.ftk);
        add3(&mut self.attitude_var, &o.attitude_var);
        for (ra, rb) in self.ftm.iter_mut().zip(&o.ftm) {
            ra[0] += rb[0];
            ra[1] += rb[1];
        }
        self.gyro_var += o.gyro_var;
    }
}

/// `p[θ, θ] += var` (column-major `var`, as `p`).
fn add_attitude_var(p: &mut [f64; MAX_N * MAX_N], var: &[[f64; 3]; 3]) {
    for (j, col) in var.iter().enumerate() {
        for (i, v) in col.iter().enumerate() {
            p[ix(TH + i, TH + j)] += v;
        }
    }
}

/// Whether a sample's covariance step may wait (see [`Eskf::propagate_into`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CovarianceStep {
    /// Propagated now, with the steps deferred before it: an update follows (a stance
    /// sample). Deferred, the first update would bring it up to date anyway, at the cost of a
    /// copy of the covariance.
    Now,
    /// Deferred while the deferred interval stays shorter than the filter's covariance step
    /// ([`EskfNoise::covariance_step_s`]).
    MayDefer,
}

struct Transition<'a> {
    t: &'a Pending,
    lay: Layout,
    /// The bias-rate states, when the bias is estimated.
    b_rate: Option<usize>,
}

impl Transition<'_> {
    /// `c ← F·c` for one column `c` (the leading `n` elements of a column of P, or of the
    /// bias-error response): rows p, v, θ, b read the old rows v, θ, b/s/k/m, d.
    #[inline]
    fn apply(&self, c: &mut [f64]) {
        let dot2 = |m: &[f64; 2], v: [f64; 2]| m[0] * v[0] + m[1] * v[1];
        let (lay, t) = (&self.lay, self.t);
        let v = [c[V0], c[V0 + 1], c[V0 + 2]];
        let th = [c[TH], c[TH + 1], c[TH + 2]];
        let b = [c[BG], c[BG + 1], c[BG + 2]];
        let s = lay.scale.map(|i| [c[i], c[i + 1], c[i + 2]]);
        let k = lay.gsens.map(|i| [c[i], c[i + 1], c[i + 2]]);
        let m = lay.coupling.map(|i| [c[i], c[i + 1]]);
        let d = self.b_rate.map(|i| [c[i], c[i + 1], c[i + 2]]);
        for i in 0..3 {
            c[P0 + i] += t.dt * v[i];
            c[V0 + i] += dot3(&t.fvt[i], &th);
            let mut dth = dot3(&t.ftb[i], &b);
            if let Some(s) = s {
                dth += dot3(&t.fts[i], &s);
            }
            if let Some(k) = k {
                dth += dot3(&t.ftk[i], &k);
            }
            if let Some(m) = m {
                dth += dot2(&t.ftm[i], m);
            }
            c[TH + i] += dth;
            if let Some(d) = d {
                c[BG + i] += t.dt * d[i];
            }
        }
    }
}

impl Eskf {
    /// P ← F P Fᵀ + Q for the sparse F = I + G with the blocks
    /// p←v: dt·I, v←θ: −[f]×dt, θ←b: −C·dt, θ←s: −C·diag(ω)·dt, θ←k: −C·diag(f)·dt,
    /// θ←m: −C·[0 0; 0 0; ω_x ω_y]·dt (the third column of −C·dt times ω_x, ω_y), b←d: dt·I.
    /// First order in the extension estimates, as the scale factor's block: the terms they add
    /// to the others (θ←b through `(1 + s)⁻¹` and `m`, a few % of the direct ones) are left out.
    /// Written out on the column-major storage: about 500 multiply-adds for the base filter
    /// instead of the 3,500 of a dense product (the hot path of the core).
    /// `before` is the filter before the step: its covariance and bias-error response
    /// (`response.rs`) are read, `self`'s overwritten.
    ///
    /// With [`CovarianceStep::MayDefer`] the step waits, summed with the samples' before it
    /// (`Pending`), while their interval stays shorter than [`EskfNoise::covariance_step_s`]
    /// (within half a sample): `self` gets `before`'s covariance, and the first method that
    /// changes or needs it ([`Eskf::settle_covariance`]) brings it up to date.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn propagate_covariance_from(
        &mut self,
        before: &Eskf,
        f_vth: &Matrix3<f64>,
        minus_c_dt: &Matrix3<f64>,
        omega: &Vector3<f64>,
        f_body: &Vector3<f64>,
        dt: f64,
        step: CovarianceStep,
    ) {
        let lay = self.layout;
        let m3 = |m: &Matrix3<f64>| -> [[f64; 3]; 3] {
            std::array::from_fn(|i| std::array::from_fn(|k| m[(i, k)]))
        };
        let gyro = if self.at_rest {
            self.noise.rest_gyro_rad_s
        } else {
            self.noise.gyro_rad_s
        };
        let mut t = Pending {
            samples: 1,
            dt,
            fvt: m3(f_vth),
            gyro_var: gyro * gyro * dt,
            ..Default::default()
        };
        if self.estimate_bias {
            t.ftb = m3(minus_c_dt);
        }
        if !lay.static_extensions_only() {
            // θ←s and θ←k blocks: −C·diag(ω)·dt and −C·diag(f)·dt.
            t.fts = m3(&(minus_c_dt * Matrix3::from_diagonal(omega)));
            t.ftk = m3(&(minus_c_dt * Matrix3::from_diagonal(f_body)));
            // θ←m rows: (−C·dt)[i, z] · (ω_x, ω_y).
            t.ftm = std::array::from_fn(|i| {
                [minus_c_dt[(i, 2)] * omega.x, minus_c_dt[(i, 2)] * omega.y]
            });
        }
        if before.pending.samples > 0 {
            let mut sum = before.pending;
            sum.append(&t);
            t = sum;
        }
        if step == CovarianceStep::MayDefer && t.dt + 0.5 * dt < self.noise.covariance_step_s {
            // The leading n columns in one copy (whole columns: one call, not n).
            let used = lay.n.min(MAX_N) * MAX_N;
            self.p[..used].copy_from_slice(&before.p[..used]);
            self.response = before.response;
            self.pending = t;
            return;
        }
        self.pending = Pending::default();
        self.step_covariance(&before.p, &before.response, &t);
    }

    /// Applies the covariance steps deferred so far (see [`Eskf::propagate_covariance_from`]):
    /// every method that changes the covariance or decides from it calls this first.
    #[inline]
    pub(super) fn settle_covariance(&mut self) {
        if self.pending.samples > 0 {
            self.settle_deferred();
        }
    }

    #[cold]
    #[inline(never)]
    fn settle_deferred(&mut self) {
        let t = std::mem::take(&mut self.pending);
        let (p0, response0) = (self.p, self.response);
        self.step_covariance(&p0, &response0, &t);
    }

    /// `var` (navigation frame, rad², symmetric) onto the attitude's covariance now, or, while
    /// covariance steps wait, with their noise at the interval's end (as the gyro noise is).
    pub(super) fn widen_attitude(&mut self, var: &[[f64; 3]; 3]) {
        if self.pending.samples > 0 {
            add3(&mut self.pending.attitude_var, var);
        } else {
            add_attitude_var(&mut self.p, var);
        }
    }

    /// Whether no covariance step waits: the covariance is the current one.
    pub fn covariance_settled(&self) -> bool {
        self.pending.samples == 0
    }

    /// `self.p ← F P₀ Fᵀ + Q` and the bias-error response through F, for the transition `t`
    /// (one sample's or several summed).
    fn step_covariance(
        &mut self,
        p0: &[f64; MAX_N * MAX_N],
        response0: &response::Response,
        t: &Pending,
    ) {
        let lay = self.layout;
        let n = lay.n;
        let b_rate = lay.rate.filter(|_| self.estimate_bias);
        let dt = t.dt;
        let a = &mut self.p;
        if lay.static_extensions_only() {
            propagate_base(p0, a, n, &t.fvt, &t.ftb, dt);
            // The bias-error response (`response.rs`) goes through F alone.
            f_times_base(response0, &mut self.response, 3, &t.fvt, &t.ftb, dt);
        } else {
            let tr = Transition { t, lay, b_rate };
            self.response = *response0;
            for c in 0..3 {
                tr.apply(&mut self.response[c * MAX_N..][..MAX_N]);
            }
            for c in 0..n {
                a[c * MAX_N..][..n].copy_from_slice(&p0[c * MAX_N..][..n]);
            }
            // M = F P: rows p, v, θ, b read the old rows v, θ, b/s/k, d.
            for col in 0..n {
                tr.apply(&mut a[col * MAX_N..col * MAX_N + n]);
            }
            // P' = M Fᵀ: each row of M goes through F the same way (Fᵀ on the right).
            for row in 0..n {
                let mut x: [f64; MAX_N] = std::array::from_fn(|c| a[ix(row, c)]);
                tr.apply(&mut x[..n]);
                for (c, v) in x.iter().enumerate().take(n) {
                    a[ix(row, c)] = *v;
                }
            }
        }
        let qa = self.noise.accel_m_s2.powi(2) * dt;
        let qb = if self.estimate_bias {
            self.noise.gyro_bias_rw_rad_s_sqrt_s.powi(2) * dt
        } else {
            0.0
        };
        for i in 0..3 {
            a[ix(V0 + i, V0 + i)] += qa;
            a[ix(TH + i, TH + i)] += t.gyro_var;
            a[ix(BG + i, BG + i)] += qb;
        }
        // The rotation a clipped axis did not measure while the steps waited (one that came
        // with no step waiting went onto the covariance at once).
        if t.attitude_var != [[0.0; 3]; 3] {
            add_attitude_var(a, &t.attitude_var);
        }
        if t.samples > 1 {
            let q = self.noise.accel_m_s2.powi(2);
            for i in 0..3 {
                a[ix(P0 + i, P0 + i)] += q * t.accel_pp_s3;
                a[ix(P0 + i, V0 + i)] += q * t.accel_pv_s2;
                a[ix(V0 + i, P0 + i)] += q * t.accel_pv_s2;
            }
        }
        if let (Some(i), Some(rw)) = (b_rate, self.ext_cfg.bias_rate_rw) {
            for k in 0..3 {
                a[ix(i + k, i + k)] += rw * rw * dt;
            }
        }
    }
}
