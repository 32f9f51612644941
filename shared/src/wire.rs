//! Zero-copy wire types exchanged over iceoryx2 between the daemon and its clients.
//!
//! Every type is `#[repr(C)]`, `Copy`, of fixed size and self-contained (no pointers, no heap),
//! so it can live in shared memory. The layout is the contract: changing a type means bumping
//! [`crate::services::SERVICE_VERSION`] (old processes then never see the new layout, see the
//! service names). Each type carries an explicit `type_name` so the iceoryx2 type check does not
//! depend on the Rust module path.
//!
//! Conventions for every type:
//! - `seq`: a sequence number increasing by 1 per message of that type, set by the publisher of
//!   the type. A producer's [`ImuSample`]s count from 0 in each stream; the daemon's outputs
//!   count on across streams and across daemon restarts on a domain (its accounting file keeps
//!   them), so a consumer that stays connected sees no step back. Gaps mean lost messages.
//! - `t_s`: sensor time in **seconds** (`f64`, the clock of the IMU log, not wall-clock time).
//!   Seconds as `f64` are used rather than integer nanoseconds so that a log replayed through the
//!   daemon reaches the estimator with bit-identical times (and so bit-identical estimates) to
//!   the offline runner. Outputs keep the sensor's stamps: where its clock stepped back and the
//!   estimator took the step as a new time base, their `t_s` goes back too (`seq` orders them).
//! - angles in radians, rates in rad/s, specific force in m/s², positions in m, velocities in m/s;
//!   vectors in sensor axes (`_body`/gyro bias) or in the map frame (position, velocity), as named.

use crate::imu_csv::ImuRow;
use iceoryx2::prelude::*;

/// [`ImuSample::flags`] (and the output `flags`): the producer has finished; this message
/// carries no data. The daemon answers with one output of each kind carrying the same flag (and
/// the last state), then resets its estimator for the next stream; its periodic diagnostics
/// carry the flag too until the next stream's first sample.
pub const FLAG_END_OF_STREAM: u32 = 1 << 0;

/// Output `flags`: the bias is subtracted from the gyro rates the attitude was integrated from
/// (set once the estimator has aligned).
pub const FLAG_BIAS_CORRECTED: u32 = 1 << 1;

/// Output `flags`: the foot is at rest (stance) on this sample.
pub const FLAG_STANCE: u32 = 1 << 2;

/// Output `flags`: the bias has converged (tracking, and less than the configured
/// `estimator.converged_unabsorbed` of a bias error present when it was set is left).
pub const FLAG_CONVERGED: u32 = 1 << 3;

/// [`Diagnostics::flags`]: published because the daemon is shutting down.
pub const FLAG_SHUTDOWN: u32 = 1 << 4;

/// Output `flags`: the outputs published earlier in this stream with a `t_s` later than this
/// one's came from samples whose stamps this sample showed to be glitched (it goes back and
/// follows the time before them); the estimator dropped those samples after the fact, and its
/// state is as if they had never come. A consumer that keeps outputs should drop those (one
/// sample after a gap, or up to `sensor.max_dt_s` of a run after a jump; a clock that stepped
/// back within that time also leaves earlier outputs with a later `t_s`, which this rule
/// cannot tell apart: the glitched time is not on the wire).
pub const FLAG_RETRACTS: u32 = 1 << 5;

/// Output `flags`: the start heading (`heading.start_heading_deg`) set the map frame on this
/// sample, at the first stride's stance, turning it about the start point: the positions and
/// yaws published before it are in the frame before. The nav sample of that stance, published
/// when it began, is published again with this flag (the same `stance`, a later `imu_seq` and
/// `t_s`): it replaces the first one. Set again, at a later stance, when a health check's
/// restore forgot the footprints before tracking began (the strides between are in the frame
/// before); never on a start in fast gait, whose replay sets the frame before any output.
pub const FLAG_FRAME_SET: u32 = 1 << 6;

/// [`AngleObservation::valid`] bit: `roll_rad` is valid. The daemon does not fuse an external
/// roll (its tilt comes from gravity at every stance): such observations are counted
/// (`angles_ignored` in its report) and their heading, if any, is used.
pub const ANGLE_ROLL: u32 = 1 << 0;
/// [`AngleObservation::valid`] bit: `pitch_rad` is valid. Not fused either (see [`ANGLE_ROLL`]).
pub const ANGLE_PITCH: u32 = 1 << 1;
/// [`AngleObservation::valid`] bit: `heading_rad` is valid.
pub const ANGLE_HEADING: u32 = 1 << 2;

