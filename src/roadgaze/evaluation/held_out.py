"""The issue-21 acceptance check on real faces: Pointing'04 stills held as glances in a 15 fps clip.

Each case is one clip of one subject: the frontal still (yaw 0, pitch 0) for `LEAD_S` seconds, so
the neutral pose and the eyes are learned, then the still of the look held for the case's
duration, then the frontal still again for `TAIL_S`, cut abruptly. The clip runs through the
production pipeline (MediaPipe, the yaw model, the smoother, the monitor with the default
configuration) at the case's vehicle speed, and the case passes when

- a look that must warn raises a distraction alert (`long_distraction`) `WARN_MIN_S` to
  `WARN_MAX_S` after the look starts (ADDW above 50 km/h: 3.5 s, plus one frame and the
  pipeline's delay), and
- a look that must not warn raises no alert at all (anything but `cleared`).

`python scripts/held-out-check.py` runs every case for every development subject and prints the
pass rate per case with the measured warning times; tests/evaluation/test_held_out.py runs a
subset, one case with the speed on the Zenoh bus.
"""

from __future__ import annotations

import csv
import tempfile
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

from roadgaze.config import Config
from roadgaze.config.support import SUPPORT_RAISE_MAX_S
from roadgaze.errors import DatasetError
from roadgaze.monitor.behaviours.support import HEIGHTENED, support_output
from roadgaze.monitor.protocols.support import FORWARD
from roadgaze.types import Alert, Frame, FrameRecord

__all__ = [
    "CASES",
    "CLIP_FPS",
    "Case",
    "CaseResult",
    "Stills",
    "load_stills",
    "run_case",
    "write_clip",
]

CLIP_FPS = 15
LEAD_S = 4.0
"""Frontal still before the look: the neutral pose and the eyes' calibration are learned here."""
TAIL_S = 3.0
WARN_MIN_S = 1.5
WARN_MAX_S = 3.6
"""The window after the look's start in which a warning must come (the issue's Done when)."""
DISTRACTION_KINDS = ("long_distraction",)
SUPPORT_MAX_S = SUPPORT_RAISE_MAX_S
"""Forward support must be heightened within this long of the look's start."""


@dataclass(frozen=True, slots=True)
class Case:
    """One look: the still's yaw and pitch (degrees, the project's convention: yaw > 0 to the
    driver's left, pitch > 0 up), how long it is held (s), the speed (km/h) and whether a
    distraction warning must come."""

    name: str
    yaw_deg: int
    pitch_deg: int
    look_s: float
    speed_kmh: float
    warns: bool


CASES: tuple[Case, ...] = (
    Case("left75_4s_70", 75, 0, 4.0, 70.0, True),
    Case("right75_4s_70", -75, 0, 4.0, 70.0, True),
    Case("left90_4s_70", 90, 0, 4.0, 70.0, True),
    Case("right90_4s_70", -90, 0, 4.0, 70.0, True),
    Case("left60_4s_70", 60, 0, 4.0, 70.0, True),
    Case("right60_4s_70", -60, 0, 4.0, 70.0, True),
    Case("lap30_4s_70", 0, -30, 4.0, 70.0, True),
    Case("lap60_4s_70", 0, -60, 4.0, 70.0, True),
    Case("left_mirror30_1.5s_70", 30, 0, 1.5, 70.0, False),
    Case("left_mirror45_1.5s_70", 45, 0, 1.5, 70.0, False),
    Case("right_mirror30_1.5s_70", -30, 0, 1.5, 70.0, False),
    Case("right_mirror45_1.5s_70", -45, 0, 1.5, 70.0, False),
    Case("lap60_8s_10", 0, -60, 8.0, 10.0, False),
    Case("lap30_8s_10", 0, -30, 8.0, 10.0, False),
)


@dataclass(frozen=True, slots=True)
class Stills:
    """One subject's stills of one series: (yaw_deg, pitch_deg) -> image path."""

    subject: int
    series: int
    paths: dict[tuple[int, int], Path]


def load_stills(dataset_dir: Path) -> list[Stills]:
    """Every (subject, series) of a Pointing'04 folder with `ground_truth.csv`
    (file,yaw_deg,pitch_deg,...,subject,series). Raises `DatasetError` when it is missing."""
    csv_path = dataset_dir / "ground_truth.csv"
    if not csv_path.is_file():
        raise DatasetError(f"{csv_path} not found")
    groups: dict[tuple[int, int], dict[tuple[int, int], Path]] = {}
    with csv_path.open(newline="", encoding="utf-8") as stream:
        for row in csv.DictReader(stream):
            key = (int(row["subject"]), int(row["series"]))
            pose = (round(float(row["yaw_deg"])), round(float(row["pitch_deg"])))
            groups.setdefault(key, {})[pose] = dataset_dir / row["file"]
    return [Stills(s, series, paths) for (s, series), paths in sorted(groups.items())]


