//! The memory layout of the [`crate::wire`] types, for the clients in other languages: size,
//! alignment, and each field's offset, type and length, measured on the Rust definitions
//! (`size_of`, `align_of`, `offset_of!`). The C header ([`c_header`]) and the layout JSON that
//! the Python client's test checks its ctypes mirrors against are generated from it, so they
//! cannot drift from the Rust types.
//!
//! A field missing from a description is caught by [`TypeLayout::check`] (the fields must tile
//! the struct without gaps); a field with the wrong type does not compile.

use crate::services::Topic;
use crate::wire::{
    AngleObservation, AttitudeSample, BiasSample, Diagnostics, ImuSample, NavSample,
};
use iceoryx2::prelude::ZeroCopySend;
use serde::Serialize;
use std::fmt::Write as _;

/// One field of a wire type.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct FieldLayout {
    /// Field name (as in Rust, C and Python).
    pub name: &'static str,
    /// Element type: `u32`, `u64` or `f64`.
    pub ty: &'static str,
    /// Number of elements (1 for a scalar, N for `[T; N]`).
    pub len: usize,
    /// Offset from the start of the struct, bytes.
    pub offset: usize,
    /// Size, bytes.
    pub size: usize,
}

/// One wire type.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct TypeLayout {
    /// Rust (and C, Python) struct name.
    pub name: &'static str,
    /// The iceoryx2 type name (`#[type_name]`), which every language must announce.
    pub type_name: &'static str,
    /// The iceoryx2 service the type is published on.
    pub service: &'static str,
    /// One line of documentation.
    pub doc: &'static str,
    /// Size, bytes.
    pub size: usize,
    /// Alignment, bytes.
    pub align: usize,
    /// Fields in memory order.
    pub fields: Vec<FieldLayout>,
}

impl TypeLayout {
    /// Checks that the fields tile the struct in order, without gaps or overlap: a field left
    /// out of a description (or padding) fails here.
    pub fn check(&self) -> Result<(), String> {
        let mut end = 0;
        for f in &self.fields {
            if f.offset != end {
                return Err(format!(
                    "{}.{}: at offset {}, expected {end} (a field missing or padding?)",
                    self.name, f.name, f.offset
                ));
            }
            end += f.size;
        }
        if end != self.size {
            return Err(format!(
                "{}: fields end at {end}, the struct has {} bytes",
                self.name, self.size
            ));
        }
        Ok(())
    }
}

/// Element type name of a field type.
trait Elem {
    const TY: &'static str;
    const LEN: usize;
}
impl Elem for u32 {
    const TY: &'static str = "u32";
    const LEN: usize = 1;
}
impl Elem for u64 {
    const TY: &'static str = "u64";
    const LEN: usize = 1;
}
impl Elem for f64 {
    const TY: &'static str = "f64";
    const LEN: usize = 1;
}
impl<T: Elem, const N: usize> Elem for [T; N] {
    const TY: &'static str = T::TY;
    const LEN: usize = N;
}

fn field<F: Elem>(name: &'static str, offset: usize) -> FieldLayout {
    FieldLayout {
        name,
        ty: F::TY,
        len: F::LEN,
        offset,
        size: size_of::<F>(),
    }
}

/// `layout!(Type, "doc", field: type, ...)`: the layout, with each field's declared type checked
/// against the struct at compile time.
macro_rules! layout {
    ($t:ident, $doc:literal, $($f:ident : $ft:ty),+ $(,)?) => {{
        #[allow(dead_code)]
        fn types_match(v: &$t) { $(let _: &$ft = &v.$f;)+ }
        TypeLayout {
            name: stringify!($t),
            // SAFETY: reading the declared name has no precondition (the trait method is
            // unsafe for implementors, who must keep names unique).
            type_name: unsafe { <$t as ZeroCopySend>::type_name() },
            service: <$t as Topic>::SERVICE,
            doc: $doc,
            size: size_of::<$t>(),
            align: align_of::<$t>(),
            fields: vec![$(field::<$ft>(stringify!($f), std::mem::offset_of!($t, $f))),+],
        }
    }};
}

