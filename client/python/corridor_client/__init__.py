"""corridor_client: talk to the corridor estimator daemon over iceoryx2 shared memory.

- `wire`: ctypes mirrors of the wire types (checked against the Rust layouts by a test).
- `Domain`: the iceoryx2 namespace of one daemon (`corridor serve --domain NAME`).
- `Producer`: publishes IMU samples (and angle observations) with the daemon's delivery policy;
  `replay_csv` sends a CSV log.
- `Consumer`: receives attitude, bias, nav or diagnostics messages.
"""

from . import wire
from .consumer import Consumer
from .producer import Producer, read_imu_csv, replay_csv
from .services import QOS, CorridorError, Domain, Qos
from .wire import (
    AngleObservation,
    AttitudeSample,
    BiasSample,
    Diagnostics,
    ImuSample,
    NavSample,
)

__all__ = [
    "wire",
    "Consumer",
    "Producer",
    "read_imu_csv",
    "replay_csv",
    "QOS",
    "CorridorError",
    "Domain",
    "Qos",
    "AngleObservation",
    "AttitudeSample",
    "BiasSample",
    "Diagnostics",
    "ImuSample",
    "NavSample",
]
