"""`Consumer`: one output stream of the daemon (attitude, bias, nav or diagnostics)."""

import ctypes
import time
from typing import Generic, Optional, Type, TypeVar

import iceoryx2 as iox2

from .services import EVENT_WAIT_SLICE_S, QOS, CorridorError, Domain

T = TypeVar("T", bound=ctypes.Structure)


class Consumer(Generic[T]):
    """Receives the messages of type `t` the daemon publishes (e.g. `AttitudeSample`).

    Waits (without spinning) on the event service of the same name. Counts the messages lost
    according to their `seq` (`missed`): with `live` delivery a reader that falls behind by
    more than the buffer loses the oldest.
    """

    def __init__(
        self,
        domain: Domain,
        t: Type[T],
        node_name: str = "corridor-py-consumer",
        timeout_s: float = 10.0,
    ) -> None:
        self.domain = domain
        self.t = t
        self.node = domain.node(node_name)
        self._service = domain.open_existing(self.node, t, timeout_s)  # type: ignore[arg-type]
        q = QOS[t]  # type: ignore[index]
        self._sub = (
            self._service.subscriber_builder()
            .buffer_size(q.buffer_size)
            .history_request(q.history_size)
            .create()
        )
        self._listener = domain.event(self.node, t.SERVICE).listener_builder().create()  # type: ignore[attr-defined]
        deadline = time.monotonic() + timeout_s
        while self._service.dynamic_config.number_of_publishers == 0:
            if time.monotonic() >= deadline:
                raise CorridorError(f"{t.SERVICE!r} in domain {domain.name!r}: no publisher")  # type: ignore[attr-defined]
            time.sleep(0.005)
        # Attach the receive side of the daemon's connection now (iceoryx2 does it lazily).
        self._sub.has_samples()
        self.last_seq: Optional[int] = None
        self.missed = 0

    def try_recv(self) -> Optional[T]:
        """The next message if one is waiting (a copy, the shared-memory slot is released)."""
        sample = self._sub.receive()
        if sample is None:
            return None
        value = self.t.from_buffer_copy(sample.payload().contents)
        sample.delete()
        seq = int(value.seq)  # type: ignore[attr-defined]
        if self.last_seq is not None and seq > self.last_seq + 1:
            self.missed += seq - self.last_seq - 1
        self.last_seq = seq
        return value

    def recv(self, timeout_s: float) -> Optional[T]:
        """The next message, waiting up to `timeout_s`; None on timeout."""
        deadline = time.monotonic() + timeout_s
        while True:
            v = self.try_recv()
            if v is not None:
                return v
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            # In slices: a wake-up the event loses costs one slice, not the whole timeout.
            self._listener.timed_wait(iox2.Duration.from_secs_f64(min(left, EVENT_WAIT_SLICE_S)))

    def close(self) -> None:
        """Releases the ports and the node."""
        self._sub.delete()
        self._listener.delete()
        self._service = None
        self.node = None
