"""The sheet's driving-task glances that the side-mirror scenarios do not cover: the rear-view
mirror by the head (owl), the mirrors and the instrument cluster by the eyes alone (lizard), a
shoulder glance at the passenger side window and an eyes-only glance at the driver's side
window, each long (one `LOOK_S` look) or short (one `MIRROR_S` glance), at 70 km/h.

The sheet asks no warning of a driving-task glance (its warning cell is not applicable); it asks
forward and lane support, raised as the gaze leaves the road and held until it is back
(`roadgaze.conformance.support`). Each look is `roadgaze.conformance.locations.look_at`: the
location's direction from the head in the driver's frame (roadgaze's cabin estimate,
`roadgaze.cabin`), the head turned to it (owl) or the eyes moved within their reach (lizard).
"""

from __future__ import annotations

from dataclasses import dataclass

from roadgaze.config import MonitorConfig
from roadgaze.conformance.model import Scenario

__all__ = ["DRIVING_TASK_ROWS", "DrivingTaskLook", "driving_task_scenarios"]


@dataclass(frozen=True, slots=True)
class DrivingTaskLook:
    """One sheet row's look: by `movement` (`owl`, `lizard`) at `location`, long or short."""

    movement: str
    location: str
    long: bool

    @property
    def scenario(self) -> str:
        length = "_4s" if self.long else ""
        return f"dt_{self.movement}_{self.location}{length}_70"


DRIVING_TASK_ROWS: dict[int, DrivingTaskLook] = {
    27: DrivingTaskLook("owl", "rear_view_mirror", True),
    29: DrivingTaskLook("lizard", "driver_side_mirror", True),
    30: DrivingTaskLook("lizard", "instrument_cluster", True),
    31: DrivingTaskLook("lizard", "rear_view_mirror", True),
    40: DrivingTaskLook("owl", "rear_view_mirror", False),
    42: DrivingTaskLook("owl", "passenger_side_window", False),
    43: DrivingTaskLook("lizard", "driver_side_window", False),
    44: DrivingTaskLook("lizard", "driver_side_mirror", False),
    45: DrivingTaskLook("lizard", "instrument_cluster", False),
    46: DrivingTaskLook("lizard", "rear_view_mirror", False),
}
"""The dossier's driving-task rows measured here (rows 26, 28, 39 and 41, the side mirrors by
the head, are the mirror scenarios of `roadgaze.conformance.matrix` and `.support`)."""


def driving_task_scenarios(config: MonitorConfig) -> list[Scenario]:
    """One scenario per row of `DRIVING_TASK_ROWS`, judged on forward and lane support."""
    from roadgaze.conformance.locations import look_at
    from roadgaze.conformance.matrix import FAST_KMH, LOOK_S, MIRROR_S, ahead, back
    from roadgaze.conformance.support import support_requirements

    scenarios = []
    for look in DRIVING_TASK_ROWS.values():
        duration_s = LOOK_S if look.long else MIRROR_S
        place = look.location.replace("_", " ")
        text = (
            f"{duration_s:g} s {look.movement} look at the {place} at {FAST_KMH:g} km/h "
            "(a driving task): forward and lane support"
        )
        segments = (ahead(), look_at(config, look.location, look.movement, duration_s), back())
        requirements = support_requirements(config, look.scenario, "look", "back")
        scenarios.append(Scenario(look.scenario, text, segments, FAST_KMH, requirements))
    return scenarios
