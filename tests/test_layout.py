"""The source tree reads as the pipeline: pure stages stay pure, files stay small, folders say
what they do and export their public names."""

from __future__ import annotations

import ast
import importlib
import subprocess
import sys

import pytest

from repo_paths import SRC, child_env

PACKAGE = SRC / "roadgaze"
PURE_MODULES = (
    "roadgaze.types",
    "roadgaze.pose.geometry",
    "roadgaze.pose.smoothing",
    "roadgaze.pose.mounting",
    "roadgaze.pose",
    "roadgaze.monitor",
    "roadgaze.monitor.eyes",
    "roadgaze.monitor.eye_rules",
    "roadgaze.monitor.behaviours",
    "roadgaze.monitor.protocols",
    "roadgaze.monitor.neutral",
    "roadgaze.transport.messages",
    "roadgaze.transport.keys",
    "roadgaze.transport.speed",
    "roadgaze.speed",
    "roadgaze.transport.vss",
    "roadgaze.landmarks.features",
    "roadgaze.landmarks.driver",
    "roadgaze.landmarks.driver_track",
    "roadgaze.landmarks.seat",
    "roadgaze.capture.mcap_driver",
    "roadgaze.landmarks.eyes",
    "roadgaze.config",
    "roadgaze.eye_records",
    "roadgaze.hand_records",
    "roadgaze.mounting",
    "roadgaze.evaluation.stats",
    "roadgaze.synth.timeline",
)
"""Pose maths, the monitor, the message schemas and the feature maths: numpy and pydantic only."""
HEAVY = ("cv2", "mediapipe", "zenoh")
MAX_LINES = 400
MAX_FOLD_LINES = 60
"""The monitor's own step (`roadgaze.monitor.inattention.step`): a fold over the behaviours."""
MAX_MONITOR_FUNCTION_LINES = 80
STAGES: tuple[tuple[str, ...], ...] = (
    (
        "errors",
        "eye_records",
        "types",
        "logs",
        "csv_rows",
        "config",
        "mounting",
        "hand_records",
        "threads",
    ),
    ("speed",),
    ("capture",),
    ("landmarks",),
    ("pose", "geometry"),
    ("phone",),
    ("monitor",),
    ("transport", "outputs", "security"),
    ("pipeline",),
    ("service", "daemon"),
    ("doctor",),
    ("evaluation",),
    ("synth",),
    ("conformance", "fleet", "demo"),
    ("benchmark",),
    ("commands",),
    ("cli",),
    ("__main__",),
)
"""The order of the package's top-level modules and folders: the pipeline's stages (capture ->
landmarks -> pose -> phone (the judgement over hands, face and head pose) -> monitor ->
transport and outputs -> pipeline -> service), after the vocabulary every stage shares, then the
tools around the service and the command line. Each imports only from its own stage and earlier
ones. `speed` (the vehicle's speed: tracks, bus values, the one range check) comes before capture,
which reads a drive's track beside its video. `geometry` is the old path of pose.geometry."""
KNOWN_UPWARD: dict[tuple[str, str], str] = {}
"""Imports from a stage to a later one that are known and owned: (file under roadgaze/, the
later unit) -> why it is still here."""
FOLDERS = sorted(p for p in PACKAGE.iterdir() if p.is_dir() and (p / "__init__.py").is_file())


def test_pure_modules_import_no_opencv_mediapipe_or_zenoh() -> None:
    """One interpreter imports them in turn: the first that pulls in a heavy module is named."""
    code = (
        "import importlib, sys\n"
        f"for module in {PURE_MODULES!r}:\n"
        "    importlib.import_module(module)\n"
        f"    bad = sorted({set(HEAVY)!r} & set(sys.modules))\n"
        "    if bad:\n"
        "        print(module, 'imports', ' '.join(bad)); sys.exit(1)\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        timeout=120,
        env=child_env(),
        check=False,
    )
    assert result.returncode == 0, result.stdout + result.stderr


