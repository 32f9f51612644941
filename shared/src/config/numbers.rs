//! The checked numbers of a validated [`super::Config`]: each type holds only the values its
//! name says, and is made only through a check that names the key.

use super::{ConfigError, in_range, invalid};
use serde::Serialize;

/// A finite, strictly positive number.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Serialize)]
pub struct Positive(f64);

impl Positive {
    /// Checks `value`, naming `key` in the error.
    pub fn new(key: &str, value: f64) -> Result<Self, ConfigError> {
        if value.is_finite() && value > 0.0 {
            Ok(Self(value))
        } else {
            Err(invalid(key, value, "must be a finite number > 0"))
        }
    }
    /// Checks an angle given in degrees under `key` (the error shows the degrees as written)
    /// and keeps it in radians.
    pub fn from_degrees(key: &str, degrees: f64) -> Result<Self, ConfigError> {
        Self::new(key, degrees).map(|p| Self(p.0.to_radians()))
    }
    /// [`Positive::new`] within `[lo, hi]` as well (see the crate-private `in_range`).
    pub fn in_range(
        key: &str,
        value: f64,
        lo: f64,
        hi: f64,
        rule: &'static str,
    ) -> Result<Self, ConfigError> {
        Self::new(key, in_range(key, value, lo, hi, rule)?)
    }
    /// [`Positive::from_degrees`] within `[lo, hi]` degrees as well.
    pub fn from_degrees_in_range(
        key: &str,
        degrees: f64,
        lo: f64,
        hi: f64,
        rule: &'static str,
    ) -> Result<Self, ConfigError> {
        Self::from_degrees(key, in_range(key, degrees, lo, hi, rule)?)
    }
    /// The value.
    pub fn get(self) -> f64 {
        self.0
    }
}

/// A finite number ≥ 0: a length, a duration or a σ for which 0 means "none" or "off" (the
/// key's documentation says which).
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Serialize)]
pub struct NonNegative(f64);

impl NonNegative {
    /// Zero.
    pub const ZERO: Self = Self(0.0);
    /// Checks `value`, naming `key` in the error.
    pub fn new(key: &str, value: f64) -> Result<Self, ConfigError> {
        if value.is_finite() && value >= 0.0 {
            Ok(Self(value))
        } else {
            Err(invalid(key, value, "must be a finite number >= 0"))
        }
    }
    /// [`NonNegative::new`] within `[lo, hi]` as well (see the crate-private `in_range`).
    pub fn in_range(
        key: &str,
        value: f64,
        lo: f64,
        hi: f64,
        rule: &'static str,
    ) -> Result<Self, ConfigError> {
        Self::new(key, in_range(key, value, lo, hi, rule)?)
    }
    /// The value.
    pub fn get(self) -> f64 {
        self.0
    }
}

/// A finite number (an angle or a direction, any sign).
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Serialize)]
pub struct Finite(f64);

impl Finite {
    /// Checks `value`, naming `key` in the error.
    pub fn new(key: &str, value: f64) -> Result<Self, ConfigError> {
        if value.is_finite() {
            Ok(Self(value))
        } else {
            Err(invalid(key, value, "must be a finite number"))
        }
    }
    /// An angle given in degrees under `key`, within `[lo, hi]` degrees (`rule` says it), kept
    /// in radians.
    pub fn from_degrees_in_range(
        key: &str,
        degrees: f64,
        lo: f64,
        hi: f64,
        rule: &'static str,
    ) -> Result<Self, ConfigError> {
        Self::new(key, in_range(key, degrees, lo, hi, rule)?.to_radians())
    }
    /// The value.
    pub fn get(self) -> f64 {
        self.0
    }
}

/// A finite number in [0, 1].
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Serialize)]
pub struct Fraction(f64);

impl Fraction {
    /// Checks `value`, naming `key` in the error.
    pub fn new(key: &str, value: f64) -> Result<Self, ConfigError> {
        if (0.0..=1.0).contains(&value) {
            Ok(Self(value))
        } else {
            Err(invalid(key, value, "must be in [0, 1]"))
        }
    }
    /// The value.
    pub fn get(self) -> f64 {
        self.0
    }
}
