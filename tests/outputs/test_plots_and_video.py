"""The plot and the annotated video tell the truth: the monitor's band, labels that never
overlap, alerts on screen until cleared, the gaze and the timers."""

from __future__ import annotations

import dataclasses
import itertools
from pathlib import Path

import numpy as np
import pytest

from fakes import BLANK_FRAME
from roadgaze.config import MonitorConfig
from roadgaze.monitor import Monitor
from roadgaze.outputs import PANEL_LINES, AlertBoard, YawPlot, annotate, label_rows
from roadgaze.outputs.plots import road_bands_deg
from roadgaze.types import Alert, AlertKind, AlertLevel, EyesVerdict, FrameRecord, PoseSample

FIXED = MonitorConfig(neutral_yaw_deg=0.0, zones=[], driving_related_zones=[])
"""No zones but the road: any glance off it is a distraction."""


def monitored(config: MonitorConfig, yaws: list[tuple[float, float]]) -> list[FrameRecord]:
    """The records the monitor makes of (t_s, yaw) samples with a face."""
    monitor = Monitor(config)
    records = []
    for t_s, yaw in yaws:
        sample = PoseSample(t_s, round(t_s * 10), True, yaw, yaw, 0.0, 1.0, n_faces=1)
        alerts = monitor.update(sample, None)
        records.append(FrameRecord(sample, monitor.verdict, alerts))
    return records


def glance(
    seconds: float, yaw_deg: float = 45.0, before_s: float = 1.0
) -> list[tuple[float, float]]:
    """Road for `before_s`, off road at `yaw_deg` for `seconds`, road for 2 s; 10 samples/s."""
    steps = round((before_s + seconds + 2.0) * 10)
    return [
        (i / 10, yaw_deg if before_s <= i / 10 < before_s + seconds else 0.0) for i in range(steps)
    ]


# ---------------------------------------------------------------- the plot


def test_label_rows_keep_overlapping_labels_apart() -> None:
    spans = [(0.0, 4.0), (1.0, 3.0), (5.0, 6.0), (2.0, 9.0), (4.5, 5.5)]
    rows = label_rows(spans, gap=0.5)
    assert rows == [0, 1, 1, 2, 0]
    for (a, row_a), (b, row_b) in itertools.combinations(zip(spans, rows, strict=True), 2):
        if row_a == row_b:
            assert a[1] + 0.5 <= b[0] or b[1] + 0.5 <= a[0]
    assert label_rows([]) == []


def test_the_road_band_follows_the_neutral_with_the_hysteresis() -> None:
    neutral = np.array([0.0, 4.0, 10.0])
    (low, high), (back_low, back_high) = road_bands_deg(neutral, MonitorConfig())
    np.testing.assert_allclose(low, [-25.0, -21.0, -15.0])
    np.testing.assert_allclose(high, [25.0, 29.0, 35.0])
    np.testing.assert_allclose(back_high - back_low, [40.0] * 3)
    np.testing.assert_allclose(back_low, neutral - 20.0)


def boxes_overlap(a: tuple[float, ...], b: tuple[float, ...]) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


@pytest.mark.parametrize("count", [2, 9, 40])
def test_alert_labels_in_the_saved_figure_never_overlap(tmp_path: Path, count: int) -> None:
    """Alerts a few hundredths of a second apart, as the demo's vats and cleared are."""
    plot = YawPlot(tmp_path / "yaw.png", monitor=FIXED)
    kinds = [AlertKind.VATS, AlertKind.CLEARED, AlertKind.LONG_DISTRACTION]
    for record in monitored(FIXED, glance(4.0)):
        plot.on_record(record, BLANK_FRAME)
    plot.alerts = [
        Alert(kinds[i % 3], AlertLevel.WARNING, 3.0 + 0.07 * i, 30.0, 1.0, 10.0)
        for i in range(count)
    ]
    plot.close()
    assert (tmp_path / "yaw.png").read_bytes()[:4] == b"\x89PNG"
    boxes = plot.label_boxes
    assert len(boxes) + plot.unlabelled_alerts == count
    assert len(boxes) >= min(count, 8)
    for a, b in itertools.combinations(boxes, 2):
        assert not boxes_overlap(a, b), (a, b)


def test_plot_keeps_what_the_monitor_decided(tmp_path: Path) -> None:
    records = monitored(FIXED, glance(4.0))
    with YawPlot(tmp_path / "yaw.png", monitor=FIXED) as plot:
        for record in records:
            plot.on_record(record, BLANK_FRAME)
    assert plot.neutral_deg == [0.0] * len(records)
    assert [a.kind for a in plot.alerts] == [AlertKind.LONG_DISTRACTION, AlertKind.CLEARED]
    assert len(plot.label_boxes) == 2


