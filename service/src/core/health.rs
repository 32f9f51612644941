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
    if (0..e.dim()).any(|i| {
        let v = e.cov(i, i);
        !(v.is_finite() && v >= 0.0)
    }) {
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
