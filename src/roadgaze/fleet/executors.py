"""Where the drives run: a local process pool, or Ray tasks on a cluster; the same task function.

The executor is what `batch --engine local|ray` picks (the flag keeps its name; inside the code
"engine" means the landmark engine). An executor is a context manager (start-up and shut-down)
whose `run(tasks, stop)` yields one `DriveResult` per task as drives finish, in completion
order. At most as many drives are in flight as there are workers, so a batch of any size holds a
bounded amount in memory. When `stop` is set, no further drive is started, drives in progress end
between two frames without writing anything (`interrupted`) and the others come back as
`pending`. A worker process that dies (a crash in native code, the kernel's OOM killer) costs the
drives it held one try; a drive is tried `1 + retries` times before it is reported as failed.
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import signal
import sys
import time
from collections import Counter, deque
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from pathlib import Path
from types import TracebackType
from typing import Any, Protocol

from roadgaze.errors import ConfigError, RoadgazeError
from roadgaze.fleet.ray_connect import KeeperThread, use_ray_token, wait_for_ray_head
from roadgaze.fleet.results import DriveResult
from roadgaze.fleet.task import DriveTask, one_line, process_drive, use_stop_signal
from roadgaze.pipeline import StopSignal

log = logging.getLogger("roadgaze.batch")

POLL_S = 0.2
"""How often the parent looks at `stop` while it waits for drives."""

RAY_MISSING = "the ray engine needs Ray, which is not installed: pip install 'roadgaze[ray]'"
RAY_TIMEOUT_S = 30.0
"""How long `batch --engine ray` waits for a Ray cluster at an address (`--ray-timeout`)."""
LOCAL_RAY_START_S = 180.0
"""How long starting a local Ray instance may take at most (Ray's own bound is 60 s per step; a
loaded 2-core machine took 28 s where an idle one takes about 5), unless `--ray-timeout` is
longer."""


class Executor(Protocol):
    """Runs drive tasks; see the module documentation."""

    workers: int

    def __enter__(self) -> Executor: ...

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None: ...

    def run(self, tasks: Iterable[DriveTask], stop: StopSignal) -> Iterator[DriveResult]: ...


def available_cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        return os.cpu_count() or 1


def _init_worker(stop: Any, log_path: str, warm_up: bool) -> None:
    """In each worker: Ctrl-C is the parent's business, output goes to the batch log."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    descriptor = os.open(log_path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
    os.dup2(descriptor, 1)
    os.dup2(descriptor, 2)
    os.close(descriptor)
    logging.basicConfig(
        level=logging.WARNING,
        format="%(asctime)s pid %(process)d %(name)s %(levelname)s: %(message)s",
        stream=sys.stderr,
        force=True,
    )
    use_stop_signal(stop)
    if warm_up:  # imported once per worker here, so a drive's start-up is its own
        import cv2  # noqa: F401
        from mediapipe.tasks.python import vision  # noqa: F401


def _worker_pid() -> int:
    """A warm-up call: which worker answered (after a moment, so the others get calls too)."""
    time.sleep(0.05)
    return os.getpid()


