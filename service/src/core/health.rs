//! Estimator health: a cheap check after every update, and the last good state to fall back to.
//!
//! The check: position, velocity, attitude and bias finite; |v| within `estimator.max_speed_m_s`;
//! every bias axis within `sensor.max_gyro_bias_rad_s`; the covariance diagonal finite and not
//! negative (states not in use, such as the footprint clone before its first copy, hold 0).
//!
//! On failure the estimator undoes the update (the state before it was healthy and, unlike a copy
//! from the last stance, holds the foot's rotation since then: restoring the stance copy
//! mid-swing loses that rotation, and on exp36 it cost 20 m of heading drift). When updates keep
//! failing, it restores the copy of the last healthy stance. Either way the event is counted and
//! reported on the estimate, so nothing non-finite or absurd is ever published or saved.

use super::eskf::Eskf;
use nalgebra::Vector3;

/// Why a state failed the health check.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HealthFault {
    /// Position, velocity, attitude or bias is NaN or infinite.
    NonFinite,
    /// |v| beyond `estimator.max_speed_m_s`.
    Speed,
    /// A bias axis beyond `sensor.max_gyro_bias_rad_s`.
    Bias,
    /// A covariance diagonal element is negative or not finite.
    Covariance,
}

impl HealthFault {
    /// Stable snake_case name, for logs.
    pub fn name(self) -> &'static str {
        match self {
            HealthFault::NonFinite => "non_finite_state",
            HealthFault::Speed => "speed",
            HealthFault::Bias => "bias",
            HealthFault::Covariance => "covariance",
        }
    }
}

/// The bounds of a healthy state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HealthLimits {
    /// Largest plausible foot speed, m/s.
    pub max_speed_m_s: f64,
    /// Largest plausible gyro bias per axis, rad/s.
    pub max_gyro_bias_rad_s: f64,
}

/// Checks the filter state and the gyro bias in use (sensor axes, whichever filter owns it).
pub fn check(e: &Eskf, bias_rad_s: &Vector3<f64>, l: &HealthLimits) -> Result<(), HealthFault> {
    let q = e.nav_from_body.quaternion();
    let finite = e.p_m.iter().all(|v| v.is_finite())
        && e.v_m_s.iter().all(|v| v.is_finite())
        && q.coords.iter().all(|v| v.is_finite())
        && bias_rad_s.iter().all(|v| v.is_finite());
    if !finite {
        return Err(HealthFault::NonFinite);
    }
    if e.v_m_s.norm() > l.max_speed_m_s {
        return Err(HealthFault::Speed);
    }
    if bias_rad_s.iter().any(|b| b.abs() > l.max_gyro_bias_rad_s) {
        return Err(HealthFault::Bias);
    }
    // Every diagonal element in [0, ∞), without a branch per element, as this runs on every
    // sample: on the bits, v ∈ [0, ∞) exactly when they are below +∞'s (+0 and the positive
    // finite numbers; every NaN and negative number is above) or are −0's. Four instructions
    // an element, where the compiler made 16 of `v >= 0.0 && v < f64::INFINITY`.
    const INFINITY_BITS: u64 = 0x7ff0_0000_0000_0000;
    const NEGATIVE_ZERO_BITS: u64 = 0x8000_0000_0000_0000;
    let mut diagonal_ok = true;
    for v in e.cov_diagonal() {
        let bits = v.to_bits();
        diagonal_ok &= bits < INFINITY_BITS || bits == NEGATIVE_ZERO_BITS;
    }
    if !diagonal_ok {
        return Err(HealthFault::Covariance);
    }
    Ok(())
}

/// The last good copy of a state, kept without allocating: `save` clones into the slot.
#[derive(Debug, Clone)]
pub struct LastGood<T: Clone> {
    state: Option<T>,
}

impl<T: Clone> Default for LastGood<T> {
    fn default() -> Self {
        Self { state: None }
    }
}

impl<T: Clone> LastGood<T> {
    /// Keeps a copy of `state`.
    /// Out of line: the copy stays out of its callers' frames (see the estimator's
    /// `Pipeline::save_good`).
    #[inline(never)]
    pub fn save(&mut self, state: &T) {
        match &mut self.state {
            Some(s) => s.clone_from(state),
            None => self.state = Some(state.clone()),
        }
    }

    /// The saved copy, if any.
    pub fn get(&self) -> Option<&T> {
        self.state.as_ref()
    }

