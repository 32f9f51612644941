//! Input plausibility: the one place that decides whether an IMU sample may enter the filter,
//! shared by the offline runner and the daemon (both go through `Estimator::step`).
//!
//! A sample is refused when a value is not finite, when |ω| or |f| is beyond what the sensor can
//! output (`sensor.max_gyro_rad_s`, `sensor.max_accel_m_s2`), or when its time breaks the time
//! rule of [`TimeGuard`] (not increasing by `sensor.min_dt_s`, or a jump beyond
//! `sensor.max_dt_s` that the next sample does not confirm; a gap's far side that the next sample
//! shows to be a stamp glitch is dropped after the fact; a step back of the clock is taken only
//! when the caller's judge, the rates, says nothing was lost). A sample with an axis at the rail
//! (within [`CLIP_FRACTION`] of the range) is accepted and flagged as clipped.

use super::estimator::{ImuInput, SampleError};
use corridor_shared::sensor::{
    AXIS_ABSURD_FACTOR, CLIP_FRACTION, SensorLimits, TimeGuard, TimeVerdict,
};

/// Field names in sample order, for messages.
const FIELDS: [&str; 6] = [
    "gx_rad_s", "gy_rad_s", "gz_rad_s", "ax_m_s2", "ay_m_s2", "az_m_s2",
];

/// What [`Plausibility::check`] says about an accepted sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Accepted {
    /// An axis is at the rail of its range (probably clipped).
    pub clipped: bool,
    /// The stream's first time, which this sample and the refused one before it contradict:
    /// that first sample was the outlier ([`TimeVerdict::Rebase`]), and what was taken with it
    /// is to be dropped.
    pub replaced_first_t_s: Option<f64>,
    /// The previous accepted time, which jumped forward by a gap and which this sample goes
    /// back behind, following the time before it: that time was a stamp glitch
    /// ([`TimeVerdict::Glitch`]), and what was taken with it is to be dropped. After a run of
    /// two or more glitched stamps ([`TimeVerdict::GlitchRun`]): the first time accepted in the
    /// run, and what was taken since is to be dropped.
    pub glitch_t_s: Option<f64>,
    /// With `glitch_t_s`: a run after a jump or a gap, not a single stamp after a gap.
    pub glitch_run: bool,
    /// This sample's time came after a gap (beyond `estimator.max_dt_s`), or after a jump that
    /// it confirms, and stays provisional: the caller keeps what it needs to drop it after the
    /// fact (a gap's until the next accepted sample, a jump's while `in_jump_run`).
    pub provisional: bool,
    /// This sample is in the run after a confirmed jump, which a later time may still show to
    /// be glitched stamps ([`TimeVerdict::GlitchRun`]): the copy taken before the run is kept.
    pub in_jump_run: bool,
    /// The clock stepped back before this sample, and the caller's judge took the step
    /// ([`TimeVerdict::StepBack`]): the last accepted time before it, and the time of the
    /// sample refused after it, s.
    pub stepped_back: Option<(f64, f64)>,
}

/// A step back of the clock, for the caller to judge: the last accepted time, and the sample
/// refused just before this one, whose time went back behind it and which this one follows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepBack {
    /// The last accepted time, s.
    pub last_t_s: f64,
    /// The refused sample whose time went back (it stays refused).
    pub first: ImuInput,
    /// The step between the two accepted times around `first`'s, s, when the last
    /// [`STAMP_MEMORY`] accepted times hold them: a clock set back lands among dense times,
    /// samples delivered out of order in the hole they left.
    pub around_first_s: Option<f64>,
}

impl StepBack {
    /// What every later stamp is taken plus when the step is taken: the first sample after it
    /// taken as one sample step (`period_s`) after the last accepted time.
    pub fn shift_s(last_t_s: f64, first_t_s: f64, period_s: f64) -> f64 {
        last_t_s + period_s - first_t_s
    }
}

