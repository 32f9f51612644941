//! corridor-service: the gyro-bias and attitude estimator for foot-mounted IMUs, its offline
//! runner and its daemon.
//!
//! The module docs link to private items too: the documentation is for maintainers, read with
//! `cargo doc --document-private-items`.
//!
//! Map of the modules:
//! - [`checkpoint`]: atomic save/load of the bias, its covariance and the attitude (the only
//!   user of bincode).
//! - [`core`]: the pure estimator (no IO); everything else is an adapter around it.
//! - [`daemon`]: the estimator behind iceoryx2 services (`corridor serve`): receive and estimator
//!   threads, delivery policies, diagnostics.
//! - [`diagnose`]: residual diagnosis: rank the effects the model lacks, add the top one, compare.
//! - [`eval`]: footprint-error evaluation, a port of the reference `eval_traj.py`.
//! - [`map_file`]: corridor map files (TOML) read and checked for the core.
//! - [`plot`]: dependency-free SVG figures.
//! - [`runner`]: the offline runner (CSV log in, estimates, innovations and summary out).
//! - [`stats`]: the statistics of the residual diagnosis (distributions, NIS, whiteness, CUSUM,
//!   regression, group means), each group with its unit tests.
//! - [`suite`]: the results table over several recordings (`corridor eval`).

#![allow(rustdoc::private_intra_doc_links)]

pub mod checkpoint;
pub mod core;
pub mod daemon;
pub mod diagnose;
pub mod eval;
pub mod map_file;
pub mod plot;
pub mod runner;
pub mod stats;
pub mod suite;
