//! Synthetic gyro-bias injection, the paper's test protocol: a constant bias, a bias growing
//! linearly in time, or either one starting only after a given time (so a rest-mean prior taken
//! before it cannot see it). Used by `corridor run` and by the replay producer.

/// A bias added to every gyro sample at or after `after_s`:
/// `constant_rad_s + ramp_rad_s2 · (t_s − after_s)`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BiasInjection {
    /// Constant part, rad/s, sensor axes.
    pub constant_rad_s: [f64; 3],
    /// Growth rate, rad/s², sensor axes.
    pub ramp_rad_s2: [f64; 3],
    /// Start time, s (same clock as the log). Before it nothing is added.
    pub after_s: f64,
}

impl BiasInjection {
    /// True when nothing is ever added.
    pub fn is_none(&self) -> bool {
        self.constant_rad_s == [0.0; 3] && self.ramp_rad_s2 == [0.0; 3]
    }

    /// The injected bias at `t_s`, rad/s.
    pub fn bias_at(&self, t_s: f64) -> [f64; 3] {
        if t_s < self.after_s {
            return [0.0; 3];
        }
        let dt = t_s - self.after_s;
        std::array::from_fn(|i| self.constant_rad_s[i] + self.ramp_rad_s2[i] * dt)
    }

    /// Adds the bias at `t_s` to `gyro_rad_s` in place.
    pub fn apply(&self, t_s: f64, gyro_rad_s: &mut [f64; 3]) {
        let b = self.bias_at(t_s);
        for (g, b) in gyro_rad_s.iter_mut().zip(b) {
            *g += b;
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

/// Parses a time in seconds that must be finite and ≥ 0, for command-line flags such as
/// `--inject-after-s` (a NaN there used to run with 0 samples and exit 0).
pub fn parse_time_s(text: &str) -> Result<f64, String> {
    text.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite() && *v >= 0.0)
        .ok_or_else(|| format!("{text:?} is not a finite number of seconds >= 0"))
}

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
    fn time_parsing_refuses_nan_infinity_and_negative() {
        assert_eq!(parse_time_s(" 2.5").unwrap(), 2.5);
        for bad in ["nan", "inf", "-1", "1e400", "x"] {
            assert!(parse_time_s(bad).unwrap_err().contains(bad), "{bad}");
        }
    }
}
