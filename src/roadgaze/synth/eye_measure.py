"""How well the landmark stage recovers rendered eyes: direction, openness and closed/open.

`measure_eye_recovery` renders stills with `EyeRenderer` (known eye-in-head yaw and pitch, known
openness), runs MediaPipe on each in IMAGE mode and the eye stage exactly as the pipeline does
(`roadgaze.landmarks.eyes.driver_eyes`, `roadgaze.monitor.classify_eyes`), and compares. Three
sets:

- **direction**: head frontal, eye yaw -30..30 x eye pitch -20..20 (step 10);
- **direction with the head turned**: head yaw -20 and +20, eye yaw -30..30;
- **openness**: openness 0..1 at seven head poses (frontal, yaw +-20 and +-40, pitch +-15);
  the closed/open classifier's verdict per truth (recall of closures, false closures).

"Offset-corrected" errors remove what MediaPipe reads for the photo's own eyes at truth (0, 0)
(a per-person offset that the monitor learns as the resting eye direction in video).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from roadgaze.config import Config
from roadgaze.synth.eyes import EyeRenderer, EyeState
from roadgaze.synth.renderer import load_photo
from roadgaze.types import EyeStatus, FloatArray

EYE_DRIVE_TIMELINE = (
    "0:4,0;eyes=closed:1.5,0:4,0;eyes=closed:4,0:4,0;eye_yaw=-30;eye_pitch=-25:4,0:4"
)
"""A drive with a 1.5 s and a 4 s closure and a 4 s eyes-only glance down to the right, head
still (`roadgaze synth --timeline eyes`): microsleep, microsleep + sleep, long_distraction."""
EYE_YAWS_DEG = (-30.0, -20.0, -10.0, 0.0, 10.0, 20.0, 30.0)
EYE_PITCHES_DEG = (-20.0, -10.0, 0.0, 10.0, 20.0)
TURNED_HEAD_YAWS_DEG = (-20.0, 20.0)
OPENNESS_TRUTHS = (0.0, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0)
OPENNESS_HEADS_DEG: tuple[tuple[float, float], ...] = (
    (0.0, 0.0),
    (-20.0, 0.0),
    (20.0, 0.0),
    (-40.0, 0.0),
    (40.0, 0.0),
    (0.0, -15.0),
    (0.0, 15.0),
)
"""Head yaw and pitch (degrees) of the openness set."""
MEASURE_SIZE = (640, 480)
"""Eyes about 32 px wide, a face about 150 px wide: a typical cabin camera at 640x480."""
ROW_HEADER = (
    "set",
    "head_yaw_deg",
    "head_pitch_deg",
    "eye_yaw_deg",
    "eye_pitch_deg",
    "openness",
    "face",
    "rec_eye_yaw_deg",
    "rec_eye_pitch_deg",
    "rec_openness",
    "blink",
    "eyes",
)


@dataclass(frozen=True, slots=True)
class EyeRecovery:
    """Every rendered still and what the eye stage made of it (NaN where nothing was found).

    `rows`: (N, 11) columns `ROW_HEADER[1:]` (face 1/0, eyes 0 open, 1 closed, 2 unavailable);
    `sets`: the set of each row ('direction', 'turned', 'openness').
    """

    sets: tuple[str, ...]
    rows: FloatArray
    rest_deg: tuple[float, float]
    """Eye yaw and pitch recovered at truth (0, 0) with the head frontal: the photo's offset."""
    size: tuple[int, int]


_STATUS_CODE = {EyeStatus.OPEN: 0.0, EyeStatus.CLOSED: 1.0, EyeStatus.UNAVAILABLE: 2.0}


def _frames() -> list[tuple[str, float, float, EyeState]]:
    frames = [
        ("direction", 0.0, 0.0, EyeState.both(yaw, pitch))
        for pitch in EYE_PITCHES_DEG
        for yaw in EYE_YAWS_DEG
    ]
    frames += [
        ("turned", head, 0.0, EyeState.both(yaw, 0.0))
        for head in TURNED_HEAD_YAWS_DEG
        for yaw in EYE_YAWS_DEG
    ]
    frames += [
        ("openness", head_yaw, head_pitch, EyeState.both(openness=openness))
        for head_yaw, head_pitch in OPENNESS_HEADS_DEG
        for openness in OPENNESS_TRUTHS
    ]
    return frames


def measure_eye_recovery(
    config: Config | None = None,
    photo: Path | None = None,
    size: tuple[int, int] = MEASURE_SIZE,
    renderer: EyeRenderer | None = None,
) -> EyeRecovery:
    """Render the three sets, run the landmark and eye stages on each still, keep every value."""
    from roadgaze.landmarks import Landmarker, driver_eyes
    from roadgaze.monitor.eye_rules import classify_eyes
    from roadgaze.pose import PoseEstimator

    config = config if config is not None else Config()
    renderer = renderer if renderer is not None else EyeRenderer(load_photo(photo), size)
    pose = PoseEstimator.from_config(config)
    rows: list[list[float]] = []
    sets: list[str] = []
    with Landmarker.from_config(config, video=False) as landmarker:
        rest = landmarker.detect(renderer.render_eyes(0.0, 0.0, EyeState())).driver
        road_pitch = None if rest is None else rest.mediapipe_pitch_deg
        for name, head_yaw, head_pitch, state in _frames():
            face = landmarker.detect(renderer.render_eyes(head_yaw, head_pitch, state)).driver
            eyes = driver_eyes(face, pose.raw_yaw_deg(face), config.eyes)
            below = (
                None
                if face is None or face.mediapipe_pitch_deg is None or road_pitch is None
                else road_pitch - face.mediapipe_pitch_deg
            )
            status, _ = classify_eyes(config.monitor, eyes, below)
            rows.append(
                [
                    head_yaw,
                    head_pitch,
                    state.eye_yaw_deg,
                    state.eye_pitch_deg,
                    state.openness_right,
                    float(face is not None),
                    _value(None if eyes is None else eyes.yaw_deg),
                    _value(None if eyes is None else eyes.pitch_deg),
                    _value(None if eyes is None else eyes.openness),
                    _value(None if eyes is None else eyes.blink),
                    _STATUS_CODE[status],
                ]
            )
            sets.append(name)
    table = np.asarray(rows, dtype=np.float64)
    at_rest = (np.asarray(sets) == "direction") & (table[:, 2] == 0.0) & (table[:, 3] == 0.0)
    rest_deg = (float(np.nanmean(table[at_rest, 6])), float(np.nanmean(table[at_rest, 7])))
    return EyeRecovery(tuple(sets), table, rest_deg, renderer.size)


