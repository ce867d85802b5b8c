"""Subscribe to slope's estimates (and health reports) from Python.

    import slope_client
    for estimate in slope_client.subscribe("slope"):
        if estimate.ok and estimate.confidence >= 0.5:
            print(estimate.slope_deg, estimate.tracked_slope_deg)

Each item is a copy of one `slope.SlopeEstimate.v2` message (a
`ctypes.Structure` with the Rust struct's fields; see `messages.py`). The
generator sleeps on the topic's event (no polling) and wakes at least every
`wake_s` seconds; it ends after `timeout_s` without a message when given.

`subscribe_surfaces(prefix)` gives every surface of each frame instead (a
`slope.Surfaces.v1`: role, slope, extent; `road_surface()` is the one the
estimate's slope is measured on).
"""

import ctypes
import time
from typing import Iterator, Optional

from .messages import (
    CONFIDENCE_REASONS,
    METHOD_NAMES,
    STATUS_NAMES,
    Health,
    SlopeEstimate,
    ROLE_NAMES,
    SUPPORT_NAMES,
    StageHealth,
    SurfaceDescription,
    Surfaces,
    TimingStats,
    layout,
)

__all__ = [
    "CONFIDENCE_REASONS",
    "METHOD_NAMES",
    "STATUS_NAMES",
    "Health",
    "SlopeEstimate",
    "ROLE_NAMES",
    "SUPPORT_NAMES",
    "StageHealth",
    "SurfaceDescription",
    "Surfaces",
    "TimingStats",
    "ServiceNotFound",
    "SlopeClientError",
    "Subscription",
    "TooManySubscribers",
    "layout",
    "subscribe",
    "subscribe_health",
    "subscribe_surfaces",
]

DEFAULT_PREFIX = "slope"


class SlopeClientError(RuntimeError):
    """A subscription could not be made; the message says why and what to do."""


class ServiceNotFound(SlopeClientError):
    """The topic does not exist (yet): no estimator runs with that prefix."""


class TooManySubscribers(SlopeClientError):
    """The topic has as many subscribers as it takes."""


def subscribe(
    prefix: str = DEFAULT_PREFIX,
    timeout_s: Optional[float] = None,
    open_timeout_s: float = 10.0,
    wake_s: float = 0.1,
) -> "Subscription":
    """The estimates published on `<prefix>/estimate`, to iterate over.

    Subscribes at once, waiting up to `open_timeout_s` for the estimator to
    create the topic (`ServiceNotFound` after that): every estimate published
    after this returns is seen. Iteration ends after `timeout_s` seconds
    without an estimate when given, else runs until the caller stops.
    """
    return Subscription(f"{prefix}/estimate", SlopeEstimate, timeout_s, open_timeout_s, wake_s)


def subscribe_health(
    prefix: str = DEFAULT_PREFIX,
    timeout_s: Optional[float] = None,
    open_timeout_s: float = 10.0,
    wake_s: float = 0.1,
) -> "Subscription":
    """The health reports published on `<prefix>/health`, as `subscribe`."""
    return Subscription(f"{prefix}/health", Health, timeout_s, open_timeout_s, wake_s)


def subscribe_surfaces(
    prefix: str = DEFAULT_PREFIX,
    timeout_s: Optional[float] = None,
    open_timeout_s: float = 10.0,
    wake_s: float = 0.1,
) -> "Subscription":
    """Every surface of each frame, published on `<prefix>/surfaces` (a
    `Surfaces` per frame, beside the frame's estimate), as `subscribe`."""
    return Subscription(f"{prefix}/surfaces", Surfaces, timeout_s, open_timeout_s, wake_s)


class Subscription:
    """A subscriber on one slope topic; iterate over it for the messages
    (copies, so they outlive the shared-memory samples)."""

    def __init__(self, name, payload, timeout_s, open_timeout_s, wake_s):
        import iceoryx2 as iox2

        self.name = name
        self._payload = payload
        self._timeout_s = timeout_s
        iox2.set_log_level_from_env_or(iox2.LogLevel.Error)
        self._node = iox2.NodeBuilder.new().create(iox2.ServiceType.Ipc)
        give_up = time.monotonic() + open_timeout_s
        while True:
            try:
                # Open, never create: a service created here with iceoryx2's
                # defaults would not have the settings the daemons ask for.
                service_name = iox2.ServiceName.new(name)
                pubsub = self._node.service_builder(service_name).publish_subscribe(payload).open()
                event = self._node.service_builder(service_name).event().open()
                break
            except (iox2.PublishSubscribeOpenError, iox2.EventOpenError) as err:
                if time.monotonic() >= give_up:
                    raise ServiceNotFound(
                        f"no service '{name}' after {open_timeout_s} s: is slope-estimator "
                        f"running with the same service prefix? ({err})"
                    ) from err
                time.sleep(0.1)
        # The listener exists before the subscriber: no notification is missed.
        self._listener = event.listener_builder().create()
        try:
            self._subscriber = pubsub.subscriber_builder().create()
        except iox2.SubscriberCreateError as err:
            if "ExceedsMaxSupportedSubscribers" not in str(err):
                raise
            limit = pubsub.static_config.max_subscribers
            raise TooManySubscribers(
                f"cannot subscribe to '{name}': the topic takes at most {limit} subscribers at "
                "once and has that many: stop one (a slope-echo or slope-record left running?) "
                "or wait until one ends"
            ) from None
        self._wait_error = iox2.ListenerWaitError
        self._wake = iox2.Duration.from_millis(max(int(wake_s * 1000), 1))

    def receive(self):
        """The next waiting message (a copy), or None."""
        sample = self._subscriber.receive()
        if sample is None:
            return None
        size = ctypes.sizeof(self._payload)
        data = ctypes.string_at(ctypes.addressof(sample.payload().contents), size)
        del sample  # the sample goes back to the publisher
        return self._payload.from_buffer_copy(data)

    def __iter__(self):
        last = time.monotonic()
        while True:
            item = self.receive()
            if item is not None:
                last = time.monotonic()
                yield item
                continue
            if self._timeout_s is not None and time.monotonic() - last >= self._timeout_s:
                return
            try:
                self._listener.timed_wait(self._wake)
            except self._wait_error as err:
                # iceoryx2 ends the wait on SIGINT with its own error; the
                # caller expects Python's.
                if "InterruptSignal" in str(err):
                    raise KeyboardInterrupt from None
                raise
