"""The `run` service: kept importable here; it lives in `roadgaze.service.daemon` (the loop's
wiring in `roadgaze.pipeline.build_run`, the bus in `roadgaze.pipeline.bus`)."""

from roadgaze.pipeline.bus import EXIT_UNDELIVERED, BusOutputs, bus_outputs
from roadgaze.service.daemon import run_daemon

__all__ = ["EXIT_UNDELIVERED", "BusOutputs", "bus_outputs", "run_daemon"]
