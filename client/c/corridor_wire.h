/* corridor_wire.h: the corridor wire types for C and C++ (iceoryx2 payloads).
 * GENERATED from shared/src/wire.rs by `corridor-wire c-header`; do not edit (CI checks
 * that this file equals the generated one). Units are in the field names (_s, _rad,
 * _rad_s, _m_s2, _m, _ns); see shared/src/wire.rs for the meaning of each field.
 * Publish or subscribe with iceoryx2's C/C++ bindings on the service named below, inside
 * the domain's prefix "corridor_<domain>_", announcing the iceoryx2 type name below
 * (size and alignment as asserted) and the same QoS as shared/src/services/qos.rs.
 * C11 or C++11; the static assertions refuse a compiler that lays the structs out otherwise. */
#ifndef CORRIDOR_WIRE_H
#define CORRIDOR_WIRE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
#define CORRIDOR_STATIC_ASSERT(c, m) static_assert(c, m)
#define CORRIDOR_ALIGNOF(t) alignof(t)
#else
#define CORRIDOR_STATIC_ASSERT(c, m) _Static_assert(c, m)
#define CORRIDOR_ALIGNOF(t) _Alignof(t)
#endif

#define CORRIDOR_SERVICE_VERSION "v6"
#define CORRIDOR_FLAG_END_OF_STREAM 1u
#define CORRIDOR_FLAG_BIAS_CORRECTED 2u
#define CORRIDOR_FLAG_STANCE 4u
#define CORRIDOR_FLAG_CONVERGED 8u
#define CORRIDOR_FLAG_SHUTDOWN 16u
#define CORRIDOR_FLAG_RETRACTS 32u
#define CORRIDOR_FLAG_FRAME_SET 64u
#define CORRIDOR_ANGLE_ROLL 1u
#define CORRIDOR_ANGLE_PITCH 2u
#define CORRIDOR_ANGLE_HEADING 4u
#define CORRIDOR_PHASE_ALIGNING 0u
#define CORRIDOR_PHASE_CALIBRATING 1u
#define CORRIDOR_PHASE_TRACKING 2u
/* Event (no payload) the daemon notifies, with event id = the producer's publisher id
 * modulo 256, when it has taken that producer's first sample: a producer waits for it
 * before it drops its publisher (client/src/producer.rs). */
#define CORRIDOR_IMU_ACK_EVENT "corridor/v6/imu_ack"

/* One IMU sample, producer -> daemon. */
#define CORRIDOR_IMU_SAMPLE_SERVICE "corridor/v6/imu"
#define CORRIDOR_IMU_SAMPLE_TYPE_NAME "corridor_v6_ImuSample"
typedef struct corridor_ImuSample {
    uint64_t seq;
    double t_s;
    double gyro_rad_s[3];
    double accel_m_s2[3];
    double temp_c;
    uint32_t flags;
    uint32_t reserved;
    uint64_t sent_ns;
} corridor_ImuSample;
CORRIDOR_STATIC_ASSERT(sizeof(corridor_ImuSample) == 88, "corridor_ImuSample: size");
CORRIDOR_STATIC_ASSERT(CORRIDOR_ALIGNOF(corridor_ImuSample) == 8, "corridor_ImuSample: alignment");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_ImuSample, seq) == 0, "corridor_ImuSample.seq: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_ImuSample, t_s) == 8, "corridor_ImuSample.t_s: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_ImuSample, gyro_rad_s) == 16, "corridor_ImuSample.gyro_rad_s: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_ImuSample, accel_m_s2) == 40, "corridor_ImuSample.accel_m_s2: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_ImuSample, temp_c) == 64, "corridor_ImuSample.temp_c: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_ImuSample, flags) == 72, "corridor_ImuSample.flags: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_ImuSample, reserved) == 76, "corridor_ImuSample.reserved: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_ImuSample, sent_ns) == 80, "corridor_ImuSample.sent_ns: offset");

