"""Sinks that write what the pipeline produces: JSONL, CSV, a yaw plot, an annotated video.

Every writer is a context manager and a pipeline sink (`on_sample` / `on_frame`, `close`). A frame
record is `sample_record(sample)` plus the fields of optional `extras` callables, called in order
on the same sample (e.g. a monitor sink's `on_road` and `state`), so later stages add fields
without changing the writers.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import numpy as np
import numpy.typing as npt

from roadgaze.errors import RoadgazeError
from roadgaze.pipeline import ProcessedFrame
from roadgaze.types import ClosesOnExit, FaceFeatures, YawSample

RECORD_FIELDS = (
    "t_s",
    "frame",
    "face",
    "n_faces",
    "yaw_raw_deg",
    "yaw_deg",
    "yaw_rate_dps",
    "yaw_std_deg",
    "x_left",
    "x_right",
    "x_center",
    "roll_deg",
    "quality",
)
"""The fields of `sample_record`, in order (x_* in pixels of the roll-removed frame)."""

Extras = Callable[[YawSample], Mapping[str, Any]]


def _rounded(value: float | None, digits: int) -> float | None:
    if value is None or not math.isfinite(value):
        return None
    return round(float(value), digits)


def sample_record(sample: YawSample) -> dict[str, Any]:
    """The per-frame record as a JSON-ready dict; None (null) where there is no value."""
    features = sample.features
    return {
        "t_s": round(sample.t_s, 6),
        "frame": sample.frame,
        "face": sample.face,
        "n_faces": sample.n_faces,
        "yaw_raw_deg": _rounded(sample.yaw_raw_deg, 3),
        "yaw_deg": _rounded(sample.yaw_deg, 3),
        "yaw_rate_dps": _rounded(sample.yaw_rate_dps, 3),
        "yaw_std_deg": _rounded(sample.yaw_std_deg, 3),
        "x_left": None if features is None else _rounded(features.x_left_px, 2),
        "x_right": None if features is None else _rounded(features.x_right_px, 2),
        "x_center": None if features is None else _rounded(features.x_center_px, 2),
        "roll_deg": None if features is None else _rounded(features.roll_deg, 2),
        "quality": None if features is None else _rounded(features.quality, 3),
    }


def full_record(sample: YawSample, extras: Sequence[Extras] = ()) -> dict[str, Any]:
    record = sample_record(sample)
    for extra in extras:
        record.update(extra(sample))
    return record


def _open_for_writing(path: Path, what: str, newline: str | None = None) -> IO[str]:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        return path.open("w", encoding="utf-8", buffering=1, newline=newline)
    except OSError as exc:
        raise RoadgazeError(f"cannot write {what} {path}: {exc.strerror or exc}") from None


class _Writer(ClosesOnExit):
    """Base of the sinks that write a file: context managers closed on exit."""


class JsonlWriter(_Writer):
    """One JSON object per sample and line, flushed line by line (nothing lost on a crash).

    `target` is a path, or an open text stream (e.g. stdout) that is flushed but not closed.
    """

    def __init__(self, target: str | Path | IO[str], extras: Sequence[Extras] = ()) -> None:
        self.extras = list(extras)
        self._owned = isinstance(target, (str, Path))
        if isinstance(target, (str, Path)):
            self.path: Path | None = Path(target)
            self._file: IO[str] | None = _open_for_writing(self.path, "frame records")
        else:
            self.path = None
            self._file = target
        self.records = 0

    def on_sample(self, sample: YawSample) -> None:
        assert self._file is not None, "writer is closed"
        self._file.write(json.dumps(full_record(sample, self.extras), allow_nan=False) + "\n")
        if not self._owned:
            self._file.flush()
        self.records += 1

    def close(self) -> None:
        if self._file is not None:
            if self._owned:
                self._file.close()
            else:
                self._file.flush()
            self._file = None


class CsvWriter(_Writer):
    """The same records as CSV; empty cells for null. Extras' keys become extra columns."""

    def __init__(self, path: str | Path, extras: Sequence[Extras] = ()) -> None:
        self.path = Path(path)
        self.extras = list(extras)
        self._file: IO[str] | None = _open_for_writing(self.path, "CSV", newline="")
        self._writer: csv.DictWriter[str] | None = None
        self.records = 0

    def on_sample(self, sample: YawSample) -> None:
        assert self._file is not None, "writer is closed"
        record = full_record(sample, self.extras)
        if self._writer is None:
            self._writer = csv.DictWriter(
                self._file, fieldnames=list(record), extrasaction="ignore"
            )
            self._writer.writeheader()
        self._writer.writerow({k: "" if v is None else v for k, v in record.items()})
        self.records += 1

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None


