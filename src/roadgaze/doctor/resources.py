"""Doctor checks of the resources the service uses: the model file, Zenoh, the cameras."""

from __future__ import annotations

import socket
import threading
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any, TypeVar

from roadgaze.config import Config
from roadgaze.doctor.report import Check, Status

ENDPOINT_TIMEOUT_S = 1.0
"""How long a TCP connect to a configured endpoint may take."""
CAMERA_TIMEOUT_S = 3.0
"""How long opening a camera and reading one frame may take before it counts as hanging."""
T = TypeVar("T")


def explicit_model_check(config: Config, found: Path | None) -> list[Check]:
    """A WARN when `model.path` or $ROADGAZE_MODEL_PATH names a file that is not a verified model.

    `run` then does what `model_store.resolve_model` does: it uses `found` (the cache) or
    downloads, never that file, so the check names what is used instead. Nothing when no
    explicit path is set or it is the model found.
    """
    from roadgaze.landmarks.model_store import ENV_MODEL_PATH, check_file, explicit_model_path

    explicit = explicit_model_path(config.model)
    if explicit is None or explicit == found:
        return []
    problem = check_file(explicit)
    if problem is None:  # became valid since it was looked at
        return []
    origin = "model.path" if config.model.path is not None else f"${ENV_MODEL_PATH}"
    if found is not None:
        instead = f"uses {found} instead"
    elif config.model.allow_download:
        instead = "downloads the model into the cache instead"
    else:
        instead = "finds no model (next line)"
    return [
        Check(
            "model",
            Status.WARN,
            f"{origin} names {explicit}: {problem}; roadgaze run ignores it and {instead}",
            f"point {origin} at a verified face_landmarker.task, or unset it "
            "(roadgaze model verify checks it)",
        )
    ]


def check_model(config: Config) -> list[Check]:
    """The model file: where, size and SHA-256, and whether MediaPipe loads it; a WARN first
    when an explicit path names a file `run` cannot use."""
    from roadgaze.landmarks.model_store import (
        MODEL_FILE,
        MODEL_FILENAME,
        default_cache_dir,
        find_local_model,
    )

    found, tried = find_local_model(config.model)
    checks = explicit_model_check(config, found)
    if found is None:
        cache_file = default_cache_dir(config.model) / MODEL_FILENAME
        if config.model.allow_download:
            return [
                *checks,
                Check(
                    "model",
                    Status.WARN,
                    f"no model file yet ({'; '.join(tried)}); it is downloaded into {cache_file} "
                    "on first use",
                    "roadgaze model fetch (now, while there is a network)",
                ),
            ]
        return [
            *checks,
            Check(
                "model",
                Status.FAIL,
                f"no model file ({'; '.join(tried)}) and model.allow_download = false",
                "roadgaze model fetch, or place the file (see roadgaze model path)",
            ),
        ]
    checks.append(
        Check(
            "model",
            Status.OK,
            f"{found}: {found.stat().st_size:,} bytes, SHA-256 {MODEL_FILE.sha256[:12]}... "
            "verified",
        )
    )
    problem = landmarker_problem(found)
    if problem is not None:
        checks.append(Check("model", Status.FAIL, f"MediaPipe cannot load it: {problem}",
                            "see the imports and egl lines"))  # fmt: skip
    return checks


def landmarker_problem(model_path: Any) -> str | None:
    """None when the face landmarker loads the model (VIDEO mode and the default engine, as the
    service starts)."""
    from roadgaze.config import LandmarksConfig
    from roadgaze.errors import RoadgazeError

    try:
        from roadgaze.landmarks import Landmarker

        Landmarker(LandmarksConfig(), model_path, video=True).close()
    except (RoadgazeError, ImportError, OSError) as exc:
        return str(exc)
    return None


def endpoint_reachable(endpoint: str, timeout_s: float = ENDPOINT_TIMEOUT_S) -> str | None:
    """None when a TCP connection to a `tcp/HOST:PORT` (or `tls/`) endpoint succeeds, else why
    not. Raises ValueError for an endpoint this check cannot test."""
    protocol, _, address = endpoint.partition("/")
    if protocol not in ("tcp", "tls"):
        raise ValueError(f"{protocol}/ endpoints are not checked")
    address = address.split("#", 1)[0].split("?", 1)[0]
    host, _, port = address.rpartition(":")
    host = host.strip("[]")
    try:
        with socket.create_connection((host, int(port)), timeout=timeout_s):
            return None
    except ValueError:
        return f"no port in '{endpoint}'"
    except OSError as exc:
        return exc.strerror or str(exc) or type(exc).__name__


