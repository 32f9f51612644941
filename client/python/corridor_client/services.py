"""Domains, QoS and service opening, mirroring shared/src/services/.

Every service is opened with the same QoS as the Rust side (iceoryx2 refuses an opener that
asks for more than the creator gave). Event services of the same name carry the wake-ups.
"""

import os
import time
from dataclasses import dataclass
from typing import Any, Dict, Type

import iceoryx2 as iox2

from . import wire

DEFAULT_DOMAIN = "default"
MAX_DOMAIN_LEN = 48
EVENT_MAX_NOTIFIERS = 4
EVENT_MAX_LISTENERS = 8
# Longest single wait on an event listener (EVENT_WAIT_SLICE in Rust): iceoryx2 0.10's event
# can lose a wake-up, and only the wait's timeout ends that sleep, so long waits are cut into
# slices with a look at the data after each.
EVENT_WAIT_SLICE_S = 0.05


@dataclass(frozen=True)
class Qos:
    """Quality of service of one publish-subscribe service (`Topic::QOS` in Rust)."""

    max_publishers: int
    max_subscribers: int
    buffer_size: int
    history_size: int
    max_borrowed: int


QOS: Dict[Type[wire._Wire], Qos] = {
    wire.ImuSample: Qos(2, 4, 4096, 0, 2),
    wire.AngleObservation: Qos(4, 4, 64, 0, 2),
    wire.AttitudeSample: Qos(1, 8, 4096, 0, 2),
    wire.BiasSample: Qos(1, 8, 256, 1, 2),
    wire.NavSample: Qos(1, 8, 256, 1, 2),
    wire.Diagnostics: Qos(1, 8, 64, 1, 2),
}


class CorridorError(Exception):
    """A service could not be opened or used; the message names service and domain."""


RUNTIME_DIR_ENV = "CORRIDOR_RUNTIME_DIR"
"""Environment variable naming the runtime directory of secured domains (as in Rust)."""


class Domain:
    """An isolated iceoryx2 namespace, as in Rust: the open domain
    (`global.prefix = corridor_<name>_`), or, when `CORRIDOR_RUNTIME_DIR` is set, the secured
    domain a daemon serves there (prefix `cr_<token>_`, root `<dir>/<token>`; only the daemon's
    user can read the token)."""

    def __init__(self, name: str = DEFAULT_DOMAIN) -> None:
        ok = all(c.isascii() and (c.isalnum() or c in "_-") for c in name)
        if not name or len(name) > MAX_DOMAIN_LEN or not ok:
            raise CorridorError(
                f"domain {name!r}: 1 to {MAX_DOMAIN_LEN} characters of a-z, A-Z, 0-9, '_', '-'"
            )
        self.name = name
        self.config = iox2.config.default()
        self.secured_prefix = None
        runtime_dir = os.environ.get(RUNTIME_DIR_ENV)
        if runtime_dir:
            path = os.path.join(runtime_dir, name, "prefix")
            try:
                with open(path) as f:
                    token = f.read().strip()
            except OSError as e:
                raise CorridorError(f"domain {name!r}: {path}: {e.strerror}") from e
            if len(token) != 16 or any(c not in "0123456789abcdef" for c in token):
                raise CorridorError(f"domain {name!r}: {path}: holds {token!r}, not a token")
            self.secured_prefix = f"cr_{token}_"
            self.config.global_cfg.prefix = iox2.FileName.new(self.secured_prefix)
            self.config.global_cfg.root_path = iox2.Path.new(os.path.join(runtime_dir, token))
        else:
            self.config.global_cfg.prefix = iox2.FileName.new(f"corridor_{name}_")

    def node(self, node_name: str) -> Any:
        """A node in this domain. Signals stay Python's alone (iceoryx2's handling, which the
        Rust clients use with `node.wait`, is not asked for): Ctrl-C raises KeyboardInterrupt
        in `send`, `recv` and the waits, within one wait slice, and a `Producer` used with
        `with` then ends its stream. (A process started in the background by a non-interactive
        shell inherits SIGINT ignored, and Python then never raises KeyboardInterrupt: a
        review's "Ctrl-C is ignored"; send it SIGTERM, see examples/driver_producer.py.)"""
        node = (
            iox2.NodeBuilder.new()
            .name(iox2.NodeName.new(node_name))
            .config(self.config)
            .signal_handling_mode(iox2.SignalHandlingMode.Disabled)
            .create(iox2.ServiceType.Ipc)
        )
        if self.secured_prefix:
            # iceoryx2 makes the node-counter segment world-writable; owner only, as in Rust.
            for entry in os.scandir("/dev/shm"):
                if (
                    entry.name.startswith(self.secured_prefix)
                    and entry.name.endswith(".global_mgmt")
                    and entry.stat().st_uid == os.geteuid()
                ):
                    os.chmod(entry.path, 0o600)
        return node

    def _builder(self, node: Any, t: Type[wire._Wire]) -> Any:
        q = QOS[t]
        return (
            node.service_builder(iox2.ServiceName.new(t.SERVICE))
            .publish_subscribe(t)
            .max_publishers(q.max_publishers)
            .max_subscribers(q.max_subscribers)
            .subscriber_max_buffer_size(q.buffer_size)
            .history_size(q.history_size)
            .subscriber_max_borrowed_samples(q.max_borrowed)
        )

    def open_existing(self, node: Any, t: Type[wire._Wire], timeout_s: float) -> Any:
        """Opens the service of `t` whatever its delivery policy, waiting up to `timeout_s`
        for the daemon to create it."""
        deadline = time.monotonic() + timeout_s
        while True:
            try:
                return self._builder(node, t).open()
            except iox2.PublishSubscribeOpenError as e:
                if time.monotonic() >= deadline:
                    raise CorridorError(
                        f"service {t.SERVICE!r} in domain {self.name!r}: cannot open ({e}); "
                        f"is `corridor serve --domain {self.name}` running?"
                    ) from e
                time.sleep(0.01)

    def event(self, node: Any, service: str) -> Any:
        """Opens (or creates) the event service paired with `service`."""
        return (
            node.service_builder(iox2.ServiceName.new(service))
            .event()
            .max_notifiers(EVENT_MAX_NOTIFIERS)
            .max_listeners(EVENT_MAX_LISTENERS)
            .open_or_create()
        )