/* An external attitude observation, producer -> daemon. */
#define CORRIDOR_ANGLE_OBSERVATION_SERVICE "corridor/v6/angles"
#define CORRIDOR_ANGLE_OBSERVATION_TYPE_NAME "corridor_v6_AngleObservation"
typedef struct corridor_AngleObservation {
    uint64_t seq;
    double t_s;
    double roll_rad;
    double pitch_rad;
    double heading_rad;
    double roll_sd_rad;
    double pitch_sd_rad;
    double heading_sd_rad;
    uint32_t valid;
    uint32_t reserved;
} corridor_AngleObservation;
CORRIDOR_STATIC_ASSERT(sizeof(corridor_AngleObservation) == 72, "corridor_AngleObservation: size");
CORRIDOR_STATIC_ASSERT(CORRIDOR_ALIGNOF(corridor_AngleObservation) == 8, "corridor_AngleObservation: alignment");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AngleObservation, seq) == 0, "corridor_AngleObservation.seq: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AngleObservation, t_s) == 8, "corridor_AngleObservation.t_s: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AngleObservation, roll_rad) == 16, "corridor_AngleObservation.roll_rad: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AngleObservation, pitch_rad) == 24, "corridor_AngleObservation.pitch_rad: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AngleObservation, heading_rad) == 32, "corridor_AngleObservation.heading_rad: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AngleObservation, roll_sd_rad) == 40, "corridor_AngleObservation.roll_sd_rad: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AngleObservation, pitch_sd_rad) == 48, "corridor_AngleObservation.pitch_sd_rad: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AngleObservation, heading_sd_rad) == 56, "corridor_AngleObservation.heading_sd_rad: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AngleObservation, valid) == 64, "corridor_AngleObservation.valid: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AngleObservation, reserved) == 68, "corridor_AngleObservation.reserved: offset");

/* The gyro-bias estimate, daemon -> clients. */
#define CORRIDOR_BIAS_SAMPLE_SERVICE "corridor/v6/bias"
#define CORRIDOR_BIAS_SAMPLE_TYPE_NAME "corridor_v6_BiasSample"
typedef struct corridor_BiasSample {
    uint64_t seq;
    double t_s;
    uint64_t imu_seq;
    double gyro_bias_rad_s[3];
    double gyro_bias_sd_rad_s[3];
    double bias_unabsorbed;
    uint32_t converged;
    uint32_t flags;
} corridor_BiasSample;
CORRIDOR_STATIC_ASSERT(sizeof(corridor_BiasSample) == 88, "corridor_BiasSample: size");
CORRIDOR_STATIC_ASSERT(CORRIDOR_ALIGNOF(corridor_BiasSample) == 8, "corridor_BiasSample: alignment");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_BiasSample, seq) == 0, "corridor_BiasSample.seq: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_BiasSample, t_s) == 8, "corridor_BiasSample.t_s: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_BiasSample, imu_seq) == 16, "corridor_BiasSample.imu_seq: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_BiasSample, gyro_bias_rad_s) == 24, "corridor_BiasSample.gyro_bias_rad_s: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_BiasSample, gyro_bias_sd_rad_s) == 48, "corridor_BiasSample.gyro_bias_sd_rad_s: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_BiasSample, bias_unabsorbed) == 72, "corridor_BiasSample.bias_unabsorbed: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_BiasSample, converged) == 80, "corridor_BiasSample.converged: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_BiasSample, flags) == 84, "corridor_BiasSample.flags: offset");

