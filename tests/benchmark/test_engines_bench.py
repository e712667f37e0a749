"""`bench --engines`: rounds interleave the engines between raw passes; medians and ratios."""

from __future__ import annotations

import itertools

from roadgaze.benchmark.engines import EnginePass, compare_engines, format_engines
from roadgaze.benchmark.raw import RawResult


def test_rounds_interleave_and_ratios_use_the_raw_passes_around_them() -> None:
    calls: list[str] = []
    raw_fps = iter([100.0, 50.0, 100.0])  # each raw pass: 10 frames at this rate

    def raw_pass() -> RawResult:
        calls.append("raw")
        fps = next(raw_fps)
        return RawResult(tuple([1.0 / fps] * 10), cpu_s=10 * 0.01, passes_fps=(fps,))

    def engine_pass(name: str) -> EnginePass:
        calls.append(name)
        fps = 60.0 if name == "litert" else 30.0
        stages = {"landmarks": (5.0, 9.0), "total": (8.0, 12.0)}
        return EnginePass(fps, 8.0 if name == "litert" else 12.0, stages, name)

    result = compare_engines(2, engine_pass, raw_pass)
    assert calls == ["raw", "litert", "mediapipe", "raw", "mediapipe", "litert", "raw"]
    litert, mediapipe = result["engines"]["litert"], result["engines"]["mediapipe"]
    # Each pass against the mean of the raw passes around its round: (100 + 50) / 2 = 75 fps.
    assert litert["fps"] == 60.0 and litert["fps_ratio_to_raw"] == 0.8
    assert mediapipe["fps_ratio_to_raw"] == 0.4
    assert litert["cpu_ratio_to_raw"] == 0.8 and mediapipe["cpu_ratio_to_raw"] == 1.2
    assert litert["stages"]["landmarks"] == {"median_ms": 5.0, "p99_ms": 9.0}
    assert litert["ran"] == ["litert"]
    assert result["raw"]["passes_fps"] == [100.0, 50.0, 100.0]
    text = "\n".join(format_engines(result))
    assert "litert" in text and "x0.8 of raw" in text


def test_the_models_alone_follow_each_raw_pass_and_are_read_against_it() -> None:
    calls: list[str] = []
    raw_cpu_s = itertools.cycle([0.10, 0.20])  # 10 frames: 10 and 20 ms of CPU a frame

    def raw_pass() -> RawResult:
        calls.append("raw")
        return RawResult(tuple([0.01] * 10), cpu_s=next(raw_cpu_s), passes_fps=(100.0,))

    def models_pass() -> RawResult:
        calls.append("models")
        return RawResult(tuple([0.005] * 10), cpu_s=0.06, passes_fps=(200.0,))

    def engine_pass(name: str) -> EnginePass:
        calls.append(name)
        return EnginePass(50.0, 10.0, {}, name)

    result = compare_engines(1, engine_pass, raw_pass, models_pass)
    assert calls == ["raw", "models", "litert", "mediapipe", "raw", "models"]
    # 6 ms a frame against 10 and against 20: ratios 0.6 and 0.3, median 0.45.
    assert result["models"]["cpu_ms_per_frame"] == 6.0
    assert result["models"]["cpu_ratio_to_raw"] == 0.45
    assert "models alone" in "\n".join(format_engines(result))
    assert "models" not in compare_engines(1, engine_pass, raw_pass)
