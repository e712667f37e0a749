"""Every defect issue 10 lists ends in one line and exit 2, or is refused before anything is
written. `replay` runs in this process with a scripted source and detector (no MediaPipe)."""

from __future__ import annotations

import errno
import hashlib
import io
import os
from pathlib import Path
from typing import IO

import pytest

import roadgaze.capture
import roadgaze.outputs.records
import roadgaze.pipeline
from fakes import ListSource, ScriptedDetector
from roadgaze.cli import main

FRAMES = 60


pytestmark = pytest.mark.usefixtures("restore_logging")


@pytest.fixture
def scripted(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    """A 'video' whose frames come from a fake source; returns its (real, untouched) path."""
    video = tmp_path / "v.mp4"
    video.write_bytes(b"not really a video, but it must survive every command below")
    monkeypatch.setattr(roadgaze.capture, "open_source", lambda *a, **k: ListSource(FRAMES))
    monkeypatch.setattr(
        roadgaze.pipeline, "create_detector", lambda config: ScriptedDetector([10.0] * FRAMES)
    )
    return video


def one_error_line(capsys: pytest.CaptureFixture[str]) -> str:
    lines = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    errors = [line for line in lines if ": error: " in line]
    assert len(errors) == 1 and "Traceback" not in "\n".join(lines), lines
    return errors[0]


class FullDisk(io.StringIO):
    """A text stream on a disk that is full: every write fails as a full disk's does."""

    def write(self, text: str) -> int:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


def test_replay_to_a_full_disk_is_one_line_and_keeps_the_other_outputs(
    scripted: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    records, table = tmp_path / "frames.jsonl", tmp_path / "frames.csv"
    real_open = roadgaze.outputs.records.open_for_writing

    def open_on_a_full_disk(path: Path, what: str, newline: str | None = None) -> IO[str]:
        return FullDisk() if path == table else real_open(path, what, newline)

    monkeypatch.setattr(roadgaze.outputs.records, "open_for_writing", open_on_a_full_disk)
    code = main(["replay", str(scripted), "--out", str(records), "--csv", str(table),
                 "--no-progress"])  # fmt: skip
    assert code == 2
    assert one_error_line(capsys).endswith(f"No space left on device: {table}")
    lines = records.read_text().splitlines()
    assert len(lines) >= 1 and '"frame": 0' in lines[0]  # what was written so far is kept


def test_replay_to_a_device_is_refused_before_the_run(
    scripted: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    if not Path("/dev/full").exists():
        pytest.skip("/dev/full is Linux only")
    records = tmp_path / "frames.jsonl"
    code = main(["replay", str(scripted), "--out", str(records), "--csv", "/dev/full",
                 "--no-progress"])  # fmt: skip
    assert code == 2
    assert "--csv /dev/full is not a regular file" in one_error_line(capsys)
    assert not records.exists()  # refused before anything was written


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (["--plot", "p.xyz"], "--plot"),
        (["--annotate", "clip.gif"], "--annotate"),
        (["--annotate", "{video}"], "is the input"),
        (["--out", "{video}"], "is the input"),
        (["--out", "same.jsonl", "--csv", "same.jsonl"], "are the same file"),
        (["--plot", "x.png", "--annotate", "./x.png"], "--annotate"),
    ],
)
def test_replay_refuses_bad_output_paths_before_writing_anything(
    scripted: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    options: list[str],
    message: str,
) -> None:
    monkeypatch.chdir(tmp_path)
    before = hashlib.sha256(scripted.read_bytes()).hexdigest()
    listed = sorted(tmp_path.iterdir())
    options = [option.replace("{video}", str(scripted)) for option in options]
    assert main(["replay", str(scripted), "--no-progress", *options]) == 2
    assert message in one_error_line(capsys)
    assert hashlib.sha256(scripted.read_bytes()).hexdigest() == before
    assert sorted(tmp_path.iterdir()) == listed


def test_replay_refuses_two_outputs_on_one_path_through_a_symlink(
    scripted: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    target = tmp_path / "records.jsonl"
    target.write_text("")
    (tmp_path / "link.csv").symlink_to(target)
    code = main(["replay", str(scripted), "--no-progress", "--out", str(target),
                 "--csv", str(tmp_path / "link.csv")])  # fmt: skip
    assert code == 2 and "are the same file" in one_error_line(capsys)


@pytest.mark.parametrize("seconds", ["nan", "inf", "-1", "0"])
def test_bench_refuses_a_loop_that_would_never_end(
    scripted: Path, capsys: pytest.CaptureFixture[str], seconds: str
) -> None:
    assert main(["bench", str(scripted), "--loop-seconds", seconds]) == 2
    assert "--loop-seconds must be a finite number of seconds > 0" in one_error_line(capsys)


@pytest.mark.parametrize(
    ("setting", "message"),
    [
        ("monitor.critical_distraction_s=2", "must not be below long_distraction_s"),
        ("monitor.hysteresis_deg=30", "must be smaller than road_half_width_deg"),
        ("monitor.min_speed_kmh=inf", "finite number"),
        ("monitor.min_speed_kmh=nan", "finite number"),
        ("monitor.min_speed_kmh=true", "found a boolean"),
        ("monitor.min_speed_kmh=" + "9" * 5000, "limited to 4300 digits"),
        ("monitor.min_speed_kmh=" + "9" * 5000 + ".0", "finite number"),
        ("zenoh.vehicle_id='*'", "zenoh.vehicle_id"),
        ("zenoh.prefix='vehicle/*/dms'", "zenoh.prefix"),
        ("zenoh.speed_key='vehicle/{vehicle_id}//speed'", "zenoh.speed_key"),
        ("zenoh.alert_cache_size=0", "zenoh.alert_cache_size"),
    ],
)
def test_bad_settings_are_one_line_errors(
    capsys: pytest.CaptureFixture[str], setting: str, message: str
) -> None:
    assert main(["run", "--source", "/dev/video97", "--set", setting]) == 2
    line = one_error_line(capsys)
    assert message in line and len(line) < 500


def test_a_5000_digit_number_in_a_file_or_the_environment_is_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "roadgaze.toml"
    path.write_text("[monitor]\nmin_speed_kmh = " + "9" * 5000 + "\n")
    assert main(["run", "--source", "/dev/video97", "--config", str(path)]) == 2
    assert "4300 digits" in one_error_line(capsys)
    monkeypatch.setenv("ROADGAZE__MONITOR__MIN_SPEED_KMH", "9" * 5000)
    assert main(["run", "--source", "/dev/video97"]) == 2
    assert "ROADGAZE__MONITOR__MIN_SPEED_KMH" in one_error_line(capsys)


@pytest.mark.parametrize(
    ("rows", "message"),
    [
        ("file,yaw_deg\na.jpg\n", "must be numbers (finite)"),  # a short row: no yaw at all
        ("file,yaw_deg\na.jpg,\n", "must be numbers (finite)"),
        ("file,yaw_deg\na.jpg,nan\n", "must be numbers (finite)"),
        ("file,yaw_deg,pitch_deg\na.jpg,10,inf\n", "must be numbers (finite)"),
        ("file,yaw_deg\nmissing1.jpg,10\nmissing2.jpg,20\n", "none of the 2 images"),
    ],
)
def test_eval_refuses_bad_ground_truth_before_writing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], rows: str, message: str
) -> None:
    dataset = tmp_path / "set"
    dataset.mkdir()
    (dataset / "ground_truth.csv").write_text(rows)
    (dataset / "a.jpg").write_bytes(b"")
    report = tmp_path / "report.json"
    assert main(["eval", str(dataset), "--report", str(report), "--no-progress"]) == 2
    assert message in one_error_line(capsys)
    assert not report.exists()


def test_eval_refuses_a_report_over_its_own_ground_truth(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    dataset = tmp_path / "set"
    dataset.mkdir()
    truth = dataset / "ground_truth.csv"
    truth.write_text("file,yaw_deg\na.jpg,10\n")
    assert main(["eval", str(dataset), "--predictions", str(truth)]) == 2
    assert "is the input" in one_error_line(capsys)
    assert truth.read_text() == "file,yaw_deg\na.jpg,10\n"
