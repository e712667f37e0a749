"""How the conformance suite judges forward and lane support on a drive's logged changes, and a
rendered look through the service."""

from __future__ import annotations

from pathlib import Path

import pytest

from roadgaze.config import MonitorConfig
from roadgaze.conformance.matrix import scenario_matrix
from roadgaze.conformance.support import (
    AFTER_WARNING,
    SUPPORTED,
    judge_support,
    support_requirements,
)

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


def test_drowsiness_support_counts_from_its_warning_and_may_already_be_heightened() -> None:
    """Row 68's support follows the drowsiness warning (`AFTER_WARNING`): its clock starts at
    the first `drowsy` alert, the long blinks before may already have raised it, and it must be
    held to the end of the trip."""
    from roadgaze.conformance.run import outcomes_of

    drowsy = {s.name: s for s in scenario_matrix(MonitorConfig(protocol="euroncap"))}["drowsy_70"]
    support = [r for r in drowsy.requirements if r.held_until]
    assert [(r.from_alert, r.held_until) for r in support] == [("drowsy", "end")] * 2
    assert AFTER_WARNING == {"drowsy_70": "drowsy"}
    end_s = drowsy.duration_s

    def judged(alerts: list[tuple[str, str, float]]) -> dict[str, tuple[float | None, bool]]:
        outcomes = outcomes_of(drowsy, alerts)
        return {o.requirement.key.rpartition(".")[2]: (o.measured_s, o.passed) for o in outcomes}

    raised_by_a_blink = [
        ("support_forward", "normal", 0.0),
        ("support_lane", "normal", 0.0),
        ("support_forward", "heightened", 5.1),  # a long blink, before the warning
        ("support_lane", "heightened", 5.1),
        ("drowsy", "warning", 12.3),
    ]
    got = judged(raised_by_a_blink)
    assert got["warns"][1] and got["support_forward"] == (0.0, True)
    assert got["support_lane"] == (0.0, True)
    late = judged(
        [
            *raised_by_a_blink[:2],
            ("drowsy", "warning", 12.3),
            ("support_forward", "heightened", 12.9),  # 0.6 s after the warning: too late
            ("support_lane", "heightened", 12.5),
        ]
    )
    assert late["support_forward"] == (pytest.approx(0.6), False)
    assert late["support_lane"] == (pytest.approx(0.2), True)
    dropped = judged([*raised_by_a_blink, ("support_lane", "normal", end_s - 1.0)])
    assert dropped["support_lane"][1] is False and dropped["support_forward"][1] is True
    assert judged(raised_by_a_blink[:4])["support_forward"] == (None, False)  # never warned


def test_support_after_a_warning_counts_an_output_already_heightened() -> None:
    changes = [("support_forward", "normal", 1.0), ("support_forward", "heightened", 2.0)]
    assert judge_support(FORWARD, 3.0, 7.0, changes) == (0.0, False)  # a glance's: not its own
    assert judge_support(FORWARD, 3.0, 7.0, changes, from_normal=False) == (0.0, True)


@pytest.mark.slow
@pytest.mark.parametrize(("road_edge", "in_time"), [(True, True), (False, False)])
def test_a_mirror_look_under_a_beard_raises_support_at_the_road_edge_through_the_service(
    tmp_path: Path, road_edge: bool, in_time: bool
) -> None:
    """Through the real service: the head 32 deg to the rear-view mirror under the rendered
    beard reads about 23 deg (docs/pose.md, "Facial hair"), inside the road's exit bound (25);
    support raised at its entry bound (`support_road_edge`) comes within 0.5 s (measured
    0.40 s), at the zone's edge only it came at 1.27 s."""
    from roadgaze.commands.conformance import FPS, SIZE
    from roadgaze.config import Config
    from roadgaze.conformance.clips import ScenarioRenderer
    from roadgaze.conformance.dossier_general import under
    from roadgaze.conformance.run import run_suite
    from roadgaze.synth import EyeRenderer, load_photo

    monitor = Config().monitor.model_copy(
        update={"protocol": "euroncap", "support_road_edge": road_edge}
    )
    config = Config().model_copy(update={"monitor": monitor})
    scenario = next(s for s in scenario_matrix(monitor) if s.name == "dt_owl_rear_view_mirror_70")
    eyes = EyeRenderer(load_photo(), SIZE, config=config, eyeball_at_rest=True)
    renderer = ScenarioRenderer(eyes, FPS, monitor.cabin)
    suite = run_suite([under("beard")(scenario)], config, tmp_path, renderer)
    forward = next(o for o in suite.outcomes if o.requirement.key.endswith(".support_forward"))
    assert forward.passed is in_time
    if in_time:
        assert forward.measured_s is not None and forward.measured_s <= 0.5
    else:
        assert forward.measured_s is None or forward.measured_s > 0.5
