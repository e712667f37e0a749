"""The dossier scored by Euro NCAP's own calculator (`roadgaze.conformance.dossier_score`): the
real `euroncap_rating_2026` command line selects the tests, each is answered by running its
scenarios again (here a runner that answers without the service: the service itself is the
conformance suite's), and its report's Driver Monitoring score is read back."""

from __future__ import annotations

from pathlib import Path

import pytest

from dossier_fakes import FakeRunner, euroncap_scenarios, outcomes_of
from roadgaze.conformance import dossier_score
from roadgaze.conformance.dossier import judge, with_gates_met
from roadgaze.conformance.dossier_score import Calculator, require_calculator, score
from roadgaze.conformance.dossier_xlsx import write_dossier
from roadgaze.errors import ConfigError

SCENARIOS = euroncap_scenarios()


@pytest.mark.parametrize(
    ("version", "said"),
    [
        (None, "--dossier and --score need Euro NCAP's rating calculator: pip install"),
        ("5.5.0", "euroncap-rating-2026 5.5.0 is installed; roadgaze's dossier reads the sheet"),
    ],
)
def test_without_the_pinned_calculator_one_line_says_how_to_install_it(
    monkeypatch: pytest.MonkeyPatch, version: str | None, said: str
) -> None:
    monkeypatch.setattr(dossier_score, "installed_version", lambda: version)
    with pytest.raises(ConfigError) as raised:
        require_calculator()
    assert str(raised.value).startswith(said) and "'.[euroncap]'" in str(raised.value)


@pytest.mark.slow
def test_the_calculator_pays_the_rows_whose_tests_pass_again(tmp_path: Path) -> None:
    """Every scenario passing and the gates taken as met: the long and short distraction groups
    whose every cell is GREEN (owl, lizard, body lean: warning, forward and lane support; the
    driving-task glances: forward and lane support), basic and advanced phone use, drowsiness,
    microsleep and sleep (warning, forward and lane support) and the unresponsive driver's
    emergency function: 23.0 points (non-fatigue impairment is RED), each selected test answered
    PASS;
    a sleep test failing when run again takes its points. The calculator draws the distraction
    tests at random: only the fixed ones are named."""
    pytest.importorskip("euroncap_rating_2026", reason="needs roadgaze[euroncap]")
    assert require_calculator() == dossier_score.PINNED
    template = Calculator(tmp_path / "template").template()
    dossier = with_gates_met(judge(outcomes_of(SCENARIOS), SCENARIOS, FakeRunner(), "lhd"))
    path = write_dossier(template, dossier, tmp_path / "d.xlsx")

    runner = FakeRunner()
    passed = score(dossier, path, Calculator(tmp_path / "pass"), SCENARIOS, runner, True)
    categories = {name: got for name, got, _ in passed.score.categories}
    assert categories == {
        "Transient - Long distraction": 5.0,  # non-driving and driving-task glances, all cells
        "Transient - Short distraction": 5.0,
        # basic phone use by the head and the eyes (rows 51-60, one group: 1.25, 1.0, 0.25),
        # advanced phone use (61-64) likewise
        "Transient - Phone use": 5.0,
        "Non-transient - Impairment": 2.0,  # drowsiness' warning and support; non-fatigue RED
        "Non-transient - Microsleep": 2.0,
        "Non-transient - Sleep": 2.0,
        "Non-transient - Unresponsive": 2.0,
    }
    assert passed.score.points == 23.0 and passed.score.max_points == 25.0
    answers = {(a.column, a.row, a.value) for a in passed.answers}
    assert {("D", 70, "PASS"), ("D", 71, "PASS"), ("F", 72, "PASS")} <= answers
    assert all(value == "PASS" for _, _, value in answers)
    assert {"microsleep_70", "sleep_70", "unresponsive_closed_70", "unresponsive_away_70"} <= set(
        runner.calls
    )

    failing = FakeRunner(failing={"sleep_70"})
    failed = score(dossier, path, Calculator(tmp_path / "fail"), SCENARIOS, failing, True)
    assert failed.score.points < passed.score.points
    sleep = next(a for a in failed.answers if a.row == 71)
    assert sleep.value == "FAIL" and sleep.why.startswith("sleep_70: FAIL: sleep_70.warns")
    assert (tmp_path / "fail" / "sd_verified.xlsx").is_file() and failed.report.is_file()
