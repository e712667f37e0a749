"""The loop's phone step on real frames: hands and the judgement in every record at the stage's
pace, and nothing but null fields with phone detection off."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from repo_paths import STATEFARM
from roadgaze.capture.files import ImageFolderSource
from roadgaze.config import load_config
from roadgaze.errors import ModelError
from roadgaze.outputs.records import record_fields
from roadgaze.pipeline import Pipeline, create_detector


@pytest.fixture(scope="module")
def frames(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """12 frames of one driver holding a phone to the ear (links to the data, not copies)."""
    if not (STATEFARM / "ground_truth.csv").is_file():
        pytest.skip(f"no State Farm development images at {STATEFARM}")
    from roadgaze.landmarks.hands.models import fetch_hand_models
    from roadgaze.landmarks.model_store import default_cache_dir

    config = load_config(environ={})
    try:
        fetch_hand_models(config.model)
    except ModelError as exc:
        pytest.skip(f"hand models unavailable: {exc}")
    assert default_cache_dir(config.model).is_dir()
    with (STATEFARM / "ground_truth.csv").open(encoding="utf-8") as stream:
        rows = [r for r in csv.DictReader(stream) if r["subject"] == "p002" and r["class"] == "c2"]
    folder = tmp_path_factory.mktemp("frames")
    for index, row in enumerate(sorted(rows, key=lambda r: r["file"])[:12]):
        (folder / f"{index:03d}.jpg").symlink_to(STATEFARM / row["file"])
    return folder


def _records(folder: Path, **hands: object) -> list[dict[str, object]]:
    config = load_config(environ={})
    config = config.model_copy(update={"hands": config.hands.model_copy(update=hands)})
    detector = create_detector(config)
    try:
        pipeline = Pipeline.from_config(config, detector)
        with ImageFolderSource(folder, fps=10.0) as source:
            return [record_fields(pipeline.process(frame).record) for frame in source]
    finally:
        detector.close()


def test_every_frame_carries_the_hands_and_the_judgement_at_the_stage_pace(frames: Path) -> None:
    records = _records(frames, interval_s=0.3)
    assert len(records) == 12
    assert all(r["n_hands"] is not None and r["phone_use"] is not None for r in records)
    assert sum(r["phone_use"] is True for r in records) >= 6  # a phone at the ear, seen
    assert {r["phone_hand"] for r in records if r["phone_use"]} <= {"left", "right"}
    # 10 frames a second, hands every 0.3 s: frames 1-2 carry frame 0's judgement.
    assert records[1]["phone_score"] == records[0]["phone_score"] == records[2]["phone_score"]


def test_phone_detection_off_leaves_the_fields_null(frames: Path) -> None:
    records = _records(frames, enabled=False)
    assert all(r["n_hands"] is None and r["phone_use"] is None for r in records)


def test_the_body_is_measured_at_its_own_slower_pace_and_carried_between(frames: Path) -> None:
    import cv2

    from roadgaze.landmarks.hands.stage import HandStage

    config = load_config(environ={})
    hands = config.hands.model_copy(update={"interval_s": 0.3, "body_interval_s": 0.9})
    stage = HandStage.from_config(config.model_copy(update={"hands": hands}))
    assert stage is not None
    images = [cv2.imread(str(path)) for path in sorted(frames.iterdir())]
    body_runs = []
    try:
        for index in range(7):  # 0 .. 1.86 s
            assert stage.run(images[index], index * 0.31).fresh  # the hands every 0.31 s
            body_runs.append(stage.body_runs)
    finally:
        stage.close()
    assert body_runs == [1, 1, 1, 2, 2, 2, 3]  # the body at 0, 0.93 and 1.86 s, carried between