/// The layouts of every wire type.
pub fn layouts() -> Vec<TypeLayout> {
    vec![
        layout!(ImuSample, "One IMU sample, producer -> daemon.",
            seq: u64, t_s: f64, gyro_rad_s: [f64; 3], accel_m_s2: [f64; 3], temp_c: f64,
            flags: u32, reserved: u32, sent_ns: u64),
        layout!(AngleObservation, "An external attitude observation, producer -> daemon.",
            seq: u64, t_s: f64, roll_rad: f64, pitch_rad: f64, heading_rad: f64,
            roll_sd_rad: f64, pitch_sd_rad: f64, heading_sd_rad: f64, valid: u32, reserved: u32),
        layout!(BiasSample, "The gyro-bias estimate, daemon -> clients.",
            seq: u64, t_s: f64, imu_seq: u64, gyro_bias_rad_s: [f64; 3],
            gyro_bias_sd_rad_s: [f64; 3], bias_unabsorbed: f64, converged: u32, flags: u32),
        layout!(AttitudeSample, "The attitude after one IMU sample, daemon -> clients.",
            seq: u64, t_s: f64, imu_seq: u64, nav_from_body_wxyz: [f64; 4], roll_rad: f64,
            pitch_rad: f64, yaw_rad: f64, gyro_bias_rad_s: [f64; 3],
            gyro_bias_sd_rad_s: [f64; 3], phase: u32, flags: u32, imu_sent_ns: u64),
        layout!(NavSample, "Position and velocity at a footfall, daemon -> clients.",
            seq: u64, t_s: f64, imu_seq: u64, stance: u64, p_m: [f64; 3], v_m_s: [f64; 3],
            yaw_rad: f64, flags: u32, reserved: u32),
        layout!(Diagnostics, "Counters of the daemon, daemon -> clients.",
            seq: u64, t_s: f64, received: u64, seq_gaps: u64, rejected_duplicate_seq: u64,
            late: u64, rejected_non_finite: u64, rejected_time: u64,
            rejected_implausible: u64, rejected_time_jump: u64, dropped_overflow: u64,
            accepted: u64, undelivered: u64, stances: u64, heading_used: u64, last_nis: f64,
            producer_changes: u64, latency_p50_s: f64, latency_p99_s: f64, head_missing: u64,
            missing_at_restart: u64, lost_in_daemon: u64, angles_dropped: u64, lives: u64,
            foreign_samples: u64, angles_ignored: u64, headings_refused: u64,
            headings_superseded: u64, headings_outside_gate: u64, headings_expired: u64,
            headings_undone: u64, clipped_samples: u64, clipped_peaks_restored: u64,
            clipped_peaks_not_restored: u64, stalled_consumers: u64,
            discarded_for_stalled: u64, phase: u32, flags: u32),
    ]
}

/// The flag and phase constants of [`crate::wire`], name and value.
pub fn constants() -> Vec<(&'static str, u32)> {
    use crate::wire::*;
    vec![
        ("FLAG_END_OF_STREAM", FLAG_END_OF_STREAM),
        ("FLAG_BIAS_CORRECTED", FLAG_BIAS_CORRECTED),
        ("FLAG_STANCE", FLAG_STANCE),
        ("FLAG_CONVERGED", FLAG_CONVERGED),
        ("FLAG_SHUTDOWN", FLAG_SHUTDOWN),
        ("FLAG_RETRACTS", FLAG_RETRACTS),
        ("FLAG_FRAME_SET", FLAG_FRAME_SET),
        ("ANGLE_ROLL", ANGLE_ROLL),
        ("ANGLE_PITCH", ANGLE_PITCH),
        ("ANGLE_HEADING", ANGLE_HEADING),
        ("PHASE_ALIGNING", phase::ALIGNING),
        ("PHASE_CALIBRATING", phase::CALIBRATING),
        ("PHASE_TRACKING", phase::TRACKING),
    ]
}

/// Layouts, constants and service version as JSON (the Python client's test reads it).
pub fn layout_json() -> String {
    let consts: serde_json::Map<String, serde_json::Value> = constants()
        .into_iter()
        .map(|(k, v)| (k.to_owned(), v.into()))
        .collect();
    let v = serde_json::json!({
        "service_version": crate::services::SERVICE_VERSION,
        "constants": consts,
        // What the Python client's `services.py` mirrors beyond the wire.
        "service_constants": {
            "DEFAULT_DOMAIN": crate::services::DEFAULT_DOMAIN,
            "MAX_DOMAIN_LEN": crate::services::MAX_DOMAIN_LEN,
            "EVENT_MAX_NOTIFIERS": crate::services::EVENT_MAX_NOTIFIERS,
            "EVENT_MAX_LISTENERS": crate::services::EVENT_MAX_LISTENERS,
            "EVENT_WAIT_SLICE_S": crate::services::EVENT_WAIT_SLICE.as_secs_f64(),
        },
        "types": layouts(),
    });
    serde_json::to_string_pretty(&v).expect("serialisable") + "\n"
}