/// Accepted times remembered for [`StepBack::around_first_s`] (1.3 s at 200 Hz).
pub const STAMP_MEMORY: usize = 256;

/// The plausibility check of one stream.
#[derive(Debug, Clone)]
pub struct Plausibility {
    limits: SensorLimits,
    /// Per field, in sample order: the value beyond which one axis is absurd.
    axis_limits: [f64; 6],
    time: TimeGuard,
    /// The last sample refused for a time that did not increase (a step back's first sample),
    /// until a step back is judged: a step refused, the samples that run on from it are refused
    /// without asking again.
    went_back: Option<ImuInput>,
    /// The last [`STAMP_MEMORY`] accepted times, a ring, and how many were accepted.
    stamps: [f64; STAMP_MEMORY],
    accepted: usize,
}

impl Plausibility {
    /// A check with `limits` and no time base yet; a step beyond `gap_dt_s` is provisional
    /// until the next accepted sample ([`TimeVerdict::Glitch`]).
    pub fn new(limits: SensorLimits, gap_dt_s: f64) -> Self {
        let (g, a) = (
            AXIS_ABSURD_FACTOR * limits.gyro_range_rad_s(),
            AXIS_ABSURD_FACTOR * limits.accel_range_m_s2(),
        );
        Self {
            time: TimeGuard::from_limits(&limits, gap_dt_s),
            axis_limits: [g, g, g, a, a, a],
            limits,
            went_back: None,
            stamps: [f64::NAN; STAMP_MEMORY],
            accepted: 0,
        }
    }

    /// The previous accepted time.
    pub fn last_t_s(&self) -> Option<f64> {
        self.time.last_s()
    }

    /// The previous accepted time once no later time can show it to be a glitched stamp: a
    /// time has followed the first, the last step was no gap still provisional, and no run
    /// after a jump or a gap is open. `None` otherwise (the time may yet be dropped).
    pub fn settled_t_s(&self) -> Option<f64> {
        let t = &self.time;
        let settled = t.confirmed() && !t.provisional() && t.jump_run().is_none();
        t.last_s().filter(|_| settled)
    }

    /// The step between the remembered accepted times around `t_s` (newest first).
    #[cold]
    fn step_around(&self, t_s: f64) -> Option<f64> {
        let n = self.accepted.min(STAMP_MEMORY);
        let at = |k: usize| self.stamps[(self.accepted - 1 - k) % STAMP_MEMORY];
        (1..n).find_map(|k| {
            let (before, after) = (at(k), at(k - 1));
            (before < t_s && t_s < after).then_some(after - before)
        })
    }

