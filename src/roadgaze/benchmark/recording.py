"""What recording costs per frame: pipeline passes without a recorder, with one recording the
records and alerts, and with one recording camera frames too, interleaved (`bench --record`).

Per pass: the loop thread's CPU time in the recorder's `on_record` (it only stamps and queues
the record there), the writer thread's CPU time per frame (the record, limits, annotations,
alerts, state and log messages, the MCAP writing with its compression, the flushes and syncs)
and the image thread's CPU time per camera frame (scaling, JPEG encoding, writing). Thread CPU
time is what the work costs whatever else the machine does (a loaded machine still inflates it
through shared caches); the sink stage's median wall time and the process's CPU per frame are
reported beside it, but on a shared machine they move more with the load than with the
recorder. The passes alternate (the order rotating each round), the figures are medians over
the rounds, and the load average is reported with them.
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from roadgaze.config import Config
from roadgaze.pipeline import RunSummary, Sink, StageTimings
from roadgaze.types import Alert, Frame, FrameRecord

KINDS = ("none", "records", "images")
RECORDS_TARGET_MS = 0.2
"""The goal: recording the records and alerts adds at most this per frame."""
IMAGE_TARGET_MS = 1.0
"""The goal: camera frames at 5 fps, 640x480, at most this per recorded frame, off the loop."""


@dataclass(frozen=True, slots=True)
class RecordingPass:
    """One timed pass and what its recorder did (nothing for `none`)."""

    kind: str
    frames: int
    sinks_median_ms: float
    process_cpu_ms_per_frame: float | None
    loop_cpu_ms_per_frame: float | None = None
    writer_cpu_ms_per_frame: float | None = None
    image_cpu_ms_per_image: float | None = None
    images: int = 0
    images_dropped: int = 0
    waits: int = 0

    def to_json(self) -> dict[str, Any]:
        def rounded(value: float | None) -> float | None:
            return None if value is None else round(value, 4)

        return {
            "kind": self.kind,
            "frames": self.frames,
            "sinks_median_ms": rounded(self.sinks_median_ms),
            "process_cpu_ms_per_frame": rounded(self.process_cpu_ms_per_frame),
            "loop_cpu_ms_per_frame": rounded(self.loop_cpu_ms_per_frame),
            "writer_cpu_ms_per_frame": rounded(self.writer_cpu_ms_per_frame),
            "image_cpu_ms_per_image": rounded(self.image_cpu_ms_per_image),
            "images": self.images,
            "images_dropped": self.images_dropped,
            "waits": self.waits,
        }


class LoopTimed:
    """A sink around the recorder that adds up the loop thread's CPU time in its `on_record`."""

    def __init__(self, sink: Sink) -> None:
        self.sink = sink
        self.cpu_s = 0.0
        self.frames = 0

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        started = time.thread_time()
        self.sink.on_record(record, frame)
        self.cpu_s += time.thread_time() - started
        self.frames += 1

    def on_alert(self, alert: Alert) -> None:
        self.sink.on_alert(alert)

    def close(self) -> None:
        return None


PassRunner = Callable[[Sequence[Sink], StageTimings], tuple[RunSummary, float | None]]
"""Runs one pipeline pass with these sinks: (its summary, process CPU ms per frame)."""


def recording_pass(
    kind: str, run_pass: PassRunner, config: Config, source: str, folder: Path, warmup: int
) -> RecordingPass:
    """One pass of `kind` (`none`, `records`, `images`), its MCAP written under `folder`."""
    from roadgaze.outputs.foxglove.open import replay_recorder
    from roadgaze.transport import Health, Keys

    timings = StageTimings(skip_first=warmup)
    if kind == "none":
        summary, cpu_ms = run_pass(
            [Health(config, Keys.from_config(config.zenoh), None, source)], timings
        )
        return RecordingPass(kind, summary.frames, _sinks_ms(timings), cpu_ms)
    record = config.record.model_copy(update={"images": kind == "images"})
    config = config.model_copy(update={"record": record})
    health = Health(config, Keys.from_config(config.zenoh), None, source)
    recorder = replay_recorder(
        config, source, folder / f"{kind}.mcap", health.state_json, block_on_images=False
    )
    timed = LoopTimed(recorder)
    with recorder:
        summary, cpu_ms = run_pass([health, timed], timings)
    frames = max(1, recorder.records_written)
    images = recorder.images_written
    return RecordingPass(
        kind,
        summary.frames,
        _sinks_ms(timings),
        cpu_ms,
        loop_cpu_ms_per_frame=1e3 * timed.cpu_s / max(1, timed.frames),
        writer_cpu_ms_per_frame=1e3 * recorder.writer_cpu_s / frames,
        image_cpu_ms_per_image=1e3 * recorder.image_cpu_s / images if images else None,
        images=images,
        images_dropped=recorder.images_dropped,
        waits=recorder.waits,
    )


