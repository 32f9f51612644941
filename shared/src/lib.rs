//! Code shared by the corridor daemon (`corridor-service`) and its clients (`corridor-client`).
//!
//! Map of the modules:
//! - [`config`]: the TOML configuration, parsed with `deny_unknown_fields` and validated into
//!   types that cannot hold bad values.
//! - [`imu_csv`]: the reader for IMU logs in the `t_s,gx_rad_s,...` CSV format, with row-level
//!   rejection that names file, line, column and value.
//! - [`sensor`]: the `[sensor]` limits (range, plausible magnitudes, time steps) and the time
//!   rule shared by the CSV reader and the estimator.
//! - [`truth_csv`]: the reader for surveyed footprint ground truth (`ground_truth.csv`).
//! - [`injection`]: synthetic gyro-bias injection (constant, ramp, delayed) used by the
//!   offline runner and the replay producer, and the sensor errors ([`injection::LogInjection`]:
//!   scale, cross-coupling, drift, clock, g-sensitivity, clipping, slip) of the detection matrix.
//! - [`wire`]: the zero-copy `#[repr(C)]` messages exchanged with the daemon over iceoryx2.
//! - [`wire_layout`]: the measured layout of the wire types, and the C header and layout JSON
//!   generated from it for the C and Python clients.
//! - [`services`]: service names, QoS, the [`services::Domain`] namespace and the functions both
//!   sides use to open the services.
//! - [`text_file`]: reading a configuration, a map, a suite or a ground truth, no further than
//!   such a file can be long.
//! - [`runtime_dir`]: the runtime directory of a secured domain (who can reach iceoryx2's files,
//!   what iceoryx2 0.10 lets one control, the daemon's lock and prefix token).

pub mod config;
pub mod imu_csv;
pub mod injection;
pub mod runtime_dir;
pub mod sensor;
pub mod services;
pub mod text_file;
pub mod truth_csv;
pub mod wire;
pub mod wire_layout;
