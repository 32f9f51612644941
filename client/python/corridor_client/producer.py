"""`Producer`: feeds IMU samples to the daemon (the Python twin of the Rust `Producer`)."""

import csv
import math
import time
import warnings
from typing import Any, Iterable, Optional, Sequence

import iceoryx2 as iox2

from .services import EVENT_WAIT_SLICE_S, CorridorError, Domain
from .wire import FLAG_END_OF_STREAM, AngleObservation, ImuSample

#: How long a lossless send retries a sample that reached no subscriber although one is
#: connected (its receive side not attached yet), s.
LOSSLESS_RETRY_S = 2.0

#: Event service on which the daemon acknowledges a producer when it has taken its first
#: sample, with the producer's event id (the Rust `IMU_ACK_SERVICE` and `ack_event_id`).
IMU_ACK_SERVICE = "corridor/v6/imu_ack"

#: How long `close` waits for that acknowledgement, s (the Rust `END_ACK_WAIT`).
END_ACK_WAIT_S = 5.0


def ack_event_id(publisher_id: int) -> int:
    """The acknowledgement event id of an IMU publisher (`UniquePublisherId.value`)."""
    return publisher_id % 256


class Producer:
    """Publishes `ImuSample`s (and `AngleObservation`s) to the daemon of a domain.

    The daemon must be running: the producer opens its input services and takes their
    delivery policy (`live` or `lossless`); `delivery`, when given, is an assertion.
    `seq` is numbered 0, 1, 2, ... and `sent_ns` stamped with the monotonic clock.
    """

    def __init__(
        self,
        domain: Domain,
        node_name: str = "corridor-py-producer",
        delivery: Optional[str] = None,
        timeout_s: float = 10.0,
    ) -> None:
        self.domain = domain
        self.node = domain.node(node_name)
        self._imu_service = domain.open_existing(self.node, ImuSample, timeout_s)
        live = self._imu_service.static_config.has_safe_overflow
        self.delivery = "live" if live else "lossless"
        if delivery is not None and delivery != self.delivery:
            raise CorridorError(
                f"service {ImuSample.SERVICE!r} in domain {domain.name!r} uses "
                f"{self.delivery} delivery, but {delivery} was asked for "
                "(leave delivery out to take the daemon's policy)"
            )
        strategy = (
            iox2.BackpressureStrategy.DiscardData
            if live
            else iox2.BackpressureStrategy.RetryUntilDelivered
        )
        self._imu = (
            self._imu_service.publisher_builder()
            .backpressure_strategy(strategy)
            .max_loaned_samples(2)
            .create()
        )
        self._imu_notifier = domain.event(self.node, ImuSample.SERVICE).notifier_builder().create()
        self._angles_service = domain.open_existing(self.node, AngleObservation, timeout_s)
        self._angles = (
            self._angles_service.publisher_builder()
            .backpressure_strategy(strategy)
            .max_loaned_samples(2)
            .create()
        )
        self._angles_notifier = (
            domain.event(self.node, AngleObservation.SERVICE).notifier_builder().create()
        )
        self._ack = domain.event(self.node, IMU_ACK_SERVICE).listener_builder().create()
        self._ack_id = ack_event_id(self._imu.id.value)
        self._taken = False
        self.next_seq = 0
        self.next_angles_seq = 0
        self.sent = 0
        self.undelivered = 0
        self.closes_unconfirmed = 0
        # The end-of-stream marker was sent (`finish`); the ports were released (`close`).
        self.finished = False
        self.closed = False

    def wait_for_daemon(self, timeout_s: float = 10.0) -> None:
        """Waits until the daemon reads the IMU service."""
        deadline = time.monotonic() + timeout_s
        while self._imu_service.dynamic_config.number_of_subscribers == 0:
            if time.monotonic() >= deadline:
                raise CorridorError(
                    f"service {ImuSample.SERVICE!r} in domain {self.domain.name!r}: "
                    f"no subscriber after {timeout_s} s"
                )
            time.sleep(0.005)
        self._imu.update_connections()

    def send(
        self,
        t_s: float,
        gyro_rad_s: Sequence[float],
        accel_m_s2: Sequence[float],
        temp_c: float = math.nan,
    ) -> int:
        """Sends one sample (sensor time in s, rad/s, m/s², °C); returns the receivers."""
        s = ImuSample()
        s.t_s = t_s
        s.gyro_rad_s[:] = list(gyro_rad_s)
        s.accel_m_s2[:] = list(accel_m_s2)
        s.temp_c = temp_c
        return self.send_sample(s)

    def send_sample(self, s: ImuSample) -> int:
        """Sends `s` with the next `seq` (and `sent_ns` when 0)."""
        s.seq = self.next_seq
        self.next_seq += 1
        if s.sent_ns == 0:
            s.sent_ns = time.monotonic_ns()
        n = int(self._imu.send_copy(s))
        if n == 0 and self.delivery == "lossless":
            deadline = time.monotonic() + LOSSLESS_RETRY_S
            while (
                n == 0
                and self._imu_service.dynamic_config.number_of_subscribers > 0
                and time.monotonic() < deadline
            ):
                time.sleep(0.0002)
                n = int(self._imu.send_copy(s))
        self.sent += 1
        if n == 0:
            self.undelivered += 1
        self._imu_notifier.notify()
        return n

    def send_angles(self, obs: AngleObservation) -> int:
        """Sends an external attitude observation with the next `seq`.

        Its `t_s` is on the IMU samples' clock: the daemon uses its heading at the stance that
        time falls in or the next one, within 2 s (older: counted as expired; one already 2 s
        behind the latest sample when it arrives, such as t_s left at 0, is refused and counted
        as headings_refused)."""
        obs.seq = self.next_angles_seq
        self.next_angles_seq += 1
        n = int(self._angles.send_copy(obs))
        self._angles_notifier.notify()
        return n

    def finish(self) -> int:
        """Sends the end-of-stream marker: the daemon answers and resets for the next stream."""
        s = ImuSample()
        s.t_s = math.nan
        s.temp_c = math.nan
        s.flags = FLAG_END_OF_STREAM
        # (Set first: an interrupt during the send must not send a second marker, which the
        # daemon would take for an empty stream.)
        self.finished = True
        return self.send_sample(s)

    def _mine(self, activations: Any) -> bool:
        return any(a.id.as_value == self._ack_id for a in activations)

    def close(self) -> None:
        """Releases the ports and the node, once the daemon has taken this producer's samples.

        iceoryx2 0.10 attaches the daemon's side of a connection only when the daemon next
        receives; a publisher closed before that takes its queued samples with it. So when a
        sample reached a subscriber and the daemon has not yet acknowledged this producer (it
        does at the first sample it takes), this waits up to `END_ACK_WAIT_S` for that (none in
        time: `closes_unconfirmed`).
        """
        if self.closed:
            return
        self.closed = True
        try:
            if self.sent > self.undelivered:
                deadline = time.monotonic() + END_ACK_WAIT_S
                while not self._taken:
                    left = deadline - time.monotonic()
                    if left <= 0:
                        self.closes_unconfirmed += 1
                        break
                    try:
                        self._taken = self._mine(
                            self._ack.timed_wait(
                                iox2.Duration.from_secs_f64(min(left, EVENT_WAIT_SLICE_S))
                            )
                        )
                    except iox2.ListenerWaitError:
                        pass  # a signal cut the wait short (SIGCONT after Ctrl-Z): wait on
            self._taken = True
        finally:
            for port in (
                self._imu,
                self._imu_notifier,
                self._angles,
                self._angles_notifier,
                self._ack,
            ):
                port.delete()
            self._imu_service = self._angles_service = None
            self.node = None

    def __enter__(self) -> "Producer":
        return self

    def __exit__(self, exc_type: Any, *exc: Any) -> None:
        # A driver stopped by Ctrl-C (KeyboardInterrupt), by SIGTERM turned into SystemExit
        # (see examples/driver_producer.py) or by any error (a log `read_imu_csv` refuses) ends
        # its stream, as `corridor-replay` does: without the marker the daemon's stream stayed
        # open, "running / phase: tracking" for ever (two reviews).
        # Not when no daemon reads (a lossless send would wait for one), and a failure to send
        # it is said but does not replace the exception.
        try:
            if (
                exc_type is not None
                and not self.finished
                and not self.closed
                and self._imu_service.dynamic_config.number_of_subscribers > 0
            ):
                try:
                    self.finish()
                except Exception as e:  # noqa: BLE001 - said, and the interrupt goes on
                    warnings.warn(f"corridor producer: the end-of-stream marker was not sent: {e}")
        finally:
            self.close()


