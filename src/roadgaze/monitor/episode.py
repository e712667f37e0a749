"""The monitor's timers at one sample: the counted off-road episode and its distraction time, the
finished episodes within the VATS window, the on-road and unavailable times. Pure.

Every behaviour reads these through the context and every alert is stamped with them, so they
are measured once per sample, before the behaviours run (`step_episode`).

- counted off road: off the road (any zone but `road`), or the face lost while the image works
  (a driver not seen is not seen on the road; a failed camera is a temporary failure instead),
  while moving. An episode starts at its first counted sample and ends at the first other one.
- distraction time: the episode's time outside the driving-related zones (`driving_related_zones`,
  the mirrors: their time pauses it, up to `driving_glance_max_s` per continuous stay when set,
  and only for a stay entered before the episode has counted `driving_glance_entry_s` elsewhere).
- on road since: the start of the current run of on-road samples with a face.
- unavailable since: the start of the current run of moving samples whose gaze is unknown.
"""

from __future__ import annotations

from dataclasses import dataclass

from roadgaze.config import MonitorConfig
from roadgaze.types import Gaze

__all__ = [
    "EPS_S",
    "Episode",
    "run_since",
    "segment_distraction_s",
    "step_episode",
    "window_total",
]

EPS_S = 1e-6
"""Durations are sums of float timestamps: compare them with this tolerance."""


@dataclass(frozen=True, slots=True)
class Episode:
    """The timers after the last sample; replace, never mutate."""

    off_since_s: float | None = None
    """Start of the current counted (off road and moving) episode."""
    segment_since_s: float | None = None
    """Start of the current run of driving-related (or of other) samples within the episode."""
    segment_driving: bool = False
    distraction_before_s: float = 0.0
    """Distraction time of the episode's runs before the current one."""
    last_off_road_s: float = 0.0
    """Duration of the most recent finished episode."""
    off_intervals: tuple[tuple[float, float], ...] = ()
    """Finished counted episodes [start, end) that still overlap the VATS window."""
    on_since_s: float | None = None
    """Start of the current continuous on-road period (with a face)."""
    unavailable_since_s: float | None = None
    """Start of the current run of moving samples with the gaze unknown."""

    @property
    def off_road(self) -> bool:
        """The last sample was counted off road."""
        return self.off_since_s is not None

    def off_road_s(self, t_s: float | None) -> float:
        """Length of the current counted off-road episode at `t_s`."""
        if self.off_since_s is None or t_s is None:
            return 0.0
        return t_s - self.off_since_s

    def window_s(self, t_s: float | None, window_s: float) -> float:
        """Counted off-road time within `window_s` before `t_s`."""
        if t_s is None:
            return 0.0
        return window_total(self.off_intervals, self.off_since_s, t_s, window_s)

    def distraction_s(self, config: MonitorConfig, t_s: float | None) -> float:
        """The long-distraction timer at `t_s`: the episode's time outside the driving-related
        zones."""
        if self.off_since_s is None or t_s is None:
            return 0.0
        return self.distraction_before_s + segment_distraction_s(
            config, self.segment_since_s, t_s, self.segment_driving
        )

    def on_road_s(self, t_s: float) -> float:
        """How long the driver has looked at the road with a face, at `t_s` (0: not now)."""
        return 0.0 if self.on_since_s is None else t_s - self.on_since_s

    def unavailable_s(self, t_s: float | None) -> float:
        if self.unavailable_since_s is None or t_s is None:
            return 0.0
        return t_s - self.unavailable_since_s


def window_total(
    intervals: tuple[tuple[float, float], ...],
    open_since_s: float | None,
    t_s: float,
    window_s: float,
) -> float:
    """Time of `intervals` (and of an episode open since `open_since_s`) within `window_s`."""
    start_s = t_s - window_s
    total = sum(max(0.0, min(end, t_s) - max(begin, start_s)) for begin, end in intervals)
    if open_since_s is not None:
        total += max(0.0, t_s - max(open_since_s, start_s))
    return total


def segment_distraction_s(
    config: MonitorConfig, since_s: float | None, t_s: float, driving: bool
) -> float:
    """Distraction time of one run of samples: all of it, or none for a driving-related run
    (unless it outlasts `driving_glance_max_s`)."""
    if since_s is None:
        return 0.0
    length_s = t_s - since_s
    if not driving:
        return length_s
    limit_s = config.driving_glance_max_s
    return length_s if limit_s is not None and length_s >= limit_s - EPS_S else 0.0


def run_since(condition: bool, since_s: float | None, t_s: float) -> float | None:
    """The start of a run of samples where `condition` holds (None: it does not now)."""
    if not condition:
        return None
    return t_s if since_s is None else since_s


def step_episode(
    config: MonitorConfig,
    episode: Episode,
    t_s: float,
    gaze: Gaze,
    driving: bool,
    face: bool,
    image_works: bool,
    moving: bool,
) -> Episode:
    """The timers after a sample at `t_s` whose gaze is `gaze` (`driving`: in a driving-related
    zone), with or without a `face`; `image_works`: no black, blocked or saturated frame."""
    unseen = gaze is Gaze.UNKNOWN and image_works
    counted_off = (gaze is Gaze.OFF_ROAD or unseen) and moving
    off_since, last_off_road_s = episode.off_since_s, episode.last_off_road_s
    segment_since, segment_driving = episode.segment_since_s, episode.segment_driving
    before_s, intervals = episode.distraction_before_s, episode.off_intervals
    entry_s = config.driving_glance_entry_s
    if driving and not segment_driving and off_since is not None and entry_s is not None:
        # entered after a look elsewhere: the look goes on
        driving = episode.distraction_s(config, t_s) < entry_s - EPS_S
    if counted_off and off_since is None:
        off_since = segment_since = t_s
        segment_driving, before_s = driving, 0.0
    elif counted_off and driving != segment_driving:
        before_s += segment_distraction_s(config, segment_since, t_s, segment_driving)
        segment_since, segment_driving = t_s, driving
    elif not counted_off and off_since is not None:
        intervals = (*intervals, (off_since, t_s))
        last_off_road_s = t_s - off_since
        off_since = segment_since = None
        segment_driving, before_s = False, 0.0
    intervals = tuple(iv for iv in intervals if iv[1] > t_s - config.vats_window_s)
    on_with_face = gaze is Gaze.ON_ROAD and face
    unknown = gaze is Gaze.UNKNOWN and moving
    on_since = run_since(on_with_face, episode.on_since_s, t_s)
    unavailable_since = run_since(unknown, episode.unavailable_since_s, t_s)
    return Episode(
        off_since_s=off_since,
        segment_since_s=segment_since,
        segment_driving=segment_driving,
        distraction_before_s=before_s,
        last_off_road_s=last_off_road_s,
        off_intervals=intervals,
        on_since_s=on_since,
        unavailable_since_s=unavailable_since,
    )
