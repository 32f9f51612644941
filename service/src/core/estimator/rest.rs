//! The initial rest's means of specific force and rate, without its last part.

use nalgebra::Vector3;

/// Sums of specific force and rate over part of the rest.
#[derive(Debug, Clone, Copy, Default)]
struct Sums {
    n: u64,
    /// Blocks summed (settled part only).
    blocks: u64,
    f: Vector3<f64>,
    w: Vector3<f64>,
    /// Sum of the squared rates, per axis.
    w2: Vector3<f64>,
}

impl Sums {
    fn add(&mut self, o: &Sums) {
        self.n += o.n;
        self.blocks += 1;
        self.f += o.f;
        self.w += o.w;
        self.w2 += o.w2;
    }
}

/// A rest's mean specific force (m/s²) and mean rate (rad/s), and the standard error of the mean
/// rate (rad/s), sensor axes.
pub(super) type RestMeans = (Vector3<f64>, Vector3<f64>, Vector3<f64>);

/// The initial rest, in blocks, so that its last `tail_s` (the foot already starting to move
/// while the detector still says "stance") can be left out of the means. Fixed capacity.
#[derive(Debug, Clone)]
pub(super) struct RestSums {
    pub(super) t_first_s: f64,
    settled: Sums,
    recent: std::collections::VecDeque<Sums>,
    current: Sums,
    current_start_s: f64,
    capacity: usize,
}

/// Block length of the rest accumulator.
const REST_BLOCK_S: f64 = 0.05;

impl RestSums {
    pub(super) fn new(tail_s: f64) -> Self {
        let capacity = (tail_s / REST_BLOCK_S).ceil() as usize + 1;
        Self {
            t_first_s: f64::NAN,
            settled: Sums::default(),
            recent: std::collections::VecDeque::with_capacity(capacity + 1),
            current: Sums::default(),
            current_start_s: f64::NAN,
            capacity,
        }
    }

    pub(super) fn clear(&mut self) {
        self.t_first_s = f64::NAN;
        self.settled = Sums::default();
        self.recent.clear();
        self.current = Sums::default();
    }

    pub(super) fn is_empty(&self) -> bool {
        self.t_first_s.is_nan()
    }

    pub(super) fn push(&mut self, t_s: f64, f: &Vector3<f64>, w: &Vector3<f64>) {
        if self.is_empty() {
            self.t_first_s = t_s;
            self.current_start_s = t_s;
        }
        if t_s - self.current_start_s >= REST_BLOCK_S {
            if self.recent.len() == self.capacity
                && let Some(old) = self.recent.pop_front()
            {
                self.settled.add(&old);
            }
            self.recent.push_back(self.current);
            self.current = Sums::default();
            self.current_start_s = t_s;
        }
        self.current.n += 1;
        self.current.f += f;
        self.current.w += w;
        self.current.w2 += w.component_mul(w);
    }

    /// Means of specific force and rate over the settled part (the rest without its tail), when
    /// that part lasts at least `min_s`.
    /// With the standard error of the mean rate ([`RestSums::rate_sd_of_mean`]).
    pub(super) fn settled_means(&self, min_s: f64) -> Option<RestMeans> {
        let s = &self.settled;
        (s.n > 0 && s.blocks as f64 * REST_BLOCK_S >= min_s)
            .then(|| (s.f / s.n as f64, s.w / s.n as f64, self.rate_sd_of_mean()))
    }

    /// Means over the settled part, or over everything when the rest was too short for that.
    pub(super) fn means(&self) -> (Vector3<f64>, Vector3<f64>) {
        let s = self.used();
        let n = s.n.max(1) as f64;
        (s.f / n, s.w / n)
    }

    /// A conservative standard error of the mean rate of [`RestSums::means`], per axis: the
    /// rate's per-sample spread over the square root of the number of 50 ms blocks, not of
    /// samples (samples within a block are not independent when the foot sways; for white noise
    /// alone this overstates the error by √(samples per block)). A rest that is not one (a foot that still moves) gives
    /// a mean rate far from the bias, and says so here.
    pub(super) fn rate_sd_of_mean(&self) -> Vector3<f64> {
        let s = self.used();
        let n = s.n.max(1) as f64;
        let mean = s.w / n;
        let var = (s.w2 / n - mean.component_mul(&mean)).map(|v| v.max(0.0));
        var.map(|v| (v / s.blocks.max(1) as f64).sqrt())
    }

    /// The part the means use: the settled part, or everything when that is empty.
    fn used(&self) -> Sums {
        let mut s = self.settled;
        if s.n == 0 {
            s.blocks = 0;
            for b in &self.recent {
                s.add(b);
            }
            s.add(&self.current);
        }
        s
    }
}
