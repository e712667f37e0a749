"""`roadgaze doctor`: each check's FAIL path with its probe replaced, and one real run."""

from __future__ import annotations

import json
import socket
import subprocess
import sys
from pathlib import Path

import pytest

import roadgaze.doctor.resources as service
import roadgaze.doctor.software as software
from roadgaze.cli import main
from roadgaze.config import Config, load_config
from roadgaze.doctor import (
    Check,
    Status,
    check_cameras,
    check_egl,
    check_model,
    check_opencv,
    check_versions,
    check_zenoh,
    endpoint_reachable,
    format_checks,
    opencv_fix,
    run_checks,
    worst,
)


def statuses(checks: list[Check]) -> list[Status]:
    return [check.status for check in checks]


def test_worst_and_the_report_layout() -> None:
    checks = [
        Check("model", Status.OK, "fine"),
        Check("camera", Status.WARN, "none", "plug one in"),
        Check("zenoh", Status.FAIL, "no session", "fix it"),
    ]
    assert worst(checks) is Status.FAIL and worst(checks[:2]) is Status.WARN
    assert worst(checks[:1]) is Status.OK
    assert format_checks(checks).splitlines() == [
        "OK    model   fine",
        "WARN  camera  none",
        "              fix: plug one in",
        "FAIL  zenoh   no session",
        "              fix: fix it",
        "FAIL: 1 ok, 1 warnings, 1 failures",
    ]


def test_a_missing_package_and_a_failing_import_fail(monkeypatch: pytest.MonkeyPatch) -> None:
    real = software.distribution_version
    monkeypatch.setattr(
        software, "distribution_version", lambda name: None if name == "filterpy" else real(name)
    )
    monkeypatch.setattr(
        software,
        "import_error",
        lambda module: (
            "OSError: libEGL.so.1: cannot open shared object file"
            if module == "mediapipe"
            else None
        ),
    )
    failed = [check for check in check_versions() if check.status is Status.FAIL]
    assert [check.detail for check in failed] == [
        "filterpy is not installed",
        "import mediapipe: OSError: libEGL.so.1: cannot open shared object file",
    ]
    assert failed[0].fix == "pip install filterpy" and "egl" in (failed[1].fix or "")


def test_two_opencv_builds_in_one_folder_warn_with_the_fix(monkeypatch: pytest.MonkeyPatch) -> None:
    versions = {"opencv-python-headless": "5.0.0.93", "opencv-contrib-python": "5.0.0.93"}
    monkeypatch.setattr(software, "distribution_version", versions.get)
    monkeypatch.setattr(
        software, "_record_hash", lambda name, path: "H" if "contrib" in name else "X"
    )
    monkeypatch.setattr(software, "_file_hash", lambda path: "H")
    first, second = check_opencv()
    assert (
        first.status is Status.OK and "the files of opencv-contrib-python 5.0.0.93" in first.detail
    )
    assert second.status is Status.WARN and second.detail.startswith("opencv-python-headless")
    assert second.fix is not None and second.fix.startswith(
        "pip uninstall -y opencv-contrib-python opencv-python-headless && "
        "pip install --no-deps --force-reinstall opencv-contrib-python==5.0.0.93"
    )


@pytest.mark.parametrize(
    ("versions", "record", "expected"),
    [
        ({"opencv-python-headless": "5.0.0.93"}, "H", [Status.OK]),
        ({"opencv-python-headless": "5.0.0.93", "opencv-contrib-python": "5.0.0.93"}, "X",
         [Status.FAIL]),  # the binary on disk is nobody's: a mix of two installs
        ({"opencv-python-headless": "4.10.0.84", "opencv-contrib-python": "5.0.0.93"}, "H",
         [Status.OK, Status.FAIL]),
    ],
    ids=["one-build", "mixed-files", "two-versions"],
)  # fmt: skip
def test_opencv_verdicts(
    monkeypatch: pytest.MonkeyPatch, versions: dict[str, str], record: str, expected: list[Status]
) -> None:
    monkeypatch.setattr(software, "distribution_version", versions.get)
    monkeypatch.setattr(software, "_record_hash", lambda name, path: record)
    monkeypatch.setattr(software, "_file_hash", lambda path: "H")
    assert statuses(check_opencv()) == expected


def test_opencv_fix_keeps_the_build_mediapipe_requires_at_its_version() -> None:
    both = {"opencv-python-headless": "5.0.0.93", "opencv-contrib-python": "5.1.0.95"}
    assert opencv_fix(both) == (
        "pip uninstall -y opencv-contrib-python opencv-python-headless && "
        "pip install --no-deps --force-reinstall opencv-contrib-python==5.1.0.95"
    )
    assert opencv_fix({}) == "pip install --no-deps --force-reinstall opencv-contrib-python"


def test_this_install_has_one_opencv_and_the_doctor_passes_it() -> None:
    """The README's own install leaves one distribution in `cv2/` (0.1's two failed doctor)."""
    installed = {
        name: version
        for name in software.OPENCV_DISTRIBUTIONS
        if (version := software.distribution_version(name)) is not None
    }
    assert list(installed) == ["opencv-contrib-python"]
    assert statuses(check_opencv()) == [Status.OK]


def test_missing_gl_libraries_fail(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(software, "load_library", lambda soname: f"{soname}: cannot open")
    checks = check_egl()
    assert statuses(checks) == [Status.FAIL, Status.FAIL]
    assert [check.fix for check in checks] == [
        "install the system package libegl1 (apt-get install libegl1)",
        "install the system package libgles2 (apt-get install libgles2)",
    ]


def config_with(**model: object) -> Config:
    return Config.model_validate({"model": model})


@pytest.mark.parametrize(("allow", "expected"), [(True, Status.WARN), (False, Status.FAIL)])
def test_no_model_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, allow: bool, expected: Status
) -> None:
    monkeypatch.delenv("ROADGAZE_MODEL_PATH", raising=False)
    [check] = check_model(config_with(cache_dir=str(tmp_path), allow_download=allow))
    assert check.status is expected and str(tmp_path) in check.detail
    assert check.fix is not None and "roadgaze model fetch" in check.fix


