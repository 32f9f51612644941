//! Synthetic gyro-bias injection, the paper's test protocol: a constant bias, a bias growing
//! linearly in time, or either one starting only after a given time (so a rest-mean prior taken
//! before it cannot see it). Used by `corridor run` and by the replay producer.

/// A bias added to every gyro sample from `after_s` after the log's first sample on:
/// `constant_rad_s + ramp_rad_s2 · (t − after_s)`, with t counted from that first sample (so a
/// log stamped in epoch seconds, or from a negative time, gets the injection a log stamped from
/// 0 gets).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BiasInjection {
    /// Constant part, rad/s, sensor axes.
    pub constant_rad_s: [f64; 3],
    /// Growth rate, rad/s², sensor axes.
    pub ramp_rad_s2: [f64; 3],
    /// Start, s after the log's first sample. Before it nothing is added.
    pub after_s: f64,
}

impl BiasInjection {
    /// True when nothing is ever added.
    pub fn is_none(&self) -> bool {
        self.constant_rad_s == [0.0; 3] && self.ramp_rad_s2 == [0.0; 3]
    }

    /// The injected bias `since_start_s` after the log's first sample, rad/s.
    pub fn bias_at(&self, since_start_s: f64) -> [f64; 3] {
        if since_start_s < self.after_s {
            return [0.0; 3];
        }
        let dt = since_start_s - self.after_s;
        std::array::from_fn(|i| self.constant_rad_s[i] + self.ramp_rad_s2[i] * dt)
    }

    /// Adds the bias `since_start_s` after the log's first sample to `gyro_rad_s` in place.
    pub fn apply(&self, since_start_s: f64, gyro_rad_s: &mut [f64; 3]) {
        let b = self.bias_at(since_start_s);
        for (g, b) in gyro_rad_s.iter_mut().zip(b) {
            *g += b;
        }
    }
}

/// A sensor error added to a whole recording, for the diagnosis's detection matrix and its
/// power checks: each variant changes the samples the way the named sensor or mounting error
/// would (sensor axes, rad/s and m/s²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LogInjection {
    /// Gyro scale-factor error on one axis: `g[axis] *= 1 + fraction`.
    GyroScale {
        /// Sensor axis (0 x, 1 y, 2 z).
        axis: usize,
        /// Scale error (0.02 = +2 %).
        fraction: f64,
    },
    /// Gyro cross-coupling (axis misalignment): `g[to] += coupling_rad · g[from]`.
    GyroCoupling {
        /// Axis whose rate leaks.
        from: usize,
        /// Axis it leaks into.
        to: usize,
        /// Coupling, rad (small angle).
        coupling_rad: f64,
    },
    /// A gyro bias growing linearly from `after_s`: `g[axis] += rate · (t − after_s)`.
    BiasRamp {
        /// Sensor axis.
        axis: usize,
        /// Growth rate, rad/s².
        rate_rad_s2: f64,
        /// Start time, s.
        after_s: f64,
    },
    /// A gyro bias step at `at_s`.
    BiasStep {
        /// Sensor axis.
        axis: usize,
        /// Step, rad/s.
        step_rad_s: f64,
        /// Time of the step, s.
        at_s: f64,
    },
    /// The logger's clock runs fast: every time stamp becomes `t0 + (t − t0)(1 + fraction)`.
    ClockRate {
        /// Rate error (0.01 = 1 % fast).
        fraction: f64,
    },
    /// A g-sensitive gyro: `g[k] += k_rad_s_per_m_s2 · f[k]` on every axis.
    GSensitivity {
        /// Sensitivity, rad/s per m/s².
        k_rad_s_per_m_s2: f64,
    },
    /// An accelerometer scale-factor error, the same on every axis: `f[k] *= 1 + fraction`
    /// (gravity too: a filter that takes gravity from the rest sees only the horizontal part,
    /// strides `fraction` too long).
    AccelScale {
        /// Scale error (0.02 = +2 %).
        fraction: f64,
    },
    /// A gyro with a smaller range: every axis clamped to `±range_rad_s`.
    Clipping {
        /// Range, rad/s.
        range_rad_s: f64,
    },
    /// The sensor turns on the shoe about the vertical at `after_s` (the gyro does not see the
    /// turn): from then on gyro and specific force are rotated by `angle_rad` about the up
    /// direction of the first second of the log.
    MountingSlip {
        /// Rotation, rad.
        angle_rad: f64,
        /// Time of the slip, s.
        after_s: f64,
    },
}

