"""The eyes in the pose plot: the gaze yaw beside the head yaw, and an eye panel with the
openness, the closed and unavailable stretches shaded, PERCLOS and the true openness."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from roadgaze.types import EyeStatus, FloatArray, FrameRecord


@dataclass
class EyeTrace:
    """The eye values of every record, kept for the plot (one float per record and series)."""

    t_s: list[float] = field(default_factory=list)
    openness: list[float] = field(default_factory=list)
    gaze_yaw_deg: list[float] = field(default_factory=list)
    perclos: list[float] = field(default_factory=list)
    closed: list[bool] = field(default_factory=list)
    unavailable: list[bool] = field(default_factory=list)

    def add(self, record: FrameRecord) -> None:
        eyes = record.verdict.eyes
        self.t_s.append(record.t_s)
        self.openness.append(math.nan if eyes.openness is None else eyes.openness)
        self.gaze_yaw_deg.append(
            math.nan
            if eyes.gaze_yaw_deg is None or eyes.gaze_source != "eyes"
            else eyes.gaze_yaw_deg
        )
        self.perclos.append(math.nan if eyes.perclos is None else eyes.perclos)
        self.closed.append(eyes.status is EyeStatus.CLOSED)
        self.unavailable.append(eyes.status is EyeStatus.UNAVAILABLE)

    @property
    def measured(self) -> bool:
        """Whether any record judged the eyes (else the plot has no eye panel)."""
        return bool(np.any(np.isfinite(self.openness)))

    def draw(self, yaw_axes: Any, axes: Any, truth: FloatArray | None) -> None:
        """The gaze yaw on `yaw_axes`; openness, closures and PERCLOS on `axes`."""
        t_s = np.asarray(self.t_s)
        yaw_axes.plot(t_s, self.gaze_yaw_deg, "-", color="tab:green", lw=1, label="gaze (eyes)")
        for flags, colour, label in (
            (self.closed, "tab:red", "closed"),
            (self.unavailable, "tab:gray", "unavailable"),
        ):
            axes.fill_between(
                t_s, 0, 1, where=np.asarray(flags), color=colour, alpha=0.2, step="mid",
                transform=axes.get_xaxis_transform(), label=label,
            )  # fmt: skip
        if truth is not None and truth.shape[1] >= 6:
            axes.plot(truth[:, 0], 0.3 * truth[:, 5], "-", color="black", lw=1, label="truth x0.3")
        axes.plot(t_s, self.openness, ".", markersize=3, color="tab:blue", label="openness")
        axes.plot(t_s, self.perclos, "-", color="tab:orange", lw=1, label="PERCLOS")
        axes.set_ylim(0.0, max(0.5, float(np.nanmax(self.openness)) + 0.05))
        axes.set_ylabel("eyes (lid gap / width)")
        axes.legend(loc="upper left", fontsize=7, ncol=3)
        axes.grid(alpha=0.3)
