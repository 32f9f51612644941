//! The catalogue: the effects the diagnosis tests for ([`Effect`]), the model changes that add
//! them ([`Fix`]), which fixes each effect tries ([`Effect::fixes`]) and how a fix changes a
//! configuration ([`apply_fix`]). The names and labels are those of `report.json` and
//! `report.md`.

use corridor_shared::config::{ConfigFile, Mode, defaults};
use serde::{Serialize, Serializer};
use std::fmt;

/// An effect the model may lack.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Effect {
    /// The walking direction differs from the map direction by a constant.
    HeadingOffset,
    /// The gyro bias drifts (ramp) or steps.
    BiasDrift,
    /// The residual grows with the turn: a gyro scale-factor error.
    GyroScaleFactor,
    /// The residual grows with the specific-force excess: a g-sensitive gyro.
    GSensitivity,
    /// The residual grows with the total rotation, not the turn.
    AxisMisalignment,
    /// The residual grows with the time-step deviations, or every axis shows the same scale
    /// factor (a clock-rate error).
    Timing,
    /// The foot is not flat at stance (the paper's model only).
    MountingTilt,
    /// The gyro clips below its configured range (a rail in the data, see `clipping`).
    GyroClipping,
    /// The strides come out longer or shorter than the footprints say (position information
    /// only, see `stride_length`).
    StrideLength,
    /// The residuals are inconsistent and nothing in the catalogue explains them.
    Unexplained,
}

impl Effect {
    /// Every effect, in the catalogue's order.
    pub const ALL: [Effect; 10] = [
        Effect::HeadingOffset,
        Effect::BiasDrift,
        Effect::GyroScaleFactor,
        Effect::GSensitivity,
        Effect::AxisMisalignment,
        Effect::Timing,
        Effect::MountingTilt,
        Effect::GyroClipping,
        Effect::StrideLength,
        Effect::Unexplained,
    ];

    /// The catalogue name (in the reports).
    pub fn name(self) -> &'static str {
        match self {
            Effect::HeadingOffset => "heading_offset",
            Effect::BiasDrift => "bias_drift",
            Effect::GyroScaleFactor => "gyro_scale_factor",
            Effect::GSensitivity => "g_sensitivity",
            Effect::AxisMisalignment => "axis_misalignment",
            Effect::Timing => "timing",
            Effect::MountingTilt => "mounting_tilt",
            Effect::GyroClipping => "gyro_clipping",
            Effect::StrideLength => "stride_length",
            Effect::Unexplained => "unexplained",
        }
    }

    /// The fixes tried for this effect, with the number of parameters each adds; empty when
    /// corridor has no model change for it, or when the fix depends on the data (the clipping
    /// finding carries its own, [`Fix::GyroRail`]). The ten times faster bias random walk counts
    /// three, as the bias-rate fix's three states: it frees the bias on each axis, the most
    /// flexible fix of the catalogue. Counted as one (until session 45), it out-scored fixes
    /// that lowered the residuals as much: exp24 with a +5 % z scale factor, the scale states
    /// F = 10.7 for 3 parameters, the random walk F = 33.2 for 1, the same reduction, and
    /// `bias_drift` was named first. Three is a heuristic penalty chosen after that case, not
    /// a derived count (that would be the smoother's effective number of parameters;
    /// `docs/diagnosis.md`).
    pub fn fixes(self) -> &'static [(Fix, usize)] {
        match self {
            Effect::HeadingOffset => &[(Fix::HeadingOffset, 1)],
            Effect::BiasDrift => &[(Fix::BiasRate, 3), (Fix::BiasRandomWalkTimes10, 3)],
            Effect::GyroScaleFactor | Effect::Timing => &[(Fix::ScaleFactor, 3)],
            Effect::GSensitivity => &[(Fix::GSensitivity, 3)],
            Effect::MountingTilt => &[(Fix::RotationAware, 3)],
            Effect::AxisMisalignment => &[(Fix::GyroCouplingZ, 2)],
            Effect::StrideLength => &[(Fix::RollingStance, 1)],
            Effect::GyroClipping | Effect::Unexplained => &[],
        }
    }
}

