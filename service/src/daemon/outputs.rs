//! The output publishers (attitude, bias, nav, diagnostics) and the conversion of an
//! [`Estimate`] into the wire messages.

use super::stall::{StallCounts, StallGuard};
use super::state::StateFile;
use super::{DaemonConfig, DaemonError};
use crate::core::{Estimate, Phase};
use corridor_shared::services::{Access, ServiceError, Topic};
use corridor_shared::wire::{
    AttitudeSample, BiasSample, Diagnostics, FLAG_BIAS_CORRECTED, FLAG_CONVERGED, FLAG_FRAME_SET,
    FLAG_RETRACTS, FLAG_STANCE, NavSample, phase,
};
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::prelude::*;
use std::sync::Arc;
use std::sync::atomic::Ordering;

/// A publisher with its paired notifier.
pub(super) struct Out<T: Topic> {
    pub(super) publisher: Publisher<ipc::Service, T, ()>,
    pub(super) notifier: Notifier<ipc::Service>,
    pub(super) seq: u64,
    /// The accounting file and this output's slot in [`super::state::Record::out_seq`]: `seq`
    /// continues across daemon lives.
    state: Arc<StateFile>,
    slot: usize,
    pub(super) failed_once: bool,
    /// Consumers that stalled this publisher (lossless delivery).
    pub(super) stall: StallGuard,
    /// The guard's discarded count after the last send or refresh (the guard discards only
    /// within them, so it is the count before the next send).
    discarded_seen: u64,
}

impl<T: Topic> Out<T> {
    pub(super) fn new(
        cfg: &DaemonConfig,
        node: &Node<ipc::Service>,
        state: &Arc<StateFile>,
        slot: usize,
    ) -> Result<Self, DaemonError> {
        let d = &cfg.domain;
        let stall = StallGuard::new(cfg.stall_timeout);
        let publisher = d
            .open::<T>(node, Access::Owner(cfg.delivery))?
            .publisher_builder()
            .backpressure_strategy(cfg.delivery.backpressure())
            .set_backpressure_handler(stall.handler())
            .max_loaned_samples(2)
            .create()
            .map_err(|e| ServiceError::port(d, T::SERVICE, "publisher", e))?;
        let notifier = d
            .open_event(node, T::SERVICE, true)?
            .notifier_builder()
            .create()
            .map_err(|e| ServiceError::port(d, T::SERVICE, "notifier", e))?;
        Ok(Self {
            publisher,
            notifier,
            seq: state.out_seq[slot].load(Ordering::Relaxed),
            state: Arc::clone(state),
            slot,
            failed_once: false,
            stall,
            discarded_seen: 0,
        })
    }

    /// Connects subscribers that joined since the last send and hands them the history (the
    /// latest value), so a late reader of an idle daemon (`corridor status`) gets it too.
    pub(super) fn refresh(&mut self) {
        use iceoryx2::port::update_connections::UpdateConnections;
        let _ = self.publisher.update_connections();
        // (A history handed to a full buffer is discarded here, not in a send.)
        self.discarded_seen = self.stall.counts().discarded;
    }

    /// Publishes `value` with the next `seq`; returns false when nobody received it and no
    /// stalled consumer's discard accounts for it (the caller counts it undelivered).
    pub(super) fn publish(&mut self, set_seq: impl FnOnce(&mut T, u64), mut value: T) -> bool {
        set_seq(&mut value, self.seq);
        self.seq += 1;
        self.state.out_seq[self.slot].store(self.seq, Ordering::Relaxed);
        let delivered = match self.publisher.loan_uninit() {
            Ok(slot) => slot.write_payload(value).send(),
            Err(e) => Err(e.into()),
        };
        let _ = self.notifier.notify();
        let (new_stalls, discarded) = self.stall.take_new_stalls();
        let discarded_in_send = discarded > self.discarded_seen;
        self.discarded_seen = discarded;
        for port in new_stalls {
            tracing::warn!(
                service = T::SERVICE,
                "consumer {port:#x} stalled the publisher for more than the stall bound; it now \
                 loses (counted) the samples its full buffer cannot take"
            );
        }
        match delivered {
            // The stall guard discarded it for a stalled consumer, and iceoryx2 0.10 then counts
            // no receiver when that one was the only one: counted as discarded for it (the
            // stall counts), not as undelivered as well (a review: 9,905 of exp36's attitude
            // samples were in both, and `corridor status` shows undelivered outputs as
            // published while none was subscribed).
            Ok(0) => discarded_in_send,
            Ok(n) => n > 0,
            Err(e) => {
                if !self.failed_once {
                    self.failed_once = true;
                    tracing::warn!(
                        service = T::SERVICE,
                        "publishing failed: {e:?} (reported once)"
                    );
                }
                false
            }
        }
    }
}

pub(super) struct Outputs {
    pub(super) attitude: Out<AttitudeSample>,
    pub(super) bias: Out<BiasSample>,
    pub(super) nav: Out<NavSample>,
    pub(super) diagnostics: Out<Diagnostics>,
}

impl Outputs {
    /// The stalled consumers of each publisher and the samples they lost: attitude, bias, nav,
    /// diagnostics.
    pub(super) fn stall_counts(&self) -> [StallCounts; 4] {
        [
            self.attitude.stall.counts(),
            self.bias.stall.counts(),
            self.nav.stall.counts(),
            self.diagnostics.stall.counts(),
        ]
    }
}

pub(super) fn phase_code(p: Phase) -> u32 {
    match p {
        Phase::Aligning => phase::ALIGNING,
        Phase::Calibrating => phase::CALIBRATING,
        Phase::Tracking => phase::TRACKING,
    }
}

pub(super) fn flags_of(e: &Estimate) -> u32 {
    let mut f = 0;
    if e.phase != Phase::Aligning {
        f |= FLAG_BIAS_CORRECTED;
    }
    if e.stance {
        f |= FLAG_STANCE;
    }
    if e.converged {
        f |= FLAG_CONVERGED;
    }
    if e.glitch_t_s.is_some() {
        f |= FLAG_RETRACTS;
    }
    if e.frame_set {
        f |= FLAG_FRAME_SET;
    }
    f
}

pub(super) fn attitude_of(e: &Estimate, imu_seq: u64, imu_sent_ns: u64) -> AttitudeSample {
    AttitudeSample {
        seq: 0,
        t_s: e.t_s,
        imu_seq,
        nav_from_body_wxyz: e.nav_from_body,
        roll_rad: e.roll_rad,
        pitch_rad: e.pitch_rad,
        yaw_rad: e.yaw_rad,
        gyro_bias_rad_s: e.gyro_bias_rad_s,
        gyro_bias_sd_rad_s: e.gyro_bias_sd_rad_s,
        phase: phase_code(e.phase),
        flags: flags_of(e),
        imu_sent_ns,
    }
}

pub(super) fn bias_of(e: &Estimate, imu_seq: u64) -> BiasSample {
    BiasSample {
        seq: 0,
        t_s: e.t_s,
        imu_seq,
        gyro_bias_rad_s: e.gyro_bias_rad_s,
        gyro_bias_sd_rad_s: e.gyro_bias_sd_rad_s,
        bias_unabsorbed: e.bias_unabsorbed,
        converged: u32::from(e.converged),
        flags: flags_of(e) & (FLAG_CONVERGED | FLAG_RETRACTS),
    }
}
