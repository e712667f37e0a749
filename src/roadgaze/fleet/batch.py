"""A batch: every drive through an executor, resumable, with the fleet summary and report at the
end.

Output folder layout: `frames/<drive_id>.parquet`, `alerts/<drive_id>.parquet`,
`summary.parquet`, `report.html` and `batch.log` (the workers' own output). One batch at a time
may write to a folder (a lock file says so). Files left under temporary names by a killed run
are removed at the start of the next, which skips the drives already done.
"""

from __future__ import annotations

import fcntl
import os
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from roadgaze.config import Config
from roadgaze.errors import ConfigError
from roadgaze.fleet.drives import Drive
from roadgaze.fleet.executors import RAY_TIMEOUT_S, Executor, LocalExecutor, RayExecutor
from roadgaze.fleet.report import render_report
from roadgaze.fleet.results import DriveResult
from roadgaze.fleet.summary import BatchOutcome, summary_table
from roadgaze.fleet.tables import (
    remove_temporary_files,
    write_table_atomically,
    write_text_atomically,
)
from roadgaze.fleet.task import DriveTask, find_done
from roadgaze.service.signals import StopFlag, signal_handlers

SUMMARY_NAME = "summary.parquet"
REPORT_NAME = "report.html"
LOG_NAME = "batch.log"
LOCK_NAME = ".batch.lock"

EngineName = Literal["local", "ray"]


@dataclass(frozen=True, slots=True)
class BatchOptions:
    """How to run a batch (the `roadgaze batch` options)."""

    out_dir: Path
    engine: EngineName = "local"
    workers: int | None = None
    """Local: processes (default: one per core). Ray: drives in flight (default: cluster CPUs)."""
    ray_address: str | None = None
    ray_timeout_s: float = RAY_TIMEOUT_S
    """How long to wait for the Ray cluster at `ray_address` before failing."""
    content_hash: bool = False
    retries: int = 2
    progress: bool = True
    speed_kmh: float | None = None
    """One vehicle speed (km/h) for every drive instead of their speed tracks."""


@contextmanager
def batch_lock(out_dir: Path) -> Iterator[None]:
    """Hold the output folder for this batch; ConfigError when another batch holds it.

    The lock file is removed on the way out, while still held. A batch that opened the file
    just before it went checks, once it holds its lock, that the path still names the file it
    locked, and takes a fresh one otherwise, so two batches never both hold the folder.
    """
    path = out_dir / LOCK_NAME
    while True:
        try:
            out_dir.mkdir(parents=True, exist_ok=True)
            descriptor = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise ConfigError(f"cannot write to output folder {out_dir}: {exc.strerror}") from None
        try:
            fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(descriptor)
            raise ConfigError(
                f"another roadgaze batch is writing to {out_dir}; wait for it or pick another --out"
            ) from None
        if _same_file(descriptor, path):
            break
        os.close(descriptor)
    try:
        yield
    finally:
        path.unlink(missing_ok=True)
        os.close(descriptor)


def _same_file(descriptor: int, path: Path) -> bool:
    try:
        named = path.stat()
    except FileNotFoundError:
        return False
    held = os.fstat(descriptor)
    return (held.st_dev, held.st_ino) == (named.st_dev, named.st_ino)


def pinned_model(config: Config) -> Config:
    """`config` with the face landmarker model resolved once (fetched if needed) and pinned, so
    workers neither look for it nor fetch it; raises ModelError when it cannot be had."""
    from roadgaze.landmarks.model_store import resolve_model

    path = resolve_model(config.model)
    return config.model_copy(update={"model": config.model.model_copy(update={"path": path})})


def make_executor(options: BatchOptions) -> Executor:
    if options.engine == "ray":
        return RayExecutor(
            options.out_dir / LOG_NAME,
            options.ray_address,
            options.workers,
            options.retries,
            options.ray_timeout_s,
        )
    return LocalExecutor(options.out_dir / LOG_NAME, options.workers, options.retries)


class BatchProgress:
    """A tqdm bar over drives on stderr: drives done, frames/s of the batch so far, ETA."""

    def __init__(self, total: int, enabled: bool) -> None:
        from roadgaze.outputs.progress import terminal_bar

        self._bar = terminal_bar(total, "drives", "drive", enabled)
        self._start = time.perf_counter()
        self.frames = 0
        self.failed = 0

    def update(self, result: DriveResult) -> None:
        if result.status == "ok" and not result.resumed:
            self.frames += result.frames
        self.failed += result.status == "failed"
        elapsed = time.perf_counter() - self._start
        fps = self.frames / elapsed if elapsed > 0 else 0.0
        postfix = f"{fps:.0f} frames/s" + (f", {self.failed} failed" if self.failed else "")
        self._bar.set_postfix_str(postfix, refresh=False)
        self._bar.update(1)

    def stopping(self) -> None:
        self._bar.set_description_str("stopping (drives in progress end without output)")

    def close(self) -> None:
        self._bar.close()


def run_batch(drives: Sequence[Drive], config: Config, options: BatchOptions) -> BatchOutcome:
    """Run every drive not already done, then write `summary.parquet` and `report.html`.

    Raises `ConfigError` for an unusable output folder or engine and `ModelError` when the
    model cannot be had; a bad drive is never raised, it is a failed result. SIGINT/SIGTERM stop
    the batch cleanly (the outcome says `interrupted`); a second one exits at once.
    """
    out_dir = options.out_dir
    with batch_lock(out_dir):
        for folder in (out_dir, out_dir / "frames", out_dir / "alerts"):
            if folder.is_dir():
                remove_temporary_files(folder)
        (out_dir / LOG_NAME).write_text("", encoding="utf-8")
        if options.engine == "local":
            config = pinned_model(config)
        tasks = [
            DriveTask(
                drive=drive,
                out_dir=out_dir,
                config=config,
                content_hash=options.content_hash,
                speed_kmh=options.speed_kmh,
            )
            for drive in drives
        ]
        results: dict[str, DriveResult] = {}
        if not options.content_hash:  # cheap to check here: size and mtime
            for task in tasks:
                done = find_done(task)
                if done is not None:
                    results[task.drive.drive_id] = done
        to_run = [task for task in tasks if task.drive.drive_id not in results]
        stop = StopFlag()
        executor_start = time.perf_counter()
        with make_executor(options) as executor:
            startup_s = time.perf_counter() - executor_start
            run_start = time.perf_counter()
            progress = BatchProgress(len(to_run), options.progress)
            try:
                with signal_handlers(stop, log_name="roadgaze.batch", hard_exit=False):
                    for result in executor.run(to_run, stop):
                        results[result.drive_id] = result
                        progress.update(result)
                        if stop.is_set():
                            progress.stopping()
            finally:
                progress.close()
            wall_s = time.perf_counter() - run_start
        outcome = BatchOutcome(
            results=tuple(results.get(d.drive_id) or DriveResult.of(d, "pending") for d in drives),
            engine=options.engine,
            workers=executor.workers,
            wall_s=wall_s,
            startup_s=startup_s,
            interrupted=stop.is_set(),
            worker_deaths=getattr(executor, "worker_deaths", 0),
            retries=getattr(executor, "retried", 0),
        )
        write_summary(out_dir, outcome)
    return outcome


def write_summary(out_dir: Path, outcome: BatchOutcome) -> None:
    """`summary.parquet` and `report.html` of `outcome`, each written atomically."""
    write_table_atomically(out_dir / SUMMARY_NAME, summary_table(outcome.results))
    write_text_atomically(out_dir / REPORT_NAME, render_report(outcome))