def read_imu_csv(path: str) -> Iterable[ImuSample]:
    """The rows of an IMU log (`t_s,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2[,temp_c]`)
    as samples; columns are found by name. A header without a column, or a row whose field is
    no number, raises `ValueError` naming the file, the line, the column and the value (it raised
    a bare `KeyError: 't_s'` or "could not convert string to float: 'x'", a review; the Rust
    reader, which `corridor-replay` uses, skips such rows and counts them). A UTF-8 BOM is read
    as the Rust reader reads it, and a `temp_c` field that is no number is an unknown
    temperature (NaN)."""
    with open(path, newline="", encoding="utf-8-sig") as f:
        rows = csv.reader(f)
        header = [h.strip().strip('"') for h in next(rows)]
        col = {name: i for i, name in enumerate(header)}
        names = ["t_s", "gx_rad_s", "gy_rad_s", "gz_rad_s", "ax_m_s2", "ay_m_s2", "az_m_s2"]
        missing = [n for n in names if n not in col]
        if missing:
            raise ValueError(f"{path}:1: the header has no column {', '.join(missing)}: {header}")
        temp = col.get("temp_c")

        def number(row: list, name: str, line: int) -> float:
            field = row[col[name]] if col[name] < len(row) else ""
            try:
                return float(field)
            except ValueError:
                raise ValueError(f"{path}:{line}: column {name}: {field!r} is no number") from None

        for line, row in enumerate(rows, start=2):
            if not row:
                continue
            s = ImuSample()
            s.t_s = number(row, "t_s", line)
            s.gyro_rad_s[:] = [number(row, n, line) for n in names[1:4]]
            s.accel_m_s2[:] = [number(row, n, line) for n in names[4:7]]
            s.temp_c = math.nan
            if temp is not None and temp < len(row):
                try:
                    s.temp_c = float(row[temp])
                except ValueError:
                    pass
            yield s


def replay_csv(producer: Producer, path: str, speed: float = math.inf) -> int:
    """Sends a CSV log (`speed` × real time; `math.inf`: as fast as the daemon takes it), then
    the end-of-stream marker; returns the samples sent."""
    start = time.monotonic()
    first_t: Optional[float] = None
    n = 0
    for s in read_imu_csv(path):
        if first_t is None:
            first_t = s.t_s
        if math.isfinite(speed):
            wait = start + (s.t_s - first_t) / speed - time.monotonic()
            if wait > 0:
                time.sleep(wait)
        producer.send_sample(s)
        n += 1
    producer.finish()
    return n
