"""One output convention for every command: records and results on stdout (or in files),
progress, logs and "wrote FILE" on stderr, log lines never inside a progress bar, each event
told once (`roadgaze.logs`)."""

from __future__ import annotations

import csv
import json
import logging
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest
from skimage import data as skimage_data

from roadgaze.cli import main
from roadgaze.logs import ProgressAwareHandler, records_dropped, setup_logging

GLANCE = "0:1,0/-35:3.8,0:1"
"""One 3.8 s look into the lap: a long_distraction warning, then cleared."""
LOG_LINE = re.compile(r"^\d{4}-\d\d-\d\d \d\d:\d\d:\d\d,\d{3} (INFO|WARNING|ERROR) roadgaze")


def stderr_lines(err: str) -> list[str]:
    """What a terminal would show on each line: the text after the last carriage return."""
    return [line.rsplit("\r", 1)[-1] for line in err.split("\n") if line.rsplit("\r", 1)[-1]]


def log_lines(err: str) -> list[str]:
    return [line for line in stderr_lines(err) if LOG_LINE.match(line)]


def assert_logs_on_their_own_lines(err: str) -> None:
    """A log line glued to a progress bar would have bar text before its time stamp."""
    for line in err.split("\n"):
        shown = line.rsplit("\r", 1)[-1]
        if " INFO roadgaze" in shown or " WARNING roadgaze" in shown:
            assert LOG_LINE.match(shown), f"log line not on a line of its own: {line!r}"


def wrote(err: str) -> list[str]:
    return [line.split(": wrote ", 1)[1] for line in log_lines(err) if ": wrote " in line]


# ---------------------------------------------------------------- the logging itself


def test_log_lines_clear_a_progress_bar_first(capsys: pytest.CaptureFixture[str]) -> None:
    from tqdm import tqdm

    setup_logging("INFO")
    log = logging.getLogger("roadgaze.test")
    with tqdm(total=10, desc="work", file=None) as bar:
        for step in range(10):
            bar.update(1)
            if step in (3, 7):
                log.info("step %d done", step)
    err = capsys.readouterr().err
    assert_logs_on_their_own_lines(err)
    assert [line.split(": ", 1)[1] for line in log_lines(err)] == ["step 3 done", "step 7 done"]
    assert isinstance(logging.getLogger("roadgaze").handlers[0], ProgressAwareHandler)


def test_records_dropped_only_within_the_block(capsys: pytest.CaptureFixture[str]) -> None:
    setup_logging("INFO")
    log = logging.getLogger("roadgaze.daemon")
    with records_dropped("roadgaze.daemon", lambda record: hasattr(record, "alert")):
        log.info("alert one", extra={"alert": {}})
        log.info("other news")
    log.info("alert two", extra={"alert": {}})
    messages = [line.split(": ", 1)[1] for line in log_lines(capsys.readouterr().err)]
    assert messages == ["other news", "alert two"]


# ---------------------------------------------------------------- every command


@pytest.fixture(scope="module")
def glance_clip(synthetic_clip: Callable[[str], tuple[Path, Any]]) -> Path:
    return synthetic_clip(GLANCE)[0]


