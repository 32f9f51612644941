//! Gaps in the data: a step longer than `estimator.max_dt_s` is bridged by one step when it is
//! short (a few lost samples), else it starts a new segment.

use super::*;

/// What [`Pipeline::cross_gap`] did with the step before the current sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Gap {
    /// A regular step, or a gap bridged: integrate it as usual.
    Integrate,
    /// A new segment: nothing is integrated over the step.
    NewSegment,
}

impl Pipeline {
    /// Judges the step `dt` from the previous sample (`w.0`, `f.0`) to this one (`w.1`, `f.1`)
    /// and widens the covariance of a gap; counts and reports it.
    pub(super) fn cross_gap(
        &mut self,
        eskf: &mut Eskf,
        dt: f64,
        w: (&Vector3<f64>, &Vector3<f64>),
        f: (&Vector3<f64>, &Vector3<f64>),
    ) -> Gap {
        if dt <= self.cfg.max_dt_s.get() {
            return Gap::Integrate;
        }
        self.counters.gaps += 1;
        self.out.gap_s = Some(dt);
        if dt <= self.cfg.max_bridge_s {
            // A short gap (a few lost samples) is bridged: one step on the mean of the rates and
            // forces on both sides of it, as every step is integrated. What that interpolation
            // misses is at most half the change of the rate (force) across the gap times its
            // length: the attitude variance grows by that about the axis of the change, the
            // velocity variance by its square. Dropping the gap instead lost the rotation of a
            // swing (0.3 rad in 55 ms) with an attitude σ of a few mrad.
            self.counters.gaps_bridged += 1;
            let dw = (w.1 - w.0) * (0.5 * dt);
            let dv = ((f.1 - f.0) * (0.5 * dt)).norm();
            eskf.widen_velocity(dv * dv);
            if let Some(axis) = dw.try_normalize(0.0) {
                eskf.widen_attitude_about(&axis, dw.norm().min(std::f64::consts::PI).powi(2));
            }
            return Gap::Integrate;
        }
        // A new segment. Extrapolating two samples over the gap is meaningless (a 10 s gap once
        // gave a vertical velocity of −286 m/s), so nothing is integrated over it. The velocity
        // is kept (the best guess for a short gap; the next ZUPT settles it) but its variance
        // grows by the largest plausible speed, so that ZUPT moves nothing else; the attitude
        // variance grows by the gyro noise over the gap. A reset to zero would be wrong when the
        // gap falls in a swing and the data go on with the same stride. (Widening the attitude
        // by the rate times the gap as well, about the rate's axis, made gaps of 0.3–1 s cut out
        // of the suite's walks worse: worst +32 % of path at 1 s against +21 %. Bridging them
        // too: worse from 0.2 s on, see `max_bridge_s`.)
        let v_max = self.cfg.max_speed_m_s.get();
        eskf.widen_after_gap(dt, v_max * v_max);
        Gap::NewSegment
    }
}
