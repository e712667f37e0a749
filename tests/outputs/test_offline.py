"""The offline columns: written null while streaming, filled atomically at the end of a replay."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from fakes import BLANK_FRAME, record_of
from roadgaze.errors import RoadgazeError
from roadgaze.outputs import CsvWriter, JsonlWriter, fill_offline_columns
from roadgaze.pose import offline_pose
from roadgaze.types import PoseSample

FPS = 15.0


def noisy_turn() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.arange(90) / FPS
    truth = 30.0 * np.clip(t - 2.0, 0.0, 1.0)
    rng = np.random.default_rng(3)
    yaw = truth + rng.normal(0.0, 3.0, t.shape)
    pitch = -0.5 * truth + rng.normal(0.0, 3.0, t.shape)
    yaw[40:44] = np.nan  # a short loss of the face
    return t, yaw, pitch


def write_records(path: Path, writer_type: type[JsonlWriter] | type[CsvWriter]) -> None:
    t, yaw, pitch = noisy_turn()
    with writer_type(path) as writer:
        for i, t_s in enumerate(t):
            face = bool(np.isfinite(yaw[i]))
            sample = PoseSample(
                float(t_s), i, face, float(yaw[i]) if face else None, None, None, None,
                pitch_raw_deg=float(pitch[i]) if face else None,
            )  # fmt: skip
            writer.on_record(record_of(sample), BLANK_FRAME)


def read_column(path: Path, name: str) -> np.ndarray:
    if path.suffix == ".csv":
        with path.open(newline="") as stream:
            cells = [row[name] for row in csv.DictReader(stream)]
        return np.array([float(c) if c else np.nan for c in cells])
    values = [json.loads(line)[name] for line in path.read_text().splitlines()]
    return np.array([np.nan if v is None else v for v in values], dtype=float)


@pytest.mark.parametrize(
    ("name", "writer_type"), [("frames.jsonl", JsonlWriter), ("frames.csv", CsvWriter)]
)
def test_streamed_nulls_are_filled_with_the_offline_pass(
    tmp_path: Path, name: str, writer_type: type[JsonlWriter] | type[CsvWriter]
) -> None:
    path = tmp_path / name
    write_records(path, writer_type)
    assert np.all(np.isnan(read_column(path, "yaw_offline_deg")))  # null while streaming
    before = read_column(path, "yaw_raw_deg")
    assert fill_offline_columns(path) == 90
    t, yaw, pitch = noisy_turn()
    expected = offline_pose(t, yaw, np.where(np.isfinite(yaw), pitch, np.nan))
    yaw_filled = read_column(path, "yaw_offline_deg")
    np.testing.assert_allclose(yaw_filled, expected.yaw_deg, atol=0.01)  # from rounded raw
    np.testing.assert_allclose(
        read_column(path, "pitch_offline_deg"), expected.pitch_deg, atol=1e-3
    )
    np.testing.assert_array_equal(read_column(path, "yaw_raw_deg"), before)  # the rest is kept
    assert np.all(np.isfinite(yaw_filled[40:44]))  # a short gap is bridged offline
    assert [p.name for p in tmp_path.iterdir()] == [name]  # no temporary file left behind


def test_a_file_that_cannot_be_read_is_left_as_it_was(tmp_path: Path) -> None:
    path = tmp_path / "frames.jsonl"
    text = '{"t_s": 0.0, "yaw_raw_deg": 1.0}\nnot json\n'
    path.write_text(text)
    with pytest.raises(RoadgazeError, match=r"frames\.jsonl:2"):
        fill_offline_columns(path)
    assert path.read_text() == text
    path.write_text('{"t_s": 1.0, "yaw_raw_deg": 1.0}\n{"t_s": 0.5, "yaw_raw_deg": 2.0}\n')
    with pytest.raises(RoadgazeError, match="increase"):
        fill_offline_columns(path)
    with pytest.raises(RoadgazeError, match="cannot"):
        fill_offline_columns(tmp_path / "absent.jsonl")
