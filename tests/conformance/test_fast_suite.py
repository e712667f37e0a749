"""`roadgaze conformance --fast` end to end: rendered drives through the real service (MediaPipe),
the issue's acceptance cases among them, every requirement PASS, the reports written."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from roadgaze.cli import main

pytestmark = pytest.mark.usefixtures("restore_logging")

ACCEPTANCE = {
    "side_left_70": (1.5, 3.6),
    "side_right_70": (1.5, 3.6),
    "lap_70": (1.5, 3.6),
    "mirror_left_70": None,
    "lap_8s_10": None,
}
"""The issue's hard acceptance: at 70 km/h a 4 s look beyond 55 deg to either side or into the
lap warns 1.5-3.6 s after the look starts; a 1.5 s mirror glance and an 8 s lap glance at
10 km/h do not."""


@pytest.mark.slow
def test_fast_suite_passes_with_the_acceptance_cases(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["conformance", "--fast", "--out", str(tmp_path)])
    out, err = capsys.readouterr()
    report = json.loads((tmp_path / "conformance.json").read_text(encoding="utf-8"))
    failed = [o for o in report["outcomes"] if o["result"] != "PASS"]
    assert code == 0 and failed == [], failed
    assert report["protocol"] == "both" and 6 <= report["scenarios"] <= 10
    # each scenario's first requirement (the warning); forward and lane support follow it
    by_scenario = {o["scenario"]: o for o in reversed(report["outcomes"])}
    support = [o for o in report["outcomes"] if o["requirement"].endswith(".support_forward")]
    assert {o["scenario"] for o in support} >= {"lap_70", "side_left_70", "mirror_left_70"}
    assert all(0.0 <= o["measured_s"] <= 0.5 for o in support)
    for name, window in ACCEPTANCE.items():
        outcome = by_scenario[name]
        if window is None:
            assert outcome["measured_s"] is None and outcome["expected_window_s"] is None
        else:
            assert window[0] <= outcome["measured_s"] <= window[1]
            assert outcome["expected_window_s"] == list(window)
    assert "| `lap_70` |" in out and "PASS" in out
    assert (tmp_path / "conformance.md").read_text(encoding="utf-8").count("| PASS |") == len(
        report["outcomes"]
    )
    assert (tmp_path / "clips" / "lap_70.speed.csv").is_file()
    assert not (tmp_path / "clips" / "lap_70.mkv").exists()
    assert "requirements PASS" in err


def test_bad_arguments_are_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["conformance", "--only", "nope", "--out", str(tmp_path)]) == 2
    assert "unknown scenario nope" in capsys.readouterr().err
    (tmp_path / "file").write_text("x", encoding="utf-8")
    assert main(["conformance", "--fast", "--out", str(tmp_path / "file")]) == 2
    assert "is a file" in capsys.readouterr().err
