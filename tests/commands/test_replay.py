"""`roadgaze replay`'s wiring as a user meets it: no output ever lands on a file the replay reads
(the speed track found beside the video included, through links too), the log says where the
vehicle speed comes from and when it holds alerts back, and `--publish` says in its own terms
what never reached the bus. The camera and the model are scripted (no MediaPipe)."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import pytest

from fakes import ListSource, ScriptedDetector
from roadgaze.cli import main
from roadgaze.pipeline import EXIT_UNDELIVERED
from zenoh_helpers import endpoint, free_port

pytestmark = pytest.mark.usefixtures("restore_logging")

GLANCE = [0.0] * 10 + [-30.0] * 50
"""Road 1 s, then away: long_distraction warning at t = 4.1 s (10 fps)."""
TRACK = "t_s,kmh\n" + "".join(f"{0.5 * i:g},70\n" for i in range(13))


@pytest.fixture
def scripted(monkeypatch: pytest.MonkeyPatch) -> None:
    """The video's frames and the model: 60 frames at 10 fps of the glance."""
    import roadgaze.capture
    import roadgaze.pipeline

    monkeypatch.setattr(roadgaze.pipeline, "create_detector", lambda c: ScriptedDetector(GLANCE))
    monkeypatch.setattr(roadgaze.capture, "open_source", lambda *a, **k: ListSource(60, 10.0))


@pytest.fixture
def drive(tmp_path: Path) -> Path:
    """`d.mp4` with its speed track `d.speed.csv` beside it."""
    video = tmp_path / "d.mp4"
    video.write_bytes(b"the frames come from the scripted source")
    (tmp_path / "d.speed.csv").write_text(TRACK, encoding="utf-8")
    return video


def link(kind: str) -> Callable[[Path, Path], None]:
    return {"symlink": os.symlink, "hardlink": os.link}[kind]


@pytest.mark.parametrize(
    ("option", "name", "made"),
    [
        ("--csv", "d.speed.csv", None),
        ("--out", "d.speed.csv", None),
        ("--csv", "alias.csv", "symlink"),
        ("--out", "alias.jsonl", "hardlink"),
        ("--out", "d.mp4", None),
        ("--out", "settings.toml", None),
    ],
)
@pytest.mark.usefixtures("scripted")
def test_no_output_lands_on_a_file_the_replay_reads(
    drive: Path,
    capsys: pytest.CaptureFixture[str],
    option: str,
    name: str,
    made: str | None,
) -> None:
    """The track found beside the video (not named on the command line) was read, then
    overwritten by `--csv d.speed.csv`; now every input is checked, through links too: one
    line, exit 2, nothing written."""
    folder = drive.parent
    track = folder / "d.speed.csv"
    settings = folder / "settings.toml"
    settings.write_text("[monitor]\n", encoding="utf-8")
    if made is not None:
        link(made)(track, folder / name)
    before = {path.name: path.read_bytes() for path in folder.iterdir()}
    others = ["--plot", str(folder / "plot.png"), "--annotate", str(folder / "a.mp4")]
    argv = ["replay", str(drive), option, str(folder / name), *others, "--no-progress"]
    assert main([*argv, "--config", str(settings)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "is the input" in err and "would be overwritten" in err, err
    assert {path.name: path.read_bytes() for path in folder.iterdir()} == before


@pytest.mark.usefixtures("scripted")
def test_the_log_says_where_the_speed_comes_from_and_when_it_holds_alerts_back(
    drive: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = ["--out", str(tmp_path / "frames.jsonl"), "--no-progress"]
    assert main(["replay", str(drive), *out]) == 0
    err = capsys.readouterr().err
    assert f"vehicle speed from {drive.with_name('d.speed.csv')} (13 samples" in err
    assert "held back" not in err  # 70 km/h: alerts allowed throughout
    other = tmp_path / "other.mp4"
    other.write_bytes(b"no track beside this one")
    assert main(["replay", str(other), *out]) == 0
    err = capsys.readouterr().err
    assert f"replay {other}: no vehicle speed: taken as moving" in err
    assert "nowhere" not in err
    assert main(["replay", str(other), *out, "--speed-kmh", "10"]) == 0
    err = capsys.readouterr().err
    assert "vehicle speed 10 km/h at t=0.00 s, at or below the active speed" in err
    assert "alerts held back" in err
    assert "alerts were held back by the vehicle speed for 5.9 s in all (1 time)" in err


@pytest.mark.usefixtures("scripted")
def test_replay_publish_names_what_never_reached_the_bus_in_its_own_terms(
    drive: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(
        ["replay", str(drive), "--publish", "--out", str(tmp_path / "frames.jsonl"),
         "--zenoh-mode", "client", "--zenoh-connect", endpoint(free_port()),
         "--set", "zenoh.delivery_wait_s=0.2", "--no-progress"]
    )  # fmt: skip
    err = capsys.readouterr().err
    assert code == EXIT_UNDELIVERED, err[-2000:]
    named = "#0 long_distraction warning t=4.10s: never published: no zenoh session"
    assert f"{named} when the replay ended" in err
    assert "daemon" not in err
