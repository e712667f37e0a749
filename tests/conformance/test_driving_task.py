"""The sheet's driving-task rows (`roadgaze.conformance.driving_task`): each row's look is a
scenario of the Euro NCAP matrix, owl by the head and lizard by the eyes, judged on forward and
lane support held until the gaze is back, and the row's support cells follow it."""

from __future__ import annotations

import pytest

from dossier_fakes import euroncap_scenarios, outcomes_of
from roadgaze.conformance.dossier import GREEN, RED, judge_cells, outcomes_by_key
from roadgaze.conformance.dossier_rows import row_at
from roadgaze.conformance.driving_task import DRIVING_TASK_ROWS

SCENARIOS = {scenario.name: scenario for scenario in euroncap_scenarios()}


@pytest.mark.parametrize("row", sorted(DRIVING_TASK_ROWS))
def test_each_driving_task_row_is_a_look_judged_on_support(row: int) -> None:
    look = DRIVING_TASK_ROWS[row]
    sheet = row_at(row)
    assert sheet is not None and sheet.task == "Driving task"
    assert (sheet.movement, sheet.location) == (
        look.movement.capitalize(),
        look.location.replace("_", " ").capitalize(),
    )
    scenario = SCENARIOS[look.scenario]
    assert [r.key for r in scenario.requirements] == [
        f"{look.scenario}.support_forward",
        f"{look.scenario}.support_lane",
    ]
    assert all(r.held_until == "back" and r.window_s == (0.0, 0.5) for r in scenario.requirements)
    [glance] = [s for s in scenario.segments if s.label == "look"]
    assert glance.duration_s == (4.0 if look.long else 1.5)
    eyes = (glance.eye_yaw_deg, glance.eye_pitch_deg)
    if look.movement == "owl":
        assert eyes == (0.0, 0.0) and (glance.yaw_deg, glance.pitch_deg) != (0.0, 0.0)
    else:
        assert max(abs(e) for e in eyes) >= 10.0


def test_the_support_cells_of_a_driving_task_row_follow_its_scenario() -> None:
    failed = ("dt_lizard_instrument_cluster_70.support_lane",)
    cells = {
        (c.row.row, c.column): c
        for c in judge_cells(outcomes_by_key(outcomes_of(SCENARIOS.values(), failed)), "lhd")
    }
    assert (cells[(40, "E")].colour, cells[(40, "F")].colour) == (GREEN, GREEN)
    assert cells[(40, "E")].keys == ("dt_owl_rear_view_mirror_70.support_forward",)
    assert (cells[(45, "E")].colour, cells[(45, "F")].colour) == (GREEN, RED)
    assert cells[(27, "D")].colour is None  # a driving-task look earns no warning points
