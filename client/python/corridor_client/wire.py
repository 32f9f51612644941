"""ctypes mirrors of the corridor wire types (shared/src/wire.rs).

Every field, offset, size and iceoryx2 type name must equal the Rust definition; the test
tests/test_wire_layout.py checks them against the layout the Rust code measures
(`corridor-wire layout`), so the two cannot drift. Units are in the field names.
"""

import ctypes
from typing import List, Tuple, Type

SERVICE_VERSION = "v6"

FLAG_END_OF_STREAM = 1 << 0
FLAG_BIAS_CORRECTED = 1 << 1
FLAG_STANCE = 1 << 2
FLAG_CONVERGED = 1 << 3
FLAG_SHUTDOWN = 1 << 4
# Outputs published earlier in the stream with a later t_s came from glitched stamps: drop them.
FLAG_RETRACTS = 1 << 5
# The start heading set the map frame on this sample (positions and yaws before it are in the
# frame before); the nav sample of that stance is sent again with it and replaces the first.
FLAG_FRAME_SET = 1 << 6
# Roll and pitch are not fused by the daemon (its tilt comes from gravity at every stance):
# observations carrying them are counted (angles_ignored); their heading, if any, is used.
ANGLE_ROLL = 1 << 0
ANGLE_PITCH = 1 << 1
ANGLE_HEADING = 1 << 2
PHASE_ALIGNING = 0
PHASE_CALIBRATING = 1
PHASE_TRACKING = 2

_u32 = ctypes.c_uint32
_u64 = ctypes.c_uint64
_f64 = ctypes.c_double
_v3 = ctypes.c_double * 3
_v4 = ctypes.c_double * 4


class _Wire(ctypes.Structure):
    """A wire type: `type_name()` is the iceoryx2 type name the Rust side declares."""

    TYPE_NAME = ""
    SERVICE = ""

    @classmethod
    def type_name(cls) -> str:
        return cls.TYPE_NAME

    def __repr__(self) -> str:
        parts = []
        for name, _ in self._fields_:
            v = getattr(self, name)
            parts.append(f"{name}={list(v) if isinstance(v, ctypes.Array) else v}")
        return f"{type(self).__name__}({', '.join(parts)})"


class ImuSample(_Wire):
    """One IMU sample, producer -> daemon."""

    TYPE_NAME = "corridor_v6_ImuSample"
    SERVICE = "corridor/v6/imu"
    _fields_: List[Tuple[str, Type]] = [
        ("seq", _u64),
        ("t_s", _f64),
        ("gyro_rad_s", _v3),
        ("accel_m_s2", _v3),
        ("temp_c", _f64),
        ("flags", _u32),
        ("reserved", _u32),
        ("sent_ns", _u64),
    ]


class AngleObservation(_Wire):
    """An external attitude observation, producer -> daemon."""

    TYPE_NAME = "corridor_v6_AngleObservation"
    SERVICE = "corridor/v6/angles"
    _fields_ = [
        ("seq", _u64),
        ("t_s", _f64),
        ("roll_rad", _f64),
        ("pitch_rad", _f64),
        ("heading_rad", _f64),
        ("roll_sd_rad", _f64),
        ("pitch_sd_rad", _f64),
        ("heading_sd_rad", _f64),
        ("valid", _u32),
        ("reserved", _u32),
    ]


class BiasSample(_Wire):
    """The gyro-bias estimate, daemon -> clients."""

    TYPE_NAME = "corridor_v6_BiasSample"
    SERVICE = "corridor/v6/bias"
    _fields_ = [
        ("seq", _u64),
        ("t_s", _f64),
        ("imu_seq", _u64),
        ("gyro_bias_rad_s", _v3),
        ("gyro_bias_sd_rad_s", _v3),
        ("bias_unabsorbed", _f64),
        ("converged", _u32),
        ("flags", _u32),
    ]


class AttitudeSample(_Wire):
    """The attitude after one IMU sample, daemon -> clients."""

    TYPE_NAME = "corridor_v6_AttitudeSample"
    SERVICE = "corridor/v6/attitude"
    _fields_ = [
        ("seq", _u64),
        ("t_s", _f64),
        ("imu_seq", _u64),
        ("nav_from_body_wxyz", _v4),
        ("roll_rad", _f64),
        ("pitch_rad", _f64),
        ("yaw_rad", _f64),
        ("gyro_bias_rad_s", _v3),
        ("gyro_bias_sd_rad_s", _v3),
        ("phase", _u32),
        ("flags", _u32),
        ("imu_sent_ns", _u64),
    ]


class NavSample(_Wire):
    """Position and velocity at a footfall, daemon -> clients."""

    TYPE_NAME = "corridor_v6_NavSample"
    SERVICE = "corridor/v6/nav"
    _fields_ = [
        ("seq", _u64),
        ("t_s", _f64),
        ("imu_seq", _u64),
        ("stance", _u64),
        ("p_m", _v3),
        ("v_m_s", _v3),
        ("yaw_rad", _f64),
        ("flags", _u32),
        ("reserved", _u32),
    ]


class Diagnostics(_Wire):
    """Counters of the daemon, daemon -> clients."""

    TYPE_NAME = "corridor_v6_Diagnostics"
    SERVICE = "corridor/v6/diagnostics"
    _fields_ = [
        ("seq", _u64),
        ("t_s", _f64),
        ("received", _u64),
        ("seq_gaps", _u64),
        ("rejected_duplicate_seq", _u64),
        ("late", _u64),
        ("rejected_non_finite", _u64),
        ("rejected_time", _u64),
        ("rejected_implausible", _u64),
        ("rejected_time_jump", _u64),
        ("dropped_overflow", _u64),
        ("accepted", _u64),
        ("undelivered", _u64),
        ("stances", _u64),
        ("heading_used", _u64),
        ("last_nis", _f64),
        ("producer_changes", _u64),
        ("latency_p50_s", _f64),
        ("latency_p99_s", _f64),
        ("head_missing", _u64),
        ("missing_at_restart", _u64),
        ("lost_in_daemon", _u64),
        ("angles_dropped", _u64),
        ("lives", _u64),
        ("foreign_samples", _u64),
        ("angles_ignored", _u64),
        ("headings_refused", _u64),
        ("headings_superseded", _u64),
        ("headings_outside_gate", _u64),
        ("headings_expired", _u64),
        ("headings_undone", _u64),
        ("clipped_samples", _u64),
        ("clipped_peaks_restored", _u64),
        ("clipped_peaks_not_restored", _u64),
        ("stalled_consumers", _u64),
        ("discarded_for_stalled", _u64),
        ("phase", _u32),
        ("flags", _u32),
    ]


WIRE_TYPES: List[Type[_Wire]] = [
    ImuSample,
    AngleObservation,
    BiasSample,
    AttitudeSample,
    NavSample,
    Diagnostics,
]
