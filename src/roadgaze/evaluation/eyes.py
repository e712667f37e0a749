"""The eyes on labelled stills: gaze against head yaw, and the closed/open classifier.

On a still there is no learned neutral: the road pitch and the resting eye direction are taken
as 0, and the classifier has no history. Scored over the faces found with |yaw| <= 60 (the
paper's range; rows with |pitch| = 90 are already left out):

- **gaze vs head yaw**: MAE against the label per 15 deg bin and overall; where the eyes give no
  direction the gaze is the head yaw, as in the service;
- **leave half of the subjects out** (when `ground_truth.csv` names subjects): the deadband is
  chosen among `DEADBANDS_DEG` on one half of the subjects and scored on the other, both ways;
- **closure**: the share of faces called open, closed and not judged (eyes unavailable), over all
  faces, per tilt label and over the open-eyed faces (|tilt| <= `OPEN_EYED_TILT_DEG`: at tilt
  -60 the lids of Pointing'04's subjects read nearly shut); a face not judged is not counted as
  open, and is never a false closure.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from roadgaze.config import Config
from roadgaze.evaluation.ground_truth import GroundTruth
from roadgaze.landmarks.eyes import driver_eyes
from roadgaze.monitor.eye_rules import classify_eyes, gaze_deg, soft_threshold
from roadgaze.types import EyeStatus, FaceFeatures, FloatArray

DEADBANDS_DEG = (5.0, 10.0, 15.0)
CAPS_DEG = (45.0, 60.0)
"""The leave-half-out check chooses among these deadbands x head-yaw limits of the eye direction
(`monitor.gaze_deadband_deg`, `eyes.max_head_yaw_deg`; the defaults are 10 and 45)."""
RANGE_DEG = 60.0
BIN_DEG = 15.0
OPEN_EYED_TILT_DEG = 30.0
"""Faces up to this |tilt| have their eyes visibly open (the fail-safe goal's set, docs/eyes.md)."""


@dataclass(frozen=True, slots=True)
class EyeEstimate:
    """The eyes of one still as the service judges them (neutral 0, no history)."""

    status: EyeStatus
    reason: str
    openness: float | None
    eye_yaw_deg: float | None
    eye_pitch_deg: float | None
    gaze_yaw_deg: float | None
    gaze_pitch_deg: float | None
    head_yaw_deg: float | None = None
    eye_yaw_any_head_deg: float | None = None
    """The eye yaw whatever the head yaw (open eyes), for the leave-half-out check of the limit."""

    @property
    def closed(self) -> bool | None:
        """True closed, False open, None not judged."""
        return None if self.status is EyeStatus.UNAVAILABLE else self.status is EyeStatus.CLOSED


def still_eyes(
    face: FaceFeatures, yaw_deg: float | None, pitch_deg: float | None, config: Config
) -> EyeEstimate:
    """The eye stage and the closed/open rule on one still's driver face."""
    eyes = driver_eyes(face, yaw_deg, config.eyes)
    below = None if face.mediapipe_pitch_deg is None else -face.mediapipe_pitch_deg
    status, reason = classify_eyes(config.monitor, eyes, below)
    gaze_yaw = gaze_pitch = None
    if yaw_deg is not None:
        use = eyes if status is EyeStatus.OPEN else None
        gaze_yaw, gaze_pitch, _ = gaze_deg(
            yaw_deg, pitch_deg or 0.0, use, config.monitor.gaze_deadband_deg
        )
    anywhere = driver_eyes(face, yaw_deg, config.eyes.model_copy(update={"max_head_yaw_deg": 90.0}))
    return EyeEstimate(
        head_yaw_deg=yaw_deg,
        eye_yaw_any_head_deg=(
            None if anywhere is None or status is not EyeStatus.OPEN else anywhere.yaw_deg
        ),
        status=status,
        reason=reason,
        openness=None if eyes is None or status is EyeStatus.UNAVAILABLE else eyes.openness,
        eye_yaw_deg=None if eyes is None or status is not EyeStatus.OPEN else eyes.yaw_deg,
        eye_pitch_deg=None if eyes is None or status is not EyeStatus.OPEN else eyes.pitch_deg,
        gaze_yaw_deg=gaze_yaw,
        gaze_pitch_deg=gaze_pitch,
    )


@dataclass(frozen=True, slots=True)
class EyeReport:
    """Every eye figure `roadgaze eval` prints (see the module docstring)."""

    faces: int
    open: int
    closed: int
    not_judged: int
    looking_down: int
    """Faces called open because narrowed lids with a lowered head read as looking down."""
    by_tilt: tuple[tuple[float, int, int, int, int], ...]
    """(tilt label, faces, open, closed, not judged)."""
    head_mae_deg: float
    gaze_mae_deg: float
    eyes_used: int
    """Faces whose gaze used the eyes (the rest fall back to the head yaw)."""
    bins: tuple[tuple[float, int, float, float], ...]
    """(label yaw bin, faces, head MAE, gaze MAE)."""
    held_out: tuple[tuple[str, float, float, float, float], ...]
    """(which half was held out, deadband and head-yaw limit chosen on the other, gaze MAE and
    head MAE there)."""

    def open_eyed(self) -> tuple[int, int, int, int]:
        """(faces, open, closed, not judged) over the tilts within +-`OPEN_EYED_TILT_DEG`."""
        rows = [row for row in self.by_tilt if abs(row[0]) <= OPEN_EYED_TILT_DEG]
        return (
            sum(r[1] for r in rows),
            sum(r[2] for r in rows),
            sum(r[3] for r in rows),
            sum(r[4] for r in rows),
        )

    def to_json_dict(self) -> dict[str, Any]:
        faces, opened, closed, unjudged = self.open_eyed()
        return {
            "open_eyed": {
                "max_tilt_deg": OPEN_EYED_TILT_DEG,
                "faces": faces,
                "open": opened,
                "closed": closed,
                "not_judged": unjudged,
            },
            "faces": self.faces,
            "open": self.open,
            "closed": self.closed,
            "not_judged": self.not_judged,
            "looking_down": self.looking_down,
            "open_rate": self.open / self.faces if self.faces else None,
            "by_tilt": [
                {"tilt_deg": t, "faces": n, "open": o, "closed": c, "not_judged": u}
                for t, n, o, c, u in self.by_tilt
            ],
            "head_yaw_mae_deg": self.head_mae_deg,
            "gaze_yaw_mae_deg": self.gaze_mae_deg,
            "eyes_used": self.eyes_used,
            "bins": [
                {"yaw_deg": b, "faces": n, "head_mae_deg": h, "gaze_mae_deg": g}
                for b, n, h, g in self.bins
            ],
            "held_out": [
                {
                    "held_out": who,
                    "deadband_deg": d,
                    "max_head_yaw_deg": c,
                    "gaze_mae_deg": g,
                    "head_mae_deg": h,
                }
                for who, d, c, g, h in self.held_out
            ],
        }


def _nan(value: float | None) -> float:
    return math.nan if value is None else float(value)


def evaluate_eyes(truths: Sequence[GroundTruth], estimates: Sequence[Any]) -> EyeReport | None:
    """Score the eye estimates (`ImageEstimate.eyes`); None when no estimate has eyes."""
    rows = [
        (t, e)
        for t, e in zip(truths, estimates, strict=True)
        if e.face and e.eyes is not None and e.yaw_deg is not None and abs(t.yaw_deg) <= RANGE_DEG
    ]
    if not rows:
        return None
    label = np.array([t.yaw_deg for t, _ in rows])
    tilt = np.array([_nan(t.pitch_deg) for t, _ in rows])
    head = np.array([e.yaw_deg for _, e in rows])
    gaze = np.array([_nan(e.eyes.gaze_yaw_deg) for _, e in rows])
    eye = np.array([_nan(e.eyes.eye_yaw_deg) for _, e in rows])
    eye_any = np.array([_nan(e.eyes.eye_yaw_any_head_deg) for _, e in rows])
    status = [e.eyes.status for _, e in rows]
    is_open = np.array([s is EyeStatus.OPEN for s in status])
    is_closed = np.array([s is EyeStatus.CLOSED for s in status])
    down = sum(1 for _, e in rows if e.eyes.reason == "looking down")
    by_tilt = tuple(
        (
            float(value),
            int(np.sum(tilt == value)),
            int(np.sum(is_open[tilt == value])),
            int(np.sum(is_closed[tilt == value])),
            int(np.sum((~is_open & ~is_closed)[tilt == value])),
        )
        for value in np.unique(tilt[np.isfinite(tilt)])
    )
    bin_of = np.round(label / BIN_DEG) * BIN_DEG
    bins = tuple(
        (
            float(b),
            int(np.sum(bin_of == b)),
            _mae(head, label, bin_of == b),
            _mae(gaze, label, bin_of == b),
        )
        for b in np.unique(bin_of)
    )
    subjects = [t.subject for t, _ in rows]
    return EyeReport(
        faces=len(rows),
        open=int(np.sum(is_open)),
        closed=int(np.sum(is_closed)),
        not_judged=int(np.sum(~is_open & ~is_closed)),
        looking_down=down,
        by_tilt=by_tilt,
        head_mae_deg=_mae(head, label, np.ones(len(rows), bool)),
        gaze_mae_deg=_mae(gaze, label, np.ones(len(rows), bool)),
        eyes_used=int(np.sum(np.isfinite(eye))),
        bins=bins,
        held_out=_leave_half_out(subjects, label, head, eye_any),
    )


def _mae(estimate: FloatArray, label: FloatArray, mask: np.ndarray) -> float:
    chosen = mask & np.isfinite(estimate)
    return float(np.mean(np.abs(estimate[chosen] - label[chosen]))) if chosen.any() else math.nan


def _gaze_with(
    head: FloatArray, eye: FloatArray, deadband_deg: float, cap_deg: float
) -> FloatArray:
    shifted = [
        h if not math.isfinite(e) or abs(h) > cap_deg else h + soft_threshold(e, deadband_deg)
        for h, e in zip(head, eye, strict=True)
    ]
    return np.asarray(shifted, dtype=np.float64)


def _leave_half_out(
    subjects: list[str | None], label: FloatArray, head: FloatArray, eye: FloatArray
) -> tuple[tuple[str, float, float, float, float], ...]:
    """Choose the deadband and head-yaw limit on one half of the subjects, score the choice on
    the other half, both ways."""
    named = sorted({s for s in subjects if s is not None}, key=_subject_order)
    if len(named) < 2:
        return ()
    halves = (named[: len(named) // 2], named[len(named) // 2 :])
    variants = [(d, c) for d in DEADBANDS_DEG for c in CAPS_DEG]
    gazes = {v: _gaze_with(head, eye, *v) for v in variants}
    result = []
    for chosen_on, held in (halves, halves[::-1]):
        train = np.array([s in chosen_on for s in subjects])
        test = np.array([s in held for s in subjects])
        best = min(variants, key=lambda v: _mae(gazes[v], label, train))
        result.append(
            (
                f"subjects {held[0]}-{held[-1]}",
                *best,
                _mae(gazes[best], label, test),
                _mae(head, label, test),
            )
        )
    return tuple(result)


def _subject_order(subject: str) -> tuple[int, str]:
    return (int(subject), subject) if subject.isdigit() else (10**9, subject)


def format_eye_report(report: EyeReport) -> str:
    """The eye figures as plain text."""

    def share(count: int) -> str:
        return f"{count} ({100.0 * count / report.faces:.2f}%)" if report.faces else "0"

    lines = [
        f"Eyes on {report.faces} faces found with |yaw| <= 60 (neutral 0, no history):",
        f"  closure: open {share(report.open)} (of which {report.looking_down} looking down), "
        f"closed {share(report.closed)}, not judged {share(report.not_judged)}",
        f"{'tilt':>6} {'faces':>6} {'open%':>7} {'closed':>7} {'not judged':>11}",
    ]
    for tilt, faces, opened, closed, unjudged in report.by_tilt:
        lines.append(
            f"{tilt:>6.0f} {faces:>6} {100.0 * opened / faces:>7.2f} {closed:>7} {unjudged:>11}"
        )
    faces, opened, closed, unjudged = report.open_eyed()
    if faces:
        lines.append(
            f"  open-eyed (|tilt| <= {OPEN_EYED_TILT_DEG:g}): {faces} faces, open {opened} "
            f"({100.0 * opened / faces:.2f}%), closed {closed} ({100.0 * closed / faces:.2f}%), "
            f"not judged {unjudged}"
        )
    lines += [
        f"  gaze yaw vs head yaw against the label: gaze MAE {report.gaze_mae_deg:.2f}, head MAE "
        f"{report.head_mae_deg:.2f} deg (eyes used on {report.eyes_used} faces)",
        f"{'yaw':>6} {'faces':>6} {'head':>7} {'gaze':>7}",
    ]
    for center, faces, head, gaze in report.bins:
        lines.append(f"{center:>6.0f} {faces:>6} {head:>7.2f} {gaze:>7.2f}")
    for held, deadband, cap, gaze, head in report.held_out:
        lines.append(
            f"  leave half out: deadband {deadband:g}, limit {cap:g} chosen on the other half; "
            f"on {held}: gaze {gaze:.2f}, head {head:.2f} deg"
        )
    return "\n".join(lines)
