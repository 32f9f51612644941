"""Turn a Python sensor-driver loop into a corridor producer.

    corridor serve --config configs/gdins.toml --domain lab      # in another shell
    python3 client/python/examples/driver_producer.py --domain lab --seconds 10

`read_imu()` stands in for your driver: replace it with the call that returns one sample
(time in s, gyro in rad/s, specific force in m/s², sensor axes). The four marked lines are all
the corridor-specific code.
"""

import argparse
import signal
import sys
import time
from typing import Iterator, Tuple

from corridor_client import Domain, Producer

Sample = Tuple[float, Tuple[float, float, float], Tuple[float, float, float]]


def read_imu(rate_hz: float, seconds: float) -> Iterator[Sample]:
    """A stand-in driver: a sensor at rest (gravity on z, a small gyro bias), paced in real time."""
    start = time.monotonic()
    for k in range(int(rate_hz * seconds)):
        t_s = k / rate_hz
        delay = start + t_s - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        yield t_s, (0.001, -0.002, 0.005), (0.0, 0.0, 9.81)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--domain", default="default")
    ap.add_argument("--rate-hz", type=float, default=200.0)
    ap.add_argument("--seconds", type=float, default=10.0)
    a = ap.parse_args()
    # A service manager stops a driver with SIGTERM: as SystemExit, it leaves the `with` block
    # below the way Ctrl-C (KeyboardInterrupt) does, and the producer ends its stream there.
    # (Python runs the handler between two calls: a lossless send that a daemon which stopped
    # reading holds up defers it; the manager's SIGKILL after its stop timeout ends that.)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(128 + signal.SIGTERM))

    producer = Producer(Domain(a.domain), "py-driver")  # 1: connect (daemon's policy)
    try:
        with producer:
            producer.wait_for_daemon()  # 2: wait until the daemon listens
            for t_s, gyro_rad_s, accel_m_s2 in read_imu(a.rate_hz, a.seconds):
                producer.send(t_s, gyro_rad_s, accel_m_s2)  # 3: one sample
            producer.finish()  # 4: end of stream
    except KeyboardInterrupt:
        ended = "the stream was ended" if producer.finished else "no daemon read the stream"
        print(f"interrupted: {ended}", file=sys.stderr)
        sys.exit(130)
    finally:
        print(f"sent {producer.sent} messages, {producer.undelivered} undelivered")


if __name__ == "__main__":
    main()
