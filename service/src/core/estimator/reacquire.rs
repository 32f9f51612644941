//! A heading lost beyond the association's reach, and the way back.
//!
//! The association takes a stride or foot axis only within `heading.gate_deg` of a direction
//! and with a weight the filter's own heading variance sets. A heading that a fault turned by
//! more than that (a rotation the gyro did not measure: a stumble, lost samples in a turn, a
//! slip of the sensor) is never observed again: every stride is "walking off the corridor".
//! But a walker in a corridor building does not walk straight, stride after stride, at one
//! angle off every corridor. After `heading.reacquire_strides` straight strides in a row
//! (the footprint-line test, which does not depend on the heading) that no direction took and
//! that run off the nearest direction by the same angle (within
//! `heading.straight_max_change_deg`), the heading is taken as lost: its variance is widened to
//! that angle, and the gate to 3σ until a direction takes a stride again. The association then
//! decides with its weight, as at the start; nothing is snapped.
//!
//! What it cannot tell apart: a straight walk that long across a hall at an angle to the
//! corridors. With a grid and no map, such a walk is taken for a lost heading and pulled
//! towards the grid.

use crate::core::rotation::wrap_pi;

/// Straight strides in a row that no direction took, and the angle they run off the nearest
/// one (as a sum of unit vectors, so that the mean wraps).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct OffDirectionRun {
    strides: u32,
    sum_cos: f64,
    sum_sin: f64,
}

impl OffDirectionRun {
    /// The mean angle off the nearest direction, rad (0 for an empty run).
    pub fn mean_rad(&self) -> f64 {
        if self.strides == 0 {
            0.0
        } else {
            self.sum_sin.atan2(self.sum_cos)
        }
    }

    /// A straight stride that no direction took runs `off_rad` off the nearest one. A stride
    /// further than `spread_rad` from the run's mean starts a new run. Returns the mean of the
    /// run when it reached `strides` (and starts over), else `None`.
    pub fn push(&mut self, off_rad: f64, spread_rad: f64, strides: u32) -> Option<f64> {
        if self.strides > 0 && wrap_pi(off_rad - self.mean_rad()).abs() > spread_rad {
            *self = Self::default();
        }
        self.strides += 1;
        self.sum_cos += off_rad.cos();
        self.sum_sin += off_rad.sin();
        (self.strides >= strides).then(|| {
            let mean = self.mean_rad();
            *self = Self::default();
            mean
        })
    }

    /// A stride a direction took, or one not straight: the run ends.
    pub fn clear(&mut self) {
        *self = Self::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_at_one_angle_reaches_its_length_and_a_scattered_one_does_not() {
        let deg = f64::to_radians;
        let mut run = OffDirectionRun::default();
        for off in [21.0, 19.0, 22.0, 20.0, 18.0] {
            assert_eq!(run.push(deg(off), deg(10.0), 6), None);
        }
        let mean = run.push(deg(20.0), deg(10.0), 6).expect("six in a row");
        assert!((mean - deg(20.0)).abs() < deg(0.1), "{}", mean.to_degrees());
        // it starts over
        assert_eq!(run, OffDirectionRun::default());
        // a weave: the angle changes by more than the spread, each change starts a new run
        for off in [20.0, -15.0, 25.0, -20.0, 18.0, -22.0, 20.0, -19.0] {
            assert_eq!(run.push(deg(off), deg(10.0), 6), None);
        }
        // the mean wraps: a run about ±180°
        let mut run = OffDirectionRun::default();
        for off in [179.0, -179.0, 178.0] {
            run.push(deg(off), deg(10.0), 10);
        }
        assert!((wrap_pi(run.mean_rad() - deg(179.3))).abs() < deg(0.5));
        run.clear();
        assert_eq!(run.mean_rad(), 0.0);
    }
}
