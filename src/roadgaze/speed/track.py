"""A recorded drive's speed samples and the rule between them; which speed a drive gets (pure).

**The rule.** A sample's speed holds from its time for `hold_s` seconds (not including the instant
`hold_s` later), or until the next sample if that comes first; the speed is unknown before the
first sample, after an unknown sample (an empty `kmh`: a CAN dropout) and in a gap longer than
`hold_s`. Unknown is taken as moving. Held, never interpolated: a value between two samples
would be a speed nobody measured, and a speed crossing the protocols' active speed (20 km/h)
between two samples would start or stop the alerts at an invented time; holding is also what the
bus does live (its newest value) and what `roadgaze speed --track` puts on the bus, so a replay
of a track and a run fed that track see the same speed at every frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from roadgaze.errors import SpeedError
from roadgaze.speed.values import MAX_KMH, checked_kmh

FloatArray = npt.NDArray[np.float64]

DEFAULT_HOLD_S = 2.0
"""How long a sample holds without a newer one: the bus's default `zenoh.speed_timeout_s`."""


@dataclass(frozen=True, slots=True, eq=False, init=False)
class SpeedTrack:
    """Speed samples of one drive; `kmh_at(t_s)` follows the rule of the module doc.

    `t_s`: seconds on the drive's timeline, finite and strictly increasing (at least one);
    `kmh`: km/h within 0-400, NaN (or None when given) for unknown. Both read-only arrays.
    `SpeedError` for anything else.
    """

    t_s: FloatArray
    kmh: FloatArray
    hold_s: float
    name: str

    def __init__(
        self,
        t_s: Any,
        kmh: Any,
        hold_s: float = DEFAULT_HOLD_S,
        name: str = "speed track",
    ) -> None:
        times = np.array(t_s, dtype=np.float64)
        speeds = np.array(kmh, dtype=np.float64)  # None -> NaN
        if times.ndim != 1 or times.shape != speeds.shape or times.size == 0:
            raise SpeedError(f"{name}: expected as many speeds as times, at least one")
        if not np.isfinite(times).all() or (np.diff(times) <= 0).any():
            raise SpeedError(f"{name}: times must be finite and strictly increasing")
        known = speeds[~np.isnan(speeds)]
        if known.size and not (known.min() >= 0.0 and known.max() <= MAX_KMH):  # inf too
            raise SpeedError(f"{name}: speeds must be within 0-{MAX_KMH:g} km/h")
        if not hold_s > 0:
            raise SpeedError(f"{name}: a sample must hold for more than 0 s, found {hold_s}")
        times.flags.writeable = False
        speeds.flags.writeable = False
        object.__setattr__(self, "t_s", times)
        object.__setattr__(self, "kmh", speeds)
        object.__setattr__(self, "hold_s", float(hold_s))
        object.__setattr__(self, "name", name)

    @classmethod
    def constant(cls, kmh: float) -> SpeedTrack:
        """One speed from time 0 on, held for ever (`roadgaze speed --kmh`)."""
        return cls((0.0,), (checked_kmh(kmh, "--kmh"),), hold_s=math.inf, name=f"{kmh:g} km/h")

    @property
    def duration_s(self) -> float:
        """The time of the last sample."""
        return float(self.t_s[-1])

    @property
    def end_s(self) -> float:
        """When the last sample stops holding (infinity for a constant)."""
        return float(self.t_s[-1]) + self.hold_s

    def _index(self, t_s: float) -> int:
        return int(np.searchsorted(self.t_s, t_s, side="right")) - 1

    def kmh_at(self, t_s: float) -> float | None:
        """The speed at `t_s` (km/h), or None when unknown (taken as moving)."""
        index = self._index(t_s)
        if index < 0 or t_s >= self.t_s[index] + self.hold_s:
            return None
        value = float(self.kmh[index])
        return None if math.isnan(value) else value

    def next_change_s(self, t_s: float) -> float:
        """The first time after `t_s` at which `kmh_at` may answer differently: the next sample,
        or the end of the current one's hold (infinity when there is none)."""
        index = self._index(t_s)
        following = float(self.t_s[index + 1]) if index + 1 < self.t_s.size else math.inf
        if index >= 0 and (expires := float(self.t_s[index]) + self.hold_s) > t_s:
            return min(following, expires)
        return following

    def describe(self) -> str:
        known = self.kmh[~np.isnan(self.kmh)]
        span = f"{self.t_s[0]:.2f}-{self.t_s[-1]:.2f} s"
        speeds = f"{known.min():.0f}-{known.max():.0f} km/h" if known.size else "no known speed"
        return f"{self.name} ({self.t_s.size} samples, {span}, {speeds})"
