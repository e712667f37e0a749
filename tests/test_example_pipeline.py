"""docs/examples/pipeline.py runs: the pipeline in a user's own process, on a synthetic drive
with a 4 s glance away (the clip test_pipeline_synthetic renders too, so it costs no render)."""

from __future__ import annotations

import importlib.util
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

from repo_paths import REPO


def load_example() -> ModuleType:
    path = REPO / "docs" / "examples" / "pipeline.py"
    spec = importlib.util.spec_from_file_location("roadgaze_example_pipeline", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_pipeline_example_prints_the_alerts_of_a_glance(
    synthetic_clip: Callable[[str], tuple[Path, Any]],
    capsys: pytest.CaptureFixture[str],
) -> None:
    path, truth = synthetic_clip("0:1.5,-35:4,0:1.5")
    example = load_example()
    assert example.main(["pipeline.py", str(path)]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert lines[0].startswith("t=") and "ALERT long_distraction warning" in lines[0]
    assert "ALERT cleared info" in lines[1]
    assert lines[2].startswith(f"{len(truth)} frames, a face in {len(truth)}, in ")
    assert lines[2].endswith("alerts: long_distraction:warning, cleared:info")
    # 3 s after the turn, which starts at 1.5 s, leaves the road band.
    assert 4.5 <= float(lines[0].removeprefix("t=").split()[0]) <= 5.2