impl fmt::Display for Effect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl Serialize for Effect {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

/// A model change that adds an effect.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Fix {
    /// A heading-offset state (`model.heading_offset_sd_deg = 5`).
    HeadingOffset,
    /// Bias-rate states (`model.bias_rate_rw_rad_s2_sqrt_s = 1e-6`).
    BiasRate,
    /// A ten times faster bias random walk (`eskf.gyro_bias_rw_rad_s_sqrt_s × 10`).
    BiasRandomWalkTimes10,
    /// Gyro scale-factor states (`model.scale_factor_sd = 0.02`).
    ScaleFactor,
    /// Gyro g-sensitivity states (`model.g_sensitivity_sd = 1e-3`).
    GSensitivity,
    /// Gyro cross-coupling states into the sensor z axis (`model.gyro_coupling_z_sd_deg = 3`).
    GyroCouplingZ,
    /// The rotation-aware variant of the paper's filter (`estimator.mode = rotation_aware`).
    RotationAware,
    /// The rolling-foot stance update (`eskf.zupt_rolling_height_m = 0.08`, the sensor's
    /// height on the instep).
    RollingStance,
    /// The gyro range at the rail found in the data, so that its samples are flagged as
    /// clipped, with the clipping model on (`sensor.gyro_range_rad_s = rail / 0.99`,
    /// `eskf.clipped_rate_sd_rad_s` at its default when it was 0, the peaks put back,
    /// `eskf.restore_clipped_peaks`, when they were not).
    GyroRail {
        /// The rail, mrad/s.
        milli_rad_s: u32,
    },
    /// The strides' scale against the footprints taken out as an accelerometer scale error
    /// (`model.accel_scale_factor`, composed with the one the model has): what a model with
    /// the rolling-foot stance update can still do about strides of the wrong length. Not a
    /// state: only position information shows it.
    StrideScale {
        /// Estimated / surveyed stride length − 1, parts per million.
        ratio_ppm: i32,
    },
}

/// The rolling height the stance-length fix sets, m: the sensor's height on the instep above
/// the sole (the configuration's own figure, chosen from the ZUPT NIS without footprints).
pub const ROLLING_HEIGHT_M: f64 = 0.08;

/// The gyro range the clipping fix sets: the rail is this fraction of it (inside
/// [`CLIP_FRACTION`](corridor_shared::sensor::CLIP_FRACTION), so the rail's samples count as
/// clipped).
pub const RAIL_OF_RANGE: f64 = 0.99;

impl Fix {
    /// Every fix (the clipping fix at a 5 rad/s rail).
    pub const ALL: [Fix; 10] = [
        Fix::HeadingOffset,
        Fix::BiasRate,
        Fix::BiasRandomWalkTimes10,
        Fix::ScaleFactor,
        Fix::GSensitivity,
        Fix::GyroCouplingZ,
        Fix::RotationAware,
        Fix::RollingStance,
        Fix::GyroRail { milli_rad_s: 5000 },
        Fix::StrideScale { ratio_ppm: 20_000 },
    ];

    /// The configuration change in words, without the data's figures (see `Display`).
    pub fn label(self) -> &'static str {
        match self {
            Fix::HeadingOffset => "model.heading_offset_sd_deg = 5",
            Fix::BiasRate => "model.bias_rate_rw_rad_s2_sqrt_s = 1e-6",
            Fix::BiasRandomWalkTimes10 => "eskf.gyro_bias_rw_rad_s_sqrt_s × 10",
            Fix::ScaleFactor => "model.scale_factor_sd = 0.02",
            Fix::GSensitivity => "model.g_sensitivity_sd = 1e-3",
            Fix::GyroCouplingZ => "model.gyro_coupling_z_sd_deg = 3",
            Fix::RotationAware => "estimator.mode = rotation_aware",
            Fix::RollingStance => "eskf.zupt_rolling_height_m = 0.08",
            Fix::GyroRail { .. } => "sensor.gyro_range_rad_s = the rail / 0.99",
            Fix::StrideScale { .. } => "model.accel_scale_factor from the stride ratio",
        }
    }

    /// The stride-scale fix for strides `ratio` times the surveyed length (within the ±19 % the
    /// configuration takes: beyond 20 % it is a wrong unit, not a scale).
    pub fn stride_scale(ratio: f64) -> Fix {
        Fix::StrideScale {
            ratio_ppm: ((ratio - 1.0).clamp(-0.19, 0.19) * 1e6).round() as i32,
        }
    }

    /// An extension state of the error-state filter (a `model.` key).
    pub fn is_model_extension(self) -> bool {
        matches!(
            self,
            Fix::HeadingOffset
                | Fix::BiasRate
                | Fix::ScaleFactor
                | Fix::GSensitivity
                | Fix::GyroCouplingZ
        )
    }
}

