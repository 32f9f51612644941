//! The CSV rows of the daemon's attitude and bias streams, shared by `corridor-log` and the
//! `corridor demo` logger. The attitude columns are those of `corridor run`'s `estimates.csv`
//! that apply (no position or velocity: those are in the nav stream), preceded by
//! `seq,imu_seq`. Both have `retracts`: 1 on a row whose sample showed earlier ones to come
//! from glitched stamps ([`FLAG_RETRACTS`]): the rows before it with a later `t_s` are to be
//! dropped (the files are written as the rows come, as `NAME.partial` until the logger stops).
//! `bias.csv` ends each stream with the daemon's end-of-stream bias (`end_of_stream` 1: the
//! stream's final estimate, which it left out before session 40), so a log of several streams
//! shows where each ended.

use corridor_shared::wire::{
    AttitudeSample, BiasSample, FLAG_CONVERGED, FLAG_END_OF_STREAM, FLAG_RETRACTS, FLAG_STANCE,
    phase,
};
use std::io::Write;

/// Header of `attitude.csv`.
pub const ATTITUDE_HEADER: &str = "seq,imu_seq,t_s,roll_rad,pitch_rad,yaw_rad,qw,qx,qy,qz,bias_x_rad_s,bias_y_rad_s,bias_z_rad_s,bias_sd_x_rad_s,bias_sd_y_rad_s,bias_sd_z_rad_s,stance,converged,phase,retracts";

/// Header of `bias.csv`.
pub const BIAS_HEADER: &str = "seq,imu_seq,t_s,bias_x_rad_s,bias_y_rad_s,bias_z_rad_s,bias_sd_x_rad_s,bias_sd_y_rad_s,bias_sd_z_rad_s,bias_unabsorbed,converged,retracts,end_of_stream";

/// Writes one `attitude.csv` row.
pub fn write_attitude_row(w: &mut impl Write, x: &AttitudeSample) -> std::io::Result<()> {
    let (q, b, s) = (
        x.nav_from_body_wxyz,
        x.gyro_bias_rad_s,
        x.gyro_bias_sd_rad_s,
    );
    writeln!(
        w,
        "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
        x.seq,
        x.imu_seq,
        x.t_s,
        x.roll_rad,
        x.pitch_rad,
        x.yaw_rad,
        q[0],
        q[1],
        q[2],
        q[3],
        b[0],
        b[1],
        b[2],
        s[0],
        s[1],
        s[2],
        u8::from(x.flags & FLAG_STANCE != 0),
        u8::from(x.flags & FLAG_CONVERGED != 0),
        phase::name(x.phase),
        u8::from(x.flags & FLAG_RETRACTS != 0)
    )
}

/// Writes one `bias.csv` row.
pub fn write_bias_row(w: &mut impl Write, b: &BiasSample) -> std::io::Result<()> {
    let (v, s) = (b.gyro_bias_rad_s, b.gyro_bias_sd_rad_s);
    writeln!(
        w,
        "{},{},{},{},{},{},{},{},{},{},{},{},{}",
        b.seq,
        b.imu_seq,
        b.t_s,
        v[0],
        v[1],
        v[2],
        s[0],
        s[1],
        s[2],
        b.bias_unabsorbed,
        b.converged,
        u8::from(b.flags & FLAG_RETRACTS != 0),
        u8::from(b.flags & FLAG_END_OF_STREAM != 0)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_have_as_many_fields_as_their_headers() {
        let mut a = Vec::new();
        write_attitude_row(&mut a, &AttitudeSample::default()).unwrap();
        let a = String::from_utf8(a).unwrap();
        assert_eq!(
            a.trim_end().split(',').count(),
            ATTITUDE_HEADER.split(',').count()
        );
        assert!(a.trim_end().ends_with(",0,0,aligning,0"), "{a}");
        let mut b = Vec::new();
        write_bias_row(&mut b, &BiasSample::default()).unwrap();
        let b = String::from_utf8(b).unwrap();
        assert_eq!(
            b.trim_end().split(',').count(),
            BIAS_HEADER.split(',').count()
        );
    }

    #[test]
    fn attitude_row_carries_the_flags_and_the_phase_name() {
        let row = |flags: u32, phase_code: u32| {
            let mut w = Vec::new();
            let x = AttitudeSample {
                flags,
                phase: phase_code,
                ..AttitudeSample::default()
            };
            write_attitude_row(&mut w, &x).unwrap();
            String::from_utf8(w).unwrap().trim_end().to_owned()
        };
        assert!(row(FLAG_STANCE, phase::CALIBRATING).ends_with(",1,0,calibrating,0"));
        assert!(row(FLAG_CONVERGED, phase::TRACKING).ends_with(",0,1,tracking,0"));
        assert!(row(FLAG_STANCE | FLAG_CONVERGED, 7).ends_with(",1,1,unknown,0"));
        assert!(row(FLAG_RETRACTS, phase::TRACKING).ends_with(",0,0,tracking,1"));
    }
}