def open_session_problem(config: Config) -> tuple[str, str | None]:
    """The session `roadgaze run` would open (mode and endpoints, the rendezvous included) and
    None when it opens (and closes), else the problem."""
    from roadgaze.errors import TransportError
    from roadgaze.transport import open_session, plan_session

    plan = plan_session(config.zenoh, "daemon")
    listen, connect = list(plan.listen) or "-", list(plan.connect) or "-"
    where = f"mode {plan.mode}, listen {listen}, connect {connect}"
    try:
        open_session(plan).close()
    except TransportError as exc:
        return where, str(exc)
    return where, None


def check_zenoh(config: Config) -> list[Check]:
    zenoh = config.zenoh
    where, problem = open_session_problem(config)
    checks = []
    if problem is None:
        checks.append(Check("zenoh", Status.OK, f"a session opens ({where})"))
    else:
        checks.append(
            Check(
                "zenoh",
                Status.FAIL,
                f"no session with the configured settings ({where}): {problem}",
                "check [zenoh] in the configuration (docs/zenoh.md); a fixed listen port may "
                "already be taken by a running roadgaze or zenohd",
            )
        )
    for endpoint in zenoh.connect:
        try:
            unreachable = endpoint_reachable(endpoint)
        except ValueError as exc:
            checks.append(Check("zenoh", Status.WARN, f"connect {endpoint}: {exc}"))
            continue
        if unreachable is None:
            checks.append(Check("zenoh", Status.OK, f"connect {endpoint}: reachable (TCP)"))
        else:
            checks.append(
                Check(
                    "zenoh",
                    Status.FAIL,
                    f"connect {endpoint}: not reachable ({unreachable})",
                    "start the router or peer there (zenohd, or roadgaze run), or fix "
                    "zenoh.connect",
                )
            )
    return checks


def camera_devices() -> list[str]:
    """The V4L2 device nodes, /dev/video0 first."""
    names = [str(path) for path in Path("/dev").glob("video*")]
    return sorted(names, key=lambda name: (len(name), name))


def open_camera(device: str) -> str:
    """What OpenCV makes of a V4L2 device: its frame size, or why not (raises OSError)."""
    import cv2

    capture = cv2.VideoCapture(device, cv2.CAP_V4L2)
    try:
        if not capture.isOpened():
            raise OSError("OpenCV cannot open it (busy, not a capture node, or no permission)")
        ok, image = capture.read()
        if not ok or image is None:
            raise OSError("opens but delivers no frame")
        height, width = image.shape[:2]
        return f"{width}x{height}"
    finally:
        capture.release()


def _with_timeout(action: Callable[[], T], timeout_s: float) -> T:
    """`action()` in a thread; TimeoutError when it has not finished after `timeout_s`."""
    result: list[T] = []
    error: list[BaseException] = []

    def run() -> None:
        try:
            result.append(action())
        except BaseException as exc:
            error.append(exc)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(timeout_s)
    if thread.is_alive():
        raise TimeoutError(f"no answer within {timeout_s:g} s")
    if error:
        raise error[0]
    return result[0]


def check_cameras() -> list[Check]:
    devices = camera_devices()
    if not devices:
        return [
            Check(
                "camera",
                Status.WARN,
                "no /dev/video* device: `roadgaze run` needs a camera (or --source FILE)",
                "plug in a V4L2 camera; in a container pass it with --device /dev/video0",
            )
        ]
    checks = []
    for device in devices:
        try:
            size = _with_timeout(partial(open_camera, device), CAMERA_TIMEOUT_S)
        except (OSError, TimeoutError) as exc:
            checks.append(Check("camera", Status.WARN, f"{device}: {exc}"))
        else:
            checks.append(Check("camera", Status.OK, f"{device}: opens, first frame {size}"))
    if all(check.status is not Status.OK for check in checks):
        checks.append(
            Check("camera", Status.FAIL, "none of the video devices delivers frames",
                  "check the cable, permissions (group video) and that nothing else holds it")
        )  # fmt: skip
    return checks
