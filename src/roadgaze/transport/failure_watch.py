"""Permanent failure warnings (EU 2023/2590 Annex I 3.5.1): the camera gone past the reconnect
limit, or the model unusable. Raised outside the frame loop, since no frame arrives then.

`PermanentFailureWatch` runs a small thread (`start`, `close`) that looks at the source's
status every `interval_s`: a camera lost (reconnecting) or never opened for
`[monitor] permanent_failure_s` raises a `permanent_failure` alert with the reason, published
like any alert and kept in the state message; the first frame after it clears it (a `cleared`
alert). `model_failure` raises one for a model that cannot be loaded, before the service exits.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

from roadgaze.monitor.protocols import addw, roadgaze
from roadgaze.transport.health import Health
from roadgaze.types import Alert, AlertKind, AlertLevel

__all__ = ["PermanentFailureWatch", "failure_alert"]

log = logging.getLogger("roadgaze.daemon")


def failure_alert(t_s: float, reason: str, clears: bool = False) -> Alert:
    """A `permanent_failure` alert (or, with `clears`, the `cleared` alert that ends one)."""
    rule = roadgaze.CLEAR if clears else addw.FAILURE_PERMANENT
    return Alert(
        kind=AlertKind.CLEARED if clears else AlertKind.PERMANENT_FAILURE,
        level=AlertLevel.INFO if clears else AlertLevel.CRITICAL,
        t_s=t_s,
        yaw_deg=None,
        off_road_s=0.0,
        window_off_road_s=0.0,
        clears=(AlertKind.PERMANENT_FAILURE,) if clears else (),
        reason=reason,
        rule=rule.key,
        source=rule.source,
    )


class PermanentFailureWatch:
    """Watches the health's source; `publish` sends an alert (and counts it in the health)."""

    def __init__(
        self,
        health: Health,
        publish: Callable[[Alert], None],
        limit_s: float,
        clock: Callable[[], float] = time.monotonic,
        interval_s: float = 0.5,
    ) -> None:
        self.health, self.publish = health, publish
        self.limit_s, self.interval_s = limit_s, interval_s
        self._clock, self._started = clock, clock()
        self._lost_since: float | None = None
        self._frames_at_failure = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="roadgaze-failures", daemon=True)

    def _t_s(self) -> float:
        """Seconds on the source timeline: since start, as a live source counts."""
        return self._clock() - self._started

    def check(self) -> Alert | None:
        """One look at the source: the alert to publish now, if any."""
        source = self.health.source
        now = self._clock()
        lost = source is not None and not source.status.connected
        if self.health.permanent_failure:
            if self.health.frames > self._frames_at_failure:  # frames flow again
                self.health.permanent_failure = ""
                self._lost_since = None
                return failure_alert(self._t_s(), "frames again", clears=True)
            return None
        if not lost:
            self._lost_since = None
            return None
        self._lost_since = now if self._lost_since is None else self._lost_since
        lost_s = now - self._lost_since
        if lost_s < self.limit_s:
            return None
        message = source.status.message if source is not None else None
        reason = f"camera lost {lost_s:.0f} s" + (f" ({message})" if message else "")
        self.health.permanent_failure = reason
        self._frames_at_failure = self.health.frames
        return failure_alert(self._t_s(), reason)

    def _run(self) -> None:
        while not self._stop.wait(self.interval_s):
            try:
                alert = self.check()
                if alert is not None:
                    self.publish(alert)
            except Exception as exc:  # a safety warning must not die silently: say so, go on
                log.warning("permanent failure watch: %s", exc)

    def start(self) -> PermanentFailureWatch:
        """Start watching (a daemon thread); `close` stops it."""
        self._thread.start()
        return self

    def close(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=2.0)
