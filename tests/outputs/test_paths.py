"""Where a run may write: never onto a file it reads, by any name (symbolic or hard link),
never onto a file an output folder's writer manages, never two outputs on one file."""

from __future__ import annotations

from pathlib import Path

import pytest

from roadgaze.errors import ConfigError
from roadgaze.outputs.paths import check_output_paths, same_file


def test_one_file_by_any_name(tmp_path: Path) -> None:
    track = tmp_path / "d.speed.csv"
    track.write_text("t_s,kmh\n", encoding="utf-8")
    (tmp_path / "soft.csv").symlink_to(track)
    (tmp_path / "hard.csv").hardlink_to(track)
    (tmp_path / "sub").mkdir()
    assert same_file(track, tmp_path / "soft.csv") and same_file(track, tmp_path / "hard.csv")
    assert same_file(track, tmp_path / "sub" / ".." / "d.speed.csv")
    assert not same_file(track, tmp_path / "other.csv")  # not there yet: another file
    (tmp_path / "loop").symlink_to(tmp_path / "loop")
    assert not same_file(track, tmp_path / "loop")  # a symlink loop is no error here
    for name in ("d.speed.csv", "soft.csv", "hard.csv"):
        with pytest.raises(ConfigError, match=r"is the input \(the track\)"):
            check_output_paths({"the track": track}, {"--csv": tmp_path / name})


def test_a_folder_writer_never_manages_an_input(tmp_path: Path) -> None:
    segment = tmp_path / "roadgaze-car-0-20260101T000000Z-0001.mcap"
    segment.write_bytes(b"")
    other = tmp_path / "drive.mp4"
    other.write_bytes(b"")
    folders = {"--record": (tmp_path, "roadgaze-car-0-*.mcap*")}
    check_output_paths({"the source": other}, {}, folders=folders)
    with pytest.raises(ConfigError, match=r"--record .* would prune or recover the input"):
        check_output_paths({"the source": segment}, {}, folders=folders)


def test_two_outputs_on_one_file_and_a_type_no_writer_writes(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="--out and --csv are the same file"):
        check_output_paths({}, {"--out": tmp_path / "a", "--csv": tmp_path / "a"})
    with pytest.raises(ConfigError, match=r"--plot .*: cannot write a \.txt file"):
        check_output_paths({}, {"--plot": tmp_path / "p.txt"}, {"--plot": (".png",)})
    check_output_paths({"the source": "-"}, {"--out": "-", "--csv": None})  # stdout, none


@pytest.mark.parametrize("kind", ["device", "fifo", "folder"])
def test_an_output_that_is_no_regular_file_is_refused_before_anything_runs(
    tmp_path: Path, kind: str
) -> None:
    """`replay --out /dev/null` used to replace /dev/null with a regular file (the offline pass
    writes a temporary file and renames it over the output)."""
    import os

    if kind == "device":
        target = Path("/dev/null")
    elif kind == "fifo":
        target = tmp_path / "pipe"
        os.mkfifo(target)
    else:
        target = tmp_path / "folder"
        target.mkdir()
    with pytest.raises(ConfigError, match=r"--out .* is not a regular file"):
        check_output_paths({}, {"--out": target})
    assert kind != "device" or not target.is_file()