def write_clip(path: Path, stills: Stills, case: Case) -> float:
    """The case's clip (MJPG); returns the time (s) at which the look starts."""
    import cv2

    frontal = cv2.imread(str(stills.paths[(0, 0)]))
    look = cv2.imread(str(stills.paths[(case.yaw_deg, case.pitch_deg)]))
    if frontal is None or look is None:
        raise DatasetError(f"subject {stills.subject}: a still of {case.name} cannot be read")
    height, width = frontal.shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), CLIP_FPS, (width, height))
    try:
        for image, seconds in ((frontal, LEAD_S), (look, case.look_s), (frontal, TAIL_S)):
            for _ in range(round(seconds * CLIP_FPS)):
                writer.write(image)
    finally:
        writer.release()
    return round(LEAD_S * CLIP_FPS) / CLIP_FPS


@dataclass(slots=True)
class _Collect:
    alerts: list[tuple[float, str, str]] = field(default_factory=list)
    zones: list[str | None] = field(default_factory=list)
    yaws: list[float | None] = field(default_factory=list)
    support: list[str | None] = field(default_factory=list)

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        del frame
        for alert in record.alerts:
            self.on_alert(alert)
        self.zones.append(record.verdict.zone if record.verdict is not None else None)
        self.yaws.append(record.sample.yaw_deg)
        forward = support_output(record.verdict, FORWARD)
        self.support.append(None if forward is None else forward.value)

    def on_alert(self, alert: Alert) -> None:
        self.alerts.append((alert.t_s, alert.kind.value, alert.reason))

    def close(self) -> None:
        pass


@dataclass(frozen=True, slots=True)
class CaseResult:
    """A case run on one subject: the alerts (time from the look's start (s), kind, reason),
    the zones read during the look, whether it passed and why not."""

    case: Case
    subject: int
    series: int
    alerts: tuple[tuple[float, str, str], ...]
    look_zones: tuple[str | None, ...]
    look_yaw_deg: float | None
    """The median smoothed yaw in the look's second half (None: no face)."""
    support_s: float | None = None
    """When forward support turned heightened, from the look's start (s; None: it did not)."""
    support_before: str | None = None
    """Forward support on the frame before the look (`normal` when the driver was seen
    watching the road long enough)."""

    @property
    def warn_s(self) -> float | None:
        """When the first distraction alert came, from the look's start (s)."""
        times = [t for t, kind, _ in self.alerts if kind in DISTRACTION_KINDS]
        return min(times) if times else None

    @property
    def why_failed(self) -> str:
        """'' when the case passed, else what went wrong."""
        if self.case.warns:
            warn = self.warn_s
            if warn is None:
                return "no warning"
            if not WARN_MIN_S <= warn <= WARN_MAX_S:
                return f"warned at {warn:.2f} s"
            return ""
        raised = [kind for _, kind, _ in self.alerts if kind != "cleared"]
        return f"raised {','.join(raised)}" if raised else ""

    @property
    def passed(self) -> bool:
        return not self.why_failed

    @property
    def support_failed(self) -> str:
        """'' when forward support was normal before the look and heightened within
        `SUPPORT_MAX_S` of its start, else what went wrong (every look leaves the road)."""
        if self.support_before != "normal":
            return f"support {self.support_before} before the look"
        if self.support_s is None:
            return "support not raised"
        if self.support_s > SUPPORT_MAX_S + 1e-6:
            return f"support raised at {self.support_s:.2f} s"
        return ""


def run_case(
    stills: Stills,
    case: Case,
    config: Config | None = None,
    folder: Path | None = None,
) -> CaseResult:
    """One case through the in-process pipeline with a constant speed (`--speed-kmh`)."""
    from roadgaze.pipeline import RunOptions, build_run

    config = config if config is not None else Config()
    with tempfile.TemporaryDirectory(dir=folder) as tmp:
        clip = Path(tmp) / f"s{stills.subject}_{case.name}.avi"
        look_t_s = write_clip(clip, stills, case)
        collect = _Collect()
        options = RunOptions(str(clip), command="held-out", speed_kmh=case.speed_kmh, quiet=True)
        with build_run(config, options, sinks=(collect,)) as run:
            run.run()
    result = result_of(stills, case, look_t_s, collect.alerts, collect.zones, collect.yaws)
    return with_support(result, look_t_s, collect.support)


def result_of(
    stills: Stills,
    case: Case,
    look_t_s: float,
    alerts: Iterable[tuple[float, str, str]],
    zones: Sequence[str | None],
    yaws: Sequence[float | None],
) -> CaseResult:
    """A case's result from per-frame zones and yaws and the alerts (times on the clip's)."""
    first = round(look_t_s * CLIP_FPS)
    last = first + round(case.look_s * CLIP_FPS)
    half = [y for y in yaws[(first + last) // 2 : last] if y is not None]
    return CaseResult(
        case=case,
        subject=stills.subject,
        series=stills.series,
        alerts=tuple((t - look_t_s, kind, reason) for t, kind, reason in alerts),
        look_zones=tuple(zones[first:last]),
        look_yaw_deg=sorted(half)[len(half) // 2] if half else None,
    )


def with_support(result: CaseResult, look_t_s: float, support: Sequence[str | None]) -> CaseResult:
    """`result` with the forward support per frame (`support`) measured against the look."""
    first = round(look_t_s * CLIP_FPS)
    before = support[first - 1] if 0 < first <= len(support) else None
    raised = next((i for i in range(first, len(support)) if support[i] == HEIGHTENED), None)
    support_s = None if raised is None else (raised - first) / CLIP_FPS
    return replace(result, support_s=support_s, support_before=before)
