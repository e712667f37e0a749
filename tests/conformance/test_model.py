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
