"""The pipeline and the monitor on synthetic clips with known yaw (no evaluation data needed)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from roadgaze.capture import open_source
from roadgaze.config import Config
from roadgaze.monitor import AlertKind
from roadgaze.pipeline import Pipeline, create_detector
from roadgaze.types import Frame, FrameRecord, PoseSample

SyntheticClip = Callable[[str], tuple[Path, Any]]


class Collect:
    def __init__(self) -> None:
        self.records: list[FrameRecord] = []

    def on_record(self, record: FrameRecord, frame: Frame) -> None:
        self.records.append(record)

    def close(self) -> None:
        return None

    @property
    def samples(self) -> list[PoseSample]:
        return [record.sample for record in self.records]

    @property
    def alerts(self) -> list[Any]:
        return [alert for record in self.records for alert in record.alerts]


def run_pipeline(path: Path, config: Config) -> Collect:
    collect = Collect()
    with open_source(str(path), config) as source:
        detector = create_detector(config)
        try:
            Pipeline.from_config(config, detector).run(source, [collect])
        finally:
            detector.close()
    return collect


@pytest.mark.slow
def test_pipeline_yaw_follows_the_synthetic_truth(synthetic_clip: SyntheticClip) -> None:
    path, truth = synthetic_clip("0:1,30:1.5,0:1,-30:1.5")
    samples = run_pipeline(path, Config()).samples
    assert len(samples) == len(truth)
    np.testing.assert_allclose([s.t_s for s in samples], truth[:, 0], atol=1e-3)
    assert all(s.face and s.n_faces == 1 for s in samples)
    raw = np.array([s.yaw_raw_deg for s in samples], dtype=float)
    smoothed = np.array([s.yaw_deg for s in samples], dtype=float)
    holding = np.abs(np.gradient(truth[:, 1])) < 1e-9  # frames between turns
    assert np.max(np.abs(raw - truth[:, 1])[holding]) < 8.0
    assert np.all(
        np.sign(raw[holding & (np.abs(truth[:, 1]) > 10)])
        == np.sign(truth[holding & (np.abs(truth[:, 1]) > 10), 1])
    )
    # The smoother follows the turns: settled within 0.5 s of the end of each turn.
    t_s = truth[:, 0]
    settled = holding & (((t_s > 1.5 + 0.5) & (t_s < 2.5)) | ((t_s > 3.5 + 0.5) & (t_s < 5.0)))
    assert np.mean(np.abs(smoothed - truth[:, 1])[settled]) < 6.0


@pytest.mark.slow
def test_monitor_raises_long_distraction_when_the_glance_lasts(
    synthetic_clip: SyntheticClip,
) -> None:
    path, truth = synthetic_clip("0:1.5,-35:4,0:1.5")
    # -35 is the right mirror since the mirrors end where ADDW's areas begin; with no
    # driving-related zones every glance off the road runs the timer from the band's edge.
    config = Config.model_validate({"monitor": {"driving_related_zones": []}})
    monitor = run_pipeline(path, config)
    samples = monitor.samples
    kinds = [alert.kind for alert in monitor.alerts]
    assert kinds == [AlertKind.LONG_DISTRACTION, AlertKind.CLEARED]
    # Off road once the estimate leaves the 25 deg road band: truth reaches ~25 deg mid-turn.
    band = config.monitor.road_half_width_deg
    left_road_s = next(s.t_s for s in samples if s.yaw_deg is not None and s.yaw_deg < -band)
    long_alert = monitor.alerts[0]
    expected_s = left_road_s + config.monitor.long_distraction_s
    assert abs(long_alert.t_s - expected_s) < 0.2
    assert 1.5 + 0.25 < left_road_s < 1.5 + 0.6  # the truth crosses -25 deg about 0.32 s in
    assert monitor.alerts[1].t_s > 5.5  # cleared after the head is back (turn starts at 5.5 s)
    assert len(samples) == len(truth)


@pytest.mark.slow
def test_monitor_stays_quiet_for_short_glances(synthetic_clip: SyntheticClip) -> None:
    path, _ = synthetic_clip("0:1,35:1.2,0:1,-35:1.2,0:1")
    config = Config()
    monitor = run_pipeline(path, config)
    assert monitor.alerts == []
    assert monitor.records[-1].verdict.on_road


@pytest.mark.slow
def test_replay_on_a_synthetic_clip_writes_every_output(
    synthetic_clip: SyntheticClip, tmp_path: Path
) -> None:
    import json

    import cv2

    from roadgaze.cli import main

    path, truth = synthetic_clip("0:1,30:1.5,0:1,-30:1.5")
    out, table = tmp_path / "frames.jsonl", tmp_path / "frames.csv"
    plot, video = tmp_path / "yaw.png", tmp_path / "annotated.mp4"
    arguments = ["replay", str(path), "--out", str(out), "--csv", str(table)]
    arguments += ["--plot", str(plot), "--annotate", str(video), "--no-progress"]
    assert main(arguments) == 0
    records = [json.loads(line) for line in out.read_text().splitlines()]
    assert [r["frame"] for r in records] == list(range(len(truth)))
    raw = np.array([r["yaw_raw_deg"] for r in records], dtype=float)
    holding = np.abs(np.gradient(truth[:, 1])) < 1e-9
    assert np.max(np.abs(raw - truth[:, 1])[holding]) < 8.0
    assert len(table.read_text().splitlines()) == len(truth) + 1
    # the offline columns, null while streaming, are filled at the normal end
    offline = np.array([r["yaw_offline_deg"] for r in records], dtype=float)
    assert np.all(np.isfinite(offline[raw == raw]))
    assert np.max(np.abs(offline - truth[:, 1])[holding]) < 8.0
    # After the first frames: the rendered frontal face reads a pitch of -11 to -15 deg, at the
    # road zone's lower edge while the neutral pitch is still being learned (one frame may read
    # `cluster` there).
    assert all(r["zone"] in ("road", "left_mirror", "away") for r in records[5:])
    assert "yaw_offline_deg" in table.read_text().splitlines()[0]
    assert cv2.imread(str(plot)) is not None
    capture = cv2.VideoCapture(str(video))
    assert capture.get(cv2.CAP_PROP_FRAME_COUNT) == len(truth)
    capture.release()
