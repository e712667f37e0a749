"""Forward and lane support settings (in `[monitor]`): when the service asks the vehicle's
forward-collision warning and lane keeping to be heightened (roadgaze.monitor.behaviours.support;
the rules and their sources: docs/monitor.md, "Forward and lane support")."""

from __future__ import annotations

from pydantic import Field

from roadgaze.config.section import Section

SUPPORT_RAISE_MAX_S = 0.5
"""Support must be heightened within this long of the gaze leaving the road (the Euro NCAP
dossier's support cells are judged against it: docs/euroncap.md)."""


class SupportSettings(Section):
    """When forward and lane support turn heightened and when they return to normal."""

    support_raise_s: float = Field(default=0.0, ge=0, le=SUPPORT_RAISE_MAX_S)
    """Support turns heightened once the driver has not been watching the road (or the service
    cannot tell) this long; at most 0.5 s. 0: at the first such sample."""
    support_clear_s: float = Field(default=2.0, ge=0)
    """Support returns to normal once the driver has watched the road, with everything known,
    this long."""
    support_road_edge: bool = True
    """A head past the road's entry bound (`road_half_width_deg - hysteresis_deg`, 20 deg of yaw;
    the road's pitch band) counts as not watching the road, though the zone stays the road until
    its exit bound (25 deg): the hysteresis keeps the warnings from flapping, support is raised at
    the entry bound. A 30 deg mirror look whose head reads 21-25 deg raises support (false support
    costs an earlier FCW; a missed one, a later one). False: support at the zone's edge only."""
    support_hold_impaired: bool = True
    """An impairment alert (drowsy, microsleep, sleep: a rule marked `impairment`) holds support
    heightened to the end of the trip."""
