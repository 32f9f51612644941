//! The estimator's copy of itself before a sample whose time came after a gap and is
//! provisional (`corridor_shared::sensor::TimeGuard`): the next sample may show that time to be
//! a glitched stamp, and the estimator then goes back to the copy (`recovery.rs`). The copy
//! lives in one buffer, allocated at the first gap and reused: a gap costs a copy of about
//! 160 KB (the stride memory most of it; while aligning, about 150 KB more: the samples a
//! start in fast gait may go back over, `fast_start.rs`) and no allocation after the first gap
//! and the first after the alignment (the filter's boxes are made then), also on a stream whose
//! every step is a gap (a producer slower than 1 / `estimator.max_dt_s`).

use super::*;

/// The copy before a provisional sample, and whether it is current.
#[derive(Debug, Clone, Default)]
pub(super) struct GapCopy {
    buffer: Option<Box<(Stage, Pipeline)>>,
    /// The buffer holds the estimator before the last accepted sample.
    current: bool,
}

impl GapCopy {
    /// Copies the estimator (before the sample about to be processed) into the buffer.
    /// Allocates the first time, and the first time after the alignment.
    /// Out of line: its copies of the filter stay out of the per-sample step's frame (see
    /// `Pipeline::save_good`).
    #[inline(never)]
    pub(super) fn save(&mut self, stage: &Stage, p: &Pipeline) {
        match &mut self.buffer {
            Some(b) => {
                b.0.copy_from(stage);
                b.1.copy_from(p);
            }
            None => self.buffer = Some(Box::new((stage.clone(), p.clone()))),
        }
        self.current = true;
    }

    /// The last accepted sample came after no gap: the copy is not needed (the buffer stays).
    pub(super) fn forget(&mut self) {
        self.current = false;
    }

    /// Swaps the copy in: `stage` and `p` become the estimator before the last accepted
    /// sample, and the returned pipeline is the one that had taken it (for what is kept from
    /// it). `None` (nothing changed) without a current copy.
    pub(super) fn swap_in(&mut self, stage: &mut Stage, p: &mut Pipeline) -> Option<&mut Pipeline> {
        if !std::mem::take(&mut self.current) {
            return None;
        }
        let b = self.buffer.as_mut()?;
        std::mem::swap(stage, &mut b.0);
        std::mem::swap(p, &mut b.1);
        Some(&mut b.1)
    }
}

impl Stage {
    /// Becomes a copy of `src` in its own box: no allocation while both are in the same stage
    /// (the alignment changes it once).
    fn copy_from(&mut self, src: &Self) {
        match (self, src) {
            (Stage::Aligning(a), Stage::Aligning(b)) => a.copy_from(b),
            (Stage::Running(a), Stage::Running(b)) => a.clone_from(b),
            (this, src) => *this = src.clone(),
        }
    }
}

/// Copies every field of a [`Pipeline`]: the pattern names them all, so a new field does not
/// compile until it is listed, either as copied by `clone_from` (no heap, or a `Box` or
/// `Option` whose `clone_from` reuses it) or by its own `copy_from` (buffers reused).
macro_rules! copy_pipeline {
    ($dst:expr, $src:expr; clone_from: $($c:ident),*; copy_from: $($h:ident),*) => {{
        let src = $src;
        let Pipeline { $($c,)* $($h,)* } = $dst;
        $( $c.clone_from(&src.$c); )*
        $( $h.copy_from(&src.$h); )*
    }};
}

impl Pipeline {
    /// Becomes a copy of `src` in its own buffers: no allocation when it has them.
    fn copy_from(&mut self, src: &Self) {
        copy_pipeline!(self, src;
            clone_from: cfg, aid, phase, counters, plausibility, last, bias, good,
                good_saved_this_stance, before, before_bias, consecutive_faults,
                restores_in_a_row, relevel_next_stance, tilt0,
                mount_yaw_rad, forward_body, mount_sum, last_footprint, footprint_yaw_rad,
                prev_footprint_yaw_rad, footprint_t_s, line_before, heading_suspect,
                off_direction, reacquiring, line, stance_events, stance_edge, stances_seen,
                resumed_look, was_stance, clock, late, undo, zero_rate_applied, clipped_gyro_axes, rails,
                stance_obs_done, stance_f_sum, pending_heading, headings_queued, last_queued,
                stance_force,
                warm_start, converged_at_s, out;
            copy_from: detector, straight, memory, stance_rest);
    }
}
