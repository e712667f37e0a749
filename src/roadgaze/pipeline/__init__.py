"""The one loop: frames -> landmarks -> pose -> monitor -> sinks, on three threads, timed."""

from roadgaze.pipeline.build import Run, RunOptions, build_run, choose_speed
from roadgaze.pipeline.bus import EXIT_UNDELIVERED, BusOutputs, bus_outputs
from roadgaze.pipeline.loop import (
    INFER_AHEAD_FRAMES,
    READ_AHEAD_FRAMES,
    STOP_GRACE_S,
    Pipeline,
    ProcessedFrame,
    StopSignal,
    create_detector,
)
from roadgaze.pipeline.speed_gate import SpeedGateLog
from roadgaze.pipeline.timing import STAGES, RunSummary, StageStats, StageTimes, StageTimings
from roadgaze.speed import (
    BusSpeed,
    ConstantSpeed,
    SpeedSource,
    VehicleSpeed,
    no_speed,
    vehicle_speed,
)
from roadgaze.types import Sink

__all__ = [
    "EXIT_UNDELIVERED",
    "INFER_AHEAD_FRAMES",
    "READ_AHEAD_FRAMES",
    "STAGES",
    "STOP_GRACE_S",
    "BusOutputs",
    "BusSpeed",
    "ConstantSpeed",
    "Pipeline",
    "ProcessedFrame",
    "Run",
    "RunOptions",
    "RunSummary",
    "Sink",
    "SpeedGateLog",
    "SpeedSource",
    "StageStats",
    "StageTimes",
    "StageTimings",
    "StopSignal",
    "VehicleSpeed",
    "build_run",
    "bus_outputs",
    "choose_speed",
    "create_detector",
    "no_speed",
    "vehicle_speed",
]
