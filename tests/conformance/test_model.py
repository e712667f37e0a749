"""The suite's judging and its scripted drives, without rendering: windows and starts."""

from __future__ import annotations

import pytest

from roadgaze.conformance.model import Requirement, Scenario, Segment, judge


def requirement(window: tuple[float, float] | None) -> Requirement:
    return Requirement("r", "text", "source", ("long_distraction",), window)


def test_first_alert_of_the_kinds_is_measured_from_the_labelled_start() -> None:
    alerts = [("cleared", "info", 1.0), ("long_distraction", "warning", 6.2), ("vats", "w", 5.0)]
    measured, passed = judge(requirement((1.5, 3.6)), 3.0, alerts)
    assert measured == pytest.approx(3.2) and passed
    assert judge(requirement((1.5, 3.0)), 3.0, alerts) == (pytest.approx(3.2), False)
    assert judge(requirement((1.5, 3.6)), 3.0, []) == (None, False)


def test_an_alert_before_the_start_is_early_and_none_means_none() -> None:
    early = [("long_distraction", "warning", 2.0)]
    assert judge(requirement((1.5, 3.6)), 3.0, early) == (pytest.approx(-1.0), False)
    assert judge(requirement(None), 3.0, early) == (pytest.approx(-1.0), False)
    assert judge(requirement(None), 3.0, [("vats", "warning", 9.0)]) == (None, True)


def test_scenario_starts_and_duration() -> None:
    scenario = Scenario(
        "s", "", (Segment(3.0), Segment(4.0, label="look"), Segment(2.0, label="back")), 70.0, ()
    )
    assert scenario.duration_s == 9.0
    assert scenario.start_of("look") == 3.0 and scenario.start_of("back") == 7.0
    with pytest.raises(KeyError, match="no segment labelled 'event'"):
        scenario.start_of("event")


@pytest.mark.parametrize("protocol", ["addw", "euroncap", "both"])
def test_the_matrix_covers_the_issue_and_every_clock_has_its_start(protocol: str) -> None:
    from roadgaze.config import Config
    from roadgaze.conformance.matrix import scenario_matrix

    monitor = Config().monitor.model_copy(update={"protocol": protocol})
    scenarios = scenario_matrix(monitor)
    names = {s.name for s in scenarios}
    assert {"lap_70", "side_left_70", "side_right_70", "mirror_left_70", "lap_8s_10"} <= names
    assert 6 <= sum(s.fast for s in scenarios) <= 10
    assert len(names) == len(scenarios)
    for scenario in scenarios:
        assert scenario.duration_s <= 25.0
        for requirement in scenario.requirements:
            start_s = scenario.start_of(requirement.from_label)
            assert 0.0 < start_s < scenario.duration_s
            if requirement.window_s is not None:
                assert start_s + requirement.window_s[1] < scenario.duration_s
    by_name = {s.name: s for s in scenarios}
    assert by_name["lap_8s_10"].speed_kmh == 10.0 and by_name["lap_unknown_speed"].speed_kmh is None
    # The windows follow the rule tables: ADDW alone waits 6 s at 35 km/h, Euro NCAP 3 s.
    lap_35 = by_name["lap_35"].requirements[0].window_s
    assert lap_35 == pytest.approx((4.5, 6.6) if protocol == "addw" else (1.5, 3.6))
    # A rule of a protocol not configured is measured, not judged.
    assert by_name["vats_70"].requirements[0].applies is (protocol != "addw")
    assert by_name["covered_70"].requirements[0].applies is (protocol != "euroncap")


def test_a_requirement_that_does_not_apply_passes_and_says_so() -> None:
    from roadgaze.conformance.model import Outcome

    other = Requirement("r", "t", "s", ("vats",), (1.0, 2.0), "look", applies=False)
    assert judge(other, 0.0, []) == (None, True)
    assert Outcome("s", other, None, True).to_json()["result"] == "N/A"


def test_a_requirement_of_another_protocol_is_never_counted_failed() -> None:
    from roadgaze.conformance.model import Outcome
    from roadgaze.conformance.report import summary_line
    from roadgaze.conformance.run import SuiteRun

    other = Requirement("o", "t", "s", ("phone_use",), (1.0, 2.0), "look", applies=False)
    mine = Requirement("m", "t", "s", ("long_distraction",), (1.0, 2.0), "look")
    outcomes = (
        Outcome("a", other, None, False),  # not warned, but not this protocol's to judge
        Outcome("a", mine, 1.5, True),
        Outcome("b", mine, None, False),
    )
    run = SuiteRun(outcomes, 2, 1.0)
    assert [o.scenario for o in run.failed] == ["b"]
    line = summary_line(run, "addw")
    assert line.startswith("protocol addw: 1 of 2 requirements PASS, 1 FAIL, 1 of other")