/// Estimator phase as carried on the wire ([`AttitudeSample::phase`], [`Diagnostics::phase`]).
pub mod phase {
    /// Waiting for the end of the initial rest.
    pub const ALIGNING: u32 = 0;
    /// Fixing the map frame and the sensor's yaw on the foot.
    pub const CALIBRATING: u32 = 1;
    /// Heading observations in use.
    pub const TRACKING: u32 = 2;

    /// The name of a phase code (`aligning`, `calibrating`, `tracking`, as in
    /// `estimates.csv`), `unknown` for any other value.
    pub fn name(code: u32) -> &'static str {
        match code {
            ALIGNING => "aligning",
            CALIBRATING => "calibrating",
            TRACKING => "tracking",
            _ => "unknown",
        }
    }
}

/// One IMU sample, producer → daemon (`corridor/v6/imu`).
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("corridor_v6_ImuSample")]
#[repr(C)]
pub struct ImuSample {
    /// Sequence number of the producer, +1 per sample (end-of-stream markers included).
    pub seq: u64,
    /// Sensor time, s.
    pub t_s: f64,
    /// Angular rate, rad/s, sensor axes.
    pub gyro_rad_s: [f64; 3],
    /// Specific force, m/s², sensor axes (points up at rest).
    pub accel_m_s2: [f64; 3],
    /// Sensor temperature, °C; NaN when the sensor has none.
    pub temp_c: f64,
    /// Bit set of `FLAG_*` ([`FLAG_END_OF_STREAM`]).
    pub flags: u32,
    /// Reserved, 0.
    pub reserved: u32,
    /// When the producer sent it: [`monotonic_ns`] of the producer's host, 0 when unknown.
    /// The client `Producer` stamps it; the daemon uses it for its latency figures and copies
    /// it into [`AttitudeSample::imu_sent_ns`].
    pub sent_ns: u64,
}

impl ImuSample {
    /// True when this is an end-of-stream marker (no data).
    pub fn is_end_of_stream(&self) -> bool {
        self.flags & FLAG_END_OF_STREAM != 0
    }
}

impl From<&ImuRow> for ImuSample {
    /// A row of an IMU log as a sample: time, gyro, accelerometer, and the temperature (NaN when
    /// the log has none); `seq` and `sent_ns` are left to the producer.
    fn from(r: &ImuRow) -> Self {
        Self {
            t_s: r.t_s,
            gyro_rad_s: r.gyro_rad_s,
            accel_m_s2: r.accel_m_s2,
            temp_c: r.temp_c.unwrap_or(f64::NAN),
            ..Self::default()
        }
    }
}

/// An external attitude observation, producer → daemon (`corridor/v6/angles`), e.g. a heading
/// from a map matcher or a camera. The heading is used when its bit is set in `valid`, instead
/// of the map, at the stance its `t_s` falls in or the next one: at the first stance observed
/// from 0.5 s before `t_s` on, and only within 2 s after `t_s` (older, it is counted as expired,
/// `Diagnostics::headings_expired`; one already 2 s behind the latest sample when it arrives,
/// such as `t_s = 0` mid-walk, is refused then, `Diagnostics::headings_refused`); roll and
/// pitch are not fused (see [`ANGLE_ROLL`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("corridor_v6_AngleObservation")]
#[repr(C)]
pub struct AngleObservation {
    /// Sequence number of the producer.
    pub seq: u64,
    /// Sensor time the observation refers to, s: the clock of the [`ImuSample`]s' `t_s`. Not
    /// finite, more than an hour ahead of the latest sample or at least 2 s behind it:
    /// refused (`Diagnostics::headings_refused`).
    pub t_s: f64,
    /// Roll, rad.
    pub roll_rad: f64,
    /// Pitch, rad.
    pub pitch_rad: f64,
    /// Walking (foot) heading in the map frame, rad.
    pub heading_rad: f64,
    /// σ of roll, rad.
    pub roll_sd_rad: f64,
    /// σ of pitch, rad.
    pub pitch_sd_rad: f64,
    /// σ of heading, rad.
    pub heading_sd_rad: f64,
    /// Bit set of [`ANGLE_ROLL`], [`ANGLE_PITCH`], [`ANGLE_HEADING`].
    pub valid: u32,
    /// Reserved, 0.
    pub reserved: u32,
}

