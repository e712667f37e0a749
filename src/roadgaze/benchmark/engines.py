"""Both landmark engines and raw FaceLandmarker in one run, interleaved (`bench --engines`).

On a shared machine the load changes from minute to minute, so the engines are compared pass
against pass: each round runs a raw MediaPipe pass, then one pipeline pass per engine (their order
alternating from round to round), and a last raw pass closes the run. Each engine's figures are
the medians over its passes; `ratio_to_raw` and `cpu_ratio_to_raw` compare every pass with the
mean of the raw passes just before and after its round. The load average is reported beside them.

With a `models_pass`, each raw pass is followed by one of the bundle's landmark and blendshape
models alone on LiteRT (`roadgaze.benchmark.raw.litert_models_pass`): the CPU no engine of these
models can go below, as a share of FaceLandmarker's (`models.cpu_ratio_to_raw`, each models pass
against the raw pass just before it).
"""

from __future__ import annotations

import os
import statistics
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from roadgaze.benchmark.raw import RawResult
from roadgaze.landmarks.engines import ENGINES


@dataclass(frozen=True, slots=True)
class EnginePass:
    """One pipeline pass: fps and CPU per frame after the warm-up, per-stage median and p99 ms."""

    fps: float | None
    cpu_ms_per_frame: float | None
    stages: dict[str, tuple[float, float]]
    engine_ran: str
    """The engine that actually ran (after a fallback)."""


def _median(values: Sequence[float | None]) -> float | None:
    known = [v for v in values if v is not None]
    return float(statistics.median(known)) if known else None


def _round(value: float | None, digits: int = 3) -> float | None:
    return None if value is None else round(value, digits)


def load_average() -> list[float] | None:
    """The 1, 5 and 15 minute load averages (None where the system has none)."""
    try:
        return [round(value, 2) for value in os.getloadavg()]
    except (OSError, AttributeError):
        return None


def compare_engines(
    rounds: int,
    pipeline_pass: Callable[[str], EnginePass],
    raw_pass: Callable[[], RawResult],
    models_pass: Callable[[], RawResult] | None = None,
) -> dict[str, Any]:
    """`rounds` rounds of [raw, (models,) one pass per engine], then a last raw (and models)
    pass; the result's `engines` maps each engine to its medians and ratios, `raw` is
    FaceLandmarker alone, `models` (with `models_pass`) the models alone."""
    load_start = load_average()
    raws: list[RawResult] = []
    models: list[RawResult] = []

    def reference_passes() -> None:
        raws.append(raw_pass())
        if models_pass is not None:
            models.append(models_pass())

    reference_passes()
    passes: dict[str, list[tuple[EnginePass, int]]] = {name: [] for name in ENGINES}
    for number in range(rounds):
        order = ENGINES if number % 2 == 0 else tuple(reversed(ENGINES))
        for name in order:
            passes[name].append((pipeline_pass(name), number))
        reference_passes()
    raw = sum(raws[1:], raws[0])
    engines: dict[str, Any] = {}
    for name, results in passes.items():
        fps_ratios, cpu_ratios = [], []
        for result, number in results:
            before, after = raws[number], raws[number + 1]
            raw_fps = 0.5 * (before.fps + after.fps)
            raw_cpu = 0.5 * (before.cpu_ms_per_frame + after.cpu_ms_per_frame)
            if result.fps is not None and raw_fps > 0:
                fps_ratios.append(result.fps / raw_fps)
            if result.cpu_ms_per_frame is not None and raw_cpu > 0:
                cpu_ratios.append(result.cpu_ms_per_frame / raw_cpu)
        stage_names = results[0][0].stages if results else {}
        engines[name] = {
            "ran": sorted({result.engine_ran for result, _ in results}),
            "fps": _round(_median([r.fps for r, _ in results]), 2),
            "cpu_ms_per_frame": _round(_median([r.cpu_ms_per_frame for r, _ in results])),
            "fps_ratio_to_raw": _round(_median(fps_ratios), 4),
            "cpu_ratio_to_raw": _round(_median(cpu_ratios), 4),
            "passes_fps": [_round(r.fps, 2) for r, _ in results],
            "passes_cpu_ms_per_frame": [_round(r.cpu_ms_per_frame) for r, _ in results],
            "stages": {
                stage: {
                    "median_ms": _round(_median([r.stages[stage][0] for r, _ in results])),
                    "p99_ms": _round(_median([r.stages[stage][1] for r, _ in results])),
                }
                for stage in stage_names
            },
        }
    summary: dict[str, Any] = {
        "rounds": rounds,
        "load_average_start": load_start,
        "load_average_end": load_average(),
        "raw": {
            "fps": round(raw.fps, 2),
            "cpu_ms_per_frame": round(raw.cpu_ms_per_frame, 3),
            "passes_fps": [round(fps, 2) for fps in raw.passes_fps],
        },
        "engines": engines,
    }
    if models:
        ratios = [
            m.cpu_ms_per_frame / r.cpu_ms_per_frame for m, r in zip(models, raws, strict=True)
        ]
        summary["models"] = {
            "cpu_ms_per_frame": _round(_median([m.cpu_ms_per_frame for m in models])),
            "cpu_ratio_to_raw": _round(_median(ratios), 4),
            "passes_cpu_ms_per_frame": [_round(m.cpu_ms_per_frame) for m in models],
        }
    return summary


def format_engines(result: dict[str, Any]) -> list[str]:
    """The human-readable lines of `compare_engines`' result."""
    raw = result["raw"]
    lines = [
        f"engines ({result['rounds']} interleaved rounds; load average "
        f"{result['load_average_start']} -> {result['load_average_end']})",
        f"  raw FaceLandmarker  {raw['fps']:.1f} fps, {raw['cpu_ms_per_frame']:.2f} ms CPU/frame",
    ]
    for name, figures in result["engines"].items():
        landmarks = figures["stages"].get("landmarks", {})
        lines.append(
            f"  {name:<10} {figures['fps']} fps, {figures['cpu_ms_per_frame']} ms CPU/frame "
            f"(fps x{figures['fps_ratio_to_raw']} of raw, CPU x{figures['cpu_ratio_to_raw']}); "
            f"landmarks median {landmarks.get('median_ms')} ms, p99 {landmarks.get('p99_ms')} ms"
        )
    models = result.get("models")
    if models is not None:
        lines.append(
            f"  models alone (LiteRT, landmarks + blendshapes) {models['cpu_ms_per_frame']} ms "
            f"CPU/frame (CPU x{models['cpu_ratio_to_raw']} of raw): no engine of these models "
            "costs less"
        )
    return lines