/* The attitude after one IMU sample, daemon -> clients. */
#define CORRIDOR_ATTITUDE_SAMPLE_SERVICE "corridor/v6/attitude"
#define CORRIDOR_ATTITUDE_SAMPLE_TYPE_NAME "corridor_v6_AttitudeSample"
typedef struct corridor_AttitudeSample {
    uint64_t seq;
    double t_s;
    uint64_t imu_seq;
    double nav_from_body_wxyz[4];
    double roll_rad;
    double pitch_rad;
    double yaw_rad;
    double gyro_bias_rad_s[3];
    double gyro_bias_sd_rad_s[3];
    uint32_t phase;
    uint32_t flags;
    uint64_t imu_sent_ns;
} corridor_AttitudeSample;
CORRIDOR_STATIC_ASSERT(sizeof(corridor_AttitudeSample) == 144, "corridor_AttitudeSample: size");
CORRIDOR_STATIC_ASSERT(CORRIDOR_ALIGNOF(corridor_AttitudeSample) == 8, "corridor_AttitudeSample: alignment");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AttitudeSample, seq) == 0, "corridor_AttitudeSample.seq: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AttitudeSample, t_s) == 8, "corridor_AttitudeSample.t_s: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AttitudeSample, imu_seq) == 16, "corridor_AttitudeSample.imu_seq: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AttitudeSample, nav_from_body_wxyz) == 24, "corridor_AttitudeSample.nav_from_body_wxyz: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AttitudeSample, roll_rad) == 56, "corridor_AttitudeSample.roll_rad: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AttitudeSample, pitch_rad) == 64, "corridor_AttitudeSample.pitch_rad: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AttitudeSample, yaw_rad) == 72, "corridor_AttitudeSample.yaw_rad: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AttitudeSample, gyro_bias_rad_s) == 80, "corridor_AttitudeSample.gyro_bias_rad_s: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AttitudeSample, gyro_bias_sd_rad_s) == 104, "corridor_AttitudeSample.gyro_bias_sd_rad_s: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AttitudeSample, phase) == 128, "corridor_AttitudeSample.phase: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AttitudeSample, flags) == 132, "corridor_AttitudeSample.flags: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_AttitudeSample, imu_sent_ns) == 136, "corridor_AttitudeSample.imu_sent_ns: offset");

/* Position and velocity at a footfall, daemon -> clients. */
#define CORRIDOR_NAV_SAMPLE_SERVICE "corridor/v6/nav"
#define CORRIDOR_NAV_SAMPLE_TYPE_NAME "corridor_v6_NavSample"
typedef struct corridor_NavSample {
    uint64_t seq;
    double t_s;
    uint64_t imu_seq;
    uint64_t stance;
    double p_m[3];
    double v_m_s[3];
    double yaw_rad;
    uint32_t flags;
    uint32_t reserved;
} corridor_NavSample;
CORRIDOR_STATIC_ASSERT(sizeof(corridor_NavSample) == 96, "corridor_NavSample: size");
CORRIDOR_STATIC_ASSERT(CORRIDOR_ALIGNOF(corridor_NavSample) == 8, "corridor_NavSample: alignment");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_NavSample, seq) == 0, "corridor_NavSample.seq: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_NavSample, t_s) == 8, "corridor_NavSample.t_s: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_NavSample, imu_seq) == 16, "corridor_NavSample.imu_seq: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_NavSample, stance) == 24, "corridor_NavSample.stance: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_NavSample, p_m) == 32, "corridor_NavSample.p_m: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_NavSample, v_m_s) == 56, "corridor_NavSample.v_m_s: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_NavSample, yaw_rad) == 80, "corridor_NavSample.yaw_rad: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_NavSample, flags) == 88, "corridor_NavSample.flags: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_NavSample, reserved) == 92, "corridor_NavSample.reserved: offset");

