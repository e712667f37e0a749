"""Fleet fixtures: a folder of synthetic drives (plus an empty and a corrupt file) and one local
batch over it, shared by the batch and the Ray tests."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

TIMELINES = {
    "glance.mkv": "0:1,-35:4.5,0:1",  # away to the right: a long distraction, then cleared
    "right.mkv": "0:1,45:1.5,0:1",  # a glance to the left mirror: no alert
    "trip/road.mkv": "0:2",
}
"""Synthetic drives (relative path -> timeline), 320x320 at 15 fps."""
FPS = 15.0


@dataclass(frozen=True)
class FleetInput:
    folder: Path
    videos: dict[str, Path]
    """drive id -> video, for the drives that can be read."""


@dataclass(frozen=True)
class LocalBatch:
    input: FleetInput
    out_dir: Path
    outcome: Any


@pytest.fixture(scope="session")
def fleet_input(tmp_path_factory: pytest.TempPathFactory, synthetic_renderer: Any) -> FleetInput:
    from roadgaze.synth import render_clip

    folder = tmp_path_factory.mktemp("fleet")
    videos = {}
    for name, timeline in TIMELINES.items():
        path = folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        render_clip(timeline, path, fps=FPS, renderer=synthetic_renderer)
        videos[name.removesuffix(".mkv").replace("/", "__")] = path
    (folder / "empty.mp4").write_bytes(b"")
    (folder / "corrupt.mp4").write_bytes(b"not a video " * 100)
    return FleetInput(folder, videos)


@pytest.fixture(scope="session")
def local_batch(fleet_input: FleetInput, tmp_path_factory: pytest.TempPathFactory) -> LocalBatch:
    """The fleet input through the local engine with two workers."""
    from roadgaze.config import Config
    from roadgaze.fleet import BatchOptions, discover_drives, run_batch

    out_dir = tmp_path_factory.mktemp("fleet-out")
    options = BatchOptions(out_dir=out_dir, workers=2, progress=False)
    outcome = run_batch(discover_drives(fleet_input.folder), Config(), options)
    return LocalBatch(fleet_input, out_dir, outcome)