@pytest.mark.parametrize("explicit_file", ["missing", "corrupt"])
@pytest.mark.parametrize(
    ("cached", "allow", "expected"),
    [
        (True, False, [Status.WARN, Status.OK]),
        (False, True, [Status.WARN, Status.WARN]),
        (False, False, [Status.WARN, Status.FAIL]),
    ],
)
def test_an_explicit_model_path_run_cannot_use_is_never_ok(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    explicit_file: str,
    cached: bool,
    allow: bool,
    expected: list[Status],
) -> None:
    """$ROADGAZE_MODEL_PATH naming a missing or corrupt file: doctor warns and says what `run`
    (resolve_model) uses instead; it fails only when `run` would find no model at all."""
    from roadgaze.errors import ModelError
    from roadgaze.landmarks.model_store import resolve_model

    monkeypatch.delenv("ROADGAZE_MODEL_PATH", raising=False)
    cache_dir = resolve_model(Config().model).parent if cached else tmp_path / "empty-cache"
    explicit = tmp_path / "face_landmarker.task"
    if explicit_file == "corrupt":
        explicit.write_bytes(b"not a model")
    monkeypatch.setenv("ROADGAZE_MODEL_PATH", str(explicit))
    monkeypatch.setattr(service, "landmarker_problem", lambda path: None)
    config = config_with(cache_dir=str(cache_dir), allow_download=allow)

    checks = check_model(config)

    assert statuses(checks) == expected
    warning = checks[0]
    problem = "not found" if explicit_file == "missing" else "size 11 bytes, expected 3758596"
    assert f"$ROADGAZE_MODEL_PATH names {explicit}: {problem}" in warning.detail
    assert warning.fix is not None and "ROADGAZE_MODEL_PATH" in warning.fix
    if cached:  # run really uses the cached file the warning names
        used = resolve_model(config.model, sources=[])
        assert used != explicit and f"ignores it and uses {used} instead" in warning.detail
    elif allow:
        assert "downloads the model into the cache instead" in warning.detail
    else:
        with pytest.raises(ModelError):
            resolve_model(config.model, sources=[])


def test_a_model_mediapipe_cannot_load_fails(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(service, "landmarker_problem", lambda path: "bad flatbuffer")
    checks = check_model(load_config(environ={}))
    assert statuses(checks) == [Status.OK, Status.FAIL]
    assert "verified" in checks[0].detail and "bad flatbuffer" in checks[1].detail


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


def test_endpoints_reachable_or_not() -> None:
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        port = server.getsockname()[1]
        assert endpoint_reachable(f"tcp/127.0.0.1:{port}") is None
    assert endpoint_reachable(f"tcp/127.0.0.1:{free_port()}", 0.5) is not None
    with pytest.raises(ValueError, match="udp/ endpoints are not checked"):
        endpoint_reachable("udp/127.0.0.1:7447")


def test_an_unreachable_connect_endpoint_and_a_session_that_cannot_open_fail(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    config = Config.model_validate({"zenoh": {"connect": [endpoint]}})
    monkeypatch.setattr(
        service, "open_session_problem", lambda config: ("mode peer", "cannot bind")
    )
    session, connect = check_zenoh(config)
    assert (session.status, connect.status) == (Status.FAIL, Status.FAIL)
    assert "cannot bind" in session.detail and endpoint in connect.detail


def test_cameras_none_or_none_working(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(service, "camera_devices", list)
    assert statuses(check_cameras()) == [Status.WARN]
    monkeypatch.setattr(service, "camera_devices", lambda: ["/dev/video0", "/dev/video1"])

    def broken(device: str) -> str:
        raise OSError("OpenCV cannot open it")

    monkeypatch.setattr(service, "open_camera", broken)
    assert statuses(check_cameras()) == [Status.WARN, Status.WARN, Status.FAIL]
    monkeypatch.setattr(service, "open_camera", lambda device: "640x480")
    assert statuses(check_cameras()) == [Status.OK, Status.OK]


def test_a_crashing_check_is_a_fail_line_not_a_traceback(monkeypatch: pytest.MonkeyPatch) -> None:
    def crash() -> list[Check]:
        raise RuntimeError("boom")

    monkeypatch.setattr(software, "check_egl", crash)
    egl = [check for check in run_checks(load_config(environ={})) if check.area == "egl"]
    assert [(check.status, "boom" in check.detail) for check in egl] == [(Status.FAIL, True)]


def test_exit_code_is_1_on_a_failure(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(software, "load_library", lambda soname: "missing")
    assert main(["doctor"]) == 1
    out = capsys.readouterr().out
    assert out.splitlines()[-1].startswith("FAIL: ")


def test_a_real_run(subprocess_env: dict[str, str]) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "roadgaze", "doctor", "--json"],
        capture_output=True,
        text=True,
        env=subprocess_env,
        timeout=120,
        check=False,
    )
    document = json.loads(result.stdout)
    areas = {check["area"] for check in document["checks"]}
    assert {"roadgaze", "packages", "opencv", "egl", "model", "zenoh", "camera"} <= areas
    assert document["status"] in ("OK", "WARN", "FAIL")
    assert result.returncode == (1 if document["status"] == "FAIL" else 0)
    by_area = {check["area"]: check for check in document["checks"]}
    assert by_area["zenoh"]["status"] == "OK"  # the default settings open a session
    assert by_area["model"]["status"] in ("OK", "WARN")