impl LogInjection {
    /// Applies the error to `rows` in place (rows in time order, as read).
    pub fn apply(&self, rows: &mut [crate::imu_csv::ImuRow]) {
        let Some(t0) = rows.first().map(|r| r.t_s) else {
            return;
        };
        match *self {
            LogInjection::GyroScale { axis, fraction } => {
                rows.iter_mut()
                    .for_each(|r| r.gyro_rad_s[axis] *= 1.0 + fraction);
            }
            LogInjection::GyroCoupling {
                from,
                to,
                coupling_rad,
            } => rows.iter_mut().for_each(|r| {
                r.gyro_rad_s[to] += coupling_rad * r.gyro_rad_s[from];
            }),
            LogInjection::BiasRamp {
                axis,
                rate_rad_s2,
                after_s,
            } => rows.iter_mut().for_each(|r| {
                r.gyro_rad_s[axis] += rate_rad_s2 * (r.t_s - after_s).max(0.0);
            }),
            LogInjection::BiasStep {
                axis,
                step_rad_s,
                at_s,
            } => rows.iter_mut().filter(|r| r.t_s >= at_s).for_each(|r| {
                r.gyro_rad_s[axis] += step_rad_s;
            }),
            LogInjection::ClockRate { fraction } => rows.iter_mut().for_each(|r| {
                r.t_s = t0 + (r.t_s - t0) * (1.0 + fraction);
            }),
            LogInjection::GSensitivity { k_rad_s_per_m_s2 } => rows.iter_mut().for_each(|r| {
                for (g, a) in r.gyro_rad_s.iter_mut().zip(r.accel_m_s2) {
                    *g += k_rad_s_per_m_s2 * a;
                }
            }),
            LogInjection::AccelScale { fraction } => rows.iter_mut().for_each(|r| {
                for a in &mut r.accel_m_s2 {
                    *a *= 1.0 + fraction;
                }
            }),
            LogInjection::Clipping { range_rad_s } => rows.iter_mut().for_each(|r| {
                for g in &mut r.gyro_rad_s {
                    *g = g.clamp(-range_rad_s, range_rad_s);
                }
            }),
            LogInjection::MountingSlip { angle_rad, after_s } => {
                let first: Vec<_> = rows.iter().take_while(|r| r.t_s < t0 + 1.0).collect();
                let n = first.len().max(1) as f64;
                let mut up = [0.0; 3];
                for r in &first {
                    for (u, a) in up.iter_mut().zip(r.accel_m_s2) {
                        *u += a / n;
                    }
                }
                let norm = up.iter().map(|v| v * v).sum::<f64>().sqrt();
                if norm == 0.0 {
                    return;
                }
                let up = up.map(|v| v / norm);
                let (s, c) = angle_rad.sin_cos();
                // Rodrigues' rotation about `up`.
                let rot = |v: &mut [f64; 3]| {
                    let d = up[0] * v[0] + up[1] * v[1] + up[2] * v[2];
                    let x = [
                        up[1] * v[2] - up[2] * v[1],
                        up[2] * v[0] - up[0] * v[2],
                        up[0] * v[1] - up[1] * v[0],
                    ];
                    for i in 0..3 {
                        v[i] = v[i] * c + x[i] * s + up[i] * d * (1.0 - c);
                    }
                };
                for r in rows.iter_mut().filter(|r| r.t_s > after_s) {
                    rot(&mut r.gyro_rad_s);
                    rot(&mut r.accel_m_s2);
                }
            }
        }
    }

    /// The time on the injected log's clock of an event at `t_s` on the original clock
    /// (`t0` the log's first time stamp): only a clock-rate error moves it.
    pub fn map_time(&self, t0: f64, t_s: f64) -> f64 {
        match *self {
            LogInjection::ClockRate { fraction } => t0 + (t_s - t0) * (1.0 + fraction),
            _ => t_s,
        }
    }
}

/// Parses `X,Y,Z` (three comma-separated numbers), for command-line flags.
pub fn parse_vec3(text: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!("expected X,Y,Z (three numbers), found {text:?}"));
    }
    let mut out = [0.0; 3];
    for (o, p) in out.iter_mut().zip(&parts) {
        *o = p
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("{p:?} in {text:?} is not a finite number"))?;
    }
    Ok(out)
}

/// Largest constant bias an injection may add, rad/s: a bias the estimator's health check
/// allows (`sensor.max_gyro_bias_rad_s` of the shipped configurations). A larger one made every
/// sample implausible, and the refusal then named the log's line, not the flag.
pub const MAX_INJECTED_BIAS_RAD_S: f64 = 0.2;

