"""Documented figures reproduce: the quick commands of scripts/documented_figures.py are run and
what they print is compared with what the README and docs say (`scripts/measure-readme.py
--check` runs all of them, the evaluation on Pointing'04 included)."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path
from types import ModuleType

from repo_paths import REPO, child_env


def load_figures() -> ModuleType:
    path = REPO / "scripts" / "documented_figures.py"
    spec = importlib.util.spec_from_file_location("documented_figures", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


figures = load_figures()


def roadgaze(args: Sequence[str]) -> str:
    result = subprocess.run(
        [sys.executable, "-m", "roadgaze", *args],
        capture_output=True, text=True, env=child_env(), timeout=300, check=False,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    return result.stdout


def test_a_place_matches_across_line_breaks_and_is_updated_in_place() -> None:
    place = figures.Place("README.md", "MAE {a:.1f} / {b} deg for |yaw| in 0-15")
    text = "Center-CE MAE 1.3 /\n2.7 deg for |yaw| in 0-15 / 15-30, and more"
    mismatches, updated = figures.compare(place, {"a": 1.36, "b": "2.88"}, text)
    assert [str(m) for m in mismatches] == [
        "README.md: documents a = 1.3, the command prints 1.4",
        "README.md: documents b = 2.7, the command prints 2.88",
    ]
    assert updated == "Center-CE MAE 1.4 /\n2.88 deg for |yaw| in 0-15 / 15-30, and more"
    assert figures.compare(place, {"a": 1.36, "b": "2.88"}, updated)[0] == []
    missing, same = figures.compare(place, {"a": 1.0, "b": "2"}, "no such sentence")
    assert len(missing) == 1 and "nothing like it" in str(missing[0]) and same == "no such sentence"


def test_every_figure_has_its_places_in_the_documents() -> None:
    """Each template still finds its sentence (the values are what --check compares)."""
    for figure in figures.FIGURES:
        for place in figure.places:
            text = (REPO / place.path).read_text(encoding="utf-8")
            assert place.pattern().search(text), f"{place.path}: {place.template[:80]}"


def test_the_quick_documented_figures_are_what_their_commands_print(tmp_path: Path) -> None:
    quick = [figure for figure in figures.FIGURES if figure.cheap]
    assert {figure.args[0] for figure in quick} == {"paper-tables", "synth"}
    problems = figures.check_figures(quick, tmp_path, run=roadgaze, say=lambda _: None)
    assert [str(problem) for problem in problems] == []
