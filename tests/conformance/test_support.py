"""How the conformance suite judges forward and lane support on a drive's logged changes."""

from __future__ import annotations

import pytest

from roadgaze.config import MonitorConfig
from roadgaze.conformance.matrix import scenario_matrix
from roadgaze.conformance.support import SUPPORTED, judge_support, support_requirements

FORWARD = support_requirements(MonitorConfig(), "look_70", "look", "back")[0]


@pytest.mark.parametrize(
    ("changes", "measured", "passed"),
    [
        ([("support_forward", "normal", 2.0), ("support_forward", "heightened", 3.4)], 0.4, True),
        ([("support_forward", "normal", 2.0), ("support_forward", "heightened", 3.6)], 0.6, False),
        ([("support_forward", "heightened", 0.0)], 0.0, False),  # never normal: not the look's
        ([("support_forward", "normal", 2.0)], None, False),  # never raised
        (
            [
                ("support_forward", "normal", 2.0),
                ("support_forward", "heightened", 3.2),
                ("support_forward", "normal", 5.0),  # dropped during the look (ends at 7)
            ],
            0.2,
            False,
        ),
        (  # the lane's changes and the alerts do not count for forward
            [
                ("support_lane", "normal", 2.0),
                ("support_forward", "normal", 2.1),
                ("long_distraction", "warning", 3.1),
                ("support_forward", "heightened", 3.3),
                ("support_forward", "normal", 9.0),
            ],
            0.3,
            True,
        ),
    ],
)
def test_support_must_turn_heightened_from_normal_within_half_a_second_and_hold(
    changes: list[tuple[str, str, float]], measured: float | None, passed: bool
) -> None:
    got_measured, got_passed = judge_support(FORWARD, 3.0, 7.0, changes)
    assert got_passed is passed
    assert got_measured == (None if measured is None else pytest.approx(measured))


def test_the_matrix_judges_support_on_the_listed_scenarios_and_two_long_mirror_looks() -> None:
    scenarios = {s.name: s for s in scenario_matrix(MonitorConfig())}
    for name in (*SUPPORTED, "mirror_left_4s_70", "mirror_right_4s_70"):
        keys = [r.key for r in scenarios[name].requirements if r.held_until]
        assert keys == [f"{name}.support_forward", f"{name}.support_lane"]
    assert scenarios["mirror_left_4s_70"].duration_s == 3.0 + 4.0 + 2.0
    sleep = [r for r in scenarios["sleep_70"].requirements if r.held_until]
    assert {r.held_until for r in sleep} == {"end"}  # an impairment: to the end of the trip
    assert FORWARD.window_s == (0.0, 0.5)
