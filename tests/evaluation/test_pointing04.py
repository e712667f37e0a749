"""`roadgaze data pointing04`: the evaluation set from the public archive's file names, with the
sign flip (yaw_deg = -pan), checked against the development set's ground_truth.csv."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from repo_paths import POINTING04
from roadgaze.cli import main
from roadgaze.evaluation import load_ground_truth
from roadgaze.evaluation.pointing04 import find_images, parse_name

ARCHIVE_NAMES = (
    "Person01/personne01146+0+0.jpg",
    "Person01/personne01100-90+0.jpg",
    "Person01/personne01163+15-45.jpg",
    "Person02/personne02215-30+90.jpg",
    "Person02/personne02215-30+90.txt",  # the archive's face box files are not images
    "Front/readme.jpg",
)


def make_archive(root: Path) -> Path:
    for name in ARCHIVE_NAMES:
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(b"\xff\xd8 jpeg " + name.encode())
    return root


def read_rows(csv_path: Path) -> list[dict[str, str]]:
    with csv_path.open(newline="") as stream:
        return list(csv.DictReader(stream))


def test_the_name_holds_subject_series_index_tilt_and_pan() -> None:
    image = parse_name(Path("personne02215-30+90.jpg"))
    assert image is not None
    assert (image.subject, image.series, image.index) == (2, 2, 15)
    assert (image.tilt_deg, image.pan_deg, image.yaw_deg) == (-30, 90, -90)
    assert parse_name(Path("person01146+0+0.JPG")) is not None  # copies that drop the "ne"
    assert parse_name(Path("personne01146+0+0.txt")) is None
    assert parse_name(Path("portrait.jpg")) is None


def test_the_command_builds_the_set_eval_reads(tmp_path: Path) -> None:
    source = make_archive(tmp_path / "archive")
    out = tmp_path / "set"
    assert main(["data", "pointing04", str(source), str(out)]) == 0
    rows = read_rows(out / "ground_truth.csv")
    assert [row["file"] for row in rows] == [
        "images/Person01/person01100-90+0.jpg",
        "images/Person01/person01146+0+0.jpg",
        "images/Person01/person01163+15-45.jpg",
        "images/Person02/person02215-30+90.jpg",
    ]
    assert [(row["yaw_deg"], row["pitch_deg"]) for row in rows] == [
        ("0", "-90"),
        ("0", "0"),
        ("45", "15"),  # pan -45: turned to the subject's own left, yaw > 0
        ("-90", "-30"),
    ]
    assert [(row["subject"], row["series"]) for row in rows] == [
        ("1", "1"),
        ("1", "1"),
        ("1", "1"),
        ("2", "2"),
    ]
    copied = out / rows[2]["file"]
    assert copied.read_bytes() == (source / ARCHIVE_NAMES[2]).read_bytes()
    truths, skipped = load_ground_truth(out)
    assert skipped == 1 and [t.yaw_deg for t in truths] == [0.0, 45.0, -90.0]


def test_subjects_symlinks_and_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    source = make_archive(tmp_path / "archive")
    out = tmp_path / "set"
    assert main(["data", "pointing04", str(source), str(out), "--subjects", "2", "--symlink"]) == 0
    rows = read_rows(out / "ground_truth.csv")
    assert [row["subject"] for row in rows] == ["2"]
    assert (out / rows[0]["file"]).is_symlink()
    # Again into the same folder, from nothing, twice the same image: one line each, exit 2.
    assert main(["data", "pointing04", str(source), str(out)]) == 2
    assert main(["data", "pointing04", str(tmp_path / "none"), str(tmp_path / "b")]) == 2
    (source / "copy").mkdir()
    (source / "copy" / "personne01146+0+0.jpg").write_bytes(b"x")
    assert main(["data", "pointing04", str(source), str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err.splitlines()
    errors = [line for line in err if "error:" in line]
    assert len(errors) == 3 and "Traceback" not in "\n".join(err)
    assert "exists" in errors[0] and "not a folder" in errors[1] and "same image" in errors[2]


def test_eval_without_a_folder_names_the_variable(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.delenv("ROADGAZE_DATA", raising=False)
    assert main(["eval"]) == 2
    assert "ROADGAZE_DATA is not set" in capsys.readouterr().err


@pytest.mark.skipif(not POINTING04.is_dir(), reason="needs the Pointing'04 set ($ROADGAZE_DATA)")
def test_the_development_set_is_what_the_command_builds_from_its_images(tmp_path: Path) -> None:
    """The images carry their labels in their names: rebuilding the set from them gives the same
    ground_truth.csv, row for row (the sign flip included)."""
    images = find_images(POINTING04 / "images")
    assert len(images) == len(read_rows(POINTING04 / "ground_truth.csv"))
    out = tmp_path / "rebuilt"
    assert main(["data", "pointing04", str(POINTING04 / "images"), str(out), "--symlink"]) == 0
    rebuilt = read_rows(out / "ground_truth.csv")
    original = read_rows(POINTING04 / "ground_truth.csv")
    key = lambda row: row["file"]  # noqa: E731
    assert sorted(rebuilt, key=key) == sorted(original, key=key)
