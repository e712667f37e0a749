"""Failure warnings: what tells a failed camera from a driver. Pure (numpy only).

`check_frame` measures one image cheaply: the green channel (most of luma) of every
`FRAME_STRIDE`-th pixel in each direction (4,800 pixels of a 640x480 frame: 0.033 ms of CPU per
frame on a shared 2-core machine, `scripts/bench-frame-check.py`), its mean, spread,
saturated fraction and largest absolute difference from the previous frame's samples.
`step_failures` turns those checks and the face into a temporary failure (EU 2023/2590 Annex I
3.5.2; docs/monitor.md, "Failures"), each timed while the vehicle moves:

- frames black (mean grey below `frame_dark_mean`), blocked (spread below `frame_min_std`: a
  covered lens) or saturated (more than `frame_saturated_fraction` at 250 or more: blinded), with
  no judgeable face, for `frame_failure_s` (a dark image that still shows a face is working);
- frames frozen (no sample differing from the previous frame's by more than `frozen_max_diff`
  grey levels: a repeated frame; a live camera's noise changes some sample every frame, and a
  rendered face whose eyes alone move is not frozen) for `frozen_failure_s`;
- no judgeable face (none, or one whose yaw the model cannot explain) for `no_face_failure_s`;
- the eyes unjudgeable (`degraded`) while a Euro NCAP rule needs them.

A `temporary_failure` is raised once, carries the reason, and is cleared (by the `cleared` alert)
at the first sample where none of the conditions holds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from roadgaze.config import MonitorConfig
from roadgaze.types import AlertKind, AlertLevel, FrameCheck, PoseSample

__all__ = ["FRAME_STRIDE", "FailureState", "check_frame", "frame_issue", "step_failures"]

FRAME_STRIDE = 8
"""Pixels between the grey samples in each direction."""
SATURATED_GREY = 250
EPS_S = 1e-6


def check_frame(
    image: npt.NDArray[np.uint8], previous: npt.NDArray[np.float32] | None
) -> tuple[FrameCheck, npt.NDArray[np.float32]]:
    """The checks of one BGR (or grey) image and its grey sample, to pass as `previous` next."""
    # The green channel as the grey level (most of luma), as float32 for exact sums.
    view = image[::FRAME_STRIDE, ::FRAME_STRIDE]
    grey = (view[:, :, 1] if view.ndim == 3 else view).astype(np.float32)
    count = max(1, grey.size)
    flat = grey.ravel()
    mean = float(flat.sum()) / count
    variance = max(0.0, float(np.dot(flat, flat)) / count - mean * mean)
    diff = None
    if previous is not None and previous.shape == grey.shape:
        diff = float(np.abs(grey - previous).max())
    check = FrameCheck(
        mean_grey=mean,
        std_grey=variance**0.5,
        saturated_fraction=float(np.count_nonzero(flat >= SATURATED_GREY)) / count,
        diff_grey=diff,
    )
    return check, grey


def frame_issue(config: MonitorConfig, check: FrameCheck | None) -> str:
    """What is wrong with the image ('' for nothing, or no check): `black`, `saturated`,
    `blocked`."""
    if check is None:
        return ""
    if check.mean_grey < config.frame_dark_mean:
        return "black"
    if check.saturated_fraction > config.frame_saturated_fraction:
        return "saturated"
    if check.std_grey < config.frame_min_std:
        return "blocked"
    return ""


@dataclass(frozen=True, slots=True)
class FailureState:
    """The failure timers between samples; replace, never mutate."""

    issue: str = ""
    """The image's issue at the last sample ('' for none)."""
    issue_since_s: float | None = None
    frozen_since_s: float | None = None
    no_face_since_s: float | None = None
    reason: str = ""
    """The temporary failure in force ('' for none)."""


def _since(condition: bool, since_s: float | None, t_s: float) -> float | None:
    if not condition:
        return None
    return t_s if since_s is None else since_s


def step_failures(
    config: MonitorConfig,
    state: FailureState,
    sample: PoseSample,
    moving: bool,
    eyes_needed_and_degraded: bool,
) -> tuple[FailureState, tuple[tuple[AlertKind, AlertLevel, str], ...], bool]:
    """Advance the failure timers by one sample (time from `sample.t_s`). Returns the new state,
    the alert to raise (at most one `temporary_failure`) and whether a failure in force ended."""
    t_s = sample.t_s
    check = sample.frame_check
    issue = frame_issue(config, check)
    diff = None if check is None else check.diff_grey
    frozen = diff is not None and diff <= config.frozen_max_diff
    no_face = not sample.face or (sample.yaw_raw_deg is None and sample.yaw_deg is None)
    # A dark or flat image that still shows a judgeable face (night, infrared) is working.
    issue = issue if no_face else ""
    issue_since = _since(moving and bool(issue), state.issue_since_s, t_s)
    if issue != state.issue:
        issue_since = t_s if moving and issue else None
    frozen_since = _since(moving and frozen, state.frozen_since_s, t_s)
    no_face_since = _since(moving and no_face, state.no_face_since_s, t_s)

    reason = ""
    if issue_since is not None and t_s - issue_since >= config.frame_failure_s - EPS_S:
        word = {"black": "frames black", "saturated": "frames saturated"}.get(
            issue, "camera blocked"
        )
        reason = f"{word} {t_s - issue_since:.1f} s"
    elif frozen_since is not None and t_s - frozen_since >= config.frozen_failure_s - EPS_S:
        reason = f"frames frozen {t_s - frozen_since:.1f} s"
    elif no_face_since is not None and t_s - no_face_since >= config.no_face_failure_s - EPS_S:
        reason = f"no face {t_s - no_face_since:.1f} s"
    elif eyes_needed_and_degraded:
        reason = "eyes unjudgeable"

    events: tuple[tuple[AlertKind, AlertLevel, str], ...] = ()
    ended = False
    if reason and not state.reason:
        events = ((AlertKind.TEMPORARY_FAILURE, AlertLevel.WARNING, reason),)
    elif state.reason and not reason:
        # Recovered only once nothing is wrong any more, moving or not.
        still = bool(issue) or frozen or no_face or eyes_needed_and_degraded
        if still:
            reason = state.reason
        else:
            ended = True
    new_state = FailureState(issue, issue_since, frozen_since, no_face_since, reason)
    return new_state, events, ended
