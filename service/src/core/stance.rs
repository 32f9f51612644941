//! Zero-velocity (stance) detection: the SHOE, ARE and MV statistics of Skog et al. (2010,
//! "Zero-velocity detection — an algorithm evaluation") over a trailing window, and stance
//! intervals with a minimum length.
//!
//! The window is causal (the last `window` samples), so the decision for a sample never waits
//! for later samples. A stance only counts once it has lasted `min_stance_s`; shorter dips of the
//! statistic are ignored.

use corridor_shared::config::{DetectorConfig, DetectorKind};
use nalgebra::Vector3;

/// Stance detector state. Allocates its window once, at construction.
#[derive(Debug, Clone)]
pub struct StanceDetector {
    kind: DetectorKind,
    threshold: f64,
    inv_var_a: f64,
    inv_var_g: f64,
    min_stance_s: f64,
    gravity_m_s2: f64,
    gyro: Vec<Vector3<f64>>,
    accel: Vec<Vector3<f64>>,
    next: usize,
    filled: usize,
    raw_since_s: Option<f64>,
    last_statistic: f64,
}

/// What the detector says about one sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StanceDecision {
    /// The statistic (dimensionless, compared with the threshold).
    pub statistic: f64,
    /// The statistic is below the threshold on this sample.
    pub raw: bool,
    /// A stance that has lasted at least the minimum length.
    pub stance: bool,
    /// Seconds since the stance began (0 when not in stance).
    pub stance_age_s: f64,
}

impl StanceDetector {
    /// A detector with the given configuration; `gravity_m_s2` is refined by
    /// [`StanceDetector::set_gravity`] after alignment.
    pub fn new(cfg: &DetectorConfig, gravity_m_s2: f64) -> Self {
        let w = cfg.window;
        Self {
            kind: cfg.kind,
            threshold: cfg.threshold.get(),
            inv_var_a: 1.0 / cfg.sigma_accel_m_s2.get().powi(2),
            inv_var_g: 1.0 / cfg.sigma_gyro_rad_s.get().powi(2),
            min_stance_s: cfg.min_stance_s,
            gravity_m_s2,
            gyro: vec![Vector3::zeros(); w],
            accel: vec![Vector3::zeros(); w],
            next: 0,
            filled: 0,
            raw_since_s: None,
            last_statistic: f64::INFINITY,
        }
    }

    /// Sets the gravity magnitude used by SHOE.
    pub fn set_gravity(&mut self, gravity_m_s2: f64) {
        self.gravity_m_s2 = gravity_m_s2;
    }

    /// The statistic of the last sample.
    pub fn last_statistic(&self) -> f64 {
        self.last_statistic
    }

    /// The threshold.
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// Adds one sample and decides.
    pub fn push(
        &mut self,
        t_s: f64,
        gyro_rad_s: &Vector3<f64>,
        accel_m_s2: &Vector3<f64>,
    ) -> StanceDecision {
        let w = self.gyro.len();
        self.gyro[self.next] = *gyro_rad_s;
        self.accel[self.next] = *accel_m_s2;
        self.next = (self.next + 1) % w;
        self.filled = (self.filled + 1).min(w);
        let n = self.filled as f64;
        let statistic = {
            let gyro = &self.gyro[..self.filled];
            let accel = &self.accel[..self.filled];
            match self.kind {
                DetectorKind::Are => {
                    gyro.iter().map(|g| g.norm_squared()).sum::<f64>() * self.inv_var_g / n
                }
                DetectorKind::Mv => {
                    let mean = accel.iter().sum::<Vector3<f64>>() / n;
                    accel.iter().map(|a| (a - mean).norm_squared()).sum::<f64>() * self.inv_var_a
                        / n
                }
                DetectorKind::Shoe => {
                    let mean = accel.iter().sum::<Vector3<f64>>() / n;
                    let up = mean.normalize() * self.gravity_m_s2;
                    let sa: f64 = accel.iter().map(|a| (a - up).norm_squared()).sum();
                    let sg: f64 = gyro.iter().map(|g| g.norm_squared()).sum();
                    (sa * self.inv_var_a + sg * self.inv_var_g) / n
                }
            }
        };
        self.last_statistic = statistic;
        let raw = self.filled == w && statistic < self.threshold;
        if raw {
            self.raw_since_s.get_or_insert(t_s);
        } else {
            self.raw_since_s = None;
        }
        let age = self.raw_since_s.map_or(0.0, |t0| t_s - t0);
        let stance = raw && age >= self.min_stance_s;
        StanceDecision {
            statistic,
            raw,
            stance,
            stance_age_s: if stance { age } else { 0.0 },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use corridor_shared::config::Config;

    #[test]
    fn static_is_stance_and_rotation_is_not() {
        let cfg = Config::default().detector;
        let mut d = StanceDetector::new(&cfg, 9.81);
        let g = Vector3::new(0.0, 0.0, 9.81);
        let mut last = None;
        for i in 0..100 {
            last = Some(d.push(i as f64 * 0.005, &Vector3::zeros(), &g));
        }
        let last = last.unwrap();
        assert!(last.stance && last.stance_age_s > 0.3);
        let moving = d.push(0.5, &Vector3::new(0.0, 3.0, 0.0), &g);
        assert!(!moving.raw && !moving.stance && moving.stance_age_s == 0.0);
    }

    #[test]
    fn short_dips_are_not_stances() {
        let cfg = Config::default().detector; // min 0.04 s
        let mut d = StanceDetector::new(&cfg, 9.81);
        let g = Vector3::new(0.0, 0.0, 9.81);
        let spin = Vector3::new(2.0, 0.0, 0.0);
        for i in 0..20 {
            d.push(i as f64 * 0.005, &spin, &g);
        }
        // 6 quiet samples = 0.025 s after the window fills: too short
        let mut any = false;
        for i in 20..31 {
            any |= d.push(i as f64 * 0.005, &Vector3::zeros(), &g).stance;
        }
        assert!(!any);
    }
}
