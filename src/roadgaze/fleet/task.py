"""The task of a batch: one drive through the one loop, written as Parquet, summed up in one row.

`process_drive(task)` is what both engines run, by name, in their worker processes. It never
raises for a bad drive: a missing, empty, corrupt or unreadable video becomes a `DriveResult`
with `status="failed"` and a one-line `error`. A drive whose outputs already exist and match
its fingerprint (the input's size and mtime, or its SHA-256; the roadgaze version; the
configuration; the drive's metadata) is not run again: its stored summary comes back with
`resumed=True`. Every drive gets a fresh VIDEO-mode landmarker (one reused across files carries
its tracking state over and loses faces).
"""

from __future__ import annotations

import hashlib
import json
import logging
import time
from contextlib import ExitStack
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from roadgaze import __version__
from roadgaze.config import Config
from roadgaze.errors import RoadgazeError
from roadgaze.fleet.drives import Drive
from roadgaze.fleet.recorder import DriveRecorder
from roadgaze.fleet.results import DriveResult
from roadgaze.fleet.tables import (
    AtomicParquetWriter,
    alerts_schema,
    frames_schema,
    read_drive_metadata,
)
from roadgaze.pipeline import StopSignal

log = logging.getLogger(__name__)

HASH_CHUNK_BYTES = 1 << 20


@dataclass(frozen=True, slots=True)
class DriveTask:
    """Everything a worker needs for one drive (picklable: it travels to worker processes)."""

    drive: Drive
    out_dir: Path
    config: Config
    content_hash: bool = False
    """Fingerprint the input by its SHA-256 instead of its size and modification time."""
    version: str = __version__
    """The roadgaze version of the batch; a worker with another version refuses the drive."""
    speed_kmh: float | None = None
    """One vehicle speed for every drive (`--speed-kmh`) instead of their speed tracks."""


def speed_fingerprint(task: DriveTask) -> dict[str, Any]:
    """What the drive's vehicle speed depends on: the constant, or the track file's size and
    modification time (its SHA-256 with `content_hash`); never raises (a bad track fails the
    drive when it runs)."""
    from roadgaze.speed import track_beside

    if task.speed_kmh is not None:
        return {"kmh": task.speed_kmh}
    try:
        path = task.drive.speed_track or track_beside(task.drive.path)
        if path is None:
            return {}
        stat = path.stat()
        found: dict[str, Any] = {"track": path.name, "size": stat.st_size}
        found["mtime_ns"] = stat.st_mtime_ns
        if task.content_hash:
            found["sha256"] = hashlib.sha256(path.read_bytes()).hexdigest()
        return found
    except (RoadgazeError, OSError) as exc:
        return {"error": str(exc)}


def output_paths(out_dir: Path, drive_id: str) -> tuple[Path, Path]:
    """`frames/<drive_id>.parquet` and `alerts/<drive_id>.parquet` under `out_dir`."""
    return out_dir / "frames" / f"{drive_id}.parquet", out_dir / "alerts" / f"{drive_id}.parquet"


def config_hash(config: Config) -> str:
    """A short hash of the settings that change a drive's records."""
    sections = {
        name: getattr(config, name).model_dump(mode="json")
        for name in ("geometry", "landmarks", "smoothing", "monitor")
    }
    return hashlib.sha256(json.dumps(sections, sort_keys=True).encode()).hexdigest()[:16]


def fingerprint_of(task: DriveTask) -> dict[str, Any]:
    """What the outputs of a drive depend on; raises OSError when the input cannot be read."""
    drive = task.drive
    stat = drive.path.stat()
    source: dict[str, Any] = {"size": stat.st_size, "mtime_ns": stat.st_mtime_ns}
    if task.content_hash:
        digest = hashlib.sha256()
        with drive.path.open("rb") as handle:
            while chunk := handle.read(HASH_CHUNK_BYTES):
                digest.update(chunk)
        source["sha256"] = digest.hexdigest()
    return {
        "input": source,
        "version": task.version,
        "config": config_hash(task.config),
        "drive": [drive.driver_id, drive.vehicle_id, DriveResult.of(drive, "ok").start_time],
        "speed": speed_fingerprint(task),
    }


def fingerprints_match(stored: Any, current: dict[str, Any], content_hash: bool) -> bool:
    """Same version, configuration and metadata, and the same input: the same SHA-256 and size
    with `content_hash`, else the same size and modification time."""
    if not isinstance(stored, dict) or not isinstance(stored.get("input"), dict):
        return False
    if any(stored.get(key) != current.get(key) for key in ("version", "config", "drive", "speed")):
        return False
    keys = ("size", "sha256") if content_hash else ("size", "mtime_ns")
    return all(stored["input"].get(key) == current["input"][key] for key in keys)


