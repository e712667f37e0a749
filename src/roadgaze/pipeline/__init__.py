"""The one loop: frames -> landmarks -> pose -> monitor -> sinks, on three threads, timed."""

from roadgaze.pipeline.loop import (
    INFER_AHEAD_FRAMES,
    READ_AHEAD_FRAMES,
    STOP_GRACE_S,
    Pipeline,
    ProcessedFrame,
    Sink,
    StopSignal,
    create_detector,
)
from roadgaze.pipeline.speed import (
    BusSpeed,
    ConstantSpeed,
    SpeedSource,
    VehicleSpeed,
    no_speed,
    vehicle_speed,
)
from roadgaze.pipeline.timing import STAGES, RunSummary, StageStats, StageTimes, StageTimings

__all__ = [
    "INFER_AHEAD_FRAMES",
    "READ_AHEAD_FRAMES",
    "STAGES",
    "STOP_GRACE_S",
    "BusSpeed",
    "ConstantSpeed",
    "Pipeline",
    "ProcessedFrame",
    "RunSummary",
    "Sink",
    "SpeedSource",
    "StageStats",
    "StageTimes",
    "StageTimings",
    "StopSignal",
    "VehicleSpeed",
    "create_detector",
    "no_speed",
    "vehicle_speed",
]