    /// Checks `s`; on `Ok` the sample is accepted (its time is the new time base). On `Err`
    /// nothing changed except that a time jump or a time that went back is remembered as a
    /// candidate time base. A sample that runs on from a step back of the clock is accepted
    /// when `judge_step_back` says so (asked once per step).
    pub fn check(
        &mut self,
        s: &ImuInput,
        judge_step_back: impl FnOnce(&StepBack) -> bool,
    ) -> Result<Accepted, SampleError> {
        if !s.t_s.is_finite() {
            return Err(SampleError::NonFinite {
                t_s: s.t_s,
                field: "t_s",
                value: s.t_s,
            });
        }
        let values = [
            s.gyro_rad_s[0],
            s.gyro_rad_s[1],
            s.gyro_rad_s[2],
            s.accel_m_s2[0],
            s.accel_m_s2[1],
            s.accel_m_s2[2],
        ];
        if let Some((k, &value)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(SampleError::NonFinite {
                t_s: s.t_s,
                field: FIELDS[k],
                value,
            });
        }
        let norm = |v: &[f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let l = &self.limits;
        let (gyro_norm, accel_norm) = (norm(&s.gyro_rad_s), norm(&s.accel_m_s2));
        // Every value zero: a driver's fill for a sample it did not get (or a dead sensor), not a
        // measurement. A sensor's noise never gives six zeros, and a foot's accelerometer never
        // reads 0 on all three axes (free fall): fused, a run of them was a free fall (the final
        // height up to 14 m off, `examples/fault_scan.rs`). Refused, they are a loss like any
        // other.
        if gyro_norm == 0.0 && accel_norm == 0.0 {
            return Err(SampleError::ZeroFill { t_s: s.t_s });
        }
        for (first, field, value, limit) in [
            (0, "|gyro_rad_s|", gyro_norm, l.max_gyro_rad_s()),
            (3, "|accel_m_s2|", accel_norm, l.max_accel_m_s2()),
        ] {
            // The components are finite here; a norm that overflowed is +inf and caught too,
            // said by its largest axis and that axis's value (it said "|gyro_rad_s| = inf" of a
            // gy of 1e300: a review).
            if value > limit {
                let (field, value) = if value.is_finite() {
                    (field, value)
                } else {
                    (first..first + 3).map(|k| (FIELDS[k], values[k])).fold(
                        (field, 0.0_f64),
                        |a, b| if b.1.abs() > a.1.abs() { b } else { a },
                    )
                };
                return Err(SampleError::Implausible {
                    t_s: s.t_s,
                    field,
                    value,
                    limit,
                });
            }
        }
        // A single axis the sensor cannot output, whatever the norm.
        for ((&value, &limit), field) in values.iter().zip(&self.axis_limits).zip(FIELDS) {
            if value.abs() > limit {
                return Err(SampleError::Implausible {
                    t_s: s.t_s,
                    field,
                    value,
                    limit,
                });
            }
        }
        let last_t_s = self.time.last_s();
        let (mut replaced_first_t_s, mut glitch_t_s, mut stepped_back) = (None, None, None);
        let mut glitch_run = false;
        let not_increasing = || SampleError::TimeNotIncreasing {
            t_s: s.t_s,
            prev_t_s: last_t_s.unwrap_or(f64::NAN),
        };
        match self.time.check(s.t_s) {
            TimeVerdict::Accept | TimeVerdict::NewBase => {}
            TimeVerdict::Rebase => replaced_first_t_s = last_t_s,
            TimeVerdict::Glitch => glitch_t_s = last_t_s,
            TimeVerdict::GlitchRun => {
                glitch_t_s = self.time.jump_run().map(|r| r.first_s);
                glitch_run = true;
            }
            TimeVerdict::StepBack => match self.went_back.take().zip(last_t_s) {
                Some((first, last_t_s))
                    if judge_step_back(&StepBack {
                        last_t_s,
                        first,
                        around_first_s: self.step_around(first.t_s),
                    }) =>
                {
                    stepped_back = Some((last_t_s, first.t_s));
                }
                _ => return Err(not_increasing()),
            },
            TimeVerdict::NotIncreasing => {
                self.went_back = Some(*s);
                return Err(not_increasing());
            }
            TimeVerdict::Jump => {
                return Err(SampleError::TimeJump {
                    t_s: s.t_s,
                    prev_t_s: self.time.last_s().unwrap_or(f64::NAN),
                    max_dt_s: l.max_dt_s(),
                });
            }
        }
        self.time.accept(s.t_s);
        self.stamps[self.accepted % STAMP_MEMORY] = s.t_s;
        self.accepted += 1;
        let rail = |v: &[f64; 3], range: f64| v.iter().any(|x| x.abs() >= CLIP_FRACTION * range);
        Ok(Accepted {
            clipped: rail(&s.gyro_rad_s, l.gyro_range_rad_s())
                || rail(&s.accel_m_s2, l.accel_range_m_s2()),
            replaced_first_t_s,
            glitch_t_s,
            glitch_run,
            provisional: self.time.provisional()
                || self.time.jump_run().is_some_and(|r| r.samples == 1),
            in_jump_run: self.time.jump_run().is_some(),
            stepped_back,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use corridor_shared::sensor::SensorFile;

    fn gx5() -> Plausibility {
        let f = SensorFile {
            gyro_range_rad_s: Some(8.73),
            accel_range_m_s2: Some(78.45),
            max_gyro_rad_s: Some(20.0),
            max_accel_m_s2: Some(200.0),
            ..Default::default()
        };
        Plausibility::new(f.validate().unwrap(), 0.05)
    }

    /// A judge that takes no step back of the clock.
    fn no_step(_: &StepBack) -> bool {
        false
    }

    fn sample(t_s: f64, g: [f64; 3], a: [f64; 3]) -> ImuInput {
        ImuInput {
            t_s,
            gyro_rad_s: g,
            accel_m_s2: a,
        }
    }

    #[test]
    fn absurd_values_are_refused_rails_are_flagged_normal_values_pass() {
        let mut p = gx5();
        let clipped = |r: Result<Accepted, SampleError>| r.map(|a| a.clipped);
        assert_eq!(
            clipped(p.check(&sample(0.0, [0.1; 3], [0.0, 0.0, 9.8]), no_step)),
            Ok(false)
        );
        let err = p
            .check(&sample(0.005, [0.1; 3], [0.0, 0.0, 1e30]), no_step)
            .unwrap_err();
        assert!(matches!(
            err,
            SampleError::Implausible {
                field: "|accel_m_s2|",
                ..
            }
        ));
        assert!(err.to_string().contains("1e30"), "{err}");
        // A norm that overflows is said by its largest axis, with its value (it said
        // "|gyro_rad_s| = inf").
        let err = p
            .check(&sample(0.005, [0.1, -1e300, 0.1], [0.0, 0.0, 9.8]), no_step)
            .unwrap_err();
        assert!(
            matches!(
                err,
                SampleError::Implausible {
                    field: "gy_rad_s",
                    value: -1e300,
                    ..
                }
            ),
            "{err}"
        );
        assert!(err.to_string().contains("gy_rad_s = -1e300"), "{err}");
        // One axis beyond twice its range (the norm is within its limit): refused.
        let err = p
            .check(&sample(0.005, [0.1; 3], [0.0, 0.0, 160.0]), no_step)
            .unwrap_err();
        assert!(
            matches!(err, SampleError::Implausible { field: "az_m_s2", limit, .. } if limit == 156.9),
            "{err}"
        );
        // At the rail (8.6 ≥ 0.98 × 8.73): accepted and flagged.
        assert_eq!(
            clipped(p.check(&sample(0.005, [0.0, 8.6, 0.0], [0.0, 0.0, 9.8]), no_step)),
            Ok(true)
        );
        assert_eq!(
            clipped(p.check(&sample(0.010, [0.0; 3], [0.0, 0.0, 78.0]), no_step)),
            Ok(true)
        );
        assert_eq!(p.last_t_s(), Some(0.010));
    }

    #[test]
    fn a_time_outlier_does_not_become_the_time_base() {
        let mut p = gx5();
        let rest = |t| sample(t, [0.0; 3], [0.0, 0.0, 9.8]);
        p.check(&rest(0.0), no_step).unwrap();
        assert!(matches!(
            p.check(&rest(1e30), no_step),
            Err(SampleError::TimeJump { prev_t_s: 0.0, .. })
        ));
        assert_eq!(
            p.check(&rest(0.005), no_step),
            Ok(Accepted {
                clipped: false,
                replaced_first_t_s: None,
                glitch_t_s: None,
                glitch_run: false,
                provisional: false,
                in_jump_run: false,
                stepped_back: None,
            })
        );
        assert!(matches!(
            p.check(&rest(f64::INFINITY), no_step),
            Err(SampleError::NonFinite { field: "t_s", .. })
        ));
    }

    #[test]
    fn a_bad_first_time_is_replaced_when_the_next_two_agree() {
        let mut p = gx5();
        let rest = |t| sample(t, [0.0; 3], [0.0, 0.0, 9.8]);
        p.check(&rest(1e9), no_step).unwrap();
        assert!(matches!(
            p.check(&rest(0.0), no_step),
            Err(SampleError::TimeNotIncreasing { prev_t_s: 1e9, .. })
        ));
        let a = p.check(&rest(0.005), no_step).unwrap();
        assert_eq!(a.replaced_first_t_s, Some(1e9));
        assert_eq!(
            p.check(&rest(0.010), no_step).unwrap().replaced_first_t_s,
            None
        );
    }

    #[test]
    fn a_sample_after_a_gap_is_provisional_until_the_next_one_says_glitch_or_gap() {
        let mut p = gx5();
        let rest = |t| sample(t, [0.0; 3], [0.0, 0.0, 9.8]);
        for t in [0.0, 0.005] {
            assert!(!p.check(&rest(t), no_step).unwrap().provisional);
        }
        assert!(p.check(&rest(0.905), no_step).unwrap().provisional);
        let a = p.check(&rest(0.010), no_step).unwrap();
        assert_eq!((a.glitch_t_s, a.provisional), (Some(0.905), false));
        assert_eq!(p.last_t_s(), Some(0.010));
        // A real gap: the next sample follows its far side.
        assert!(p.check(&rest(0.9), no_step).unwrap().provisional);
        let a = p.check(&rest(0.905), no_step).unwrap();
        assert_eq!((a.glitch_t_s, a.provisional), (None, false));
        // A gap right after a gap's far side is provisional too, and its glitch caught.
        assert!(p.check(&rest(1.2), no_step).unwrap().provisional);
        assert!(p.check(&rest(1.5), no_step).unwrap().provisional);
        let a = p.check(&rest(1.205), no_step).unwrap();
        assert_eq!((a.glitch_t_s, a.provisional), (Some(1.5), false));
        // So is a glitch on the stream's second sample.
        let mut p = gx5();
        p.check(&rest(0.0), no_step).unwrap();
        assert!(p.check(&rest(0.9), no_step).unwrap().provisional);
        assert_eq!(
            p.check(&rest(0.005), no_step).unwrap().glitch_t_s,
            Some(0.9)
        );
    }

    #[test]
    fn a_step_back_is_taken_when_the_judge_says_so_and_judged_once() {
        let rest = |t| sample(t, [0.0; 3], [0.0, 0.0, 9.8]);
        let mut p = gx5();
        for t in [0.0, 0.005, 0.010] {
            p.check(&rest(t), no_step).unwrap();
        }
        let back = |p: &mut Plausibility, t: f64, take: bool, asked: &mut u32| {
            p.check(&rest(t), |b| {
                *asked += 1;
                assert_eq!((b.last_t_s, b.first.t_s), (0.010, -0.29));
                take
            })
        };
        let mut asked = 0;
        // The first sample after the step is refused; the judge sees it with the next one.
        assert!(back(&mut p, -0.29, true, &mut asked).is_err());
        assert_eq!(asked, 0);
        let mut q = p.clone();
        let a = back(&mut p, -0.285, true, &mut asked).unwrap();
        assert_eq!(asked, 1);
        assert_eq!(a.stepped_back, Some((0.010, -0.29)));
        assert_eq!(p.last_t_s(), Some(-0.285));
        // Refused: the judge is not asked again for the samples that run on from the step,
        // and a sample that follows the base is accepted as before.
        assert!(matches!(
            back(&mut q, -0.285, false, &mut asked),
            Err(SampleError::TimeNotIncreasing { .. })
        ));
        assert!(back(&mut q, -0.280, true, &mut asked).is_err());
        assert_eq!(asked, 2);
        let a = q.check(&rest(0.015), no_step).unwrap();
        assert_eq!(a.stepped_back, None);
    }
}
