"""`roadgaze conformance --dossier FILE [--score]` as a user runs it: bad arguments are one line
and exit 2 before any drive is rendered; a run through the real service and Euro NCAP's real
calculator writes the dossier and prints the official score."""

from __future__ import annotations

from pathlib import Path

import pytest

from roadgaze.cli import main
from roadgaze.conformance import dossier_score

pytestmark = pytest.mark.usefixtures("restore_logging")


@pytest.mark.parametrize(
    ("args", "said"),
    [
        (["--score"], "--score scores the dossier: pass --dossier FILE.xlsx too"),
        (["--dossier", "{tmp}/d.txt"], "expected a FILE.xlsx (the calculator's format)"),
        (["--dossier", "{tmp}/nowhere/d.xlsx"], "/nowhere does not exist"),
        (
            ["--protocol", "addw", "--dossier", "{tmp}/d.xlsx"],
            "--dossier needs Euro NCAP's rules: pass --protocol euroncap (or both)",
        ),
    ],
)
def test_bad_dossier_arguments_are_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], said: str
) -> None:
    args = [arg.replace("{tmp}", str(tmp_path)) for arg in args]
    assert main(["conformance", "--out", str(tmp_path / "out"), *args]) == 2
    err = capsys.readouterr().err.strip()
    assert said in err and len(err.splitlines()) == 1
    assert not (tmp_path / "out" / "clips").exists()


def test_without_the_calculator_one_line_says_how_to_install_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(dossier_score, "installed_version", lambda: None)
    code = main(["conformance", "--out", str(tmp_path), "--dossier", str(tmp_path / "d.xlsx")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert "need Euro NCAP's rating calculator: pip install -c constraints.txt -e" in err


@pytest.mark.slow
def test_a_run_writes_the_dossier_and_prints_the_official_score(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Run as a user types it, with relative paths (the calculator's commands run in their own
    folder: a relative --out once sent their output nowhere)."""
    openpyxl = pytest.importorskip("openpyxl", reason="needs roadgaze[euroncap]")
    pytest.importorskip("euroncap_rating_2026", reason="needs roadgaze[euroncap]")
    monkeypatch.chdir(tmp_path)
    dossier = tmp_path / "d.xlsx"
    args = ["--protocol", "euroncap", "--only", "microsleep_70", "--out", "."]
    code = main(["conformance", *args, "--dossier", "d.xlsx", "--score"])
    out = capsys.readouterr().out
    assert code == 0
    ws = openpyxl.load_workbook(dossier)["DE - DM pred."]
    assert [ws[c].value for c in ("D70", "E70", "D71", "F72")] == ["Green", "Green", "Red", "Red"]
    # Measured: behind dark lenses the eyes are not judged, so the microsleep goes unwarned;
    # at night (the infrared picture) it is warned as by day.
    assert ws["D4"].value == "Non Functional" and ws["D2"].value == "Functional"
    assert "| 71 | Sleep | RED (not run: sleep_70.warns) |" in out
    assert "\nDriver Monitoring: 0 / 25 points\n" in out
    assert "the rows alone, were those met: 2 / 25 (Non-transient - Microsleep 2)" in out
    assert "Assumed: forward and lane support count the service's support request" in out
    assert (tmp_path / "dossier.md").is_file()
    reports = sorted((tmp_path / "euroncap").glob("sd_*_report.xlsx"))
    assert len(reports) == 1