class YawPlot(_Writer):
    """Collects raw and smoothed yaw and saves a PNG of both over time when closed."""

    def __init__(self, path: str | Path, title: str | None = None) -> None:
        self.path = Path(path)
        self.title = title
        self._t_s: list[float] = []
        self._raw_deg: list[float] = []
        self._smoothed_deg: list[float] = []
        self._std_deg: list[float] = []
        self._closed = False

    def on_sample(self, sample: YawSample) -> None:
        self._t_s.append(sample.t_s)
        self._raw_deg.append(math.nan if sample.yaw_raw_deg is None else sample.yaw_raw_deg)
        self._smoothed_deg.append(math.nan if sample.yaw_deg is None else sample.yaw_deg)
        self._std_deg.append(math.nan if sample.yaw_std_deg is None else sample.yaw_std_deg)

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        t_s = np.asarray(self._t_s)
        smoothed = np.asarray(self._smoothed_deg)
        std = np.asarray(self._std_deg)
        figure, axes = plt.subplots(figsize=(9, 4), dpi=110)
        axes.fill_between(t_s, smoothed - 2 * std, smoothed + 2 * std, alpha=0.2, label="±2σ")
        axes.plot(t_s, self._raw_deg, ".", markersize=4, color="tab:gray", label="raw (Center-CE)")
        axes.plot(t_s, smoothed, "-", color="tab:blue", label="smoothed (Kalman)")
        axes.axhline(0.0, color="black", linewidth=0.5)
        axes.set_xlabel("time (s)")
        axes.set_ylabel("yaw (deg, + = driver's left)")
        axes.set_title(self.title or "head yaw")
        axes.legend(loc="best", fontsize=8)
        axes.grid(alpha=0.3)
        figure.tight_layout()
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            figure.savefig(self.path)
        except OSError as exc:
            raise RoadgazeError(f"cannot write plot {self.path}: {exc.strerror or exc}") from None
        finally:
            plt.close(figure)


StateText = Callable[[YawSample], str | None]


class AnnotatedVideoWriter(_Writer):
    """The video with face boundaries, centre line, a yaw gauge, numbers and state drawn (mp4v).

    Boundaries and centre are vertical lines in the roll-removed frame, drawn rotated back into
    the image. `state_text` may add a line (e.g. the monitor's state) per sample.
    """

    def __init__(self, path: str | Path, fps: float, state_text: StateText | None = None) -> None:
        self.path = Path(path)
        self.fps = fps if math.isfinite(fps) and fps > 0 else 30.0
        self.state_text = state_text
        self._writer: Any = None
        self._size: tuple[int, int] | None = None
        self.frames = 0

    def _open(self, width: int, height: int) -> None:
        import cv2

        self.path.parent.mkdir(parents=True, exist_ok=True)
        suffix = self.path.suffix.lower()
        fourcc = {".avi": "MJPG", ".mkv": "FFV1"}.get(suffix, "mp4v")
        writer = cv2.VideoWriter(
            str(self.path), cv2.VideoWriter.fourcc(*fourcc), self.fps, (width, height)
        )
        if not writer.isOpened():
            raise RoadgazeError(
                f"cannot write annotated video {self.path}: OpenCV cannot encode {fourcc} here; "
                "use a .mp4 (mp4v), .avi (MJPG) or .mkv (FFV1) file name"
            )
        self._writer = writer
        self._size = (width, height)

    def on_frame(self, processed: ProcessedFrame) -> None:
        import cv2

        image = processed.frame.image
        height, width = image.shape[:2]
        if self._writer is None:
            self._open(width, height)
        canvas = annotate(image, processed.sample, self._state_line(processed.sample))
        if (width, height) != self._size:
            assert self._size is not None
            canvas = np.asarray(cv2.resize(canvas, self._size), dtype=np.uint8)
        self._writer.write(canvas)
        self.frames += 1

    def _state_line(self, sample: YawSample) -> str | None:
        return None if self.state_text is None else self.state_text(sample)

    def close(self) -> None:
        if self._writer is not None:
            self._writer.release()
            self._writer = None