def find_done(task: DriveTask, fingerprint: dict[str, Any] | None = None) -> DriveResult | None:
    """The stored result of a drive whose outputs exist and match; None when it must run."""
    try:
        current = fingerprint if fingerprint is not None else fingerprint_of(task)
    except OSError:
        return None
    frames_path, alerts_path = output_paths(task.out_dir, task.drive.drive_id)
    frames_meta, alerts_meta = read_drive_metadata(frames_path), read_drive_metadata(alerts_path)
    if frames_meta is None or alerts_meta is None or "summary" not in frames_meta:
        return None
    if not all(
        fingerprints_match(meta.get("fingerprint"), current, task.content_hash)
        for meta in (frames_meta, alerts_meta)
    ):
        return None
    try:
        stored = DriveResult.from_json(frames_meta["summary"])
    except (TypeError, ValueError):
        return None
    return replace(stored, path=str(task.drive.path), resumed=True)


_stop: StopSignal | None = None


def use_stop_signal(stop: StopSignal | None) -> None:
    """Let `stop` end the drive in progress between two frames (a worker process sets this)."""
    global _stop
    _stop = stop


def one_line(exc: BaseException, limit: int = 300) -> str:
    """An exception as one line: its message (its first line for a long one, e.g. a remote
    traceback), prefixed with its type unless it is a `RoadgazeError`."""
    lines = str(exc).strip().splitlines() or [""]
    text = " ".join(lines[0].split()) if len(lines) > 3 else " ".join(" ".join(lines).split())
    text = text if isinstance(exc, RoadgazeError) else f"{type(exc).__name__}: {text}"
    return text if len(text) <= limit else text[: limit - 3] + "..."


def process_drive(task: DriveTask) -> DriveResult:
    """Run one drive and write its outputs; never raises for a bad drive (see the module doc).

    A KeyboardInterrupt (Ray's cancellation) passes through after the temporary files are gone.
    """
    started = time.perf_counter()
    drive = task.drive
    if task.version != __version__:
        return DriveResult.of(
            drive,
            "failed",
            error=f"this worker runs roadgaze {__version__}, the batch {task.version}; "
            "install the same version everywhere",
        )
    try:
        fingerprint = fingerprint_of(task)
    except FileNotFoundError:
        return DriveResult.of(drive, "failed", error=f"video file {drive.path} not found")
    except OSError as exc:
        reason = exc.strerror or str(exc)
        return DriveResult.of(drive, "failed", error=f"cannot read video {drive.path}: {reason}")
    done = find_done(task, fingerprint)
    if done is not None:
        return done
    if fingerprint["input"]["size"] == 0:
        return DriveResult.of(drive, "failed", error=f"video {drive.path} is empty (0 bytes)")
    try:
        return _run_drive(task, fingerprint, started)
    except RoadgazeError as exc:
        return DriveResult.of(drive, "failed", error=one_line(exc))
    except Exception as exc:
        log.exception("drive %s failed", drive.drive_id)
        return DriveResult.of(drive, "failed", error=one_line(exc))


def _run_drive(task: DriveTask, fingerprint: dict[str, Any], started: float) -> DriveResult:
    from roadgaze.capture import open_file
    from roadgaze.pipeline import RunOptions, build_run

    drive, config = task.drive, task.config
    frames_path, alerts_path = output_paths(task.out_dir, drive.drive_id)
    constant = {
        "drive_id": drive.drive_id,
        "driver_id": drive.driver_id,
        "vehicle_id": drive.vehicle_id,
        "start_time": drive.start_time,
    }
    options = RunOptions(
        str(drive.path),
        command="batch",
        speed_track=drive.speed_track,
        speed_kmh=task.speed_kmh,
        track_beside=True,
        quiet=True,
    )
    with ExitStack() as stack:
        frames = stack.enter_context(AtomicParquetWriter(frames_path, frames_schema(), constant))
        alerts = stack.enter_context(AtomicParquetWriter(alerts_path, alerts_schema(), constant))
        recorder = DriveRecorder(frames, alerts)
        source = open_file(drive.path, config)
        run = stack.enter_context(build_run(config, options, source=source, sinks=(recorder,)))
        startup_s = time.perf_counter() - started
        summary = run.run(stop=_stop)
        if _stop is not None and _stop.is_set():
            return DriveResult.of(drive, "interrupted", error="stopped before the end")
        if summary.frames == 0:
            return DriveResult.of(drive, "failed", error=f"video {drive.path} has no frame")
        filled, offline_problem = recorder.offline_columns(config.smoothing)
        warnings = [text for text in (summary.source_status.message, offline_problem) if text]
        result = recorder.result(
            drive,
            period_s=1.0 / source.info.fps if source.info.fps else 0.0,
            warning="; ".join(warnings) or None,
            processing_fps=summary.fps,
            startup_s=startup_s,
        )
        alerts.commit({"fingerprint": fingerprint})
        result = replace(result, wall_s=round(time.perf_counter() - started, 3))
        frames.commit({"fingerprint": fingerprint, "summary": result.to_json()}, filled)
        return result