@pytest.mark.slow
def test_replay_without_out_writes_the_records_to_stdout_and_the_rest_to_stderr(
    glance_clip: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    plot = tmp_path / "yaw.png"
    assert main(["replay", str(glance_clip), "--plot", str(plot)]) == 0
    out, err = capsys.readouterr()
    records = [json.loads(line) for line in out.splitlines()]
    assert [record["frame"] for record in records] == list(range(round(5.8 * 15)))
    assert_logs_on_their_own_lines(err)
    logged = log_lines(err)
    assert sum("long_distraction" in line for line in logged) == 1  # told once, when raised
    alert_loggers = [line.split()[3] for line in logged if line.split()[4] == "alert"]
    assert alert_loggers == ["roadgaze.replay:"] * 2  # replay's own, not the daemon's
    assert sum("cleared" in line for line in logged) == 1
    [summary] = [line for line in logged if "frames, face in" in line]
    assert "2 alerts" in summary
    assert wrote(err) == [str(plot)]
    assert "replay: " in err  # the progress bar, on stderr


@pytest.mark.slow
def test_replay_out_file_keeps_stdout_empty(
    glance_clip: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out_path, table = tmp_path / "f.jsonl", tmp_path / "f.csv"
    args = ["replay", str(glance_clip), "--out", str(out_path), "--csv", str(table)]
    assert main([*args, "--no-progress"]) == 0
    out, err = capsys.readouterr()
    assert out == ""
    assert len(out_path.read_text().splitlines()) == round(5.8 * 15)
    assert wrote(err) == [str(out_path), str(table)]
    assert main(["replay", str(glance_clip), "--out", "-", "--no-progress"]) == 0
    assert len(capsys.readouterr().out.splitlines()) == round(5.8 * 15)
    # Each file in its option's format whatever its name, offline columns filled: `--out
    # rec.csv` (JSON lines) was read back as CSV and its offline columns left null.
    out_path, table = tmp_path / "rec.csv", tmp_path / "rec.jsonl"
    assert main([*args[:2], "--out", str(out_path), "--csv", str(table), "--no-progress"]) == 0
    assert "offline columns left null" not in capsys.readouterr().err
    records = [json.loads(line) for line in out_path.read_text().splitlines()]
    assert sum(r["yaw_offline_deg"] is not None for r in records) > 0.9 * len(records)
    with table.open(newline="") as stream:
        rows = list(csv.DictReader(stream))
    assert sum(row["yaw_offline_deg"] != "" for row in rows) > 0.9 * len(rows)


@pytest.mark.slow
def test_bench_prints_one_result_on_stdout(
    glance_clip: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["bench", str(glance_clip), "--json", "--warmup", "5", "--no-raw"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["frames"] == round(5.8 * 15)
    assert any("pipeline pass" in line for line in log_lines(err))


def test_synth_writes_files_and_says_so_on_stderr(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    clip = tmp_path / "clip.mp4"
    args = ["synth", "--timeline", "0:0.4", "--out", str(clip), "--size", "96x96"]
    assert main(args) == 0
    out, err = capsys.readouterr()
    assert out == ""
    assert wrote(err) == [str(clip), str(tmp_path / "clip.truth.csv")]


def test_paper_tables_results_on_stdout_files_on_stderr(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["paper-tables", "--plots", str(tmp_path)]) == 0
    out, err = capsys.readouterr()
    assert "Experiment 1" in out and "wrote" not in out
    assert sorted(Path(path).name for path in wrote(err)) == sorted(
        path.name for path in tmp_path.glob("*.png")
    )


def test_schema_and_model_path_print_only_their_result(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["schema", "yaw"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["title"] == "YawMessage" and err == ""
    assert main(["model", "path"]) == 0
    out, _ = capsys.readouterr()
    assert Path(out.strip()).is_file() and len(out.splitlines()) == 1


@pytest.mark.slow
def test_eval_report_on_stdout_files_on_stderr(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bgr = cv2.cvtColor(skimage_data.astronaut(), cv2.COLOR_RGB2BGR)
    cv2.imwrite(str(tmp_path / "a.png"), bgr)
    cv2.imwrite(str(tmp_path / "b.png"), np.ascontiguousarray(bgr[:, ::-1]))
    (tmp_path / "ground_truth.csv").write_text("file,yaw_deg\na.png,0\nb.png,0\n")
    report = tmp_path / "out" / "report.json"
    args = ["eval", str(tmp_path), "--workers", "1", "--report", str(report), "--no-progress"]
    assert main(args) == 0
    out, err = capsys.readouterr()
    assert "center_ce" in out.lower().replace("-", "_") and "wrote" not in out
    assert wrote(err) == [str(report)] and report.is_file()
