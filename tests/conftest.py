"""Shared test fixtures: the environment for a child `roadgaze` process, and synthetic clips of a
face turning to known yaws (no data needed). Paths live in `repo_paths`."""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from repo_paths import child_env


@pytest.fixture
def restore_logging() -> Iterator[None]:
    """`main()` points roadgaze's log handler at the captured stderr; undo it afterwards."""
    logger = logging.getLogger("roadgaze")
    handlers, level, propagate = list(logger.handlers), logger.level, logger.propagate
    yield
    logger.handlers[:] = handlers
    logger.setLevel(level)
    logger.propagate = propagate


@pytest.fixture
def subprocess_env() -> dict[str, str]:
    """Environment for a child `python -m roadgaze`: finds this checkout's sources."""
    return child_env()


# --- Synthetic ground-truth video (roadgaze.synth): fixtures that need no evaluation data -------

SYNTHETIC_SIZE = (320, 320)
SYNTHETIC_FPS = 15.0


@pytest.fixture(scope="session")
def synthetic_renderer() -> Any:
    """One `FaceRenderer` of the astronaut photo at 320x320, shared by the whole session."""
    from roadgaze.synth import FaceRenderer, load_photo

    return FaceRenderer(load_photo(), SYNTHETIC_SIZE)


@pytest.fixture(scope="session")
def synthetic_clip(
    tmp_path_factory: pytest.TempPathFactory, synthetic_renderer: Any
) -> Callable[[str], tuple[Path, Any]]:
    """Factory: `synthetic_clip("0:1,40:2")` -> (video path, (N, 3) truth `t_s,yaw,pitch`).

    320x320 at 15 fps, lossless FFV1 .mkv; each timeline is rendered once per session.
    """
    from roadgaze.synth import render_clip

    folder = tmp_path_factory.mktemp("synthetic")
    made: dict[str, tuple[Path, Any]] = {}

    def make(timeline: str) -> tuple[Path, Any]:
        if timeline not in made:
            path = folder / f"clip{len(made)}.mkv"
            truth = render_clip(timeline, path, fps=SYNTHETIC_FPS, renderer=synthetic_renderer)
            made[timeline] = (path, truth)
        return made[timeline]

    return make
