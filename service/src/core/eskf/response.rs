//! How much of a gyro-bias error the filter has absorbed: the closed-loop response of the
//! linearised filter to a bias error present when the bias was last set.
//!
//! Let the bias estimate be off by `e_b` when the bias is set (the rest-mean prior, a saved
//! state, or the initial guess). The error state then evolves as `e ← F·e` between updates and
//! `e ← (I − K·H)·e` at each update, so `e(t) = R(t)·e_b` with the `n × 3` matrix `R` that
//! starts as the identity on the bias rows and zero elsewhere. Its bias rows, `R_b`, say what
//! fraction of such an error is still in the estimate: `I` at the start, towards 0 as heading,
//! ZUPT and rest information arrives. The injected-bias protocols of the results suite measure
//! the same thing from outside (the estimate with an injection minus the one without, over the
//! injection), so this is the filter's own, real-time prediction of that hindsight figure, and
//! the convergence flag rises on it.
//!
//! Where the filter redefines a state (`clear_state`: the heading when the map frame is fixed,
//! the bias when it is set) the response treats it as P does: that state's error no longer
//! depends on the start error. The map-frame fix turns the frame by an angle computed from the
//! first stride, so to first order it also moves the positions by the heading error it removes;
//! neither P nor the response carries that term.
//!
//! Unlike the bias σ it does not contain the random walk: a bias model that lets the bias
//! move 7e-4 rad/s/√s keeps σ near 3e-3 rad/s for ever, though an error of the start is long
//! gone. Cost: three more columns through `F` and through each update (11 % more instructions per
//! sample on the default configuration, `examples/core_once` under callgrind).

use super::*;

/// The response matrix: column-major with stride `MAX_N` (indexed as the covariance, `ix`),
/// column `j` the error state that a unit error of bias axis `j` has become.
pub(super) type Response = [f64; MAX_N * 3];

impl Eskf {
    /// Starts the response: a bias error now, nothing else (when the bias is estimated).
    pub(super) fn reset_bias_response(&mut self) {
        self.response = [0.0; MAX_N * 3];
        if self.estimate_bias {
            for k in 0..3 {
                self.response[ix(BG + k, k)] = 1.0;
            }
        }
    }

    /// After an update with gain `K` (row `i` of state `i`) and sparse Jacobian `h`:
    /// `R ← R − K·(H·R)`.
    pub(super) fn update_bias_response<const M: usize>(
        &mut self,
        h: &[[(usize, f64); 4]; M],
        k: &[[f64; M]; MAX_N],
    ) {
        let n = self.layout.n;
        for c in 0..3 {
            let col = &mut self.response[c * MAX_N..][..MAX_N];
            let hr: [f64; M] = std::array::from_fn(|a| h[a].iter().map(|&(i, v)| v * col[i]).sum());
            for (x, ki) in col.iter_mut().zip(k).take(n) {
                *x -= (0..M).map(|a| ki[a] * hr[a]).sum::<f64>();
            }
        }
    }

    /// After a velocity update (H selects the velocity) with gain columns `k[a]` (one per
    /// velocity axis).
    pub(super) fn update_bias_response_velocity(&mut self, k: &[[f64; MAX_N]; 3]) {
        let n = self.layout.n;
        for c in 0..3 {
            let col = &mut self.response[c * MAX_N..][..MAX_N];
            let hr = [col[V0], col[V0 + 1], col[V0 + 2]];
            for (i, x) in col.iter_mut().enumerate().take(n) {
                *x -= k[0][i] * hr[0] + k[1][i] * hr[1] + k[2][i] * hr[2];
            }
        }
    }

    /// The navigation frame rotated by `m` about z: the p, v and θ rows (and the clone's) rotate
    /// with it.
    pub(super) fn rotate_bias_response(&mut self, m: &Matrix3<f64>) {
        let layout = self.layout;
        for c in 0..3 {
            rotate_nav_rows(&mut self.response[c * MAX_N..][..MAX_N], m, layout.clones());
        }
    }

    /// A new footprint clone at state `k`: its error is the horizontal position's; with
    /// look-ahead the clone before it (`prev`) takes the old clone's first.
    pub(super) fn clone_bias_response(&mut self, k: usize, prev: Option<usize>) {
        for c in 0..3 {
            let col = &mut self.response[c * MAX_N..][..MAX_N];
            if let Some(j) = prev {
                col[j] = col[k];
                col[j + 1] = col[k + 1];
            }
            col[k] = col[P0];
            col[k + 1] = col[P0 + 1];
        }
    }

    /// The bias rows of the response: row `i`, column `j` is the part of a bias error of axis
    /// `j` (present when the bias was set) still in the estimate of axis `i`. Zero when the
    /// bias is not estimated.
    /// As of the last covariance step ([`Eskf::covariance_settled`]): between updates it may be
    /// up to [`EskfNoise::covariance_step_s`] old. It moves between updates only with the
    /// bias-rate states (b←d), so the convergence flag read from it waits at most that long.
    pub fn unabsorbed_bias_error(&self) -> Matrix3<f64> {
        Matrix3::from_fn(|i, j| self.response[ix(BG + i, j)])
    }
}

/// Rotates the navigation-frame rows of one column (of the covariance or of the response) by
/// `m`: the horizontal clones `clones` with the upper-left 2 × 2, and the p, v and θ blocks.
pub(super) fn rotate_nav_rows(
    col: &mut [f64],
    m: &Matrix3<f64>,
    clones: impl IntoIterator<Item = usize>,
) {
    for k in clones {
        rotate_horizontal(col, k, m);
    }
    for b in [P0, V0, TH] {
        rotate_block(col, b, m);
    }
}

/// `x[b..b + 3] ← m·x[b..b + 3]`.
pub(super) fn rotate_block(x: &mut [f64], b: usize, m: &Matrix3<f64>) {
    let v = [x[b], x[b + 1], x[b + 2]];
    for i in 0..3 {
        x[b + i] = m[(i, 0)] * v[0] + m[(i, 1)] * v[1] + m[(i, 2)] * v[2];
    }
}

/// `x[k..k + 2] ← m₂ₓ₂·x[k..k + 2]` (a horizontal pair).
pub(super) fn rotate_horizontal(x: &mut [f64], k: usize, m: &Matrix3<f64>) {
    let v = [x[k], x[k + 1]];
    for i in 0..2 {
        x[k + i] = m[(i, 0)] * v[0] + m[(i, 1)] * v[1];
    }
}

/// The largest absolute row sum of `m` (the ∞-norm): with a bias error of the same size on
/// every axis, the largest fraction of it left on one axis.
#[inline]
pub fn max_row_sum(m: &Matrix3<f64>) -> f64 {
    // `column_sum` adds the columns: the vector of the row sums.
    m.abs().column_sum().max()
}