def test_the_plot_draws_the_gaze_pitch_shares_equal_thresholds_and_names_empty_series(
    tmp_path: Path,
) -> None:
    """The gaze pitch is what puts a frame in `lap`; long distraction and sleep are both 3 s
    (one label, not two printed on top of each other); PERCLOS without a value says so."""
    eyes = EyesVerdict(gaze_source="eyes", gaze_yaw_deg=2.0, gaze_pitch_deg=-30.0, openness=0.3)
    records = [
        dataclasses.replace(r, verdict=dataclasses.replace(r.verdict, eyes=eyes))
        for r in monitored(FIXED, glance(4.0))
    ]
    with YawPlot(tmp_path / "yaw.png", monitor=FIXED) as plot:
        for record in records:
            plot.on_record(record, BLANK_FRAME)
    assert plot.pitch_deg and "gaze pitch (eyes)" in plot.legend_labels["pitch"]
    assert "PERCLOS (no value in this run)" in plot.legend_labels["eyes"]
    assert "long distraction, sleep 3 s" in plot.threshold_texts
    values = [text.rsplit(" ", 2)[-2] for text in plot.threshold_texts]
    assert len(values) == len(set(values))  # one label per value


def test_without_alerts_there_is_no_alert_strip(tmp_path: Path) -> None:
    import matplotlib.image

    with YawPlot(tmp_path / "quiet.png", monitor=FIXED) as quiet:
        for record in monitored(FIXED, glance(1.0)):
            quiet.on_record(record, BLANK_FRAME)
    with YawPlot(tmp_path / "alerts.png", monitor=FIXED) as alerted:
        for record in monitored(FIXED, glance(4.0)):
            alerted.on_record(record, BLANK_FRAME)
    assert quiet.alerts == [] and quiet.label_boxes == []
    quiet_height = matplotlib.image.imread(tmp_path / "quiet.png").shape[0]
    alerts_height = matplotlib.image.imread(tmp_path / "alerts.png").shape[0]
    assert alerts_height - quiet_height == pytest.approx(1.1 * 110, abs=2)  # the strip, 1.1 in


# ---------------------------------------------------------------- the annotated video


def test_an_alert_stays_on_screen_until_cleared() -> None:
    config = FIXED
    board = AlertBoard()
    shown = {round(r.t_s, 1): board.update(r) for r in monitored(config, glance(7.0))}
    assert shown[3.9] == []
    [warning] = shown[4.0]  # 3 s into the glance
    assert (warning.kind, warning.level, warning.elapsed_s) == (
        AlertKind.LONG_DISTRACTION,
        AlertLevel.WARNING,
        0.0,
    )
    assert shown[5.5][0].elapsed_s == pytest.approx(1.5)
    # escalated at 6 s: the level changes, the time still counts; away 6 s is also unresponsive
    critical, unresponsive = shown[7.5]
    assert (critical.level, critical.elapsed_s) == (AlertLevel.CRITICAL, pytest.approx(3.5))
    assert critical.text == "LONG DISTRACTION  critical  3.5 s"
    assert (unresponsive.kind, unresponsive.elapsed_s) == (
        AlertKind.UNRESPONSIVE,
        pytest.approx(0.5),
    )
    assert [b.kind for b in shown[7.9]] == [AlertKind.LONG_DISTRACTION, AlertKind.UNRESPONSIVE]
    assert [b.kind for b in shown[8.0]] == [AlertKind.CLEARED]  # back on road
    assert [b.kind for b in shown[8.9]] == [AlertKind.CLEARED]
    assert shown[9.0] == []


def test_a_banner_is_drawn_at_the_top() -> None:
    records = monitored(FIXED, glance(4.0))
    board = AlertBoard()
    banners = []
    for record in records[:46]:
        banners = board.update(record)
    assert [b.kind for b in banners] == [AlertKind.LONG_DISTRACTION]
    image = np.full((240, 320, 3), 60, np.uint8)
    plain = annotate(image, records[45], FIXED)
    with_banner = annotate(image, records[45], FIXED, banners)
    top = with_banner[5:25, 10:150].reshape(-1, 3).astype(int)
    orange = (top[:, 2] > 200) & (top[:, 1] > 90) & (top[:, 1] < 170) & (top[:, 0] < 60)
    assert orange.mean() > 0.5
    assert not (plain[5:25, 10:150] != 60).all(axis=2).any()


def test_panel_lines_show_the_gaze_and_the_timers_against_their_thresholds() -> None:
    record = monitored(FIXED, glance(4.0))[25]  # 1.5 s into the glance
    lines = [line(record, FIXED) for line in PANEL_LINES]
    assert lines[2] == "zone AWAY  neutral +0.0/+0.0 deg  speed unknown (counting)"
    assert lines[3] == "off road 1.5 s  distraction 1.5/3 s  VATS window 1.5/10 s"
    assert lines[4] == "eyes UNAVAILABLE (no eyes measured)  gaze +45/+0 deg (head)"
    without_thresholds = [line(record, None) for line in PANEL_LINES][3]
    assert without_thresholds == "off road 1.5 s  distraction 1.5 s  VATS window 1.5 s"
