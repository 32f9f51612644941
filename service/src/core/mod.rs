//! The pure estimation core: numbers in, numbers out. No IO, no clock, no threads, no channels.
//!
//! - [`rotation`]: quaternion exponential/logarithm (closed form and Newton), Euler angles.
//! - [`stance`]: SHOE / ARE / MV zero-velocity detection.
//! - [`clock`]: the time base samples are integrated on (host-stamp jitter recognised, smoothed).
//! - [`eskf`]: the ZUPT-aided error-state Kalman filter (position, velocity, attitude, gyro bias).
//! - [`bias_kf`]: the paper's 3-state bias filter and its observers.
//! - [`heading`]: heading sources (grid, corridor map), association, straight-walk test.
//! - [`health`]: the health check after every update and the last good state.
//! - [`plausibility`]: which samples may enter the filter (sensor limits, time rule).
//! - [`estimator`]: the per-sample pipeline that ties them together.

pub mod bias_kf;
pub mod clock;
pub mod eskf;
pub mod estimator;
pub mod heading;
pub mod health;
pub mod plausibility;
pub mod rotation;
pub mod stance;

pub use estimator::{
    Counters, Estimate, Estimator, ForceWitness, GapCrossing, ImuInput, Notice, OffGravity, Phase,
    SPECIFIC_FORCE_TOLERANCE, SampleError, WarmStart, WarmStartError,
};