/// The gyro-bias estimate, daemon → clients (`corridor/v6/bias`): at each heading observation,
/// at the configured rate and at end of stream.
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[type_name("corridor_v6_BiasSample")]
#[repr(C)]
pub struct BiasSample {
    /// Sequence number of the daemon's bias stream.
    pub seq: u64,
    /// Sensor time of the last IMU sample used, s.
    pub t_s: f64,
    /// `seq` of the last IMU sample used.
    pub imu_seq: u64,
    /// Gyro bias, rad/s, sensor axes.
    pub gyro_bias_rad_s: [f64; 3],
    /// Its σ, rad/s (NaN before alignment).
    pub gyro_bias_sd_rad_s: [f64; 3],
    /// The largest fraction, on one axis, of a bias error present when the bias was set (the
    /// rest-mean prior or a saved state; the same size on every axis) that the estimate still
    /// carries: 1 at the start, towards 0 as the walk observes the bias; the flag rises below
    /// `estimator.converged_unabsorbed`. NaN before alignment (and in [`Default`]).
    pub bias_unabsorbed: f64,
    /// 1 when the bias has converged (as [`FLAG_CONVERGED`]), else 0.
    pub converged: u32,
    /// Bit set of `FLAG_*` ([`FLAG_END_OF_STREAM`], [`FLAG_CONVERGED`]).
    pub flags: u32,
}

impl Default for BiasSample {
    /// Nothing known yet: zero bias, NaN σ and NaN unabsorbed part (as before alignment).
    fn default() -> Self {
        Self {
            seq: 0,
            t_s: 0.0,
            imu_seq: 0,
            gyro_bias_rad_s: [0.0; 3],
            gyro_bias_sd_rad_s: [f64::NAN; 3],
            bias_unabsorbed: f64::NAN,
            converged: 0,
            flags: 0,
        }
    }
}

/// The attitude after one IMU sample, daemon → clients (`corridor/v6/attitude`): one per
/// accepted IMU sample, plus one end-of-stream marker.
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("corridor_v6_AttitudeSample")]
#[repr(C)]
pub struct AttitudeSample {
    /// Sequence number of the daemon's attitude stream.
    pub seq: u64,
    /// Sensor time, s.
    pub t_s: f64,
    /// `seq` of the IMU sample this attitude follows.
    pub imu_seq: u64,
    /// Attitude `nav_from_body` as (w, x, y, z).
    pub nav_from_body_wxyz: [f64; 4],
    /// ZYX roll, rad.
    pub roll_rad: f64,
    /// ZYX pitch, rad.
    pub pitch_rad: f64,
    /// ZYX yaw, rad, map frame.
    pub yaw_rad: f64,
    /// Gyro bias used, rad/s, sensor axes.
    pub gyro_bias_rad_s: [f64; 3],
    /// Its σ, rad/s.
    pub gyro_bias_sd_rad_s: [f64; 3],
    /// Estimator phase ([`phase`]).
    pub phase: u32,
    /// Bit set of `FLAG_*` ([`FLAG_BIAS_CORRECTED`], [`FLAG_STANCE`], [`FLAG_CONVERGED`],
    /// [`FLAG_END_OF_STREAM`]).
    pub flags: u32,
    /// [`ImuSample::sent_ns`] of the IMU sample this attitude follows (0 when unknown): a
    /// consumer on the same host gets the end-to-end latency as `monotonic_ns() - imu_sent_ns`.
    pub imu_sent_ns: u64,
}

/// Position and velocity at a footfall, daemon → clients (`corridor/v6/nav`): one per stance
/// (first sample of the stance), after alignment. A sample whose stamp turns out to be a glitch
/// is dropped after its nav sample went out; its stance's real first sample then sends one
/// again, with the same `stance` and a later `imu_seq` (`corridor_client`'s tracker takes it
/// for the stride it replaces). The stance during which the start heading sets the map frame
/// (the first stride's) is sent again too, in that frame, flagged [`FLAG_FRAME_SET`].
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("corridor_v6_NavSample")]
#[repr(C)]
pub struct NavSample {
    /// Sequence number of the daemon's nav stream.
    pub seq: u64,
    /// Sensor time, s.
    pub t_s: f64,
    /// `seq` of the IMU sample.
    pub imu_seq: u64,
    /// Stance count since alignment (1 for the first footfall). A start in fast gait that went
    /// back to an earlier stance (`alignment.fast_gait_replay_s`) counts the stances it ran
    /// over, whose nav samples were never published (they came while it aligned): the first
    /// nav sample of such a stream has a larger number, and its position holds those strides.
    pub stance: u64,
    /// Position, m, map frame.
    pub p_m: [f64; 3],
    /// Velocity, m/s, map frame.
    pub v_m_s: [f64; 3],
    /// Yaw, rad, map frame.
    pub yaw_rad: f64,
    /// Bit set of `FLAG_*`.
    pub flags: u32,
    /// Reserved, 0.
    pub reserved: u32,
}

