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
from roadgaze.synth.renderer import DEFAULT_SIZE, FaceRenderer, ImageBGR, load_photo
from roadgaze.synth.timeline import Timeline, parse_timeline
from roadgaze.types import FloatArray

DEFAULT_FPS = 15.0
TRUTH_HEADER = ("t_s", "yaw_deg", "pitch_deg")


def truth_path_for(video_path: Path) -> Path:
    """`clip.mp4` -> `clip.truth.csv`, beside the video."""
    return video_path.with_name(video_path.stem + ".truth.csv")


def write_truth_csv(path: Path, truth: FloatArray) -> None:
    """Write rows `t_s,yaw_deg,pitch_deg` with a header."""
    with Path(path).open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(TRUTH_HEADER)
        for t_s, yaw_deg, pitch_deg in truth:
            writer.writerow((f"{t_s:.4f}", f"{yaw_deg:.4f}", f"{pitch_deg:.4f}"))


def read_truth_csv(path: Path) -> FloatArray:
    """Read a truth CSV written by `write_truth_csv` as an (N, 3) array; raises SourceError."""
    try:
        with Path(path).open(newline="", encoding="utf-8") as handle:
            rows = list(csv.reader(handle))
    except OSError as exc:
        raise SourceError(f"cannot read truth file {path}: {exc}") from None
    if not rows or tuple(rows[0]) != TRUTH_HEADER:
        raise SourceError(f"truth file {path} must start with the header {','.join(TRUTH_HEADER)}")
    try:
        return np.array([[float(v) for v in row] for row in rows[1:]], dtype=np.float64).reshape(
            -1, 3
        )
    except ValueError as exc:
        raise SourceError(f"truth file {path} has a bad row: {exc}") from None


def render_frames(
    timeline: Timeline, renderer: FaceRenderer, fps: float = DEFAULT_FPS
) -> Iterator[tuple[FloatArray, ImageBGR]]:
    """Yield (truth row `t_s, yaw_deg, pitch_deg`, BGR frame) for every frame of the timeline."""
    for row in timeline.truth(fps):
        yield row, renderer.render(float(row[1]), float(row[2]))


def render_clip(
    timeline: Timeline | str,
    out_path: Path | str,
    photo: Path | None = None,
    fps: float = DEFAULT_FPS,
    size: tuple[int, int] = DEFAULT_SIZE,
    renderer: FaceRenderer | None = None,
    config: Config | None = None,
) -> FloatArray:
    """Render the timeline to a video and its `<stem>.truth.csv`; return the (N, 3) truth.

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
        renderer = FaceRenderer(load_photo(photo), size, config=config)
    writer = open_video_writer(out, fps, renderer.size, fourcc)
    rows = []
    try:
        for row, frame in render_frames(timeline, renderer, fps):
            writer.write(frame)
            rows.append(row)
    finally:
        writer.release()
    truth = np.asarray(rows, dtype=np.float64).reshape(-1, 3)
    write_truth_csv(truth_path_for(out), truth)
    return truth