@dataclass(frozen=True, slots=True)
class _RollFrame:
    """Image <-> roll-removed frame: q = R(angle) (p - pivot) + pivot + (offset, 0)."""

    angle_rad: float
    pivot: npt.NDArray[np.float64]
    offset_px: float

    def to_image(self, points: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        cos_a, sin_a = math.cos(self.angle_rad), math.sin(self.angle_rad)
        rotation = np.array([[cos_a, -sin_a], [sin_a, cos_a]])
        shifted = points - np.array([self.offset_px, 0.0]) - self.pivot
        result: npt.NDArray[np.float64] = shifted @ rotation + self.pivot
        return result


def _roll_frame(features: FaceFeatures) -> _RollFrame:
    """The roll-removed frame of `features` (see `roadgaze.landmarks.remove_roll`).

    With MediaPipe's 478 landmarks the frame is exact: rotation by the roll about the midpoint of
    the outer eye corners. With other landmark sets (a test's fake detector) it is rotation about
    the box centre, shifted so the rotated landmarks' extent is centred on the boundaries.
    """
    from roadgaze.landmarks import LEFT_EYE_OUTER, NUM_LANDMARKS, RIGHT_EYE_OUTER

    roll = math.radians(features.roll_deg)
    points = features.landmarks_px[:, :2].astype(np.float64)
    if len(points) == NUM_LANDMARKS:
        pivot = 0.5 * (points[RIGHT_EYE_OUTER] + points[LEFT_EYE_OUTER])
        return _RollFrame(angle_rad=roll, pivot=pivot, offset_px=0.0)
    x_min, y_min, x_max, y_max = features.box_px
    pivot = np.array([(x_min + x_max) / 2.0, (y_min + y_max) / 2.0])
    if len(points) == 0:
        return _RollFrame(angle_rad=roll, pivot=pivot, offset_px=0.0)
    cos_a, sin_a = math.cos(roll), math.sin(roll)
    rotated_x = (points - pivot) @ np.array([cos_a, -sin_a]) + pivot[0]
    mid_here = (float(rotated_x.min()) + float(rotated_x.max())) / 2.0
    mid_there = (features.x_left_px + features.x_right_px) / 2.0
    return _RollFrame(angle_rad=roll, pivot=pivot, offset_px=mid_there - mid_here)


def annotate(
    image: npt.NDArray[np.uint8], sample: YawSample, state: str | None = None
) -> npt.NDArray[np.uint8]:
    """A copy of `image` with the face geometry, a yaw gauge and the numbers drawn on it."""
    import cv2

    canvas = image.copy()
    height, width = canvas.shape[:2]
    scale = max(0.45, min(width, height) / 720.0)
    thickness = max(1, round(2 * scale))
    features = sample.features
    if features is not None:
        x_min, y_min, x_max, y_max = features.box_px
        cv2.rectangle(
            canvas, (round(x_min), round(y_min)), (round(x_max), round(y_max)), (90, 90, 90), 1
        )
        margin = 0.15 * (y_max - y_min)
        top, bottom = y_min - margin, y_max + margin
        roll_frame = _roll_frame(features)
        lines = (
            (features.x_left_px, (0, 200, 255)),
            (features.x_right_px, (0, 200, 255)),
            (features.x_center_px, (0, 255, 0)),
        )
        for x_px, colour in lines:
            ends = roll_frame.to_image(np.array([[x_px, top], [x_px, bottom]]))
            (x0, y0), (x1, y1) = ends
            cv2.line(canvas, (round(x0), round(y0)), (round(x1), round(y1)), colour, thickness)
    _draw_gauge(canvas, sample, scale)
    lines_text = [_yaw_text(sample), _state_text(sample)]
    if state:
        lines_text.append(state)
    _draw_text_panel(canvas, lines_text, scale, thickness)
    return canvas


def _draw_text_panel(
    canvas: npt.NDArray[np.uint8], lines_text: list[str], scale: float, thickness: int
) -> None:
    """White text lines at the bottom left on a darkened panel, readable on any background.

    (A black outline drawn with a thicker pen does not work: in OpenCV 5 the glyph advance grows
    with the thickness, so outline and text drift apart.)
    """
    import cv2

    font, font_scale = cv2.FONT_HERSHEY_SIMPLEX, 0.7 * scale
    line_step = round(26 * scale)
    margin = round(10 * scale)
    text_width = max(cv2.getTextSize(t, font, font_scale, thickness)[0][0] for t in lines_text)
    height, width = canvas.shape[:2]
    top = max(0, height - margin - line_step * len(lines_text))
    right = min(width, 2 * margin + text_width)
    panel = canvas[top:height, 0:right]
    panel[:] = (panel.astype(np.uint16) * 2 // 5).astype(np.uint8)
    y = top + line_step - round(6 * scale)
    for text in lines_text:
        cv2.putText(canvas, text, (margin, y), font, font_scale, (255, 255, 255), thickness,
                    cv2.LINE_AA)  # fmt: skip
        y += line_step


def _yaw_text(sample: YawSample) -> str:
    def number(value: float | None, unit: str) -> str:
        return "--" if value is None else f"{value:+.1f}{unit}"

    return (
        f"yaw {number(sample.yaw_deg, '')} (raw {number(sample.yaw_raw_deg, '')}) deg  "
        f"rate {number(sample.yaw_rate_dps, '')} dps  "
        f"sd {'--' if sample.yaw_std_deg is None else f'{sample.yaw_std_deg:.1f}'}"
    )


def _state_text(sample: YawSample) -> str:
    if not sample.face:
        tracking = "predicting" if sample.yaw_deg is not None else "no track"
        return f"t {sample.t_s:.2f} s  frame {sample.frame}  NO FACE ({tracking})"
    faces = f"{sample.n_faces} faces" if sample.n_faces > 1 else "face"
    return f"t {sample.t_s:.2f} s  frame {sample.frame}  {faces}"


def _draw_gauge(canvas: npt.NDArray[np.uint8], sample: YawSample, scale: float) -> None:
    """A half-dial, top right: up is straight ahead, right is yaw > 0 (nose to image right)."""
    import cv2

    width = canvas.shape[1]
    radius = round(55 * scale)
    centre = (width - radius - round(12 * scale), radius + round(14 * scale))
    cv2.ellipse(canvas, centre, (radius, radius), 0, 180, 360, (40, 40, 40), -1)
    cv2.ellipse(canvas, centre, (radius, radius), 0, 180, 360, (220, 220, 220), 1)
    for tick_deg in (-90, -60, -30, 0, 30, 60, 90):
        angle = math.radians(tick_deg)
        outer = (
            round(centre[0] + radius * math.sin(angle)),
            round(centre[1] - radius * math.cos(angle)),
        )
        inner = (
            round(centre[0] + 0.85 * radius * math.sin(angle)),
            round(centre[1] - 0.85 * radius * math.cos(angle)),
        )
        cv2.line(canvas, inner, outer, (220, 220, 220), 1)
    needles = ((sample.yaw_raw_deg, (160, 160, 160), 1), (sample.yaw_deg, (0, 255, 255), 3))
    for value, colour, width_px in needles:
        if value is None:
            continue
        angle = math.radians(max(-90.0, min(90.0, value)))
        tip = (
            round(centre[0] + 0.95 * radius * math.sin(angle)),
            round(centre[1] - 0.95 * radius * math.cos(angle)),
        )
        cv2.line(canvas, centre, tip, colour, max(1, round(width_px * scale)), cv2.LINE_AA)


class ProgressBar(_Writer):
    """A tqdm progress bar on stderr (frames, fps, ETA) as a sink."""

    def __init__(self, total: int | None, description: str = "replay") -> None:
        from tqdm import tqdm

        self._bar = tqdm(total=total, desc=description, unit="frame", dynamic_ncols=True)

    def on_sample(self, sample: YawSample) -> None:
        self._bar.update(1)

    def close(self) -> None:
        self._bar.close()
