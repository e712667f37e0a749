"""Doctor checks of the software: versions, which OpenCV build `cv2` really is, EGL/GLES.

Every OpenCV distribution installs the same `cv2/` folder: with two installed (roadgaze 0.1
asked for `opencv-python-headless` beside mediapipe's `opencv-contrib-python`) the last one
installed wins, `pip check` says nothing, and uninstalling one breaks `import cv2`. roadgaze now
asks for the one mediapipe requires, so a plain install has one. The files on disk are matched
against each distribution's RECORD (SHA-256 of the `cv2` binary) to tell which build is really
loaded. `libmediapipe.so`
needs `libEGL.so.1` and `libGLESv2.so.2` even on the CPU.
"""

from __future__ import annotations

import base64
import ctypes
import ctypes.util
import hashlib
import importlib
import importlib.metadata
import platform
import sys
from pathlib import Path

from roadgaze import __version__
from roadgaze.doctor.report import Check, Status

KEY_PACKAGES = (
    "mediapipe",
    "ai-edge-litert",
    "eclipse-zenoh",
    "numpy",
    "filterpy",
    "pydantic",
    "matplotlib",
    "tqdm",
    "scikit-image",
)
"""roadgaze's dependencies besides OpenCV (which has its own check); ai-edge-litert runs the
default landmark engine (without it the MediaPipe engine runs, with a warning)."""
IMPORTS = {
    "mediapipe": "mediapipe",
    "ai_edge_litert.interpreter": "ai-edge-litert",
    "zenoh": "eclipse-zenoh",
    "cv2": "opencv-contrib-python",
}
"""Modules whose import is tried, with the distribution that provides them."""
OPENCV_DISTRIBUTIONS = (
    "opencv-contrib-python",
    "opencv-python-headless",
    "opencv-python",
    "opencv-contrib-python-headless",
)
"""Every distribution that installs `cv2/`."""
GL_LIBRARIES = (("EGL", "libEGL.so.1", "libegl1"), ("GLESv2", "libGLESv2.so.2", "libgles2"))
"""(find_library name, soname libmediapipe.so loads, Debian/Ubuntu package)."""


def distribution_version(name: str) -> str | None:
    """The installed version of distribution `name`, None when it is not installed."""
    try:
        return importlib.metadata.version(name)
    except importlib.metadata.PackageNotFoundError:
        return None


def import_error(module: str) -> str | None:
    """None when `module` imports, else the error."""
    try:
        importlib.import_module(module)
    except Exception as exc:  # ImportError, or OSError from a missing shared library
        return f"{type(exc).__name__}: {exc}"
    return None


def check_versions() -> list[Check]:
    checks = [
        Check(
            "roadgaze",
            Status.OK,
            f"roadgaze {__version__}, Python {platform.python_version()} "
            f"({sys.executable}), {platform.platform()}",
        )
    ]
    versions = {name: distribution_version(name) for name in KEY_PACKAGES}
    found = ", ".join(f"{name} {version}" for name, version in versions.items() if version)
    checks.append(Check("packages", Status.OK, found))
    for name, version in versions.items():
        if version is None:
            checks.append(
                Check("packages", Status.FAIL, f"{name} is not installed", f"pip install {name}")
            )
    for module, distribution in IMPORTS.items():
        problem = import_error(module)
        if problem is not None:
            fix = (
                "install the libraries it names (see the egl line)"
                if "lib" in problem and ".so" in problem
                else f"pip install --force-reinstall {distribution}"
            )
            checks.append(Check("imports", Status.FAIL, f"import {module}: {problem}", fix))
    return checks


def _record_hash(distribution: str, relative: str) -> str | None:
    """The SHA-256 (urlsafe base64, as in RECORD) a distribution installed at `relative`."""
    try:
        files = importlib.metadata.distribution(distribution).files or []
    except importlib.metadata.PackageNotFoundError:
        return None
    for file in files:
        if str(file) == relative and file.hash is not None and file.hash.mode == "sha256":
            return str(file.hash.value)
    return None


