//! `P ← F P Fᵀ + Q`, written out on the column-major storage for the sparse transition.

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

/// The blocks of one step's transition `F = I + G` (see
/// [`Eskf::propagate_covariance_from`]).
struct Transition {
    dt: f64,
    /// v←θ: −[f]×·dt.
    fvt: [[f64; 3]; 3],
    /// θ←b: −C·dt (zero when the bias is frozen).
    ftb: [[f64; 3]; 3],
    /// θ←s: −C·diag(ω)·dt.
    fts: [[f64; 3]; 3],
    /// θ←k: −C·diag(f)·dt.
    ftk: [[f64; 3]; 3],
    /// θ←m: the z column of −C·dt times ω_x, ω_y.
    ftm: [[f64; 2]; 3],
    lay: Layout,
    /// The bias-rate states, when the bias is estimated.
    b_rate: Option<usize>,
}

impl Transition {
    /// `c ← F·c` for one column `c` (the leading `n` elements of a column of P, or of the
    /// bias-error response): rows p, v, θ, b read the old rows v, θ, b/s/k/m, d.
    #[inline]
    fn apply(&self, c: &mut [f64]) {
        let dot2 = |m: &[f64; 2], v: [f64; 2]| m[0] * v[0] + m[1] * v[1];
        let lay = &self.lay;
        let v = [c[V0], c[V0 + 1], c[V0 + 2]];
        let th = [c[TH], c[TH + 1], c[TH + 2]];
        let b = [c[BG], c[BG + 1], c[BG + 2]];
        let s = lay.scale.map(|i| [c[i], c[i + 1], c[i + 2]]);
        let k = lay.gsens.map(|i| [c[i], c[i + 1], c[i + 2]]);
        let m = lay.coupling.map(|i| [c[i], c[i + 1]]);
        let d = self.b_rate.map(|i| [c[i], c[i + 1], c[i + 2]]);
        for i in 0..3 {
            c[P0 + i] += self.dt * v[i];
            c[V0 + i] += dot3(&self.fvt[i], &th);
            let mut dth = dot3(&self.ftb[i], &b);
            if let Some(s) = s {
                dth += dot3(&self.fts[i], &s);
            }
            if let Some(k) = k {
                dth += dot3(&self.ftk[i], &k);
            }
            if let Some(m) = m {
                dth += dot2(&self.ftm[i], m);
            }
            c[TH + i] += dth;
            if let Some(d) = d {
                c[BG + i] += self.dt * d[i];
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
    pub(super) fn propagate_covariance_from(
        &mut self,
        before: &Eskf,
        f_vth: &Matrix3<f64>,
        minus_c_dt: &Matrix3<f64>,
        omega: &Vector3<f64>,
        f_body: &Vector3<f64>,
        dt: f64,
    ) {
        let (p0, response0) = (&before.p, &before.response);
        let lay = self.layout;
        let n = lay.n;
        let b_rate = lay.rate.filter(|_| self.estimate_bias);
        let m3 = |m: &Matrix3<f64>| -> [[f64; 3]; 3] {
            std::array::from_fn(|i| std::array::from_fn(|k| m[(i, k)]))
        };
        let fvt = m3(f_vth);
        let ftb = if self.estimate_bias {
            m3(minus_c_dt)
        } else {
            [[0.0; 3]; 3]
        };
        let a = &mut self.p;
        if lay.static_extensions_only() {
            propagate_base(p0, a, n, &fvt, &ftb, dt);
            // The bias-error response (`response.rs`) goes through F alone.
            f_times_base(response0, &mut self.response, 3, &fvt, &ftb, dt);
        } else {
            let tr = Transition {
                dt,
                fvt,
                ftb,
                // θ←s and θ←k blocks: −C·diag(ω)·dt and −C·diag(f)·dt.
                fts: m3(&(minus_c_dt * Matrix3::from_diagonal(omega))),
                ftk: m3(&(minus_c_dt * Matrix3::from_diagonal(f_body))),
                // θ←m rows: (−C·dt)[i, z] · (ω_x, ω_y).
                ftm: std::array::from_fn(|i| {
                    [minus_c_dt[(i, 2)] * omega.x, minus_c_dt[(i, 2)] * omega.y]
                }),
                lay,
                b_rate,
            };
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
        let gyro = if self.at_rest {
            self.noise.rest_gyro_rad_s
        } else {
            self.noise.gyro_rad_s
        };
        let qg = gyro.powi(2) * dt;
        let qb = if self.estimate_bias {
            self.noise.gyro_bias_rw_rad_s_sqrt_s.powi(2) * dt
        } else {
            0.0
        };
        for i in 0..3 {
            a[ix(V0 + i, V0 + i)] += qa;
            a[ix(TH + i, TH + i)] += qg;
            a[ix(BG + i, BG + i)] += qb;
        }
        if let (Some(i), Some(rw)) = (b_rate, self.ext_cfg.bias_rate_rw) {
            for k in 0..3 {
                a[ix(i + k, i + k)] += rw * rw * dt;
            }
        }
    }
}