/* Counters of the daemon, daemon -> clients. */
#define CORRIDOR_DIAGNOSTICS_SERVICE "corridor/v6/diagnostics"
#define CORRIDOR_DIAGNOSTICS_TYPE_NAME "corridor_v6_Diagnostics"
typedef struct corridor_Diagnostics {
    uint64_t seq;
    double t_s;
    uint64_t received;
    uint64_t seq_gaps;
    uint64_t rejected_duplicate_seq;
    uint64_t late;
    uint64_t rejected_non_finite;
    uint64_t rejected_time;
    uint64_t rejected_implausible;
    uint64_t rejected_time_jump;
    uint64_t dropped_overflow;
    uint64_t accepted;
    uint64_t undelivered;
    uint64_t stances;
    uint64_t heading_used;
    double last_nis;
    uint64_t producer_changes;
    double latency_p50_s;
    double latency_p99_s;
    uint64_t head_missing;
    uint64_t missing_at_restart;
    uint64_t lost_in_daemon;
    uint64_t angles_dropped;
    uint64_t lives;
    uint64_t foreign_samples;
    uint64_t angles_ignored;
    uint64_t headings_refused;
    uint64_t headings_superseded;
    uint64_t headings_outside_gate;
    uint64_t headings_expired;
    uint64_t headings_undone;
    uint64_t clipped_samples;
    uint64_t clipped_peaks_restored;
    uint64_t clipped_peaks_not_restored;
    uint64_t stalled_consumers;
    uint64_t discarded_for_stalled;
    uint32_t phase;
    uint32_t flags;
} corridor_Diagnostics;
CORRIDOR_STATIC_ASSERT(sizeof(corridor_Diagnostics) == 296, "corridor_Diagnostics: size");
CORRIDOR_STATIC_ASSERT(CORRIDOR_ALIGNOF(corridor_Diagnostics) == 8, "corridor_Diagnostics: alignment");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, seq) == 0, "corridor_Diagnostics.seq: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, t_s) == 8, "corridor_Diagnostics.t_s: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, received) == 16, "corridor_Diagnostics.received: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, seq_gaps) == 24, "corridor_Diagnostics.seq_gaps: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, rejected_duplicate_seq) == 32, "corridor_Diagnostics.rejected_duplicate_seq: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, late) == 40, "corridor_Diagnostics.late: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, rejected_non_finite) == 48, "corridor_Diagnostics.rejected_non_finite: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, rejected_time) == 56, "corridor_Diagnostics.rejected_time: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, rejected_implausible) == 64, "corridor_Diagnostics.rejected_implausible: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, rejected_time_jump) == 72, "corridor_Diagnostics.rejected_time_jump: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, dropped_overflow) == 80, "corridor_Diagnostics.dropped_overflow: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, accepted) == 88, "corridor_Diagnostics.accepted: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, undelivered) == 96, "corridor_Diagnostics.undelivered: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, stances) == 104, "corridor_Diagnostics.stances: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, heading_used) == 112, "corridor_Diagnostics.heading_used: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, last_nis) == 120, "corridor_Diagnostics.last_nis: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, producer_changes) == 128, "corridor_Diagnostics.producer_changes: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, latency_p50_s) == 136, "corridor_Diagnostics.latency_p50_s: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, latency_p99_s) == 144, "corridor_Diagnostics.latency_p99_s: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, head_missing) == 152, "corridor_Diagnostics.head_missing: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, missing_at_restart) == 160, "corridor_Diagnostics.missing_at_restart: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, lost_in_daemon) == 168, "corridor_Diagnostics.lost_in_daemon: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, angles_dropped) == 176, "corridor_Diagnostics.angles_dropped: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, lives) == 184, "corridor_Diagnostics.lives: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, foreign_samples) == 192, "corridor_Diagnostics.foreign_samples: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, angles_ignored) == 200, "corridor_Diagnostics.angles_ignored: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, headings_refused) == 208, "corridor_Diagnostics.headings_refused: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, headings_superseded) == 216, "corridor_Diagnostics.headings_superseded: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, headings_outside_gate) == 224, "corridor_Diagnostics.headings_outside_gate: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, headings_expired) == 232, "corridor_Diagnostics.headings_expired: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, headings_undone) == 240, "corridor_Diagnostics.headings_undone: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, clipped_samples) == 248, "corridor_Diagnostics.clipped_samples: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, clipped_peaks_restored) == 256, "corridor_Diagnostics.clipped_peaks_restored: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, clipped_peaks_not_restored) == 264, "corridor_Diagnostics.clipped_peaks_not_restored: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, stalled_consumers) == 272, "corridor_Diagnostics.stalled_consumers: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, discarded_for_stalled) == 280, "corridor_Diagnostics.discarded_for_stalled: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, phase) == 288, "corridor_Diagnostics.phase: offset");
CORRIDOR_STATIC_ASSERT(offsetof(corridor_Diagnostics, flags) == 292, "corridor_Diagnostics.flags: offset");

#endif /* CORRIDOR_WIRE_H */