impl fmt::Display for Fix {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Fix::GyroRail { milli_rad_s } => write!(
                f,
                "sensor.gyro_range_rad_s = {:.3} (the rail {:.3} / {RAIL_OF_RANGE})",
                f64::from(*milli_rad_s) / 1000.0 / RAIL_OF_RANGE,
                f64::from(*milli_rad_s) / 1000.0
            ),
            Fix::StrideScale { ratio_ppm } => write!(
                f,
                "model.accel_scale_factor composed with strides {:.4} × the surveyed",
                1.0 + f64::from(*ratio_ppm) * 1e-6
            ),
            _ => f.write_str(self.label()),
        }
    }
}

impl Serialize for Fix {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}

/// Applies `fix` to `file`; `false` when it is already in the model.
pub fn apply_fix(fix: Fix, file: &mut ConfigFile) -> bool {
    // The extension states live in the error-state filter: from the paper's bias filter (or
    // its rotation-aware variant) a model extension also moves the heading observations there.
    if fix.is_model_extension()
        && matches!(file.estimator.mode, Some(Mode::Paper | Mode::RotationAware))
    {
        let mut f = file.clone();
        f.estimator.mode = Some(Mode::Eskf);
        if apply_fix(fix, &mut f) {
            *file = f;
            return true;
        }
        return false;
    }
    let m = &mut file.model;
    match fix {
        Fix::HeadingOffset if m.heading_offset_sd_deg.is_none() => {
            m.heading_offset_sd_deg = Some(5.0)
        }
        Fix::BiasRate if m.bias_rate_rw_rad_s2_sqrt_s.is_none() => {
            m.bias_rate_rw_rad_s2_sqrt_s = Some(1e-6)
        }
        Fix::ScaleFactor if m.scale_factor_sd.is_none() => m.scale_factor_sd = Some(0.02),
        Fix::GSensitivity if m.g_sensitivity_sd.is_none() => m.g_sensitivity_sd = Some(1e-3),
        Fix::GyroCouplingZ if m.gyro_coupling_z_sd_deg.is_none() => {
            m.gyro_coupling_z_sd_deg = Some(3.0)
        }
        Fix::BiasRandomWalkTimes10 => {
            let rw = file
                .eskf
                .gyro_bias_rw_rad_s_sqrt_s
                .unwrap_or(defaults::ESKF_GYRO_BIAS_RW_RAD_S_SQRT_S);
            if rw >= 1e-3 {
                return false;
            }
            file.eskf.gyro_bias_rw_rad_s_sqrt_s = Some(rw * 10.0);
        }
        Fix::RotationAware if file.estimator.mode == Some(Mode::Paper) => {
            file.estimator.mode = Some(Mode::RotationAware)
        }
        Fix::RollingStance
            if file
                .eskf
                .zupt_rolling_height_m
                .unwrap_or(defaults::ESKF_ZUPT_ROLLING_HEIGHT_M)
                == 0.0 =>
        {
            file.eskf.zupt_rolling_height_m = Some(ROLLING_HEIGHT_M)
        }
        Fix::GyroRail { milli_rad_s } => {
            let range = f64::from(milli_rad_s) / 1000.0 / RAIL_OF_RANGE;
            if file
                .sensor
                .gyro_range_rad_s
                .is_some_and(|r| r <= range * (1.0 + 1e-9))
            {
                return false;
            }
            file.sensor.gyro_range_rad_s = Some(range);
            if file.eskf.clipped_rate_sd_rad_s == Some(0.0) {
                file.eskf.clipped_rate_sd_rad_s = None; // the default
            }
            if file.eskf.restore_clipped_peaks == Some(false) {
                file.eskf.restore_clipped_peaks = None; // the default: put back
            }
        }
        Fix::StrideScale { ratio_ppm } if ratio_ppm != 0 => {
            // The sensor reads (1 + k) × the force and the model divides by (1 + k₀): strides
            // come out (1 + k) / (1 + k₀) = ratio long, so k = (1 + k₀) · ratio − 1.
            let k0 = m.accel_scale_factor.unwrap_or(0.0);
            m.accel_scale_factor = Some((1.0 + k0) * (1.0 + f64::from(ratio_ppm) * 1e-6) - 1.0);
        }
        _ => return false,
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_labels_are_the_report_strings() {
        let names: Vec<&str> = Effect::ALL.iter().map(|e| e.name()).collect();
        assert_eq!(
            names,
            [
                "heading_offset",
                "bias_drift",
                "gyro_scale_factor",
                "g_sensitivity",
                "axis_misalignment",
                "timing",
                "mounting_tilt",
                "gyro_clipping",
                "stride_length",
                "unexplained"
            ]
        );
        for e in Effect::ALL {
            assert_eq!(e.to_string(), e.name());
            assert_eq!(serde_json::to_value(e).unwrap(), e.name());
        }
        for f in Fix::ALL {
            match f {
                Fix::GyroRail { .. } => assert_eq!(
                    f.to_string(),
                    "sensor.gyro_range_rad_s = 5.051 (the rail 5.000 / 0.99)"
                ),
                Fix::StrideScale { .. } => assert_eq!(
                    f.to_string(),
                    "model.accel_scale_factor composed with strides 1.0200 × the surveyed"
                ),
                _ => assert_eq!(f.to_string(), f.label()),
            }
            assert_eq!(serde_json::to_value(f).unwrap(), f.to_string());
            // The extension states are exactly the `model.` keys, but the stride scale's
            // (a known correction, not a state).
            let state_key =
                f.label().starts_with("model.") && !matches!(f, Fix::StrideScale { .. });
            assert_eq!(f.is_model_extension(), state_key);
        }
    }

    #[test]
    fn each_effect_maps_to_its_fixes() {
        let fixes = |e: Effect| e.fixes().iter().map(|&(f, _)| f).collect::<Vec<_>>();
        assert_eq!(fixes(Effect::HeadingOffset), [Fix::HeadingOffset]);
        assert_eq!(
            fixes(Effect::BiasDrift),
            [Fix::BiasRate, Fix::BiasRandomWalkTimes10]
        );
        assert_eq!(fixes(Effect::GyroScaleFactor), [Fix::ScaleFactor]);
        assert_eq!(fixes(Effect::Timing), [Fix::ScaleFactor]);
        assert_eq!(fixes(Effect::GSensitivity), [Fix::GSensitivity]);
        assert_eq!(fixes(Effect::MountingTilt), [Fix::RotationAware]);
        assert_eq!(fixes(Effect::AxisMisalignment), [Fix::GyroCouplingZ]);
        assert!(Effect::Unexplained.fixes().is_empty());
        assert_eq!(fixes(Effect::StrideLength), [Fix::RollingStance]);
        // The clipping finding carries its fix (the rail is the data's).
        assert!(Effect::GyroClipping.fixes().is_empty());
        // Parameters added: one offset, one rolling height, two couplings, three states or
        // the three axes' faster random walks otherwise.
        for e in Effect::ALL {
            for &(f, k) in e.fixes() {
                let want = match f {
                    Fix::HeadingOffset | Fix::RollingStance => 1,
                    Fix::GyroCouplingZ => 2,
                    _ => 3,
                };
                assert_eq!(k, want, "{e} {f}");
            }
        }
        // Every fix but the data's is reachable from some effect.
        for f in Fix::ALL
            .into_iter()
            .filter(|f| !matches!(f, Fix::GyroRail { .. } | Fix::StrideScale { .. }))
        {
            assert!(
                Effect::ALL
                    .iter()
                    .any(|e| e.fixes().iter().any(|&(g, _)| g == f)),
                "{f}"
            );
        }
    }

    /// The default model in the mode `f` applies to (the rotation-aware bias filter is the
    /// paper mode's).
    fn model_for(f: Fix) -> ConfigFile {
        let mut file = ConfigFile::default();
        file.estimator.mode = Some(if f == Fix::RotationAware {
            Mode::Paper
        } else {
            Mode::Eskf
        });
        file
    }

    #[test]
    fn every_fix_applies_once_then_reports_already_in_the_model() {
        for f in Fix::ALL {
            let mut file = model_for(f);
            let before = format!("{file:?}");
            assert!(apply_fix(f, &mut file), "{f} applies to the default model");
            assert_ne!(format!("{file:?}"), before, "{f} changed nothing");
            // The random walk and the stride scale compose (the stride scale's test is in
            // `stride_length.rs`).
            if !matches!(f, Fix::BiasRandomWalkTimes10 | Fix::StrideScale { .. }) {
                assert!(!apply_fix(f, &mut file), "{f} applied twice");
            }
        }
        // The random walk grows ×10 per application up to 1e-3.
        let mut file = ConfigFile::default();
        assert!(apply_fix(Fix::BiasRandomWalkTimes10, &mut file));
        assert_eq!(file.eskf.gyro_bias_rw_rad_s_sqrt_s, Some(1e-3));
        assert!(!apply_fix(Fix::BiasRandomWalkTimes10, &mut file));
    }

    #[test]
    fn every_fix_the_loop_keeps_shows_in_the_final_model() {
        // `report.md`'s "final model" and `report.json`'s `final_model` list the model the loop
        // ended with; a review found a kept gyro rail (`sensor.gyro_range_rad_s`) and a kept
        // stride scale (`model.accel_scale_factor`) missing from it, the final model read as
        // the starting one.
        for f in Fix::ALL {
            let mut file = model_for(f);
            file.sensor.gyro_range_rad_s = Some(8.727);
            let start = file.clone();
            let before = super::super::analysis::final_model_words(&start, &file);
            assert!(apply_fix(f, &mut file), "{f} applies to the default model");
            let after = super::super::analysis::final_model_words(&start, &file);
            assert_ne!(
                after, before,
                "{f} kept, the final model reads as the starting one"
            );
            assert_eq!(after.last().map(|m| m.starts_with("mode = ")), Some(true));
        }
    }

    #[test]
    fn the_rail_fix_flags_the_rail_and_turns_the_clipping_model_on() {
        let rail = Fix::GyroRail { milli_rad_s: 5000 };
        let mut file = ConfigFile::default();
        file.sensor.gyro_range_rad_s = Some(8.727);
        file.eskf.clipped_rate_sd_rad_s = Some(0.0);
        file.eskf.restore_clipped_peaks = Some(false);
        assert!(apply_fix(rail, &mut file));
        let range = file.sensor.gyro_range_rad_s.unwrap();
        assert!((range - 5.0 / RAIL_OF_RANGE).abs() < 1e-12);
        assert!(
            5.0 >= corridor_shared::sensor::CLIP_FRACTION * range,
            "the rail is flagged"
        );
        assert_eq!(file.eskf.clipped_rate_sd_rad_s, None, "the default σ");
        let cfg = file.validate().unwrap();
        assert!(cfg.eskf.restore_clipped_peaks, "the peaks put back");
        // A range at or below the rail already: nothing to do.
        assert!(!apply_fix(rail, &mut file));
        // A configured σ stays.
        let mut file = ConfigFile::default();
        file.eskf.clipped_rate_sd_rad_s = Some(0.3);
        assert!(apply_fix(rail, &mut file));
        assert_eq!(file.eskf.clipped_rate_sd_rad_s, Some(0.3));
    }

    #[test]
    fn model_extensions_move_the_paper_model_to_the_error_state_filter() {
        let mut file = ConfigFile::default();
        file.estimator.mode = Some(Mode::Paper);
        assert!(apply_fix(Fix::ScaleFactor, &mut file));
        assert_eq!(file.estimator.mode, Some(Mode::Eskf));
        assert_eq!(file.model.scale_factor_sd, Some(0.02));
        // Not a model extension: the mode stays.
        let mut file = ConfigFile::default();
        file.estimator.mode = Some(Mode::Paper);
        assert!(apply_fix(Fix::BiasRandomWalkTimes10, &mut file));
        assert_eq!(file.estimator.mode, Some(Mode::Paper));
        // The rotation-aware mode only replaces the paper's.
        let mut file = ConfigFile::default();
        file.estimator.mode = Some(Mode::Eskf);
        assert!(!apply_fix(Fix::RotationAware, &mut file));
    }
}
