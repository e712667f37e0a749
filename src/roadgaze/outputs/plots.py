"""The pose plot: what the monitor saw and decided, frame by frame, in one PNG.

Panels, top to bottom: the alerts (labels laid out in rows so that none overlap; no strip when
there is no alert); the yaw (raw, smoothed with its +-2 sigma band, the truth when known, the
gaze where the eyes give it; the road zone around the monitor's learned neutral, with the
narrower band the head must come back into (hysteresis); spans judged off road shaded); the pitch
the same way, with the gaze pitch (what puts a frame in `lap`), when the records have one; the
off-road timers with their thresholds (one label per threshold value: equal thresholds share
it); the eyes. Each plotted value is one `Series`: a new record field is one more entry in
`SERIES`. A series without any value in the run says so in its legend entry.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from roadgaze.config import MonitorConfig
from roadgaze.errors import RoadgazeError
from roadgaze.outputs.limits import (
    TIMER_THRESHOLDS,
    road_bands_deg,
    road_pitch_bands_deg,
    threshold_labels,
    timer_thresholds,
)
from roadgaze.types import (
    Alert,
    AlertKind,
    ClosesOnExit,
    EyeStatus,
    FloatArray,
    Frame,
    FrameRecord,
    Gaze,
    Sink,
)

ALERT_COLOURS = {"warning": "tab:orange", "critical": "tab:red", "info": "tab:green"}
MAX_LABEL_ROWS = 8
"""Rows of alert labels at most; alerts beyond them are marked but not labelled (and counted)."""
LABEL_GAP_PX = 6.0
"""Horizontal space kept between two labels in one row, in pixels."""


@dataclass(frozen=True, slots=True)
class Series:
    """One plotted value: its label, how to read it from a record, its panel and its style."""

    label: str
    value: Callable[[FrameRecord], float | None]
    panel: str
    style: Mapping[str, Any]


RAW_STYLE = {"ls": "", "marker": ".", "markersize": 3, "color": "tab:gray"}
SERIES: tuple[Series, ...] = (
    Series("raw", lambda r: r.sample.yaw_raw_deg, "yaw", RAW_STYLE),
    Series("smoothed (Kalman)", lambda r: r.sample.yaw_deg, "yaw", {"color": "tab:blue"}),
    Series("raw pitch", lambda r: r.sample.pitch_raw_deg, "pitch", RAW_STYLE),
    Series("smoothed pitch", lambda r: r.sample.pitch_deg, "pitch", {"color": "tab:purple"}),
    Series("off road, this glance", lambda r: r.verdict.off_road_s, "timers",
           {"color": "tab:red", "lw": 0.8}),
    Series("distraction (long-distraction timer)", lambda r: r.verdict.distraction_s, "timers",
           {"color": "tab:orange"}),
    Series("off road in the VATS window", lambda r: r.verdict.window_off_road_s, "timers",
           {"color": "tab:purple"}),
    Series("gaze (eyes)", lambda r: _eye_gaze_yaw_deg(r), "yaw", {"color": "tab:green", "lw": 1}),
    Series("gaze pitch (eyes)", lambda r: _eye_gaze_pitch_deg(r), "pitch",
           {"color": "tab:green", "lw": 1}),
    Series("eyes closed, this closure", lambda r: r.verdict.eyes.closure_s, "timers",
           {"color": "tab:brown", "lw": 0.8}),
    Series("openness", lambda r: r.verdict.eyes.openness, "eyes",
           {"ls": "", "marker": ".", "markersize": 3, "color": "tab:blue"}),
    Series("PERCLOS", lambda r: r.verdict.eyes.perclos, "eyes", {"color": "tab:orange", "lw": 1}),
)  # fmt: skip
"""What is plotted; a new record field (eyes, ...) joins with one line here (and a panel in
`PANELS` if it needs a new one)."""

PANELS = {
    "yaw": "yaw (deg, + = driver's left)",
    "pitch": "pitch (deg, + = up)",
    "timers": "off-road and closed time (s)",
    "eyes": "eyes (lid gap / width)",
}
"""The value panels, top to bottom, with their y labels; a panel whose values are all missing
(pitch from an old record) is left out."""
TRUTH_COLUMNS = {"yaw": 1, "pitch": 2}
"""Column of the truth array (`t_s, yaw_deg, pitch_deg`) drawn in each panel."""
TRUTH_OPENNESS_COLUMN, OPEN_EYE_GAP = 5, 0.3
"""A synthetic clip's true openness (a fraction of the photo's own; `roadgaze synth`), drawn
scaled to the lid gap of an open eye (about 0.3 of its width, docs/eyes.md)."""


def _eye_gaze_yaw_deg(record: FrameRecord) -> float | None:
    """The gaze yaw where the eyes gave it (None where it is the head's)."""
    eyes = record.verdict.eyes
    return eyes.gaze_yaw_deg if eyes.gaze_source == "eyes" else None


def _eye_gaze_pitch_deg(record: FrameRecord) -> float | None:
    """The gaze pitch where the eyes gave it (None where it is the head's)."""
    eyes = record.verdict.eyes
    return eyes.gaze_pitch_deg if eyes.gaze_source == "eyes" else None


def label_rows(spans: Sequence[tuple[float, float]], gap: float = 0.0) -> list[int]:
    """A row for each label so that labels in one row do not overlap.

    `spans` are the labels' (start, end) along x in any unit, `gap` the space kept between two
    labels of a row. Labels are placed in order of start, each in the lowest row whose last
    label ends at least `gap` before it starts.
    """
    ends: list[float] = []
    rows = [0] * len(spans)
    for index in sorted(range(len(spans)), key=lambda i: spans[i][0]):
        start, end = spans[index]
        row = next((r for r, last in enumerate(ends) if last + gap <= start), len(ends))
        if row == len(ends):
            ends.append(end)
        else:
            ends[row] = end
        rows[index] = row
    return rows


def _runs(flags: Sequence[bool]) -> list[tuple[int, int]]:
    """(first, last) index of each run of True."""
    runs: list[tuple[int, int]] = []
    start: int | None = None
    for index, flag in enumerate([*flags, False]):
        if flag and start is None:
            start = index
        elif not flag and start is not None:
            runs.append((start, index - 1))
            start = None
    return runs


def alert_label(alert: Alert) -> str:
    return alert.kind.value if alert.kind is AlertKind.CLEARED else f"{alert.kind} {alert.level}"


class YawPlot(ClosesOnExit, Sink):
    """Pipeline sink that collects every record and saves the PNG when closed.

    `monitor`: the monitor's configuration, for the road band (around each frame's learned
    neutral, with the hysteresis) and the timer thresholds; without it they are not drawn.
    `road_half_width_deg` alone (older callers) stands for a monitor with that width.
    `truth`: rows of `t_s, yaw_deg[, pitch_deg]`. After `close`, `label_boxes` holds each alert
    label's box in the saved figure (display pixels), for checking the layout.
    """

    def __init__(
        self,
        path: str | Path,
        title: str | None = None,
        truth: FloatArray | None = None,
        road_half_width_deg: float | None = None,
        monitor: MonitorConfig | None = None,
    ) -> None:
        if monitor is None and road_half_width_deg is not None:
            monitor = MonitorConfig(road_half_width_deg=road_half_width_deg)
        self.path = Path(path)
        self.title = title
        self.truth = truth
        self.monitor = monitor
        self.t_s: list[float] = []
        self.values: dict[str, list[float]] = {series.label: [] for series in SERIES}
        self.std_deg: list[float] = []
        self.neutral_deg: list[float] = []
        self.neutral_pitch_deg: list[float] = []
        self.gaze: list[Gaze] = []
        self.eye_status: list[EyeStatus] = []
        self.alerts: list[Alert] = []
        self.label_boxes: list[tuple[float, float, float, float]] = []
        self.unlabelled_alerts = 0
        self.legend_labels: dict[str, list[str]] = {}
        """Per panel, its legend entries as saved (after `close`)."""
        self.threshold_texts: list[str] = []
        """The timer panel's threshold labels as saved (after `close`)."""
        self._closed = False

    @property
    def smoothed_deg(self) -> list[float]:
        return self.values["smoothed (Kalman)"]

    @property
    def raw_deg(self) -> list[float]:
        return self.values["raw"]

    @property
    def pitch_deg(self) -> list[float]:
        return self.values["smoothed pitch"]

    @property
    def pitch_raw_deg(self) -> list[float]:
        return self.values["raw pitch"]

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        self.t_s.append(record.sample.t_s)
        for series in SERIES:
            self.values[series.label].append(_nan_for_none(series.value(record)))
        self.std_deg.append(_nan_for_none(record.sample.yaw_std_deg))
        self.neutral_deg.append(record.verdict.neutral_yaw_deg)
        self.neutral_pitch_deg.append(record.verdict.neutral_pitch_deg)
        self.gaze.append(record.verdict.gaze)
        self.eye_status.append(record.verdict.eyes.status)
        self.alerts.extend(record.alerts)

    def on_alert(self, alert: Alert) -> None:
        """An alert raised outside the frame loop: on the alert strip at its time."""
        self.alerts.append(alert)

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        panels = [
            name
            for name in PANELS
            if name == "yaw"
            or any(np.isfinite(self.values[s.label]).any() for s in SERIES if s.panel == name)
        ]
        strip = bool(self.alerts)  # no alert: no alert strip
        heights = [0.9] * strip + [3.0 if p == "yaw" else 1.6 for p in panels]
        figure, axes_list = plt.subplots(
            len(heights),
            1,
            sharex=True,
            squeeze=False,
            figsize=(12, 1.1 * strip + 0.9 + 2.6 * len(panels)),
            dpi=110,
            gridspec_kw={"height_ratios": heights},
        )
        value_axes = list(axes_list[:, 0])
        events = value_axes.pop(0) if strip else None
        axes = dict(zip(panels, value_axes, strict=True))
        t_s = np.asarray(self.t_s)
        self._draw_yaw(axes["yaw"], t_s)
        if "pitch" in axes:
            self._draw_pitch(axes["pitch"], t_s)
        if "timers" in axes:
            self._draw_timers(axes["timers"])
        if "eyes" in axes:
            self._draw_eyes(axes["eyes"], t_s)
        for name, column in TRUTH_COLUMNS.items():
            if name in axes and self.truth is not None and self.truth.shape[1] > column:
                axes[name].plot(self.truth[:, 0], self.truth[:, column], "-", color="black",
                                lw=1.2, label="truth")  # fmt: skip
        for series in SERIES:
            if series.panel in axes:
                values = self.values[series.label]
                label = series.label
                if not np.isfinite(values).any():
                    label += " (no value in this run)"
                axes[series.panel].plot(t_s, values, label=label, **series.style)
        for name, panel in axes.items():
            panel.set_ylabel(PANELS[name], fontsize=8)
            panel.grid(alpha=0.3)
            legend = panel.legend(loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize=7)
            self.legend_labels[name] = [text.get_text() for text in legend.get_texts()]
            for alert in self.alerts:
                colour = ALERT_COLOURS.get(alert.level.value, "tab:purple")
                panel.axvline(alert.t_s, color=colour, linestyle="--", linewidth=0.9)
        value_axes[-1].set_xlabel("time (s)")
        (events or value_axes[0]).set_title(self.title or "head pose")
        figure.tight_layout()
        if events is not None:
            self._draw_alert_labels(figure, events)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            figure.savefig(self.path)
        except OSError as exc:
            raise RoadgazeError(f"cannot write plot {self.path}: {exc.strerror or exc}") from None
        finally:
            plt.close(figure)

    def _draw_yaw(self, axes: Any, t_s: FloatArray) -> None:
        smoothed, std = np.asarray(self.smoothed_deg), np.asarray(self.std_deg)
        if self.monitor is not None and len(t_s):
            neutral = np.asarray(self.neutral_deg)
            (low, high), (back_low, back_high) = road_bands_deg(neutral, self.monitor)
            half = self.monitor.road_half_width_deg
            back = max(0.0, half - self.monitor.hysteresis_deg)
            axes.fill_between(t_s, low, high, color="tab:green", alpha=0.07,
                              label=f"road ahead: neutral ±{half:g}°")  # fmt: skip
            axes.fill_between(t_s, back_low, back_high, color="tab:green", alpha=0.1,
                              label=f"back on road within ±{back:g}°")  # fmt: skip
            axes.plot(t_s, neutral, "--", color="tab:green", lw=0.8, label="learned neutral")
        for gaze, colour, label in ((Gaze.OFF_ROAD, "tab:red", "judged off road"),
                                    (Gaze.UNKNOWN, "tab:gray", "gaze unknown")):  # fmt: skip
            for number, (first, last) in enumerate(_runs([g is gaze for g in self.gaze])):
                end = t_s[last + 1] if last + 1 < len(t_s) else t_s[last]
                axes.axvspan(t_s[first], end, color=colour, alpha=0.08, lw=0,
                             label=label if number == 0 else None)  # fmt: skip
        axes.fill_between(t_s, smoothed - 2 * std, smoothed + 2 * std, alpha=0.2, label="±2σ")
        axes.axhline(0.0, color="black", linewidth=0.5)

    def _draw_pitch(self, axes: Any, t_s: FloatArray) -> None:
        if self.monitor is not None and len(t_s):
            neutral = np.asarray(self.neutral_pitch_deg)
            (low, high), (back_low, back_high) = road_pitch_bands_deg(neutral, self.monitor)
            axes.fill_between(t_s, low, high, color="tab:green", alpha=0.07,
                              label="road zone (pitch)")  # fmt: skip
            axes.fill_between(t_s, back_low, back_high, color="tab:green", alpha=0.1,
                              label="back on road within")  # fmt: skip
            axes.plot(t_s, neutral, "--", color="tab:green", lw=0.8, label="learned neutral")
        axes.axhline(0.0, color="black", linewidth=0.5)

    def _draw_timers(self, axes: Any) -> None:
        if self.monitor is None:
            return
        for _, seconds, _, colour in timer_thresholds(self.monitor):
            axes.axhline(seconds, color=colour, lw=0.7, ls=":")
        for seconds, text, colour in threshold_labels(self.monitor):
            axes.annotate(text, (1.0, seconds), xycoords=("axes fraction", "data"), ha="right",
                          va="bottom", fontsize=6, color=colour)  # fmt: skip
            self.threshold_texts.append(text)

    def _draw_eyes(self, axes: Any, t_s: FloatArray) -> None:
        """Closed and unavailable stretches shaded; a synthetic clip's true openness."""
        for status, colour in ((EyeStatus.CLOSED, "tab:red"), (EyeStatus.UNAVAILABLE, "tab:gray")):
            for number, (first, last) in enumerate(_runs([e is status for e in self.eye_status])):
                end = t_s[last + 1] if last + 1 < len(t_s) else t_s[last]
                axes.axvspan(t_s[first], end, color=colour, alpha=0.12, lw=0,
                             label=f"eyes {status.value}" if number == 0 else None)  # fmt: skip
        truth = self.truth
        if truth is not None and truth.shape[1] > TRUTH_OPENNESS_COLUMN:
            axes.plot(truth[:, 0], OPEN_EYE_GAP * truth[:, TRUTH_OPENNESS_COLUMN], "-",
                      color="black", lw=1, label=f"truth x{OPEN_EYE_GAP:g}")  # fmt: skip

    def _draw_alert_labels(self, figure: Any, events: Any) -> None:
        """One label per alert in the top strip, in rows so that none overlaps another."""
        events.set_yticks([])
        for side in ("left", "right", "top"):
            events.spines[side].set_visible(False)
        if not self.alerts:
            return
        figure.canvas.draw()  # settles the x limits
        x_min, x_max = events.get_xlim()
        texts = []
        for alert in self.alerts:
            colour = ALERT_COLOURS.get(alert.level.value, "tab:purple")
            events.axvline(alert.t_s, color=colour, linestyle="--", linewidth=0.9)
            right_side = alert.t_s > x_min + 0.7 * (x_max - x_min)  # labels stay in the figure
            texts.append(
                events.text(alert.t_s, 0.0, f" {alert_label(alert)} ", fontsize=7, color=colour,
                            va="center", ha="right" if right_side else "left",
                            transform=events.get_xaxis_transform())
            )  # fmt: skip
        renderer = figure.canvas.get_renderer()
        spans = [(box.x0, box.x1) for box in (t.get_window_extent(renderer) for t in texts)]
        rows = label_rows(spans, gap=LABEL_GAP_PX)
        shown = min(MAX_LABEL_ROWS, max(rows) + 1)
        for text, row in zip(texts, rows, strict=True):
            if row >= shown:
                text.set_visible(False)
                self.unlabelled_alerts += 1
            else:
                text.set_y(1.0 - (row + 0.5) / shown)
        if self.unlabelled_alerts:
            events.set_title(f"{self.title or 'head pose'} ({self.unlabelled_alerts} more alerts "
                             "marked but not labelled)")  # fmt: skip
        figure.canvas.draw()
        self.label_boxes = [
            (float(box.x0), float(box.y0), float(box.x1), float(box.y1))
            for box in (text.get_window_extent(renderer) for text in texts if text.get_visible())
        ]


def _nan_for_none(value: float | None) -> float:
    return math.nan if value is None else value


__all__ = [
    "TIMER_THRESHOLDS",
    "Series",
    "YawPlot",
    "alert_label",
    "label_rows",
    "road_bands_deg",
    "road_pitch_bands_deg",
    "threshold_labels",
    "timer_thresholds",
]