class LocalExecutor:
    """A pool of `workers` spawned processes on this machine (default: one per core).

    The workers' own output (MediaPipe, FFmpeg, Python warnings) goes to `log_path`, not to the
    terminal.
    """

    def __init__(
        self,
        log_path: Path,
        workers: int | None = None,
        retries: int = 2,
        function: Callable[[DriveTask], DriveResult] = process_drive,
    ) -> None:
        self.workers = workers if workers is not None else available_cores()
        self.retries = retries
        self.function = function
        """The task function, a module-level function (workers import it by name)."""
        self._log_path = log_path
        self._context = multiprocessing.get_context("spawn")
        self._executor: ProcessPoolExecutor | None = None
        self._worker_stop: Any = None
        self.worker_deaths = 0
        """Worker processes that died on a drive (a crash in native code, the OOM killer)."""
        self.retried = 0
        """Drives started again after their worker died."""

    def __enter__(self) -> LocalExecutor:
        self._worker_stop = self._context.Event()
        self._warm_up()
        return self

    def _warm_up(self, timeout_s: float = 120.0) -> None:
        """Start every worker process now (spawn, imports), so that start-up is not counted
        against the first drives; gives up quietly after `timeout_s`."""
        executor = self._open_executor()
        ready: set[int] = set()
        deadline = time.monotonic() + timeout_s
        while len(ready) < self.workers and time.monotonic() < deadline:
            calls = [executor.submit(_worker_pid) for _ in range(self.workers)]
            try:
                ready.update(call.result() for call in calls)
            except BrokenProcessPool:
                self._close_executor()
                raise RoadgazeError(
                    f"the batch's worker processes cannot start; see {self._log_path}"
                ) from None

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        hurry = exc_type is not None and not issubclass(exc_type, Exception)
        self._close_executor(terminate=hurry)

    def _open_executor(self) -> ProcessPoolExecutor:
        if self._executor is None:
            self._executor = ProcessPoolExecutor(
                max_workers=self.workers,
                mp_context=self._context,
                initializer=_init_worker,
                initargs=(
                    self._worker_stop,
                    str(self._log_path),
                    self.function is process_drive,
                ),
            )
        return self._executor

    def _close_executor(self, terminate: bool = False) -> None:
        executor, self._executor = self._executor, None
        if executor is None:
            return
        if terminate:  # a second Ctrl-C or SystemExit: do not wait for the drives in progress
            for process in list(getattr(executor, "_processes", {}).values()):
                process.terminate()
        executor.shutdown(wait=not terminate, cancel_futures=True)

    def _worker_died(self, drive_id: str, tries: int, retry: bool) -> None:
        """Log a worker's death on stderr and in the batch log, and count it."""
        self.worker_deaths += 1
        self.retried += int(retry)
        then = "trying it again" if retry else "giving up on it (--retries)"
        message = (
            f"batch: a worker process died while running drive {drive_id} (try {tries} of "
            f"{self.retries + 1}; a crash in native code or out of memory): {then}"
        )
        log.warning(message)
        try:
            with self._log_path.open("a", encoding="utf-8") as batch_log:
                batch_log.write(f"{time.strftime('%Y-%m-%d %H:%M:%S')} {message}\n")
        except OSError as exc:
            log.debug("batch log not written: %s", exc)

    def run(self, tasks: Iterable[DriveTask], stop: StopSignal) -> Iterator[DriveResult]:
        queue = deque(tasks)
        in_flight: dict[Future[DriveResult], DriveTask] = {}
        tries: Counter[str] = Counter()
        while queue or in_flight:
            if stop.is_set():
                self._worker_stop.set()
            else:
                executor = self._open_executor()
                while queue and len(in_flight) < self.workers:
                    task = queue.popleft()
                    in_flight[executor.submit(self.function, task)] = task
            if not in_flight:
                break
            done, _ = wait(in_flight, timeout=POLL_S, return_when=FIRST_COMPLETED)
            broken = False
            for future in done:
                task = in_flight.pop(future)
                if future.cancelled():
                    yield DriveResult.of(task.drive, "pending")
                    continue
                try:
                    yield future.result()
                except BrokenProcessPool:
                    broken = True
                    drive_id = task.drive.drive_id
                    tries[drive_id] += 1
                    retry = tries[drive_id] <= self.retries
                    self._worker_died(drive_id, tries[drive_id], retry)
                    if not retry:
                        yield DriveResult.of(
                            task.drive,
                            "failed",
                            error=f"the worker process died {tries[drive_id]} times "
                            "on this drive (a crash in native code or out of memory)",
                        )
                    else:
                        queue.appendleft(task)
            if broken:
                self._close_executor()
        for task in queue:
            yield DriveResult.of(task.drive, "pending")


@contextmanager
def stderr_to(path: Path) -> Iterator[None]:
    """Within the block, everything written to file descriptor 2 (native code included) is
    appended to `path` instead of the terminal."""
    sys.stderr.flush()
    saved = os.dup(2)
    descriptor = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
    os.dup2(descriptor, 2)
    os.close(descriptor)
    try:
        yield
    finally:
        sys.stderr.flush()
        os.dup2(saved, 2)
        os.close(saved)