/// Largest bias ramp an injection may add, rad/s² (the detection matrix injects 2e-4). A ramp
/// grows without bound: at this one the injected bias passes [`MAX_INJECTED_BIAS_RAD_S`], a bias
/// the health check allows, 20 s after the injection starts, so a longer log wants a slower one.
pub const MAX_INJECTED_RAMP_RAD_S2: f64 = 0.01;

/// [`parse_vec3`] for `--inject-gyro-bias`: each component within ±[`MAX_INJECTED_BIAS_RAD_S`].
pub fn parse_injected_bias_rad_s(text: &str) -> Result<[f64; 3], String> {
    within(parse_vec3(text)?, text, MAX_INJECTED_BIAS_RAD_S, "rad/s")
}

/// [`parse_vec3`] for `--inject-gyro-bias-ramp`: each component within
/// ±[`MAX_INJECTED_RAMP_RAD_S2`].
pub fn parse_injected_ramp_rad_s2(text: &str) -> Result<[f64; 3], String> {
    within(parse_vec3(text)?, text, MAX_INJECTED_RAMP_RAD_S2, "rad/s²")
}

/// `v` (parsed from `text` by [`parse_vec3`]) when every component is within ±`limit`; else
/// the first one beyond, quoted as typed (it was shown as `3e-1` of a `0.3`: a review).
fn within(v: [f64; 3], text: &str, limit: f64, unit: &str) -> Result<[f64; 3], String> {
    match v.iter().position(|x| x.abs() > limit) {
        Some(i) => {
            let typed = text.split(',').nth(i).map_or("", str::trim);
            Err(format!(
                "{typed} in {text:?} is beyond ±{limit} {unit} (the largest injection allowed)"
            ))
        }
        None => Ok(v),
    }
}

/// Parses a time in seconds that must be finite, ≥ 0 and at most [`MAX_TIME_S`], for
/// command-line flags such as `--inject-after-s` (a NaN there used to run with 0 samples and
/// exit 0; a wait of 1e300 s panicked converting it to a duration).
pub fn parse_time_s(text: &str) -> Result<f64, String> {
    text.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| (0.0..=MAX_TIME_S).contains(v))
        .ok_or_else(|| format!("{text:?} is not a number of seconds in [0, {MAX_TIME_S:e}]"))
}

/// [`parse_time_s`] for a wait that must be longer than zero (a timeout of 0 s cannot be met:
/// `corridor status --timeout-s 0` said "no diagnostics within 0ns" of a live daemon).
pub fn parse_wait_s(text: &str) -> Result<f64, String> {
    match parse_time_s(text) {
        Ok(v) if v > 0.0 => Ok(v),
        _ => Err(format!("{text:?} is not a wait in (0, {MAX_TIME_S:e}] s")),
    }
}

