//! The CSV outputs of a run: `estimates.csv` and `innovations.csv` rows, and file creation.

use super::*;

/// CSV header of `estimates.csv`.
pub const ESTIMATES_HEADER: &str = "t_s,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,roll_rad,pitch_rad,yaw_rad,qw,qx,qy,qz,bias_x_rad_s,bias_y_rad_s,bias_z_rad_s,bias_sd_x_rad_s,bias_sd_y_rad_s,bias_sd_z_rad_s,bias_unabsorbed,stance,stance_began,converged,phase";

/// CSV header of `innovations.csv`.
pub const INNOVATIONS_HEADER: &str = "t_s,kind,accepted,reason,r0,r1,r2,s0,s1,s2,nis,foot_heading_deg,direction_deg,baseline_s,gyro_norm_rad_s,accel_norm_m_s2,gz_rad_s,observed_t_s";

/// Writes one `estimates.csv` row.
pub fn write_estimate_row(w: &mut impl Write, e: &Estimate) -> std::io::Result<()> {
    let b = e.gyro_bias_rad_s;
    let s = e.gyro_bias_sd_rad_s;
    let q = e.nav_from_body;
    writeln!(
        w,
        "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
        e.t_s,
        e.p_m[0],
        e.p_m[1],
        e.p_m[2],
        e.v_m_s[0],
        e.v_m_s[1],
        e.v_m_s[2],
        e.roll_rad,
        e.pitch_rad,
        e.yaw_rad,
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
        e.bias_unabsorbed,
        u8::from(e.stance),
        u8::from(e.stance_began),
        u8::from(e.converged),
        e.phase.name()
    )
}

/// Writes the `innovations.csv` rows of one estimate (ZUPT, stride-direction and heading
/// events; for a stride row `foot_heading_deg` is the stride's direction).
pub fn write_innovation_rows(
    w: &mut impl Write,
    input: &ImuInput,
    e: &Estimate,
) -> std::io::Result<()> {
    let g = input.gyro_rad_s;
    let a = input.accel_m_s2;
    let gn = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    let an = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    if let Some(z) = &e.zupt {
        writeln!(
            w,
            "{},zupt,1,,{},{},{},{},{},{},{},,,,{gn},{an},{},{}",
            e.t_s,
            z.r[0],
            z.r[1],
            z.r[2],
            z.s_diag[0],
            z.s_diag[1],
            z.s_diag[2],
            z.nis,
            g[2],
            e.t_s
        )?;
    }
    for (kind, h) in [("stride", &e.stride), ("heading", &e.heading)] {
        let Some(h) = h else { continue };
        let fh = h.foot_heading_rad.to_degrees();
        let dir = h.direction_rad.to_degrees();
        match &h.outcome {
            Ok(i) => writeln!(
                w,
                "{},{kind},1,,{},{},{},{},{},{},{},{fh},{dir},{},{gn},{an},{},{}",
                e.t_s,
                i.r[0],
                i.r[1],
                i.r[2],
                i.s_diag[0],
                i.s_diag[1],
                i.s_diag[2],
                i.nis,
                h.baseline_s,
                g[2],
                h.observed_t_s
            )?,
            Err(r) => writeln!(
                w,
                "{},{kind},0,{},,,,,,,,{fh},,,{gn},{an},{},{}",
                e.t_s,
                r.name(),
                g[2],
                h.observed_t_s
            )?,
        }
    }
    Ok(())
}

/// Creates a buffered file for writing, naming the path on error.
pub fn create(path: &Path) -> Result<std::io::BufWriter<std::fs::File>, RunError> {
    std::fs::File::create(path)
        .map(|f| std::io::BufWriter::with_capacity(1 << 16, f))
        .map_err(|source| RunError::Io {
            path: path.to_owned(),
            source,
        })
}

/// Maps an IO error to one that names `path`.
pub fn io_at(path: &Path) -> impl Fn(std::io::Error) -> RunError + '_ {
    move |source| RunError::Io {
        path: path.to_owned(),
        source,
    }
}