def import_ray(address: str | None = None) -> Any:
    """The `ray` module; ConfigError saying how to install it when it is missing. With a cluster
    to reach (`address`, or `RAY_ADDRESS`), Ray is first told to send its authentication token
    where one is at hand (`use_ray_token`: Ray reads the mode when it loads)."""
    if address is not None or os.environ.get("RAY_ADDRESS"):
        use_ray_token(os.environ, Path.home())
    try:
        import ray
    except ImportError:
        raise ConfigError(RAY_MISSING) from None
    return ray


class RayExecutor:
    """The same task function as Ray tasks (`num_cpus=1`, retried `retries` times when a worker
    dies) on the cluster at `address`, else `RAY_ADDRESS`, else a local Ray instance.

    Ray's logs stay off the terminal: workers' output is not sent to the driver, and what Ray's
    native code prints while connecting goes to `log_path`. A Ray already initialised by the
    caller is used as it is and left running. Outputs are written by the workers: on a cluster
    the output folder must be the same shared path on every node.
    """

    def __init__(
        self,
        log_path: Path,
        address: str | None = None,
        workers: int | None = None,
        retries: int = 2,
        timeout_s: float = RAY_TIMEOUT_S,
    ) -> None:
        self.address = address
        self.timeout_s = timeout_s
        self._log_path = log_path
        self.workers = workers or 0
        self.retries = retries
        self._ray: Any = None
        self._started_here = False
        self._keeper: KeeperThread | None = None

    def __enter__(self) -> RayExecutor:
        os.environ.setdefault("RAY_BACKEND_LOG_LEVEL", "error")  # before Ray's core loads
        ray = self._ray = import_ray(self.address)
        if not ray.is_initialized():
            options: dict[str, Any] = {"log_to_driver": False, "logging_level": logging.ERROR}
            if self.address is None and not os.environ.get("RAY_ADDRESS"):
                options["include_dashboard"] = False
            where = self.address or os.environ.get("RAY_ADDRESS") or "a local instance"
            local = where == "a local instance"
            bound_s = max(self.timeout_s, LOCAL_RAY_START_S) if local else self.timeout_s
            deadline = time.monotonic() + bound_s
            if not local:
                wait_for_ray_head(where, deadline, self.timeout_s)
            try:
                with stderr_to(self._log_path):
                    keeper = KeeperThread(lambda: ray.init(address=self.address, **options))
                    self._keeper = keeper.start(deadline)
            except TimeoutError:
                raise ConfigError(
                    f"no Ray cluster answered at {where} within {bound_s:g} s "
                    f"(--ray-timeout); see {self._log_path}"
                ) from None
            except (ConnectionError, ValueError, RuntimeError) as exc:
                raise ConfigError(
                    f"cannot start or reach Ray at {where}: {one_line(exc)}"
                ) from None
            self._started_here = True
        if not self.workers:
            self.workers = max(1, int(ray.cluster_resources().get("CPU", 1)))
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        if self._started_here:
            self._ray.shutdown()
            self._started_here = False
        if self._keeper is not None:
            self._keeper.release()
            self._keeper = None

    def run(self, tasks: Iterable[DriveTask], stop: StopSignal) -> Iterator[DriveResult]:
        ray = self._ray
        remote = ray.remote(num_cpus=1, max_retries=self.retries)(process_drive)
        queue = deque(tasks)
        in_flight: dict[Any, DriveTask] = {}
        cancelled = False
        while queue or in_flight:
            if stop.is_set() and not cancelled:
                for ref in in_flight:
                    ray.cancel(ref)
                cancelled = True
            while queue and not stop.is_set() and len(in_flight) < self.workers:
                task = queue.popleft()
                in_flight[remote.remote(task)] = task
            if not in_flight:
                break
            ready, _ = ray.wait(list(in_flight), num_returns=1, timeout=POLL_S)
            for ref in ready:
                task = in_flight.pop(ref)
                try:
                    yield ray.get(ref)
                except ray.exceptions.TaskCancelledError:
                    yield DriveResult.of(task.drive, "interrupted", error="stopped before the end")
                except ray.exceptions.RayError as exc:
                    yield DriveResult.of(task.drive, "failed", error=one_line(exc))
        for task in queue:
            yield DriveResult.of(task.drive, "pending")
