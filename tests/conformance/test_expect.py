"""Expected windows from the rule tables and the rendered path (`roadgaze.conformance.expect`):
a glance's off-road time is the time the eased head spends beyond the road's edge, checked
against the closed form of the cosine ease."""

from __future__ import annotations

import math

import pytest

from roadgaze.config import Config
from roadgaze.conformance import expect
from roadgaze.conformance.model import Segment
from roadgaze.monitor.zones import ZoneMap
from roadgaze.synth.timeline import DEFAULT_TRANSITION_S

MONITOR = Config().monitor.model_copy(update={"protocol": "euroncap"})
RAMP_S = DEFAULT_TRANSITION_S


def leaves_road_s(target_deg: float, edge_deg: float) -> float:
    """When a cosine-eased turn from 0 to `target_deg` over `RAMP_S` crosses `edge_deg`."""
    return RAMP_S / math.pi * math.acos(1.0 - 2.0 * edge_deg / target_deg)


@pytest.mark.parametrize("yaw_deg", [-30.0, -55.0])
def test_the_off_road_time_of_glances_follows_the_eased_turn(yaw_deg: float) -> None:
    zones = ZoneMap.from_config(MONITOR)
    edge_deg = -zones.zones[0].yaw_min_deg
    # The head leaves the road past its edge grown by the hysteresis, and is back on it at the
    # edge itself.
    t1 = leaves_road_s(-yaw_deg, edge_deg + zones.hysteresis_deg)
    back_s = RAMP_S - leaves_road_s(-yaw_deg, edge_deg)  # the ease is symmetric
    glance_s, road_s = 2.2, 1.2
    # One glance off the road for its length, less the turn in before it leaves, plus the turn
    # back until it is on the road again.
    off_one_s = glance_s - t1 + back_s
    segments = [Segment(3.0, label="ahead")]
    for index in range(2):
        segments += [Segment(glance_s, yaw_deg, label=f"g{index}"), Segment(road_s)]
    reached = expect.off_road_reached_s(MONITOR, segments, "g0", 1.0)
    assert reached == pytest.approx(t1 + 1.0, abs=2 * expect.PATH_STEP_S)
    reached = expect.off_road_reached_s(MONITOR, segments, "g0", off_one_s + 0.5)
    assert reached == pytest.approx(glance_s + road_s + t1 + 0.5, abs=2 * expect.PATH_STEP_S)
    assert expect.off_road_reached_s(MONITOR, segments, "g0", 2 * off_one_s + 0.1) is None


def test_vats_is_expected_when_the_heads_path_reaches_the_threshold() -> None:
    """A far target leaves the road early and comes back late: its glances' off-road time is
    longer than their length, so VATS is due earlier than the lengths alone say; the window is
    the distraction warnings' margins around that. Eyes-only glances keep the glances' lengths."""
    glances = [Segment(3.0, label="ahead")]
    for index in range(5):
        glances += [Segment(2.2, -55.0, -30.0, label="look" if index == 0 else f"g{index}")]
        glances += [Segment(1.2)]
    far = expect.vats(MONITOR, "far.warns", "far", glances, 4 * 1.2)
    reached = expect.off_road_reached_s(MONITOR, glances, "look", 10.0)
    assert reached is not None and reached < 10.0 + 4 * 1.2
    assert far.window_s == pytest.approx((reached - 1.5, reached + 0.6))
    eyes = [Segment(s.duration_s, 0.0, 0.0, s.yaw_deg, s.pitch_deg, label=s.label) for s in glances]
    lizard = expect.vats(MONITOR, "eyes.warns", "eyes", eyes, 4 * 1.2)
    assert lizard.window_s == pytest.approx((14.8 - 1.5, 14.8 + 0.6))