/// The longest time a flag or a configured period may give, s (about 31 years: any longer
/// wait is a mistake, and the platform's durations hold it).
pub const MAX_TIME_S: f64 = 1e9;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_and_ramp_start_at_after_s() {
        let inj = BiasInjection {
            constant_rad_s: [0.001, 0.001, 0.005],
            ramp_rad_s2: [0.0, 0.0, 5e-7],
            after_s: 10.0,
        };
        assert_eq!(inj.bias_at(9.999), [0.0; 3]);
        let b = inj.bias_at(110.0);
        assert!((b[2] - (0.005 + 5e-5)).abs() < 1e-15);
        assert_eq!(b[0], 0.001);
        let mut g = [1.0, 2.0, 3.0];
        inj.apply(10.0, &mut g);
        assert_eq!(g, [1.001, 2.001, 3.005]);
        assert!(!inj.is_none());
        assert!(BiasInjection::default().is_none());
    }

    #[test]
    fn log_injections_change_what_they_name() {
        use crate::imu_csv::ImuRow;
        let row = |t: f64| ImuRow {
            t_s: t,
            gyro_rad_s: [1.0, 2.0, 3.0],
            accel_m_s2: [0.0, 0.0, 9.8],
            temp_c: None,
            line: 2,
        };
        let run = |inj: LogInjection| {
            let mut rows: Vec<ImuRow> = (0..400).map(|i| row(10.0 + 0.01 * f64::from(i))).collect();
            inj.apply(&mut rows);
            rows
        };
        let r = run(LogInjection::GyroScale {
            axis: 2,
            fraction: 0.02,
        });
        assert_eq!(r[5].gyro_rad_s, [1.0, 2.0, 3.0 * 1.02]);
        let r = run(LogInjection::GyroCoupling {
            from: 1,
            to: 2,
            coupling_rad: 0.01,
        });
        assert_eq!(r[5].gyro_rad_s, [1.0, 2.0, 3.02]);
        let r = run(LogInjection::BiasStep {
            axis: 0,
            step_rad_s: 0.5,
            at_s: 12.0,
        });
        assert_eq!(r[199].gyro_rad_s[0], 1.0);
        assert_eq!(r[200].gyro_rad_s[0], 1.5);
        let r = run(LogInjection::BiasRamp {
            axis: 1,
            rate_rad_s2: 0.1,
            after_s: 11.0,
        });
        assert_eq!(r[50].gyro_rad_s[1], 2.0);
        assert!((r[300].gyro_rad_s[1] - 2.2).abs() < 1e-12);
        let inj = LogInjection::ClockRate { fraction: 0.03 };
        let r = run(inj);
        assert_eq!(r[0].t_s, 10.0);
        assert!((r[100].t_s - 11.03).abs() < 1e-12);
        assert!((inj.map_time(10.0, 11.0) - 11.03).abs() < 1e-12);
        let r = run(LogInjection::GSensitivity {
            k_rad_s_per_m_s2: 0.001,
        });
        assert!((r[0].gyro_rad_s[2] - (3.0 + 0.0098)).abs() < 1e-12);
        let r = run(LogInjection::AccelScale { fraction: 0.02 });
        assert_eq!(r[0].accel_m_s2, [0.0, 0.0, 9.8 * 1.02]);
        assert_eq!(r[0].gyro_rad_s, [1.0, 2.0, 3.0]);
        let r = run(LogInjection::Clipping { range_rad_s: 1.5 });
        assert_eq!(r[0].gyro_rad_s, [1.0, 1.5, 1.5]);
        // A slip about the vertical (up = z here) turns x into y and leaves z and gravity.
        let r = run(LogInjection::MountingSlip {
            angle_rad: std::f64::consts::FRAC_PI_2,
            after_s: 12.0,
        });
        assert_eq!(r[100].gyro_rad_s, [1.0, 2.0, 3.0]);
        let g = r[300].gyro_rad_s;
        assert!(
            (g[0] + 2.0).abs() < 1e-12 && (g[1] - 1.0).abs() < 1e-12 && (g[2] - 3.0).abs() < 1e-12,
            "{g:?}"
        );
        assert!((r[300].accel_m_s2[2] - 9.8).abs() < 1e-12);
    }

    #[test]
    fn vec3_parsing_names_the_bad_part() {
        assert_eq!(
            parse_vec3("0.001, 0.001,0.005").unwrap(),
            [0.001, 0.001, 0.005]
        );
        assert!(parse_vec3("1,2").unwrap_err().contains("three"));
        assert!(parse_vec3("1,x,3").unwrap_err().contains("\"x\""));
        assert!(parse_vec3("1,nan,3").is_err());
    }

    #[test]
    fn an_injection_beyond_any_bias_names_the_flag_value_not_the_log() {
        assert_eq!(
            parse_injected_bias_rad_s("-0.2,0,0.005").unwrap(),
            [-0.2, 0.0, 0.005]
        );
        let e = parse_injected_bias_rad_s("1e6,0,0").unwrap_err();
        assert!(e.contains("1e6") && e.contains("0.2 rad/s"), "{e}");
        assert!(parse_injected_bias_rad_s("0,0,-0.21").is_err());
        assert_eq!(parse_injected_ramp_rad_s2("2e-4,0,0").unwrap()[0], 2e-4);
        let e = parse_injected_ramp_rad_s2("0,1e308,0").unwrap_err();
        assert!(e.contains("1e308") && e.contains("rad/s²"), "{e}");
    }

    #[test]
    fn an_injection_beyond_the_limit_is_quoted_as_typed() {
        // `--inject-gyro-bias 0.3,0,0` said "3e-1 in \"0.3,0,0\" is beyond ±0.2 rad/s".
        assert_eq!(
            parse_injected_bias_rad_s("0.3,0,0").unwrap_err(),
            "0.3 in \"0.3,0,0\" is beyond ±0.2 rad/s (the largest injection allowed)"
        );
        let e = parse_injected_bias_rad_s("0, 0, -0.250").unwrap_err();
        assert!(e.starts_with("-0.250 in "), "{e}");
        let e = parse_injected_ramp_rad_s2("0.02,0,0").unwrap_err();
        assert!(e.starts_with("0.02 in "), "{e}");
    }

    #[test]
    fn time_parsing_refuses_nan_infinity_negative_and_beyond_any_duration() {
        assert_eq!(parse_time_s(" 2.5").unwrap(), 2.5);
        for bad in ["nan", "inf", "-1", "1e400", "1e300", "2e9", "x"] {
            assert!(parse_time_s(bad).unwrap_err().contains(bad), "{bad}");
        }
    }
}
