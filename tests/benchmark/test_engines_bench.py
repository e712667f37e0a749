"""`bench --engines`: rounds interleave the engines between raw passes; medians and ratios."""

from __future__ import annotations

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