/// Counters of the daemon, daemon → clients (`corridor/v6/diagnostics`): periodically (wall
/// clock), at end of stream and at shutdown. The input counters (`received`, `seq_gaps`,
/// `rejected_duplicate_seq`, `late`, `dropped_overflow`, `producer_changes`) and `undelivered`
/// are cumulative over every life of the domain's daemon (they live in its accounting file, so a
/// restarted daemon continues them), as are `head_missing`, `missing_at_restart`,
/// `lost_in_daemon`, `angles_dropped`, `foreign_samples` and `angles_ignored`; the estimator's
/// counts (`accepted`, `rejected_non_finite`, `rejected_time`, `stances`, `heading_used`, the
/// `headings_*`) over the current life.
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("corridor_v6_Diagnostics")]
#[repr(C)]
pub struct Diagnostics {
    /// Sequence number of the daemon's diagnostics stream.
    pub seq: u64,
    /// Sensor time of the last accepted IMU sample, s (NaN before the first).
    pub t_s: f64,
    /// IMU messages received over IPC (end-of-stream markers included).
    pub received: u64,
    /// IMU samples missing according to `seq` (sum of the gap lengths).
    pub seq_gaps: u64,
    /// Samples refused because `seq` repeated the previous one.
    pub rejected_duplicate_seq: u64,
    /// Samples refused because `seq` was older than the previous one (arrived late).
    pub late: u64,
    /// Samples refused by the estimator: a value was NaN or infinite.
    pub rejected_non_finite: u64,
    /// Samples refused by the estimator: time did not increase.
    pub rejected_time: u64,
    /// Samples refused by the estimator: a magnitude beyond what the sensor can output, or every
    /// value zero (a driver's fill) (v4).
    pub rejected_implausible: u64,
    /// Samples refused by the estimator: a time jump beyond `sensor.max_dt_s` that the next
    /// sample did not confirm, and samples dropped after the fact (a first time the samples
    /// after it contradicted, a stamp glitch) (v4).
    pub rejected_time_jump: u64,
    /// Samples dropped because the receive → estimator channel was full (live policy only).
    pub dropped_overflow: u64,
    /// Samples the estimator accepted.
    pub accepted: u64,
    /// Output messages that reached no subscriber: published while none was subscribed, or
    /// failed to publish (warned in the daemon's log). One discarded for a stalled consumer is
    /// counted in `discarded_for_stalled` instead.
    pub undelivered: u64,
    /// Stances since the start (over all streams).
    pub stances: u64,
    /// Heading observations used.
    pub heading_used: u64,
    /// Normalised innovation squared of the last heading update (NaN before the first).
    pub last_nis: f64,
    /// Times the IMU producer changed (another publisher port than the previous sample's: a
    /// restarted or replaced producer). Its `seq` numbering starts afresh; when its clock also
    /// restarted, the daemon starts a new stream as if it had received an end of stream.
    pub producer_changes: u64,
    /// Median latency from the producer's send ([`ImuSample::sent_ns`]) to the publication of
    /// the matching [`AttitudeSample`], s, over the last diagnostics period (NaN when unknown).
    pub latency_p50_s: f64,
    /// 99th percentile of the same latency, s (NaN when unknown).
    pub latency_p99_s: f64,
    /// IMU samples a producer sent before the daemon's first message from it (its first `seq`).
    pub head_missing: u64,
    /// IMU samples of the current producer's numbering between the last one an earlier daemon
    /// life received and the first one the next life received: sent while no daemon was
    /// there, or left unread in the input buffer of a daemon that stopped or was killed.
    pub missing_at_restart: u64,
    /// Samples a killed earlier daemon life had received but not yet estimated (counted by the
    /// next life).
    pub lost_in_daemon: u64,
    /// Angle observations dropped (channel full).
    pub angles_dropped: u64,
    /// Daemon lives that used the domain's accounting file, this one included (the counters
    /// above and `received` … `dropped_overflow` continue across them).
    pub lives: u64,
    /// IMU messages refused because they came from another producer than the one the daemon
    /// follows, while that one was live (one producer at a time; `daemon.producer_takeover_s`)
    /// (v5; cumulative, as `received`).
    pub foreign_samples: u64,
    /// Angle observations carrying roll or pitch, which are not fused (their heading, if any, is
    /// used) (v5; cumulative, as `received`).
    pub angles_ignored: u64,
    /// External headings refused on arrival: time or heading not finite, σ not in (0, π], or
    /// a time more than an hour ahead of the latest sample or at least 2 s behind it (v5;
    /// this life, every stream).
    pub headings_refused: u64,
    /// External headings replaced by a newer one before the stance that would have used them
    /// (v5; this life).
    pub headings_superseded: u64,
    /// External headings refused at their stance: too far from the filter's prediction (NIS
    /// beyond 16) (v5; this life).
    pub headings_outside_gate: u64,
    /// External headings not used because their time had passed: no stance within 2 s after
    /// their `t_s`, or still waiting for a stance when their stream ended or the daemon stopped
    /// (v5; this life).
    pub headings_expired: u64,
    /// External headings fused in an update the estimator's health check then undid (v5; this
    /// life).
    pub headings_undone: u64,
    /// Samples with an axis (gyro or accelerometer) at its rail, accepted and flagged as
    /// clipped (v6; this life).
    pub clipped_samples: u64,
    /// Gyro peaks a rail cut off, put back (`eskf.restore_clipped_peaks`) (v6; this life).
    pub clipped_peaks_restored: u64,
    /// Gyro peaks a rail cut off that could not be put back (a stance, gap or fault before
    /// their end, too long, no fit, a failed replay, open when the stream ended) (v6; this
    /// life).
    pub clipped_peaks_not_restored: u64,
    /// Times a consumer held one of the daemon's four publishers (attitude, bias, nav,
    /// diagnostics) for longer than `daemon.stall_timeout_s`; a consumer that caught up and
    /// stalled again counts again (v6; this life).
    pub stalled_consumers: u64,
    /// Samples of the four outputs discarded for stalled consumers (the other consumers got
    /// them) (v6; this life).
    pub discarded_for_stalled: u64,
    /// Estimator phase ([`phase`]).
    pub phase: u32,
    /// Bit set of `FLAG_*` ([`FLAG_END_OF_STREAM`], [`FLAG_SHUTDOWN`]).
    pub flags: u32,
}