    /// The saved copy, to overwrite in place.
    pub fn get_mut(&mut self) -> Option<&mut T> {
        self.state.as_mut()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::eskf::{BiasStates, EskfInit, EskfNoise, Extensions};
    use nalgebra::UnitQuaternion;

    /// A healthy filter with a heading offset and a footprint clone.
    fn filter() -> Eskf {
        Eskf::new(
            EskfInit {
                nav_from_body: UnitQuaternion::identity(),
                gyro_bias_rad_s: Vector3::zeros(),
                tilt_sd_rad: 0.01,
                bias_sd_rad_s: 0.01,
                gravity_m_s2: 9.81,
                bias: BiasStates::Estimated,
            },
            EskfNoise {
                accel_m_s2: 0.03,
                gyro_rad_s: 0.01,
                rest_gyro_rad_s: 1e-3,
                gyro_bias_rw_rad_s_sqrt_s: 7e-4,
                zupt_m_s: 0.01,
                stance_yaw_max_sd_rad: f64::INFINITY,
                covariance_step_s: 0.0,
            },
            Extensions {
                heading_offset_sd: Some(0.1),
                footprint_clone: true,
                ..Default::default()
            },
        )
    }

    const LIMITS: HealthLimits = HealthLimits {
        max_speed_m_s: 10.0,
        max_gyro_bias_rad_s: 0.2,
    };

    #[test]
    fn each_bound_of_a_healthy_state_is_checked_on_its_own() {
        // Found by mutation testing (session 45): no test had one quantity alone not finite, or
        // a speed or bias at or just beyond its bound.
        let e = filter();
        let zero = Vector3::zeros();
        assert_eq!(check(&e, &zero, &LIMITS), Ok(()));
        for k in 0..4 {
            let (mut bad, mut bias) = (e.clone(), zero);
            match k {
                0 => bad.p_m.x = f64::NAN,
                1 => bad.v_m_s.y = f64::INFINITY,
                2 => {
                    bad.nav_from_body = UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(
                        f64::NAN,
                        0.0,
                        0.0,
                        0.0,
                    ))
                }
                _ => bias.z = f64::NAN,
            }
            assert_eq!(
                check(&bad, &bias, &LIMITS),
                Err(HealthFault::NonFinite),
                "{k}"
            );
        }
        // The speed at its bound is healthy, beyond it not.
        let mut fast = e.clone();
        fast.v_m_s = Vector3::new(6.0, 8.0, 0.0);
        assert_eq!(check(&fast, &zero, &LIMITS), Ok(()));
        fast.v_m_s.z = 0.01;
        assert_eq!(check(&fast, &zero, &LIMITS), Err(HealthFault::Speed));
        // The same for the bias, on any axis and either sign.
        for axis in 0..3 {
            let mut bias = zero;
            bias[axis] = -0.2;
            assert_eq!(check(&e, &bias, &LIMITS), Ok(()));
            bias[axis] = -0.2001;
            assert_eq!(check(&e, &bias, &LIMITS), Err(HealthFault::Bias));
        }
    }

    #[test]
    fn the_covariance_check_equals_the_plain_formula() {
        let mut e = filter();
        let limits = LIMITS;
        let n = e.dim();
        assert_eq!(e.cov_diagonal().count(), n);
        for var in [
            1e-4,
            0.0,
            -0.0,
            -1e-300,
            -1.0,
            f64::NAN,
            f64::INFINITY,
            1e300,
        ] {
            e.set_heading_variance(var);
            assert!(
                e.cov_diagonal()
                    .zip(0..n)
                    .all(|(&v, i)| v.to_bits() == e.cov(i, i).to_bits())
            );
            let bad = (0..n).any(|i| {
                let v = e.cov(i, i);
                !(v.is_finite() && v >= 0.0)
            });
            let got = check(&e, &Vector3::zeros(), &limits);
            assert_eq!(got.is_err(), bad, "{var}");
            if bad {
                assert_eq!(got, Err(HealthFault::Covariance));
            }
        }
    }

    #[test]
    fn last_good_keeps_the_latest_copy() {
        let mut g = LastGood::<[f64; 2]>::default();
        assert!(g.get().is_none());
        g.save(&[1.0, 2.0]);
        g.save(&[3.0, 4.0]);
        assert_eq!(g.get(), Some(&[3.0, 4.0]));
        assert_eq!(HealthFault::Speed.name(), "speed");
    }
}
