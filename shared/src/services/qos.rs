//! Delivery policy, quality of service, and the service of each wire type.

use super::*;
use crate::wire::{
    AngleObservation, AttitudeSample, BiasSample, Diagnostics, ImuSample, NavSample,
};
use iceoryx2::prelude::*;
use std::fmt::Debug;
use std::str::FromStr;

/// What happens when a reader falls behind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Delivery {
    /// A full receive buffer drops its oldest sample (iceoryx2 safe overflow); the publisher never
    /// waits. For live sensors: the freshest data wins, losses show up as `seq` gaps.
    #[default]
    Live,
    /// A full receive buffer makes the publisher wait until the reader has taken a sample
    /// (`RetryUntilDelivered`). For replays and recordings: nothing is lost, a slow reader slows
    /// the producer down.
    Lossless,
}

impl Delivery {
    /// `live` or `lossless`.
    pub fn name(self) -> &'static str {
        match self {
            Delivery::Live => "live",
            Delivery::Lossless => "lossless",
        }
    }

    /// The iceoryx2 `enable_safe_overflow` setting of the services.
    pub fn safe_overflow(self) -> bool {
        self == Delivery::Live
    }

    /// The backpressure strategy of the publishers.
    pub fn backpressure(self) -> BackpressureStrategy {
        match self {
            Delivery::Live => BackpressureStrategy::DiscardData,
            Delivery::Lossless => BackpressureStrategy::RetryUntilDelivered,
        }
    }
}

impl FromStr for Delivery {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "live" => Ok(Delivery::Live),
            "lossless" => Ok(Delivery::Lossless),
            _ => Err(format!("delivery {s:?}: expected live or lossless")),
        }
    }
}

/// Quality of service of one publish-subscribe service.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Qos {
    /// Maximum publishers.
    pub max_publishers: usize,
    /// Maximum subscribers.
    pub max_subscribers: usize,
    /// Receive buffer of each subscriber, samples.
    pub buffer_size: usize,
    /// Samples a late subscriber receives on connecting.
    pub history_size: usize,
    /// Samples a subscriber may hold at once.
    pub max_borrowed: usize,
}

/// A wire type bound to its service.
pub trait Topic: Debug + Copy + ZeroCopySend + 'static {
    /// Service name.
    const SERVICE: &'static str;
    /// Quality of service.
    const QOS: Qos;
    /// The message's sequence number (every wire type has one; gaps mean lost messages).
    fn seq(&self) -> u64;
}

impl Topic for ImuSample {
    const SERVICE: &'static str = IMU_SERVICE;
    /// 4096 samples: about 4 s of a 1 kHz IMU.
    const QOS: Qos = Qos {
        max_publishers: 2,
        max_subscribers: 4,
        buffer_size: 4096,
        history_size: 0,
        max_borrowed: 2,
    };
    fn seq(&self) -> u64 {
        self.seq
    }
}

impl Topic for AngleObservation {
    const SERVICE: &'static str = ANGLES_SERVICE;
    const QOS: Qos = Qos {
        max_publishers: 4,
        max_subscribers: 4,
        buffer_size: 64,
        history_size: 0,
        max_borrowed: 2,
    };
    fn seq(&self) -> u64 {
        self.seq
    }
}

impl Topic for AttitudeSample {
    const SERVICE: &'static str = ATTITUDE_SERVICE;
    const QOS: Qos = Qos {
        max_publishers: 1,
        max_subscribers: 8,
        buffer_size: 4096,
        history_size: 0,
        max_borrowed: 2,
    };
    fn seq(&self) -> u64 {
        self.seq
    }
}

impl Topic for BiasSample {
    const SERVICE: &'static str = BIAS_SERVICE;
    /// History 1: a late subscriber gets the latest bias at once.
    const QOS: Qos = Qos {
        max_publishers: 1,
        max_subscribers: 8,
        buffer_size: 256,
        history_size: 1,
        max_borrowed: 2,
    };
    fn seq(&self) -> u64 {
        self.seq
    }
}

impl Topic for NavSample {
    const SERVICE: &'static str = NAV_SERVICE;
    const QOS: Qos = Qos {
        max_publishers: 1,
        max_subscribers: 8,
        buffer_size: 256,
        history_size: 1,
        max_borrowed: 2,
    };
    fn seq(&self) -> u64 {
        self.seq
    }
}

impl Topic for Diagnostics {
    const SERVICE: &'static str = DIAGNOSTICS_SERVICE;
    const QOS: Qos = Qos {
        max_publishers: 1,
        max_subscribers: 8,
        buffer_size: 64,
        history_size: 1,
        max_borrowed: 2,
    };
    fn seq(&self) -> u64 {
        self.seq
    }
}
