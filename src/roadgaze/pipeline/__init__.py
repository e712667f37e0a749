"""The one loop: frames -> landmarks -> pose -> monitor -> sinks, on three threads, timed."""

from roadgaze.pipeline.loop import (
    INFER_AHEAD_FRAMES,
    READ_AHEAD_FRAMES,
    STOP_GRACE_S,
    Pipeline,
    ProcessedFrame,
    Sink,
    SpeedSource,
    StopSignal,
    create_detector,
    no_speed,
)
from roadgaze.pipeline.timing import STAGES, RunSummary, StageStats, StageTimes, StageTimings

__all__ = [
    "INFER_AHEAD_FRAMES",
    "READ_AHEAD_FRAMES",
    "STAGES",
    "STOP_GRACE_S",
    "Pipeline",
    "ProcessedFrame",
    "RunSummary",
    "Sink",
    "SpeedSource",
    "StageStats",
    "StageTimes",
    "StageTimings",
    "StopSignal",
    "create_detector",
    "no_speed",
]