/// The host's monotonic clock (`CLOCK_MONOTONIC` on Linux), ns: comparable between processes of
/// one machine, never jumps. Used for [`ImuSample::sent_ns`] and latency measurements.
#[cfg(all(target_os = "linux", target_pointer_width = "64"))]
pub fn monotonic_ns() -> u64 {
    #[repr(C)]
    struct Timespec {
        tv_sec: i64,
        tv_nsec: i64,
    }
    unsafe extern "C" {
        fn clock_gettime(clock_id: i32, tp: *mut Timespec) -> i32;
    }
    const CLOCK_MONOTONIC: i32 = 1;
    let mut ts = Timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable `struct timespec` (two 64-bit fields on 64-bit Linux)
    // and CLOCK_MONOTONIC always exists there.
    let rc = unsafe { clock_gettime(CLOCK_MONOTONIC, &mut ts) };
    debug_assert_eq!(rc, 0);
    (ts.tv_sec as u64) * 1_000_000_000 + ts.tv_nsec as u64
}

/// Fallback of the host's monotonic clock: wall-clock time since the Unix epoch, ns (may jump;
/// only used where `CLOCK_MONOTONIC` is not wired up).
#[cfg(not(all(target_os = "linux", target_pointer_width = "64")))]
pub fn monotonic_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_fixed_and_padding_free() {
        assert_eq!(size_of::<ImuSample>(), 8 + 8 + 24 + 24 + 8 + 8 + 8);
        assert_eq!(size_of::<AngleObservation>(), 8 * 8 + 8);
        assert_eq!(size_of::<BiasSample>(), 8 * 3 + 48 + 8 + 8);
        assert_eq!(size_of::<AttitudeSample>(), 8 * 3 + 32 + 24 + 48 + 8 + 8);
        assert_eq!(size_of::<NavSample>(), 8 * 4 + 48 + 8 + 8);
        assert_eq!(size_of::<Diagnostics>(), 8 * 36 + 8);
    }

    #[test]
    fn end_of_stream_flag() {
        let s = ImuSample {
            flags: FLAG_END_OF_STREAM,
            ..ImuSample::default()
        };
        assert!(s.is_end_of_stream());
        assert!(!ImuSample::default().is_end_of_stream());
    }

    #[test]
    fn monotonic_clock_advances() {
        let a = monotonic_ns();
        std::thread::sleep(std::time::Duration::from_millis(2));
        let b = monotonic_ns();
        assert!(a > 0 && b >= a + 1_000_000, "{a} {b}");
    }
}
