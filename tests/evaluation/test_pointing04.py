"""`roadgaze data pointing04`: the evaluation set from the public archive's file names, with the
sign flip (yaw_deg = -pan), checked against the development set's ground_truth.csv."""

from __future__ import annotations

import csv
import os
import subprocess
import sys
from pathlib import Path

import pytest

from repo_paths import POINTING04, child_env
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

ARCHIVE_IN_SET = [
    "images/Person01/person01100-90+0.jpg",
    "images/Person01/person01146+0+0.jpg",
    "images/Person01/person01163+15-45.jpg",
    "images/Person02/person02215-30+90.jpg",
]
"""The archive's images in the set `data pointing04` builds, in order."""


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
    assert [row["file"] for row in rows] == ARCHIVE_IN_SET
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


def tree(root: Path) -> dict[str, str]:
    """Every entry under `root`: a link's target, a file's bytes, a folder's mark."""
    entries: dict[str, str] = {}
    for path in sorted(root.rglob("*")):
        name = str(path.relative_to(root))
        if path.is_symlink():
            entries[name] = f"-> {path.readlink()}"
        elif path.is_file():
            entries[name] = path.read_bytes().hex()
        else:
            entries[name] = "dir"
    return entries


def make_set_layout(root: Path) -> Path:
    """A source laid out as the command writes its output: every image would be copied or
    linked onto itself if OUT were SRC."""
    for name in ("images/Person01/person01146+0+0.jpg", "images/Person01/person01163+15-45.jpg"):
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(b"\xff\xd8 jpeg " + name.encode())
    return root


@pytest.mark.parametrize("symlink", [False, True], ids=["copy", "symlink"])
@pytest.mark.parametrize("where", ["same", "same by another name", "inside", "around"])
def test_out_on_or_in_the_source_is_refused_before_anything_is_touched(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], where: str, symlink: bool
) -> None:
    source = make_set_layout(tmp_path / "SRC")
    (tmp_path / "alias").symlink_to(source)
    out = {
        "same": source,
        "same by another name": tmp_path / "alias",
        "inside": source / "images" / "set",
        "around": tmp_path,
    }[where]
    before = tree(tmp_path)
    args = ["data", "pointing04", str(source), str(out)] + (["--symlink"] if symlink else [])
    assert main(args) == 2
    assert tree(tmp_path) == before  # not a byte written, moved or linked
    err = capsys.readouterr().err.strip().splitlines()
    assert (
        len(err) == 1 and "the source folder" in err[0] and "pick an OUT folder outside" in err[0]
    )


def test_links_and_special_files_under_the_source_are_never_followed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    secret = tmp_path / "outside" / "secret.txt"
    secret.parent.mkdir()
    secret.write_bytes(b"root:x:0:0 secret")
    (secret.parent / "Person03").mkdir()
    (secret.parent / "Person03" / "personne03100+0+0.jpg").write_bytes(b"secret image")
    source = make_archive(tmp_path / "archive")
    (source / "Person01" / "personne01200+0+0.jpg").symlink_to(secret)
    (source / "Person01" / "personne01201+0+15.jpg").symlink_to("../../outside/secret.txt")
    (source / "Person03").symlink_to(secret.parent / "Person03")  # a folder outside
    os.mkfifo(source / "Person01" / "personne01202+0+30.jpg")  # would block a copy
    for symlink in (False, True):
        out = tmp_path / f"set-{symlink}"
        args = ["data", "pointing04", str(source), str(out)] + (["--symlink"] if symlink else [])
        assert main(args) == 0
        rows = read_rows(out / "ground_truth.csv")
        assert [row["file"] for row in rows] == ARCHIVE_IN_SET
        for path in out.rglob("*.jpg"):
            assert b"secret" not in path.read_bytes()
            assert path.resolve().is_relative_to(source.resolve()) or not path.is_symlink()
        warnings = [line for line in capsys.readouterr().err.splitlines() if "WARNING" in line]
        assert len(warnings) == 1 and "skipped 4 symbolic links or special files" in warnings[0]


SUBJECTS_REFUSED = "Pointing'04's subjects are 1-15; give e.g. 1-10 or 1,3,5"


@pytest.mark.parametrize(
    ("subjects", "says"),
    [
        ("1-1000000000", f"--subjects 1-1000000000: {SUBJECTS_REFUSED}"),
        ("5-3", f"--subjects 5-3: {SUBJECTS_REFUSED}"),
        ("0,2", f"--subjects 0: {SUBJECTS_REFUSED}"),
        ("2-x", "--subjects: expected e.g. 1-10 or 1,3,5, found '2-x'"),
    ],
)
def test_subjects_are_checked_against_the_archive_before_they_are_expanded(
    tmp_path: Path, subjects: str, says: str
) -> None:
    """Run as a user runs it, in a process limited to 1 GiB of address space beyond what it
    holds at start: a range expanded before it is checked would end in a MemoryError."""
    source = make_archive(tmp_path / "archive")
    out = tmp_path / "set"
    code = (
        "import resource, sys\n"
        "from roadgaze.cli import main\n"
        "limit = 1 << 30\n"
        "with open('/proc/self/status') as status:\n"
        "    vm = next(int(l.split()[1]) * 1024 for l in status if l.startswith('VmSize'))\n"
        "resource.setrlimit(resource.RLIMIT_AS, (vm + limit, vm + limit))\n"
        "sys.exit(main(sys.argv[1:]))\n"
    )
    args = ["data", "pointing04", str(source), str(out), "--subjects", subjects]
    result = subprocess.run(
        [sys.executable, "-c", code, *args],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=120,
        check=False,
    )
    assert result.returncode == 2, result.stderr[-2000:]
    assert result.stderr.strip().splitlines() == [f"roadgaze data: error: {says}"]
    assert not out.exists()


def test_subjects_as_numbers() -> None:
    from roadgaze.evaluation.pointing04 import parse_subjects

    assert parse_subjects("1-3, 7,15") == frozenset({1, 2, 3, 7, 15})