def test_no_source_file_is_over_400_lines() -> None:
    long_files = {
        str(path.relative_to(SRC)): count
        for path in PACKAGE.rglob("*.py")
        if (count := len(path.read_text(encoding="utf-8").splitlines())) > MAX_LINES
    }
    assert long_files == {}


@pytest.mark.parametrize("folder", FOLDERS, ids=lambda path: path.name)
def test_each_folder_states_its_job_in_one_line_and_exports_its_names(folder: object) -> None:
    init = folder / "__init__.py"  # type: ignore[operator]
    tree = ast.parse(init.read_text(encoding="utf-8"))
    docstring = ast.get_docstring(tree)
    assert docstring is not None and "\n" not in docstring.strip(), f"{init}: one-line docstring"
    module = importlib.import_module(f"roadgaze.{folder.name}")  # type: ignore[attr-defined]
    exported = getattr(module, "__all__", None)
    assert exported, f"{init} has no __all__"
    for name in exported:
        assert hasattr(module, name), f"roadgaze.{folder.name}.{name} is exported but missing"


def test_the_yaw_models_stay_importable_from_their_old_path() -> None:
    from roadgaze.geometry import YAW_MODELS as OLD
    from roadgaze.pose.geometry import YAW_MODELS

    assert OLD is YAW_MODELS and list(OLD) == [
        "cylindrical",
        "ellipsoidal",
        "ce",
        "center_ce",
        "boundary_ce",
    ]


def _imported_units(tree: ast.AST) -> set[str]:
    """The roadgaze units (top-level module or folder) a module imports, anywhere in it
    (function-level and `TYPE_CHECKING` imports count: they are dependencies too)."""
    units = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names = [node.module] + [f"{node.module}.{alias.name}" for alias in node.names]
        elif isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        else:
            continue
        units.update(name.split(".")[1] for name in names if name.startswith("roadgaze."))
    return units


def test_each_stage_imports_only_from_itself_and_earlier_stages() -> None:
    stage_of = {unit: index for index, units in enumerate(STAGES) for unit in units}
    units = {p.stem if p.is_file() else p.name for p in PACKAGE.iterdir()}
    units = {u for u in units if (PACKAGE / u).is_dir() or (PACKAGE / f"{u}.py").is_file()}
    units -= {"__init__", "__pycache__"}
    assert sorted(units - set(stage_of)) == [], "place every module and folder in STAGES"
    upward = []
    for path in sorted(PACKAGE.rglob("*.py")):
        relative = path.relative_to(PACKAGE)
        unit = relative.parts[0].removesuffix(".py")
        if unit == "__init__":
            continue
        for target in _imported_units(ast.parse(path.read_text(encoding="utf-8"))):
            later = target in stage_of and stage_of[target] > stage_of[unit]
            if later and (relative.as_posix(), target) not in KNOWN_UPWARD:
                upward.append(f"{relative.as_posix()} imports roadgaze.{target}")
    assert upward == []


def test_the_known_upward_imports_still_exist() -> None:
    """An exception that no longer applies is removed, so it cannot hide a new one."""
    for (file, target), why in KNOWN_UPWARD.items():
        tree = ast.parse((PACKAGE / file).read_text(encoding="utf-8"))
        assert target in _imported_units(tree), f"{file} no longer imports {target} ({why})"


def _functions(path: object) -> list[tuple[str, int]]:
    tree = ast.parse(path.read_text(encoding="utf-8"))  # type: ignore[attr-defined]
    return [
        (node.name, node.end_lineno - node.lineno + 1)  # type: ignore[operator]
        for node in ast.walk(tree)
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
    ]


def test_the_monitor_step_is_a_short_fold_and_no_monitor_function_is_long() -> None:
    monitor = PACKAGE / "monitor"
    fold = dict(_functions(monitor / "inattention.py"))["step"]
    assert fold <= MAX_FOLD_LINES, f"monitor.inattention.step is {fold} lines"
    long_functions = {
        f"{path.relative_to(monitor).as_posix()}:{name}": lines
        for path in sorted(monitor.rglob("*.py"))
        for name, lines in _functions(path)
        if lines > MAX_MONITOR_FUNCTION_LINES
    }
    assert long_functions == {}
