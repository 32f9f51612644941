//! The sample clock: a log stamped with host arrival times (exp40's raw file, a driver that
//! stamps on receipt) has steps that scatter around the sensor's period by a good part of it.
//! Integrating over those steps turns the scatter into velocity and attitude noise. The clock
//! recognises such a time base from the statistics of its steps and then integrates on a
//! smoothed clock instead: a phase-locked count of the estimated period, pulled gently toward the
//! stamps. A device clock (steps within a fraction of a percent) is used as it is, bit for bit.
//!
//! Fixed size, no allocation; a gap (a step of several periods) re-synchronises the smoothed
//! clock to the stamp, so missing samples keep their time.

/// Weight of a new step in the mean relative deviation of the steps from the period.
const DEVIATION_GAIN: f64 = 0.01;
/// Mean relative deviation above which the stamps are taken as jittery (a device clock stays
/// below 0.1 %; host stamps of a 200 Hz sensor scatter by 20–50 %).
const JITTER_ON: f64 = 0.05;
/// ... and below which they are trusted again.
const JITTER_OFF: f64 = 0.02;
/// Steps seen before the decision is made (the deviation's average has settled).
const WARMUP_STEPS: u64 = 200;
/// Pull of the smoothed clock toward the stamps per sample (time constant 50 samples).
const PHASE_GAIN: f64 = 0.02;
/// Pull of the period estimate per sample of phase error (critically damped: PHASE_GAIN² / 4).
const FREQUENCY_GAIN: f64 = PHASE_GAIN * PHASE_GAIN / 4.0;
/// A stamp further than this many periods from the smoothed clock re-synchronises it (a gap).
const RESYNC_PERIODS: f64 = 3.0;

/// The time base samples are integrated on.
#[derive(Debug, Clone, Default)]
pub struct SampleClock {
    steps: u64,
    first_stamp_s: f64,
    last_stamp_s: Option<f64>,
    period_s: f64,
    deviation: f64,
    jittery: bool,
    smoothed_s: f64,
}

impl SampleClock {
    /// The time to integrate with for a sample stamped `t_s` (strictly after the previous one):
    /// the stamp itself, or the smoothed clock while the stamps are jittery.
    pub fn push(&mut self, t_s: f64) -> f64 {
        let Some(last) = self.last_stamp_s.replace(t_s) else {
            self.first_stamp_s = t_s;
            self.smoothed_s = t_s;
            return t_s;
        };
        let dt = t_s - last;
        self.steps += 1;
        if self.steps <= WARMUP_STEPS {
            // The mean step so far (unbiased by symmetric scatter), and the clock on the stamps.
            self.period_s = (t_s - self.first_stamp_s) / self.steps as f64;
            self.smoothed_s = t_s;
        } else {
            // A second-order phase-locked loop: the phase follows the stamps with PHASE_GAIN,
            // the period with FREQUENCY_GAIN (critically damped).
            let predicted = self.smoothed_s + self.period_s;
            let error = t_s - predicted;
            if error.abs() > RESYNC_PERIODS * self.period_s {
                self.smoothed_s = t_s;
            } else {
                self.smoothed_s = predicted + PHASE_GAIN * error;
                self.period_s += FREQUENCY_GAIN * error;
            }
        }
        let rel = ((dt - self.period_s).abs() / self.period_s).min(1.0);
        self.deviation += DEVIATION_GAIN * (rel - self.deviation);
        self.jittery = if self.jittery {
            self.deviation > JITTER_OFF
        } else {
            self.steps > WARMUP_STEPS && self.deviation > JITTER_ON
        };
        if self.jittery { self.smoothed_s } else { t_s }
    }

    /// Whether the stamps are being smoothed.
    pub fn jittery(&self) -> bool {
        self.jittery
    }

    /// The estimated sample period, s (0 before the second sample).
    pub fn period_s(&self) -> f64 {
        self.period_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator for the test's delays (no dependency).
    fn lcg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    #[test]
    fn a_device_clock_is_used_as_it_is() {
        let mut c = SampleClock::default();
        for k in 0..5000 {
            let t = k as f64 * 0.005 * (1.0 + 1e-5);
            assert_eq!(c.push(t), t);
        }
        assert!(!c.jittery());
    }

    #[test]
    fn host_stamps_are_recognised_and_smoothed_and_a_gap_keeps_its_time() {
        let mut c = SampleClock::default();
        let mut seed = 7;
        let (mut raw_err, mut smooth_err, mut n) = (0.0, 0.0, 0);
        let mut last = f64::NEG_INFINITY;
        for k in 0..6000 {
            // Sensor clock at 200 Hz; arrival 0–4 ms later; 100 samples lost at k = 3000.
            let true_t = if k < 3000 { k } else { k + 100 } as f64 * 0.005;
            let stamp = (true_t + 0.004 * lcg(&mut seed)).max(last + 1e-6);
            last = stamp;
            let t = c.push(stamp);
            if k > 1000 && k != 3000 {
                // Steps: the true one is 5 ms.
                n += 1;
                raw_err += ((stamp - true_t) - 0.002f64).powi(2);
                smooth_err += ((t - true_t) - 0.002f64).powi(2);
            }
            if k == 3000 {
                assert!(
                    (t - stamp).abs() < 0.01,
                    "the gap re-synchronises: {t} vs {stamp}"
                );
            }
        }
        assert!(c.jittery());
        assert!(
            (c.period_s() - 0.005).abs() < 5e-5,
            "period {}",
            c.period_s()
        );
        let (raw, smooth) = ((raw_err / n as f64).sqrt(), (smooth_err / n as f64).sqrt());
        assert!(
            smooth < 0.25 * raw,
            "timing noise: raw {raw} s, smoothed {smooth} s"
        );
    }
}
