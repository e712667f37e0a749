"""The drives of a batch: a folder searched recursively, or a CSV manifest and its errors."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta, timezone
from pathlib import Path

import pytest

from roadgaze.errors import ConfigError
from roadgaze.fleet import derived_drive_ids, discover_drives

HEADER = "path,drive_id,driver_id,vehicle_id,start_time\n"


def touch(path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(b"x")
    return path


def test_a_folder_is_searched_recursively_for_videos_in_path_order(tmp_path: Path) -> None:
    for name in ("b.mp4", "a.MKV", "fleet A/2024-05-01/cab.avi", "notes.txt", "a.truth.csv"):
        touch(tmp_path / name)
    touch(tmp_path / ".hidden" / "x.mp4")
    touch(tmp_path / ".partial.mp4")
    drives = discover_drives(tmp_path)
    assert [d.drive_id for d in drives] == ["a", "b", "fleet_A__2024-05-01__cab"]
    assert [d.path for d in drives] == [
        tmp_path / "a.MKV",
        tmp_path / "b.mp4",
        tmp_path / "fleet A/2024-05-01/cab.avi",
    ]
    assert all(d.driver_id is None and d.start_time is None for d in drives)


def test_derived_ids_are_unique_safe_and_stable() -> None:
    paths = [Path("a.mp4"), Path("a.mkv"), Path("x/é ü.mp4"), Path("x__y.mp4"), Path("x/y.mp4")]
    ids = derived_drive_ids(paths)
    assert len(set(ids)) == len(ids)
    assert ids == derived_drive_ids(paths)
    assert ids[0].startswith("a-") and ids[1].startswith("a-") and len(ids[0]) == 10
    assert ids[2] == "x"
    assert ids[3].startswith("x__y-") and ids[4].startswith("x__y-")
    assert all(name.replace("_", "").replace("-", "").isalnum() for name in ids)


def test_a_manifest_gives_ids_metadata_and_paths_relative_to_itself(tmp_path: Path) -> None:
    manifest = tmp_path / "lists" / "drives.csv"
    manifest.parent.mkdir()
    manifest.write_text(
        HEADER + "../videos/one.mp4,d-001,alice,car-7,2024-05-01T08:30:00+02:00\n"
        "/abs/two.mp4,,bob,,2024-05-02 09:00\n"
        "three.mp4,,,,\n",
        encoding="utf-8",
    )
    one, two, three = discover_drives(manifest)
    assert (one.drive_id, one.driver_id, one.vehicle_id) == ("d-001", "alice", "car-7")
    assert one.path == tmp_path / "lists" / "../videos/one.mp4"
    assert one.start_time == datetime(2024, 5, 1, 8, 30, tzinfo=timezone(timedelta(hours=2)))
    assert (two.drive_id, two.path, two.vehicle_id) == ("abs__two", Path("/abs/two.mp4"), None)
    assert two.start_time == datetime(2024, 5, 2, 9, 0, tzinfo=UTC)
    assert (three.drive_id, three.driver_id, three.start_time) == ("three", None, None)


def test_a_manifest_with_only_a_path_column_is_enough(tmp_path: Path) -> None:
    manifest = tmp_path / "m.csv"
    manifest.write_text("path\nx.mp4\nsub/x.mp4\n", encoding="utf-8")
    assert [d.drive_id for d in discover_drives(manifest)] == ["x", "sub__x"]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("file,driver_id\nx.mp4,a\n", "has no 'path' column"),
        ("path,driver\nx.mp4,a\n", "unknown columns driver"),
        ("path\n", "lists no drive"),
        (HEADER + ",d1,,,\n", "line 2: empty 'path'"),
        (HEADER + "x.mp4,../evil,,,\n", "line 2: drive_id '../evil' is not filesystem-safe"),
        (HEADER + "x.mp4,d1,,,\ny.mp4,d1,,,\n", "drive ids must be unique; repeated: d1"),
        (HEADER + "x.mp4,,,,\ny.mkv,x,,,\n", "repeated: x"),
        (HEADER + "x.mp4,,,,yesterday\n", "line 2: start_time 'yesterday' is not ISO 8601"),
        ("path\nx.mp4,extra\n", "line 2: more cells than columns"),
    ],
)
def test_manifest_errors_name_the_problem_and_the_line(
    tmp_path: Path, text: str, message: str
) -> None:
    manifest = tmp_path / "m.csv"
    manifest.write_text(text, encoding="utf-8")
    with pytest.raises(ConfigError) as error:
        discover_drives(manifest)
    assert message in str(error.value)


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda p: p / "missing", "not found"),
        (lambda p: touch(p / "list.txt"), "neither a folder nor a .csv manifest"),
        (lambda p: touch(p / "empty" / "notes.txt").parent, "no video found under"),
    ],
    ids=["missing", "not-csv", "no-video"],
)
def test_bad_batch_inputs(tmp_path: Path, make: object, message: str) -> None:
    with pytest.raises(ConfigError) as error:
        discover_drives(make(tmp_path))  # type: ignore[operator]
    assert message in str(error.value)
