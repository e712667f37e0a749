"""Where the fleet's executors used to live; kept so `roadgaze.fleet.engines` stays importable.

The executors (`batch --engine local|ray`) are in `roadgaze.fleet.executors`; "engine" in the code
means the landmark engine (roadgaze.landmarks.engines).
"""

from roadgaze.fleet.executors import (
    RAY_MISSING,
    RAY_TIMEOUT_S,
    Executor,
    LocalExecutor,
    RayExecutor,
    available_cores,
    import_ray,
)

Engine = Executor
LocalEngine = LocalExecutor
RayEngine = RayExecutor

__all__ = [
    "RAY_MISSING",
    "RAY_TIMEOUT_S",
    "Engine",
    "LocalEngine",
    "RayEngine",
    "available_cores",
    "import_ray",
]
