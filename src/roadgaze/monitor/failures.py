"""Frame checks: what tells a failed camera from a driver. Pure (numpy only).

`check_frame` measures one image cheaply: the green channel (most of luma) of every
`FRAME_STRIDE`-th pixel in each direction (4,800 pixels of a 640x480 frame: 0.033 ms of CPU per
frame on a shared 2-core machine, `scripts/bench-frame-check.py`), its mean, spread,
saturated fraction and largest absolute difference from the previous frame's samples.
The `temporary_failure` behaviour (roadgaze.monitor.behaviours.temporary_failure) turns those
checks and the face into a temporary failure (EU 2023/2590 Annex I 3.5.2; docs/monitor.md,
"Failures"), each timed while the vehicle moves:

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

import numpy as np
import numpy.typing as npt

from roadgaze.config import MonitorConfig
from roadgaze.types import FrameCheck

__all__ = ["FRAME_STRIDE", "check_frame", "frame_issue"]

FRAME_STRIDE = 8
"""Pixels between the grey samples in each direction."""
SATURATED_GREY = 250


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