def _file_hash(path: Path) -> str:
    digest = hashlib.sha256(path.read_bytes()).digest()
    return base64.urlsafe_b64encode(digest).rstrip(b"=").decode("ascii")


def opencv_fix(installed: dict[str, str]) -> str:
    """The commands that leave only the build mediapipe requires (`opencv-contrib-python`), at
    the version installed (a headless image swaps in `opencv-contrib-python-headless` instead:
    docs/deployment.md)."""
    keep = "opencv-contrib-python"
    version = installed.get(keep) or next(iter(installed.values()), "")
    pin = f"=={version}" if version else ""
    uninstall = f"pip uninstall -y {' '.join(sorted(installed))} && " if installed else ""
    return f"{uninstall}pip install --no-deps --force-reinstall {keep}{pin}"


def check_opencv() -> list[Check]:
    problem = import_error("cv2")
    if problem is not None:
        return [Check("opencv", Status.FAIL, f"import cv2: {problem}", opencv_fix({}))]
    import cv2

    installed = {
        name: version
        for name in OPENCV_DISTRIBUTIONS
        if (version := distribution_version(name)) is not None
    }
    package_dir = Path(cv2.__file__).parent
    binaries = sorted(package_dir.glob("cv2*.so")) + sorted(package_dir.glob("python-3*/cv2*.so"))
    owner = "unknown (no cv2 binary found)"
    if binaries:
        binary = binaries[0]
        relative = f"cv2/{binary.relative_to(package_dir).as_posix()}"
        actual = _file_hash(binary)
        owners = [name for name in installed if _record_hash(name, relative) == actual]
        owner = " or ".join(f"{name} {installed[name]}" for name in owners) or "none of them"
    build = cv2.getBuildInformation()
    gui = next(
        (line.split(":", 1)[1].strip() for line in build.splitlines() if "GUI:" in line), "?"
    )
    kind = "headless" if gui.upper() in ("NONE", "") else f"GUI {gui}"
    contrib = "contrib modules" if hasattr(cv2, "xfeatures2d") else "no contrib modules"
    summary = f"cv2 {cv2.__version__} is the files of {owner} ({kind}, {contrib}) in {package_dir}"
    if owner == "none of them":
        return [Check("opencv", Status.FAIL, summary + ": a mix of two installs",
                      opencv_fix(installed))]  # fmt: skip
    checks = [Check("opencv", Status.OK, summary)]
    others = sorted(name for name in installed if not owner.startswith(f"{name} "))
    if len(set(installed.values())) > 1:
        checks.append(
            Check("opencv", Status.FAIL, f"different versions share cv2/: {installed}",
                  opencv_fix(installed))
        )  # fmt: skip
    elif others:
        checks.append(
            Check(
                "opencv",
                Status.WARN,
                f"{', '.join(f'{name} {installed[name]}' for name in others)} also installed "
                "into cv2/: whichever is installed last replaces the other's files",
                opencv_fix(installed) + "  (keeps the build mediapipe requires; README, OpenCV)",
            )
        )
    return checks


def load_library(soname: str) -> str | None:
    """None when the shared library loads, else the loader's message."""
    try:
        ctypes.CDLL(soname)
    except OSError as exc:
        return str(exc)
    return None


def check_egl() -> list[Check]:
    checks = []
    for name, soname, package in GL_LIBRARIES:
        found = ctypes.util.find_library(name)
        problem = load_library(soname)
        if problem is None:
            checks.append(Check("egl", Status.OK, f"{soname} loads (found: {found})"))
        else:
            checks.append(
                Check(
                    "egl",
                    Status.FAIL,
                    f"{soname} does not load ({problem}); libmediapipe.so needs it, even on CPU",
                    f"install the system package {package} (apt-get install {package})",
                )
            )
    return checks
