"""Ground-truth clips: a timeline rendered to a video file, with its truth CSV beside it."""

from __future__ import annotations

import csv
import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from roadgaze.config import Config
from roadgaze.errors import ConfigError, SourceError
from roadgaze.outputs.video import FOURCC_BY_SUFFIX, open_video_writer
from roadgaze.synth.eyes import EyeRenderer, EyeState
from roadgaze.synth.renderer import DEFAULT_SIZE, FaceRenderer, ImageBGR, load_photo
from roadgaze.synth.timeline import Timeline, parse_timeline
from roadgaze.types import FloatArray

DEFAULT_FPS = 15.0
TRUTH_HEADER = ("t_s", "yaw_deg", "pitch_deg")
EYE_TRUTH_HEADER = (*TRUTH_HEADER, "eye_yaw_deg", "eye_pitch_deg", "openness")
"""The truth of a timeline with eye fields: eye-in-head angles (degrees) and openness (0..1)."""


def truth_path_for(video_path: Path) -> Path:
    """`clip.mp4` -> `clip.truth.csv`, beside the video."""
    return video_path.with_name(video_path.stem + ".truth.csv")


def write_truth_csv(path: Path, truth: FloatArray) -> None:
    """Write rows `t_s,yaw_deg,pitch_deg` (an (N, 3) truth), or with the eye columns of
    `EYE_TRUTH_HEADER` (an (N, 6) truth), under a header."""
    header = EYE_TRUTH_HEADER if truth.shape[1] == len(EYE_TRUTH_HEADER) else TRUTH_HEADER
    with Path(path).open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        for row in truth:
            writer.writerow([f"{value:.4f}" for value in row[: len(header)]])


def read_truth_csv(path: Path) -> FloatArray:
    """Read a truth CSV written by `write_truth_csv`: an (N, 3) array, or (N, 6) with the eye
    columns when the file has them; raises SourceError."""
    try:
        with Path(path).open(newline="", encoding="utf-8") as handle:
            rows = list(csv.reader(handle))
    except OSError as exc:
        raise SourceError(f"cannot read truth file {path}: {exc}") from None
    if not rows or tuple(rows[0]) not in (TRUTH_HEADER, EYE_TRUTH_HEADER):
        raise SourceError(
            f"truth file {path} must start with the header {','.join(TRUTH_HEADER)} "
            f"(or {','.join(EYE_TRUTH_HEADER)})"
        )
    try:
        return np.array([[float(v) for v in row] for row in rows[1:]], dtype=np.float64).reshape(
            -1, len(rows[0])
        )
    except ValueError as exc:
        raise SourceError(f"truth file {path} has a bad row: {exc}") from None


def render_frames(
    timeline: Timeline, renderer: FaceRenderer, fps: float = DEFAULT_FPS
) -> Iterator[tuple[FloatArray, ImageBGR]]:
    """Yield (truth row, BGR frame) for every frame of the timeline: rows `t_s, yaw_deg,
    pitch_deg`, with the eye columns when the timeline has eye fields (which needs an
    `EyeRenderer`; ConfigError otherwise)."""
    if not timeline.has_eyes:
        for row in timeline.truth(fps):
            yield row, renderer.render(float(row[1]), float(row[2]))
        return
    if not isinstance(renderer, EyeRenderer):
        raise ConfigError("a timeline with eye fields needs an EyeRenderer")
    for row in timeline.eye_truth(fps):
        state = EyeState.both(float(row[3]), float(row[4]), float(row[5]))
        yield row, renderer.render_eyes(float(row[1]), float(row[2]), state)


def render_clip(
    timeline: Timeline | str,
    out_path: Path | str,
    photo: Path | None = None,
    fps: float = DEFAULT_FPS,
    size: tuple[int, int] = DEFAULT_SIZE,
    renderer: FaceRenderer | None = None,
    config: Config | None = None,
) -> FloatArray:
    """Render the timeline to a video and its `<stem>.truth.csv`; return the truth: (N, 3), or
    (N, 6) with the eye columns for a timeline with eye fields.

    The container follows the suffix: .mp4 (mp4v), .avi (MJPG) or .mkv (FFV1, lossless). Pass a
    `renderer` to reuse one already built for the same photo and size. Raises ConfigError for a bad
    timeline, size, fps or suffix and SourceError for an unreadable photo or one without a face.
    """
    if isinstance(timeline, str):
        timeline = parse_timeline(timeline)
    if not math.isfinite(fps) or not 1.0 <= fps <= 240.0:
        raise ConfigError(f"fps must be within 1..240, found {fps}")
    out = Path(out_path)
    fourcc = FOURCC_BY_SUFFIX.get(out.suffix.lower())
    if fourcc is None:
        raise ConfigError(
            f"cannot write '{out.suffix}' video {out}; use one of {', '.join(FOURCC_BY_SUFFIX)}"
        )
    if renderer is None:
        kind = EyeRenderer if timeline.has_eyes else FaceRenderer
        renderer = kind(load_photo(photo), size, config=config)
    elif timeline.has_eyes and not isinstance(renderer, EyeRenderer):
        raise ConfigError("a timeline with eye fields needs an EyeRenderer")
    writer = open_video_writer(out, fps, renderer.size, fourcc)
    rows = []
    try:
        for row, frame in render_frames(timeline, renderer, fps):
            writer.write(frame)
            rows.append(row)
    finally:
        writer.release()
    truth = np.asarray(rows, dtype=np.float64).reshape(len(rows), -1)
    write_truth_csv(truth_path_for(out), truth)
    return truth