def _value(value: float | None) -> float:
    return float("nan") if value is None else float(value)


def _mae(errors: FloatArray) -> float:
    finite = errors[np.isfinite(errors)]
    return float(np.mean(np.abs(finite))) if finite.size else float("nan")


def _direction_table(result: EyeRecovery, axis: int) -> list[str]:
    """Per truth bin of eye yaw (axis 2) or pitch (axis 3) at the frontal head."""
    rows = result.rows[np.asarray(result.sets) == "direction"]
    recovered = rows[:, 4 + axis]
    offset = result.rest_deg[axis - 2]
    name = "yaw" if axis == 2 else "pitch"
    lines = [
        f"| truth eye {name} | n | recovered (mean) | MAE | MAE offset-corrected |",
        "|---|---|---|---|---|",
    ]
    for truth in EYE_YAWS_DEG if axis == 2 else EYE_PITCHES_DEG:
        chosen = rows[:, axis] == truth
        lines.append(
            f"| {truth:+.0f} | {int(np.sum(chosen))} | {np.nanmean(recovered[chosen]):+.1f} | "
            f"{_mae(recovered[chosen] - truth):.1f} | "
            f"{_mae(recovered[chosen] - offset - truth):.1f} |"
        )
    lines.append(
        f"| all | {len(rows)} | | {_mae(recovered - rows[:, axis]):.1f} | "
        f"{_mae(recovered - offset - rows[:, axis]):.1f} |"
    )
    return lines


def format_eye_measurement(result: EyeRecovery) -> str:
    """The measurement as Markdown tables: direction per bin, with the head turned, openness."""
    rows, sets = result.rows, np.asarray(result.sets)
    width, height = result.size
    lines = [
        f"Eye recovery on rendered stills ({width}x{height}, MediaPipe IMAGE mode). Photo's own "
        f"eyes read yaw {result.rest_deg[0]:+.1f}, pitch {result.rest_deg[1]:+.1f} deg "
        "(removed in the offset-corrected columns).",
        "",
        "Eye-in-head yaw, head frontal (all eye pitches):",
        *_direction_table(result, 2),
        "",
        "Eye-in-head pitch, head frontal (all eye yaws):",
        *_direction_table(result, 3),
        "",
        "Eye-in-head yaw with the head turned (eye pitch 0), offset-corrected MAE:",
        "| head yaw | n | eyes found | MAE |",
        "|---|---|---|---|",
    ]
    for head in TURNED_HEAD_YAWS_DEG:
        chosen = (sets == "turned") & (rows[:, 0] == head)
        recovered = rows[chosen, 6] - result.rest_deg[0]
        found = int(np.sum(np.isfinite(rows[chosen, 6])))
        lines.append(
            f"| {head:+.0f} | {int(np.sum(chosen))} | {found} | "
            f"{_mae(recovered - rows[chosen, 2]):.1f} |"
        )
    heads = OPENNESS_HEADS_DEG
    lines += [
        "",
        "Openness (lid gap / eye width) per truth and head pose (yaw/pitch), and the closed/open "
        "classifier: share of stills called closed",
        "| truth | " + " | ".join(f"{y:+.0f}/{p:+.0f}" for y, p in heads) + " | called closed |",
        "|---|" + "---|" * (len(heads) + 1),
    ]
    for truth in OPENNESS_TRUTHS:
        cells = []
        chosen_all = (sets == "openness") & (rows[:, 4] == truth)
        for head_yaw, head_pitch in heads:
            chosen = chosen_all & (rows[:, 0] == head_yaw) & (rows[:, 1] == head_pitch)
            value = float(np.nanmean(rows[chosen, 8])) if chosen.any() else float("nan")
            cells.append("-" if not np.isfinite(value) else f"{value:.3f}")
        closed = int(np.sum(rows[chosen_all, 10] == 1.0))
        lines.append(
            f"| {truth:.1f} | " + " | ".join(cells) + f" | {closed}/{int(np.sum(chosen_all))} |"
        )
    openness_rows = rows[sets == "openness"]
    shut = openness_rows[:, 4] <= 0.1
    wide = openness_rows[:, 4] >= 0.5
    lines += [
        "",
        f"Closure recall (truth openness <= 0.1): {int(np.sum(openness_rows[shut, 10] == 1.0))}/"
        f"{int(np.sum(shut))}; false closures (truth >= 0.5): "
        f"{int(np.sum(openness_rows[wide, 10] == 1.0))}/{int(np.sum(wide))}.",
    ]
    return "\n".join(lines)


def write_eye_measurement_csv(path: Path, result: EyeRecovery) -> None:
    """One row per rendered still, columns `ROW_HEADER`."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(ROW_HEADER)
        for name, row in zip(result.sets, result.rows, strict=True):
            writer.writerow([name, *(f"{value:.4f}" for value in row)])