def _sinks_ms(timings: StageTimings) -> float:
    stats = timings.stats().get("sinks")
    return stats.median_ms if stats is not None else float("nan")


def _median(values: Sequence[float | None]) -> float | None:
    known = [value for value in values if value is not None]
    return float(statistics.median(known)) if known else None


def recording_cost(
    run_pass: PassRunner, config: Config, source: str, rounds: int, warmup: int
) -> dict[str, Any]:
    """`rounds` rounds of the three passes (the order rotating) and the cost figures."""
    load_before = os.getloadavg()
    passes: list[RecordingPass] = []
    with tempfile.TemporaryDirectory(prefix="roadgaze-bench-") as folder:
        for number in range(rounds):
            order = KINDS[number % 3 :] + KINDS[: number % 3]
            for kind in order:
                passes.append(recording_pass(kind, run_pass, config, source, Path(folder), warmup))
    by_kind = {kind: [p for p in passes if p.kind == kind] for kind in KINDS}
    sinks = {kind: _median([p.sinks_median_ms for p in found]) for kind, found in by_kind.items()}
    process = {
        kind: _median([p.process_cpu_ms_per_frame for p in found])
        for kind, found in by_kind.items()
    }
    loop_records = _median([p.loop_cpu_ms_per_frame for p in by_kind["records"]])
    loop_images = _median([p.loop_cpu_ms_per_frame for p in by_kind["images"]])
    writer = _median([p.writer_cpu_ms_per_frame for p in by_kind["records"]])
    writer_images = _median([p.writer_cpu_ms_per_frame for p in by_kind["images"]])
    per_image = _median([p.image_cpu_ms_per_image for p in by_kind["images"]])
    image_share = _median([p.images / p.frames for p in by_kind["images"] if p.frames])
    per_frame_images = None if per_image is None or image_share is None else per_image * image_share
    records_total = None if loop_records is None or writer is None else loop_records + writer
    settings = config.record
    return {
        "load_average_before": [round(value, 2) for value in load_before],
        "load_average_after": [round(value, 2) for value in os.getloadavg()],
        "rounds": rounds,
        "image_fps": settings.image_fps,
        "image_width_px": settings.image_width_px,
        "image_format": settings.image_format,
        "records": {
            "loop_thread_cpu_ms_per_frame": _round(loop_records),
            "writer_thread_cpu_ms_per_frame": _round(writer),
            "total_ms_per_frame": _round(records_total),
            "sinks_stage_wall_ms_added": _round(_difference(sinks["records"], sinks["none"])),
            "process_cpu_ms_added": _round(_difference(process["records"], process["none"])),
            "target_ms_per_frame": RECORDS_TARGET_MS,
            "meets_target": None if records_total is None else records_total <= RECORDS_TARGET_MS,
        },
        "images": {
            "loop_thread_cpu_ms_per_frame": _round(loop_images),
            "writer_thread_cpu_ms_per_frame": _round(writer_images),
            "sinks_stage_wall_ms_added": _round(_difference(sinks["images"], sinks["none"])),
            "process_cpu_ms_added": _round(_difference(process["images"], process["none"])),
            "image_thread_cpu_ms_per_image": _round(per_image),
            "images_per_frame": _round(image_share),
            "image_thread_cpu_ms_per_frame": _round(per_frame_images),
            "dropped": sum(p.images_dropped for p in by_kind["images"]),
            "target_ms_per_frame": IMAGE_TARGET_MS,
            "meets_target": None
            if per_frame_images is None
            else per_frame_images <= IMAGE_TARGET_MS,
        },
        "passes": [p.to_json() for p in passes],
    }


def _difference(value: float | None, base: float | None) -> float | None:
    return None if value is None or base is None else value - base


def _round(value: float | None) -> float | None:
    return None if value is None else round(value, 4)


def format_recording(cost: dict[str, Any]) -> list[str]:
    """The human-readable lines of `recording_cost`'s figures."""
    records, images = cost["records"], cost["images"]
    return [
        f"recording      records+alerts {records['total_ms_per_frame']} ms/frame (loop thread CPU "
        f"{records['loop_thread_cpu_ms_per_frame']}, writer thread CPU "
        f"{records['writer_thread_cpu_ms_per_frame']}; target <= {records['target_ms_per_frame']})",
        f"  images       {cost['image_fps']:g} fps {cost['image_format']} <= "
        f"{cost['image_width_px']} px wide: image thread CPU "
        f"{images['image_thread_cpu_ms_per_image']} ms/image = "
        f"{images['image_thread_cpu_ms_per_frame']} ms/frame, loop thread CPU "
        f"{images['loop_thread_cpu_ms_per_frame']} ms/frame, {images['dropped']} dropped",
        f"  load average {cost['load_average_before']} -> {cost['load_average_after']} "
        f"({cost['rounds']} rounds)",
    ]
