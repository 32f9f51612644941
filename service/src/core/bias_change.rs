//! Detection of a gyro-bias change after start-up: a two-sided CUSUM (Page 1954) on the
//! normalised heading innovations `r/√S` of the used stride-direction and foot-axis
//! observations.
//!
//! A constant bias error makes the heading drift one way whatever the walking direction, so
//! its innovations keep one sign; white innovations do not. The statistic grows by `z − k`
//! (and `−z − k`) per observation and alarms above `h`; with k = 0.5 and h = 5 a consistent
//! mean of one σ alarms after about ten observations, and white unit-variance innovations
//! alarm about once every 900 observations (the average run length of that design).
//! On an alarm the estimator widens the bias covariance again, so that the filter can follow the
//! new bias instead of holding on to a prior that no longer holds.

/// Drift `k` of the CUSUM, in σ of the innovation.
pub const CUSUM_DRIFT: f64 = 0.5;

/// The two-sided CUSUM.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiasChangeDetector {
    threshold: f64,
    pos: f64,
    neg: f64,
}

impl BiasChangeDetector {
    /// A detector alarming above `threshold` (in σ).
    pub fn new(threshold: f64) -> Self {
        Self {
            threshold,
            pos: 0.0,
            neg: 0.0,
        }
    }

    /// Adds one normalised innovation; `true` on an alarm (the statistic then starts over).
    pub fn push(&mut self, z: f64) -> bool {
        if !z.is_finite() {
            return false;
        }
        self.pos = (self.pos + z - CUSUM_DRIFT).max(0.0);
        self.neg = (self.neg - z - CUSUM_DRIFT).max(0.0);
        if self.pos > self.threshold || self.neg > self.threshold {
            self.pos = 0.0;
            self.neg = 0.0;
            true
        } else {
            false
        }
    }

    /// The larger of the two one-sided statistics.
    pub fn statistic(&self) -> f64 {
        self.pos.max(self.neg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_consistent_one_sigma_mean_alarms_within_a_dozen_observations() {
        for sign in [1.0, -1.0] {
            let mut d = BiasChangeDetector::new(5.0);
            let n = (1..=20).find(|_| d.push(sign * 1.0)).unwrap();
            assert_eq!(n, 11, "alarm after (5 / 0.5) + 1 observations");
            assert_eq!(d.statistic(), 0.0, "starts over after an alarm");
        }
    }

    #[test]
    fn alternating_innovations_never_alarm_and_nan_is_ignored() {
        let mut d = BiasChangeDetector::new(5.0);
        for k in 0..10_000 {
            let z = if k % 2 == 0 { 1.4 } else { -1.4 };
            assert!(!d.push(z), "at {k}");
        }
        assert!(!d.push(f64::NAN));
        assert!(d.statistic() <= 1.0);
    }
}
