"""The pose plot: raw and smoothed yaw (and pitch) over time, with the truth and alerts if known."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from roadgaze.errors import RoadgazeError
from roadgaze.outputs.plot_eyes import EyeTrace
from roadgaze.types import Alert, ClosesOnExit, FloatArray, Frame, FrameRecord

ALERT_COLOURS = {"warning": "tab:orange", "critical": "tab:red", "info": "tab:green"}


class YawPlot(ClosesOnExit):
    """Pipeline sink that collects the pose of every record and saves a PNG when closed.

    Drawn: raw yaw (points), smoothed yaw with its +-2 sigma band, each alert as a dashed line
    with its kind; with `truth` (rows `t_s, yaw_deg, pitch_deg`) the true yaw too, and with
    `road_half_width_deg` the road-ahead band around 0. A second panel shows raw and smoothed
    pitch (and the true pitch) when any record has a pitch; with the eyes measured, the gaze yaw
    joins the yaw panel and a last panel shows the eyes (`roadgaze.outputs.plot_eyes`).
    """

    def __init__(
        self,
        path: str | Path,
        title: str | None = None,
        truth: FloatArray | None = None,
        road_half_width_deg: float | None = None,
    ) -> None:
        self.path = Path(path)
        self.title = title
        self.truth = truth
        self.road_half_width_deg = road_half_width_deg
        self.t_s: list[float] = []
        self.raw_deg: list[float] = []
        self.smoothed_deg: list[float] = []
        self.std_deg: list[float] = []
        self.pitch_raw_deg: list[float] = []
        self.pitch_deg: list[float] = []
        self.eyes = EyeTrace()
        self.alerts: list[Alert] = []
        self._closed = False

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        sample = record.sample
        self.t_s.append(sample.t_s)
        self.raw_deg.append(_nan_for_none(sample.yaw_raw_deg))
        self.smoothed_deg.append(_nan_for_none(sample.yaw_deg))
        self.std_deg.append(_nan_for_none(sample.yaw_std_deg))
        self.pitch_raw_deg.append(_nan_for_none(sample.pitch_raw_deg))
        self.pitch_deg.append(_nan_for_none(sample.pitch_deg))
        self.eyes.add(record)
        self.alerts.extend(record.alerts)

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        t_s = np.asarray(self.t_s)
        smoothed = np.asarray(self.smoothed_deg)
        std = np.asarray(self.std_deg)
        with_pitch = bool(np.any(np.isfinite(self.pitch_raw_deg)))
        with_eyes = self.eyes.measured
        ratios = (3, *((2,) if with_pitch else ()), *((2,) if with_eyes else ()))
        figure, panels = plt.subplots(
            len(ratios),
            1,
            figsize=(10, 4.5 + 2.5 * (len(ratios) - 1)),
            dpi=110,
            sharex=True,
            height_ratios=ratios,
            squeeze=False,
        )
        axes = panels[0, 0]
        pitch_axes = panels[1, 0] if with_pitch else None
        if with_eyes:
            self.eyes.draw(axes, panels[-1, 0], self.truth)
        if self.road_half_width_deg is not None:
            half = self.road_half_width_deg
            axes.axhspan(-half, half, color="tab:green", alpha=0.08, label="road ahead")
        if self.truth is not None:
            axes.plot(self.truth[:, 0], self.truth[:, 1], "-", color="black", lw=1.2, label="truth")
        axes.fill_between(t_s, smoothed - 2 * std, smoothed + 2 * std, alpha=0.2, label="±2σ")
        axes.plot(t_s, self.raw_deg, ".", markersize=3, color="tab:gray", label="raw")
        axes.plot(t_s, smoothed, "-", color="tab:blue", label="smoothed (Kalman)")
        axes.axhline(0.0, color="black", linewidth=0.5)
        top = axes.get_ylim()[1]
        for alert in self.alerts:
            colour = ALERT_COLOURS.get(alert.level.value, "tab:purple")
            axes.axvline(alert.t_s, color=colour, linestyle="--", linewidth=1)
            axes.text(
                alert.t_s, top, f" {alert.kind.value}", rotation=90, va="top", fontsize=7,
                color=colour,
            )  # fmt: skip
        axes.set_ylabel("yaw (deg, + = driver's left)")
        axes.set_title(self.title or "head pose")
        axes.legend(loc="lower left", fontsize=8)
        axes.grid(alpha=0.3)
        if pitch_axes is not None:
            if self.truth is not None and self.truth.shape[1] > 2:
                pitch_axes.plot(
                    self.truth[:, 0], self.truth[:, 2], "-", color="black", lw=1.2, label="truth"
                )
            pitch_axes.plot(
                t_s, self.pitch_raw_deg, ".", markersize=3, color="tab:gray", label="raw"
            )
            pitch_axes.plot(t_s, self.pitch_deg, "-", color="tab:purple", label="smoothed")
            pitch_axes.axhline(0.0, color="black", linewidth=0.5)
            pitch_axes.set_ylabel("pitch (deg, + = up)")
            pitch_axes.legend(loc="lower left", fontsize=8)
            pitch_axes.grid(alpha=0.3)
        panels[-1, 0].set_xlabel("time (s)")
        figure.tight_layout()
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            figure.savefig(self.path)
        except OSError as exc:
            raise RoadgazeError(f"cannot write plot {self.path}: {exc.strerror or exc}") from None
        finally:
            plt.close(figure)


def _nan_for_none(value: float | None) -> float:
    return math.nan if value is None else value
