"""Benchmarks: raw MediaPipe throughput, loop throughput, capture-to-Zenoh latency and memory."""

from roadgaze.benchmark.latency import LatencyResult, YawLatencyProbe, measure_latency
from roadgaze.benchmark.probes import (
    CaptureStamps,
    MemoryProbe,
    ThroughputProbe,
    cpu_seconds,
    resident_mb,
)
from roadgaze.benchmark.raw import RawResult, raw_mediapipe_pass

__all__ = [
    "CaptureStamps",
    "LatencyResult",
    "MemoryProbe",
    "RawResult",
    "ThroughputProbe",
    "YawLatencyProbe",
    "cpu_seconds",
    "measure_latency",
    "raw_mediapipe_pass",
    "resident_mb",
]
