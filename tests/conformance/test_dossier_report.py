"""The dossier in Markdown (`roadgaze.conformance.dossier_report`): docs/euroncap.md's tables are
the ones the code fills the sheet from, and the score is printed as one line a user can grep."""

from __future__ import annotations

from pathlib import Path

from dossier_fakes import (
    MANDATORY,
    FakeRunner,
    euroncap_scenarios,
    failing_everything_under,
    outcomes_of,
)
from repo_paths import REPO
from roadgaze.config import Config
from roadgaze.conformance.dossier import judge
from roadgaze.conformance.dossier_report import (
    DOC_END,
    DOC_START,
    doc_block,
    dossier_markdown,
    score_lines,
)
from roadgaze.conformance.dossier_score import Scored
from roadgaze.conformance.dossier_xlsx import Score

SCENARIOS = euroncap_scenarios()


def test_the_page_shows_the_table_the_code_fills_the_sheet_from() -> None:
    page = (REPO / "docs" / "euroncap.md").read_text(encoding="utf-8")
    shown = page[page.find(DOC_START) : page.find(DOC_END) + len(DOC_END)]
    assert shown == doc_block(Config().monitor), "run scripts/euroncap-rows.py"
    row = "| 17 | Non-driving task / Owl / Driver side window | `side_{driver}_70.warns` |"
    assert row in shown
    assert "| `euroncap.long_distraction` | `long_distraction_s` = 3 s |" in shown


def test_the_measured_sheet_shows_each_cell_with_what_was_measured() -> None:
    outcomes = outcomes_of(SCENARIOS, failed=("sleep_70.warns",))
    dossier = judge(outcomes, SCENARIOS, FakeRunner(), "lhd")
    text = dossier_markdown(dossier)
    assert "| 70 | Microsleep | GREEN (PASS: microsleep_70.warns 1.00 s, " in text
    assert (
        "| 71 | Sleep | RED (FAIL: sleep_70.warns 3.00 s (FAIL)) | GREEN (PASS: "
        "sleep_70.support_forward 0.50 s, sleep_70.support_lane 0.50 s) |" in text
    )  # forward and lane support measured beside the warning
    assert "| GREEN (PASS: mirror_left_70.support_forward 0.50 s) |" in text
    assert "| 26 | Driving task / Owl / Driver side mirror | n/a |" in text
    assert "| 4 | Dark sunglasses | Functional |" in text


def test_the_score_is_one_line_followed_by_its_categories_gates_and_assumptions() -> None:
    runner = FakeRunner(failing=failing_everything_under(*MANDATORY))
    dossier = judge(outcomes_of(SCENARIOS), SCENARIOS, runner, "lhd")
    official = Scored(Score(0.0, 25.0, (("Non-transient - Sleep", 0.0, 2.0),)), (), (), Path("r"))
    alone = Score(3.0, 25.0, (("Non-transient - Sleep", 0.5, 2.0), ("Phone use", 0.0, 5.0)))
    lines = score_lines(official, dossier, alone)
    assert lines[0] == "Driver Monitoring: 0 / 25 points"
    assert lines[1] == "  Non-transient - Sleep: 0 / 2"
    assert lines[2].startswith("  held at 0 by mandatory noise variables not shown functional")
    alone_line = "  the rows alone, were those met: 3 / 25 (Non-transient - Sleep 0.5)"
    assert lines[4].startswith(alone_line)
    assert lines[-2:] == [
        "Assumed: forward and lane support count the service's support request (the vehicle's "
        "reaction is the integrator's)",
        "Assumed: the emergency function counts the service's `unresponsive` alert as its "
        "request (the vehicle's manoeuvre is the integrator's)",
    ]
    unassessed = Scored(Score(None, 25.0, ()), (), (), Path("r"))
    assert score_lines(unassessed, dossier)[0] == "Driver Monitoring: unassessed / 25 points"
