//! A fixed-size log-scale latency histogram: no allocation when recording.

/// Sub-buckets per octave of the latency histogram (resolution about 9 %).
const SUB_BUCKETS: usize = 8;

/// A fixed-size log-scale histogram of latencies in ns: no allocation when recording.
#[derive(Debug, Clone)]
pub(super) struct LatencyHistogram {
    counts: [u32; 64 * SUB_BUCKETS],
    n: u64,
}

impl LatencyHistogram {
    pub(super) fn new() -> Self {
        Self {
            counts: [0; 64 * SUB_BUCKETS],
            n: 0,
        }
    }

    pub(super) fn bucket(ns: u64) -> usize {
        if ns < SUB_BUCKETS as u64 {
            return ns as usize;
        }
        let octave = 63 - ns.leading_zeros() as usize; // ≥ 3
        let sub = ((ns >> (octave - 3)) & (SUB_BUCKETS as u64 - 1)) as usize;
        (octave - 2) * SUB_BUCKETS + sub
    }

    /// Middle of a bucket, ns.
    pub(super) fn value(bucket: usize) -> f64 {
        if bucket < SUB_BUCKETS {
            return bucket as f64;
        }
        let octave = bucket / SUB_BUCKETS + 2;
        let sub = bucket % SUB_BUCKETS;
        let low = ((SUB_BUCKETS + sub) as f64) * (1u64 << (octave - 3)) as f64;
        low + 0.5 * (1u64 << (octave - 3)) as f64
    }

    pub(super) fn record(&mut self, ns: u64) {
        let b = Self::bucket(ns).min(self.counts.len() - 1);
        self.counts[b] = self.counts[b].saturating_add(1);
        self.n += 1;
    }

    /// The `q` quantile (0..=1), s; NaN when empty.
    pub(super) fn quantile_s(&self, q: f64) -> f64 {
        if self.n == 0 {
            return f64::NAN;
        }
        let rank = ((q * self.n as f64).ceil() as u64).clamp(1, self.n);
        let mut acc = 0u64;
        for (b, &c) in self.counts.iter().enumerate() {
            acc += u64::from(c);
            if acc >= rank {
                return Self::value(b) * 1e-9;
            }
        }
        f64::NAN
    }

    pub(super) fn clear(&mut self) {
        self.counts.fill(0);
        self.n = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latency_histogram_quantiles_are_within_a_bucket() {
        let mut h = LatencyHistogram::new();
        assert!(h.quantile_s(0.5).is_nan());
        for ns in 1..=1000u64 {
            h.record(ns * 1000); // 1 µs .. 1 ms, uniform
        }
        let p50 = h.quantile_s(0.5);
        let p99 = h.quantile_s(0.99);
        assert!((p50 - 500e-6).abs() < 0.07 * 500e-6, "{p50}");
        assert!((p99 - 990e-6).abs() < 0.07 * 990e-6, "{p99}");
        h.record(u64::MAX); // clamped into the last bucket, no panic
        h.clear();
        assert!(h.quantile_s(0.99).is_nan());
        for ns in 0..8 {
            assert_eq!(
                LatencyHistogram::value(LatencyHistogram::bucket(ns)),
                ns as f64
            );
        }
    }
}
