"""The fleet summary table, the per-driver figures and the HTML report, on hand-made results."""

from __future__ import annotations

import base64
import re
from datetime import UTC, datetime
from pathlib import Path

import pytest

from roadgaze.fleet import BatchOutcome, Drive, DriveResult, by_driver, group_stats
from roadgaze.fleet.report import render_report
from roadgaze.fleet.summary import summary_table

START = datetime(2024, 5, 1, 8, 0, tzinfo=UTC)


def ok(drive_id: str, driver: str | None, **values: object) -> DriveResult:
    drive = Drive(drive_id, Path(f"/v/{drive_id}.mp4"), driver, "car-1", START)
    defaults: dict[str, object] = {
        "frames": 1800,
        "frames_with_face": 1800,
        "frames_gaze_known": 1800,
        "frames_off_road": 180,
        "duration_s": 60.0,
        "alert_counts": (("long_distraction", 1), ("vats", 0), ("driver_unavailable", 0)),
        "longest_off_road_s": 3.5,
        "neutral_yaw_deg": 2.0,
        "processing_fps": 90.0,
        "startup_s": 0.3,
        "wall_s": 21.0,
    }
    return DriveResult.of(drive, "ok", **{**defaults, **values})  # type: ignore[arg-type]


RESULTS = (
    ok("a1", "alice"),
    ok(
        "a2",
        "alice",
        frames=900,
        frames_with_face=450,
        frames_gaze_known=600,
        frames_off_road=300,
        duration_s=30.0,
        alert_counts=(("long_distraction", 2), ("vats", 1), ("driver_unavailable", 1)),
        critical_alerts=1,
        longest_off_road_s=7.25,
        neutral_yaw_deg=-4.0,
        processing_fps=45.0,
        resumed=True,
    ),
    ok("b1", None, duration_s=120.0, frames=3600, frames_with_face=3600, frames_gaze_known=3600),
    DriveResult.of(Drive("bad", Path("/v/bad.mp4"), "bob"), "failed", error="cannot read video"),
)


def test_group_figures_are_weighted_by_frames_and_time() -> None:
    alice = group_stats("alice", RESULTS[:2])
    assert alice.drives == alice.drives_ok == 2
    assert alice.hours == pytest.approx(90.0 / 3600)
    assert alice.face_found_rate == pytest.approx((1800 + 450) / 2700)
    assert alice.off_road_ratio == pytest.approx((180 + 300) / (1800 + 600))
    eye_kinds = ("microsleep", "sleep", "drowsy", "unresponsive", "degraded")
    eye_kinds += ("temporary_failure", "permanent_failure")  # alert/3's failure kinds
    eye_kinds += ("phone_use", "non_functional")  # alert/4
    assert alice.alerts == {
        "long_distraction": 3,
        "vats": 1,
        "driver_unavailable": 1,
    } | dict.fromkeys(eye_kinds, 0)
    assert alice.alerts_per_h["long_distraction"] == pytest.approx(3 * 3600 / 90)
    assert alice.longest_off_road_s == 7.25
    assert alice.neutral_yaw_deg == pytest.approx(-1.0)
    assert alice.processing_fps == pytest.approx(2700 / (1800 / 90 + 900 / 45))
    assert alice.critical_alerts == 1


def test_drivers_are_grouped_with_an_unknown_group_and_failures_counted() -> None:
    drivers = {d.name: d for d in by_driver(RESULTS)}
    assert sorted(drivers) == ["(unknown)", "alice", "bob"]
    bob = drivers["bob"]
    assert (bob.drives, bob.drives_ok, bob.drives_failed, bob.frames) == (1, 0, 1, 0)
    assert bob.face_found_rate is None and bob.alerts_per_h["vats"] is None


def test_summary_rows_per_drive_with_rates_per_hour_and_nulls_for_failures() -> None:
    rows = summary_table(RESULTS).to_pylist()
    assert [r["drive_id"] for r in rows] == ["a1", "a2", "b1", "bad"]
    a2 = rows[1]
    assert a2["start_time"] == START and a2["resumed"] is True
    assert a2["face_found_rate"] == 0.5 and a2["off_road_ratio"] == 0.5
    assert a2["long_distraction_per_h"] == 240.0 and a2["vats_per_h"] == 120.0
    assert a2["alerts_driver_unavailable"] == 1
    assert a2["processing_fps"] == 45.0  # as measured by the run that processed it
    bad = rows[3]
    assert (bad["status"], bad["error"], bad["frames"], bad["duration_s"]) == (
        "failed",
        "cannot read video",
        None,
        None,
    )


def test_the_report_is_one_self_contained_escaped_page(tmp_path: Path) -> None:
    evil = DriveResult.of(
        Drive("x", Path("/v/<script>.mp4"), "<b>eve</b>"), "failed", error="bad <script>alert(1)"
    )
    outcome = BatchOutcome((*RESULTS, evil), "local", 2, wall_s=30.0, startup_s=0.0)
    page = render_report(outcome)
    assert "<script" not in page.replace("&lt;script", "")
    assert "bad &lt;script&gt;alert(1)" in page and "&lt;b&gt;eve&lt;/b&gt;" in page
    assert not re.search(r'(src|href)="(?!data:)', page)  # nothing loaded from elsewhere
    images = re.findall(r'src="data:image/png;base64,([^"]+)"', page)
    assert len(images) == 3
    assert all(base64.b64decode(data).startswith(b"\x89PNG") for data in images)
    assert "cannot read video" in page and "alice" in page
    assert outcome.to_json()["frames"] == 1800 + 3600  # the resumed drive is not counted


def test_the_bar_legend_sits_beside_the_bars_and_tables_fit_the_page() -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from roadgaze.fleet.report import alerts_by_driver

    figure, axes = plt.subplots(figsize=(9.0, 2.5), dpi=100)
    try:
        alerts_by_driver(axes, by_driver(RESULTS[:3]))
        figure.tight_layout()
        figure.canvas.draw()
        legend = axes.get_legend().get_window_extent()
        plot_area = axes.get_window_extent()
        assert legend.x0 >= plot_area.x1  # not over the first bar
        assert legend.x1 <= figure.bbox.x1 + 1  # and inside the image
    finally:
        plt.close(figure)
    page = render_report(BatchOutcome(RESULTS, "local", 2, wall_s=30.0, startup_s=0.0))
    tables = page.count("<table>")
    assert tables == 3 and page.count('<div class="wide"><table>') == tables  # scroll, not clip
    assert ".wide{overflow-x:auto" in page and "white-space:normal" in page  # heads wrap
    # Kinds no drive raised take no columns (eight mostly empty columns made the tables too wide).
    assert "No drive raised microsleep, sleep, drowsy, unresponsive, degraded" in page
    assert "<th>microsleep /h</th>" not in page and "<th>vats /h</th>" in page


def test_a_batch_without_alerts_draws_no_empty_alert_plot() -> None:
    quiet = tuple(ok(r.drive_id, r.driver_id, alert_counts=()) for r in RESULTS if r.status == "ok")
    page = render_report(BatchOutcome(quiet, "local", 2, wall_s=30.0, startup_s=0.0))
    assert len(re.findall(r'src="data:image/png;base64,', page)) == 2  # the two histograms
    assert "No drive raised an alert, so there are no alert rates to plot." in page
