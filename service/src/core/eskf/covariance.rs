//! `P ← F P Fᵀ + Q`, written out on the column-major storage for the sparse transition.

use super::*;

/// `P ← F P₀ Fᵀ` (without Q) for the base 12-state filter plus extension states that are
/// constant between updates (their rows of F are the identity): the common case. The first
/// pass (`F P₀`) reads `p0` and writes every used element of `a`, so `a` need not hold `P₀`.
fn propagate_base(
    p0: &[f64; MAX_N * MAX_N],
    a: &mut [f64; MAX_N * MAX_N],
    n: usize,
    fvt: &[[f64; 3]; 3],
    ftb: &[[f64; 3]; 3],
    dt: f64,
) {
    let dot3 = |m: &[f64; 3], v: &[f64; 3]| m[0] * v[0] + m[1] * v[1] + m[2] * v[2];
    // Row i of `fvt` = −[f]×·dt times v: the skew matrix's zero diagonal term is left out.
    let skew_dot = |i: usize, v: &[f64; 3]| {
        let m = &fvt[i];
        match i {
            0 => m[1] * v[1] + m[2] * v[2],
            1 => m[0] * v[0] + m[2] * v[2],
            _ => m[0] * v[0] + m[1] * v[1],
        }
    };
    for col in 0..n {
        let (s, c) = (&p0[col * MAX_N..][..MAX_N], &mut a[col * MAX_N..][..MAX_N]);
        let p = [s[P0], s[P0 + 1], s[P0 + 2]];
        let v = [s[V0], s[V0 + 1], s[V0 + 2]];
        let th = [s[TH], s[TH + 1], s[TH + 2]];
        let b = [s[BG], s[BG + 1], s[BG + 2]];
        for i in 0..3 {
            c[P0 + i] = p[i] + dt * v[i];
            c[V0 + i] = v[i] + skew_dot(i, &th);
            c[TH + i] = th[i] + dot3(&ftb[i], &b);
            c[BG + i] = b[i];
        }
        // The extension rows, and the unused ones below them (zero in both): a fixed-size
        // copy, which compiles to a few vector moves.
        c[BASE_N..].copy_from_slice(&s[BASE_N..]);
    }
    for row in 0..n {
        let v = [a[ix(row, V0)], a[ix(row, V0 + 1)], a[ix(row, V0 + 2)]];
        let th = [a[ix(row, TH)], a[ix(row, TH + 1)], a[ix(row, TH + 2)]];
        let b = [a[ix(row, BG)], a[ix(row, BG + 1)], a[ix(row, BG + 2)]];
        for i in 0..3 {
            a[ix(row, P0 + i)] += dt * v[i];
            a[ix(row, V0 + i)] += skew_dot(i, &th);
            a[ix(row, TH + i)] += dot3(&ftb[i], &b);
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
    /// `p0` is the covariance before the step; `self`'s is overwritten.
    pub(super) fn propagate_covariance_from(
        &mut self,
        p0: &[f64; MAX_N * MAX_N],
        f_vth: &Matrix3<f64>,
        minus_c_dt: &Matrix3<f64>,
        omega: &Vector3<f64>,
        f_body: &Vector3<f64>,
        dt: f64,
    ) {
        let lay = self.layout;
        let n = lay.n;
        let m3 = |m: &Matrix3<f64>| -> [[f64; 3]; 3] {
            std::array::from_fn(|i| std::array::from_fn(|k| m[(i, k)]))
        };
        let fvt = m3(f_vth);
        let ftb = if self.estimate_bias {
            m3(minus_c_dt)
        } else {
            [[0.0; 3]; 3]
        };
        let b_rate = lay.rate.filter(|_| self.estimate_bias);
        let a = &mut self.p;
        let dot3 = |m: &[f64; 3], v: [f64; 3]| m[0] * v[0] + m[1] * v[1] + m[2] * v[2];
        if lay.static_extensions_only() {
            propagate_base(p0, a, n, &fvt, &ftb, dt);
        } else {
            for c in 0..n {
                a[c * MAX_N..][..n].copy_from_slice(&p0[c * MAX_N..][..n]);
            }
            // θ←s and θ←k blocks: −C·diag(ω)·dt and −C·diag(f)·dt.
            let fts = m3(&(minus_c_dt * Matrix3::from_diagonal(omega)));
            let ftk = m3(&(minus_c_dt * Matrix3::from_diagonal(f_body)));
            // θ←m rows: (−C·dt)[i, z] · (ω_x, ω_y).
            let ftm: [[f64; 2]; 3] = std::array::from_fn(|i| {
                [minus_c_dt[(i, 2)] * omega.x, minus_c_dt[(i, 2)] * omega.y]
            });
            let dot2 = |m: &[f64; 2], v: [f64; 2]| m[0] * v[0] + m[1] * v[1];
            // M = F P: rows p, v, θ, b read the old rows v, θ, b/s/k, d.
            for col in 0..n {
                let c = &mut a[col * MAX_N..col * MAX_N + n];
                let v = [c[V0], c[V0 + 1], c[V0 + 2]];
                let th = [c[TH], c[TH + 1], c[TH + 2]];
                let b = [c[BG], c[BG + 1], c[BG + 2]];
                let s = lay.scale.map(|i| [c[i], c[i + 1], c[i + 2]]);
                let k = lay.gsens.map(|i| [c[i], c[i + 1], c[i + 2]]);
                let m = lay.coupling.map(|i| [c[i], c[i + 1]]);
                let d = b_rate.map(|i| [c[i], c[i + 1], c[i + 2]]);
                for i in 0..3 {
                    c[P0 + i] += dt * v[i];
                    c[V0 + i] += dot3(&fvt[i], th);
                    let mut dth = dot3(&ftb[i], b);
                    if let Some(s) = s {
                        dth += dot3(&fts[i], s);
                    }
                    if let Some(k) = k {
                        dth += dot3(&ftk[i], k);
                    }
                    if let Some(m) = m {
                        dth += dot2(&ftm[i], m);
                    }
                    c[TH + i] += dth;
                    if let Some(d) = d {
                        c[BG + i] += dt * d[i];
                    }
                }
            }
            // P' = M Fᵀ: columns p, v, θ, b read the old columns.
            let col = |a: &[f64; MAX_N * MAX_N], row: usize, c0: usize| {
                [a[ix(row, c0)], a[ix(row, c0 + 1)], a[ix(row, c0 + 2)]]
            };
            for row in 0..n {
                let v = col(a, row, V0);
                let th = col(a, row, TH);
                let b = col(a, row, BG);
                let s = lay.scale.map(|i| col(a, row, i));
                let k = lay.gsens.map(|i| col(a, row, i));
                let m = lay.coupling.map(|i| [a[ix(row, i)], a[ix(row, i + 1)]]);
                let d = b_rate.map(|i| col(a, row, i));
                for i in 0..3 {
                    a[ix(row, P0 + i)] += dt * v[i];
                    a[ix(row, V0 + i)] += dot3(&fvt[i], th);
                    let mut dth = dot3(&ftb[i], b);
                    if let Some(s) = s {
                        dth += dot3(&fts[i], s);
                    }
                    if let Some(k) = k {
                        dth += dot3(&ftk[i], k);
                    }
                    if let Some(m) = m {
                        dth += dot2(&ftm[i], m);
                    }
                    a[ix(row, TH + i)] += dth;
                    if let Some(d) = d {
                        a[ix(row, BG + i)] += dt * d[i];
                    }
                }
            }
        }
        let qa = self.noise.accel_m_s2.powi(2) * dt;
        let qg = self.noise.gyro_rad_s.powi(2) * dt;
        let qb = if self.estimate_bias {
            self.noise.gyro_bias_rw.powi(2) * dt
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
