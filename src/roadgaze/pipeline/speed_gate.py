"""Says when the vehicle speed holds alerts back: a known speed at or below the configured
protocols' active speed (`[monitor] min_speed_kmh`, `addw_min_speed_kmh`) stops the monitor's
timers, so no alert fires while it lasts (an unknown speed never does: it counts as moving).

`SpeedGateLog` is a sink that logs when that starts and when it stops, on the drive's own time:
a start at most once per `period_s` seconds of the drive (a flapping speed around the threshold
is summed up: the next line says how many changes it stands for), and the stop of every start
logged, so the last line always tells the state; at the end, how long alerts were held back in
all.
"""

from __future__ import annotations

import logging
import math

from roadgaze.types import Frame, FrameRecord, Sink

GATE_LOG_PERIOD_S = 10.0


class SpeedGateLog(Sink):
    """Sink logging when the speed starts and stops holding alerts back (see the module doc)."""

    def __init__(
        self, logger: str, label: str, period_s: float = GATE_LOG_PERIOD_S, level: int = 20
    ) -> None:
        self._log = logging.getLogger(logger)
        self.label = label
        self.period_s = period_s
        self.level = level
        self.holding = False
        self.held_s = 0.0
        """Seconds of the drive with alerts held back, up to the last record."""
        self.times_held = 0
        self._said_holding = False
        self._last_t_s: float | None = None
        self._said_s = -math.inf
        self._changes = 0
        """Changes since the last line."""

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        verdict, t_s = record.verdict, record.t_s
        if self.holding and self._last_t_s is not None:
            self.held_s += max(0.0, t_s - self._last_t_s)
        self._last_t_s = t_s
        if verdict.moving == self.holding:  # a change
            self.holding = not verdict.moving
            self.times_held += self.holding
            self._changes += 1
        if self.holding == self._said_holding:
            return
        if self.holding and t_s - self._said_s < self.period_s:
            return  # a start within the period: said later, if it still holds then
        self._say(t_s, verdict.speed_kmh)

    def _say(self, t_s: float, speed_kmh: float | None) -> None:
        more = self._changes - 1
        since = f"; {more} more change{'s' * (more != 1)} since the last line" if more else ""
        speed = "unknown (taken as moving)" if speed_kmh is None else f"{speed_kmh:g} km/h"
        if self.holding:
            what = "at or below the active speed of the configured protocols: alerts held back"
        else:
            what = "alerts allowed again"
        self._log.log(
            self.level,
            "%s: vehicle speed %s at t=%.2f s, %s%s",
            self.label,
            speed,
            t_s,
            what,
            since,
        )
        self._said_holding, self._changes = self.holding, 0
        if self.holding:
            self._said_s = t_s

    def close(self) -> None:
        if self.times_held:
            self._log.log(
                self.level,
                "%s: alerts were held back by the vehicle speed for %.1f s in all (%d time%s)",
                self.label,
                self.held_s,
                self.times_held,
                "s" * (self.times_held != 1),
            )
