"""Shared test fixtures: the environment for a child `roadgaze` process, and synthetic clips of a
face turning to known yaws (no data needed). Paths live in `repo_paths`.

The suite runs in parallel (`pytest -n auto`, pytest-xdist): each test file stays on one worker,
so its module fixtures run once (and the files of a folder that shares costly state stay
together), and the session fixtures below that cost a landmarker run or a render are made once
per run and shared by the workers through `shared_folder`."""

from __future__ import annotations

import hashlib
import logging
import os
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from filelock import FileLock

from repo_paths import child_env

# --- Parallel runs (pytest-xdist) ---------------------------------------------------------------

ONE_WORKER_FOLDERS = ("tests/fleet/",)
"""Folders whose test files run on one worker together: tests/fleet's files share one local
batch (a session fixture; one test changes a video's time stamp and restores it) and start Ray."""

SLOW_WEIGHT = 20
"""A `slow` test counts as this many quick ones when the heaviest scopes are sent first."""


def scope_of(nodeid: str) -> str:
    """The unit one worker runs whole: the test's file, or its folder in ONE_WORKER_FOLDERS."""
    path = nodeid.split("::", 1)[0]
    return next((folder for folder in ONE_WORKER_FOLDERS if path.startswith(folder)), path)


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config: pytest.Config, log: Any) -> Any:
    """`--dist loadfile` (pyproject.toml), by `scope_of`: a file runs on one worker (its module
    fixtures once), and so does each folder of ONE_WORKER_FOLDERS."""
    if config.getvalue("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    class FileOrFolderScheduling(LoadFileScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return scope_of(nodeid)

    config.option.loadscopereorder = False  # the order below, by weight, not by test count
    return FileOrFolderScheduling(config, log)


def pytest_sessionstart(session: pytest.Session) -> None:
    """Before any test (in the controller of a parallel run, before its workers start): the
    face and hand models in the default cache, as `roadgaze model fetch` puts them. On a fresh
    machine the first test to need them fetched them while others already ran without: the
    demo then warned that phone detection was off, and tests built no hand stage. Where they
    cannot be had (no network), the tests that need them skip, as before."""
    if hasattr(session.config, "workerinput"):
        return
    from roadgaze.config import load_config
    from roadgaze.errors import ModelError
    from roadgaze.landmarks.hands.models import fetch_hand_models
    from roadgaze.landmarks.model_store import fetch_model

    config = load_config(environ={}).model
    for fetch in (fetch_model, fetch_hand_models):
        try:
            fetch(config)
        except ModelError as exc:
            logging.getLogger(__name__).warning("models for the tests: %s", exc)


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """On a worker, the heaviest scopes first, so the run does not end waiting on one long
    file; the order within a scope is kept. Every worker sorts alike."""
    if not hasattr(config, "workerinput"):
        return
    weight: dict[str, int] = {}
    for item in items:
        key = scope_of(item.nodeid)
        weight[key] = weight.get(key, 0) + (SLOW_WEIGHT if item.get_closest_marker("slow") else 1)
    first_seen = {key: n for n, key in enumerate(dict.fromkeys(scope_of(i.nodeid) for i in items))}
    items.sort(key=lambda item: (-weight[scope_of(item.nodeid)], first_seen[scope_of(item.nodeid)]))


def shared_folder(tmp_path_factory: pytest.TempPathFactory, name: str) -> tuple[Path, FileLock]:
    """A folder shared by every worker of this run (pytest-xdist's documented pattern: the
    workers' temporary folders share a parent) and the lock to hold while filling it."""
    base = tmp_path_factory.getbasetemp()
    root = base.parent if "PYTEST_XDIST_WORKER" in os.environ else base
    folder = root / "shared" / name
    folder.mkdir(parents=True, exist_ok=True)
    return folder, FileLock(str(folder) + ".lock")


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
def synthetic_renderer(tmp_path_factory: pytest.TempPathFactory) -> Any:
    """One `FaceRenderer` of the astronaut photo at 320x320, shared by the whole session; the
    landmarker runs on the photo once per run (its mesh is shared by the workers)."""
    from roadgaze.synth import FaceRenderer, load_photo
    from roadgaze.synth.renderer import photo_landmarks_px

    photo = load_photo()
    folder, lock = shared_folder(tmp_path_factory, "synthetic")
    mesh = folder / "astronaut-landmarks.npy"
    with lock:
        if not mesh.is_file():
            np.save(mesh, photo_landmarks_px(photo))
    return FaceRenderer(photo, SYNTHETIC_SIZE, landmarks_px=np.load(mesh))


@pytest.fixture(scope="session")
def synthetic_clip(
    tmp_path_factory: pytest.TempPathFactory, synthetic_renderer: Any
) -> Callable[[str], tuple[Path, Any]]:
    """Factory: `synthetic_clip("0:1,40:2")` -> (video path, (N, 3) truth `t_s,yaw,pitch`).

    320x320 at 15 fps, lossless FFV1 .mkv; each timeline is rendered once per run (shared by the
    workers). Treat the files as read-only.
    """
    from roadgaze.synth import render_clip

    folder, _ = shared_folder(tmp_path_factory, "synthetic")

    def make(timeline: str) -> tuple[Path, Any]:
        key = hashlib.sha256(timeline.encode()).hexdigest()[:16]
        path, truth_path = folder / f"clip-{key}.mkv", folder / f"clip-{key}.truth.npy"
        with FileLock(folder / f"clip-{key}.lock"):
            if not truth_path.is_file():
                np.save(
                    truth_path,
                    render_clip(timeline, path, fps=SYNTHETIC_FPS, renderer=synthetic_renderer),
                )
        return path, np.load(truth_path)

    return make
