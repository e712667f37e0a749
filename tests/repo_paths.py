"""Where the checkout, its sources and the evaluation data are, for every test module.

The evaluation data is found in `$ROADGAZE_DATA` when it is set, else in `../shared/data` beside
the checkout (the development machines and CI); a fresh clone has neither, so tests that need it
skip with a reason. `roadgaze data pointing04 SRC $ROADGAZE_DATA/pointing04-dev` builds the
Pointing'04 set from the public archive.
"""

from __future__ import annotations

import os
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SRC = REPO / "src"
SHARED_DATA = Path(os.environ.get("ROADGAZE_DATA") or REPO.parent / "shared" / "data")
POINTING04 = SHARED_DATA / "pointing04-dev"
VIDEOS = SHARED_DATA / "videos"


def child_env(**extra: str) -> dict[str, str]:
    """Environment for a child `python -m roadgaze` that finds this checkout's sources."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(SRC), env.get("PYTHONPATH")]))
    env.update(extra)
    return env


STATEFARM = SHARED_DATA / "statefarm-dev"