/// The C header of the wire types (C11: fixed-width integers, `_Static_assert`s on every size
/// and offset, so a compiler with another layout refuses it).
pub fn c_header() -> String {
    let mut h = String::new();
    let _ = writeln!(
        h,
        "/* corridor_wire.h: the corridor wire types for C and C++ (iceoryx2 payloads).\n \
         * GENERATED from shared/src/wire.rs by `corridor-wire c-header`; do not edit (CI checks\n \
         * that this file equals the generated one). Units are in the field names (_s, _rad,\n \
         * _rad_s, _m_s2, _m, _ns); see shared/src/wire.rs for the meaning of each field.\n \
         * Publish or subscribe with iceoryx2's C/C++ bindings on the service named below, inside\n \
         * the domain's prefix \"corridor_<domain>_\", announcing the iceoryx2 type name below\n \
         * (size and alignment as asserted) and the same QoS as shared/src/services/qos.rs.
 * C11 or C++11; the static assertions refuse a compiler that lays the structs out otherwise. */\n\
         #ifndef CORRIDOR_WIRE_H\n#define CORRIDOR_WIRE_H\n\n#include <stddef.h>\n#include <stdint.h>\n\n\
         #ifdef __cplusplus\n#define CORRIDOR_STATIC_ASSERT(c, m) static_assert(c, m)\n\
         #define CORRIDOR_ALIGNOF(t) alignof(t)\n#else\n\
         #define CORRIDOR_STATIC_ASSERT(c, m) _Static_assert(c, m)\n\
         #define CORRIDOR_ALIGNOF(t) _Alignof(t)\n#endif\n"
    );
    let _ = writeln!(
        h,
        "#define CORRIDOR_SERVICE_VERSION \"{}\"",
        crate::services::SERVICE_VERSION
    );
    for (k, v) in constants() {
        let _ = writeln!(h, "#define CORRIDOR_{k} {v}u");
    }
    let _ = writeln!(
        h,
        "/* Event (no payload) the daemon notifies, with event id = the producer's publisher id\n \
         * modulo 256, when it has taken that producer's first sample: a producer waits for it\n \
         * before it drops its publisher (client/src/producer.rs). */\n\
         #define CORRIDOR_IMU_ACK_EVENT \"{}\"",
        crate::services::IMU_ACK_SERVICE
    );
    for t in layouts() {
        let upper = screaming_snake(t.name);
        let _ = writeln!(h, "\n/* {} */", t.doc);
        let _ = writeln!(
            h,
            "#define CORRIDOR_{upper}_SERVICE \"{}\"\n#define CORRIDOR_{upper}_TYPE_NAME \"{}\"",
            t.service, t.type_name
        );
        let _ = writeln!(h, "typedef struct corridor_{} {{", t.name);
        for f in &t.fields {
            let cty = match f.ty {
                "u32" => "uint32_t",
                "u64" => "uint64_t",
                _ => "double",
            };
            let arr = if f.len > 1 {
                format!("[{}]", f.len)
            } else {
                String::new()
            };
            let _ = writeln!(h, "    {cty} {}{arr};", f.name);
        }
        let _ = writeln!(h, "}} corridor_{};", t.name);
        let _ = writeln!(
            h,
            "CORRIDOR_STATIC_ASSERT(sizeof(corridor_{0}) == {1}, \"corridor_{0}: size\");\n\
             CORRIDOR_STATIC_ASSERT(CORRIDOR_ALIGNOF(corridor_{0}) == {2}, \"corridor_{0}: alignment\");",
            t.name, t.size, t.align
        );
        for f in &t.fields {
            let _ = writeln!(
                h,
                "CORRIDOR_STATIC_ASSERT(offsetof(corridor_{0}, {1}) == {2}, \"corridor_{0}.{1}: offset\");",
                t.name, f.name, f.offset
            );
        }
    }
    h.push_str("\n#endif /* CORRIDOR_WIRE_H */\n");
    h
}

/// `ImuSample` -> `IMU_SAMPLE`.
fn screaming_snake(name: &str) -> String {
    let mut out = String::new();
    for (i, c) in name.chars().enumerate() {
        if c.is_ascii_uppercase() && i > 0 {
            out.push('_');
        }
        out.push(c.to_ascii_uppercase());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_layout_tiles_its_struct() {
        let all = layouts();
        assert_eq!(all.len(), 6);
        for t in &all {
            t.check().unwrap();
            let prefix = format!("corridor_{}_", crate::services::SERVICE_VERSION);
            assert!(t.type_name.starts_with(&prefix), "{}", t.type_name);
        }
    }

    #[test]
    fn a_missing_field_is_caught() {
        let mut t = layouts().remove(0);
        t.fields.remove(2);
        assert!(t.check().is_err());
    }
}
